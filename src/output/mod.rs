//! Output of runs: the JSON contract ([`RunSummary`]), a readable text summary, and the files
//! of `--out DIR` (`series.csv`, `impacts.csv`, `summary.json`), each written atomically.

pub mod figures;
pub mod files;
pub mod parquet;
pub mod plot;

use serde::{Deserialize, Serialize};

use crate::metrics::{metrics, noise, Metrics, Noise};
use crate::run::Run;
use crate::scene::Scene;

pub use files::{table_csv, write_atomic, write_run_dir};

/// One impact as in the JSON contract.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImpactSummary {
    /// s.
    pub t: f64,
    /// `[A, B]`, e.g. `["left-wall", "ball1"]`.
    pub bodies: [String; 2],
    /// m/s.
    pub approach_speed: f64,
    /// J.
    pub energy_lost: f64,
    /// Largest contact force, N (compliant model only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_force: Option<f64>,
    /// Contact duration, s (compliant model only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact_duration: Option<f64>,
}

/// The energy account as in the JSON contract.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EnergySummary {
    /// J.
    pub initial: f64,
    /// J.
    #[serde(rename = "final")]
    pub final_: f64,
    /// J.
    pub damping_loss: f64,
    /// J.
    pub impact_loss: f64,
    /// Work done by the excitation, J (0 in free vibration).
    #[serde(default)]
    pub forcing_work: f64,
    /// Relative.
    pub balance_error: f64,
}

/// A run as in the JSON contract (`summary.json`, `lpc run --format json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    /// Scene name.
    pub scene: String,
    /// Model name.
    pub model: crate::run::Model,
    /// s.
    pub horizon: f64,
    /// Number of impacts.
    pub impact_count: usize,
    /// Every impact.
    pub impacts: Vec<ImpactSummary>,
    /// Headline metrics.
    pub metrics: Metrics,
    /// Energy account.
    pub energy: EnergySummary,
    /// Noise proxy: impact rate, energy lost, approach speed and peak force per impact.
    #[serde(default)]
    pub noise: Noise,
    /// Computing time, s.
    pub wall_time_s: f64,
    /// Present when the series keeps only every `k`-th sample, to fit in memory
    /// ([`crate::run::series_every`]); the metrics use every sample.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub series_every: Option<usize>,
}

impl RunSummary {
    /// The summary of `run`.
    pub fn of(run: &Run) -> Self {
        RunSummary {
            scene: run.scene.clone(),
            model: run.model,
            horizon: run.horizon,
            impact_count: run.impacts.len(),
            impacts: run
                .impacts
                .iter()
                .map(|i| ImpactSummary {
                    t: i.t,
                    bodies: [Scene::body_name(i.a), Scene::body_name(i.b)],
                    approach_speed: i.approach_speed,
                    energy_lost: i.energy_lost,
                    peak_force: i.peak_force,
                    contact_duration: i.contact_duration,
                })
                .collect(),
            metrics: metrics(run),
            energy: EnergySummary {
                initial: run.energy.initial,
                final_: run.energy.final_,
                damping_loss: run.energy.damping_loss,
                impact_loss: run.energy.impact_loss,
                forcing_work: run.energy.forcing_work,
                balance_error: run.energy.balance_error,
            },
            noise: noise(run),
            wall_time_s: run.wall_time_s,
            series_every: (run.series.every > 1).then_some(run.series.every),
        }
    }
}

/// Every number of a run's summary that studies tabulate, map and draw distributions of.
pub const SUMMARY_METRICS: &[&str] = &[
    "peak_displacement",
    "peak_acceleration",
    "rms_displacement",
    "settling_time",
    "energy_remaining",
    "dissipation_time_90",
    "dissipation_time_99",
    "peak_contact_force",
    "peak_true_acceleration",
    "impact_count",
    "impact_loss",
    "impact_rate",
];

/// The numbers of a run that studies tabulate, map and draw distributions of: its metrics and
/// its impact totals ([`SUMMARY_METRICS`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Headline {
    /// The metrics.
    pub metrics: Metrics,
    /// Number of impacts.
    pub impact_count: usize,
    /// Energy lost in impacts, J.
    pub impact_loss: f64,
    /// Impacts per simulated second.
    pub impact_rate: f64,
}

impl Headline {
    /// The headline of `run`, without building its summary (an ensemble member's).
    pub fn of_run(run: &Run) -> Self {
        Headline {
            metrics: metrics(run),
            impact_count: run.impacts.len(),
            impact_loss: run.energy.impact_loss,
            impact_rate: crate::metrics::impact_rate(run),
        }
    }
    /// The headline of a run's summary.
    pub fn of_summary(s: &RunSummary) -> Self {
        Headline { metrics: s.metrics, impact_count: s.impact_count, impact_loss: s.energy.impact_loss, impact_rate: s.noise.impact_rate }
    }
    /// The value of metric `name` (one of [`SUMMARY_METRICS`]); `None` when the run has none
    /// (not settled, no contact forces) or the name is unknown.
    pub fn value(&self, name: &str) -> Option<f64> {
        let m = &self.metrics;
        match name {
            "peak_displacement" => Some(m.peak_displacement),
            "peak_acceleration" => Some(m.peak_acceleration),
            "rms_displacement" => Some(m.rms_displacement),
            "settling_time" => m.settling_time,
            "energy_remaining" => m.energy_remaining,
            "dissipation_time_90" => m.dissipation_time_90,
            "dissipation_time_99" => m.dissipation_time_99,
            "peak_contact_force" => m.peak_contact_force,
            "peak_true_acceleration" => m.peak_true_acceleration,
            "impact_count" => Some(self.impact_count as f64),
            "impact_loss" => Some(self.impact_loss),
            "impact_rate" => Some(self.impact_rate),
            _ => None,
        }
    }
    /// Every metric, in [`SUMMARY_METRICS`] order.
    pub fn values(&self) -> Vec<Option<f64>> {
        SUMMARY_METRICS.iter().map(|name| self.value(name)).collect()
    }
}

/// The value of metric `name` (one of [`SUMMARY_METRICS`]) in `summary`.
pub fn metric_value(summary: &RunSummary, name: &str) -> Option<f64> {
    Headline::of_summary(summary).value(name)
}

fn noise_line(n: &Noise) -> String {
    let Some(e) = n.energy_lost else { return "no impacts".into() };
    let mut line = format!(
        "{:.1} impacts/s; energy lost per impact mean {:.3e} J, p95 {:.3e} J, max {:.3e} J",
        n.impact_rate, e.mean, e.p95, e.max
    );
    if let Some(f) = n.peak_force {
        line += &format!("; peak force mean {:.1} N, p95 {:.1} N, max {:.1} N", f.mean, f.p95, f.max);
    }
    line
}

/// A readable multi-line summary of a run.
pub fn text_summary(s: &RunSummary) -> String {
    let m = &s.metrics;
    let opt = |x: Option<f64>, unit: &str, scale: f64| x.map_or("not reached".to_string(), |v| format!("{:.4} {unit}", v * scale));
    let e = &s.energy;
    format!(
        "scene {} | model {} | horizon {} s | computed in {:.3} ms\n\
         impacts            {}\n\
         peak displacement  {:.4} mm (t >= T)\n\
         peak acceleration  {:.4} m/s^2 (t >= T){}\n\
         rms displacement   {:.4} mm\n\
         settling time      {}\n\
         energy remaining   {}\n\
         energy (J)         initial {:.6e}{} = final {:.6e} + damping {:.6e} + impacts {:.6e} (balance error {:.1e})\n\
         noise proxy        {}\n",
        s.scene,
        s.model,
        s.horizon,
        s.wall_time_s * 1e3,
        s.impact_count,
        m.peak_displacement * 1e3,
        m.peak_acceleration,
        match (m.peak_true_acceleration, m.peak_contact_force) {
            (Some(a), Some(f)) => format!("; with contact forces {a:.4} m/s^2; peak contact force {f:.1} N"),
            (Some(a), None) => format!("; with contact forces {a:.4} m/s^2"),
            _ => String::new(),
        },
        m.rms_displacement * 1e3,
        opt(m.settling_time, "s", 1.0),
        opt(m.energy_remaining.map(|x| x * 100.0), "%", 1.0),
        e.initial,
        if e.forcing_work != 0.0 { format!(" + forcing {:.6e}", e.forcing_work) } else { String::new() },
        e.final_,
        e.damping_loss,
        e.impact_loss,
        e.balance_error,
        noise_line(&s.noise),
    )
}
