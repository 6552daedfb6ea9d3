//! A run as the tool reports it: the JSON contract of `summary.json` and `lpc run --format
//! json` ([`RunSummary`]), and the numbers studies tabulate ([`Headline`]).

use serde::{Deserialize, Serialize};

use super::{metrics, noise, Metric, Metrics, Noise};
use crate::run::Run;
use crate::scene::Body;

/// One impact as in the JSON contract.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImpactSummary {
    /// s.
    pub t: f64,
    /// `[A, B]`, e.g. `["left-wall", "ball1"]`.
    pub bodies: [Body; 2],
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

fn is_zero(x: &f64) -> bool {
    *x == 0.0
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
    /// Lost in contacts besides the impacts (friction, plastic resting contacts), J; absent
    /// when 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub contact_loss: f64,
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
    /// Every impact (none when the run counted them without keeping them).
    pub impacts: Vec<ImpactSummary>,
    /// Present and true when the run counted its impacts without keeping them
    /// ([`crate::run::ImpactRecord::Count`]): `impacts` is then empty, and the noise proxy has
    /// its rate but none of its spreads.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub impacts_not_kept: bool,
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
    /// A structure's floors, bottom to top, read at the kept samples (empty without one).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub floors: Vec<FloorSummary>,
    /// The same floors without the damper (the structure alone), when the caller ran it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub floors_without_damper: Vec<FloorSummary>,
    /// Each damper's impacts and losses, when the scene carries several (empty otherwise, and
    /// when the run counted its impacts without keeping them).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub dampers: Vec<DamperSummary>,
    /// Present when the run stopped before its horizon (a budget, a broken invariant): why.
    /// The summary is then of the run so far, up to `horizon`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stop: Option<String>,
}

/// One floor's response as a structural engineer reads it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FloorSummary {
    /// 1 at the bottom.
    pub floor: usize,
    /// Largest `|u|` relative to the ground, m.
    pub peak_displacement: f64,
    /// Largest interstorey drift `|u_i - u_{i-1}|` (the ground below floor 1), m.
    pub peak_drift: f64,
    /// Largest absolute acceleration (impulses excluded), m/s^2.
    pub peak_acceleration: f64,
    /// Root mean square of `u` over the samples, m.
    pub rms_displacement: f64,
}

impl FloorSummary {
    /// Every floor of `series` (none when it has no floors), over its kept samples.
    pub fn of(series: &crate::run::Series) -> Vec<FloorSummary> {
        let n = series.floor_count();
        let samples = series.len();
        (0..n)
            .map(|i| {
                let mut f =
                    FloorSummary { floor: i + 1, peak_displacement: 0.0, peak_drift: 0.0, peak_acceleration: 0.0, rms_displacement: 0.0 };
                let mut sum = 0.0;
                for k in 0..samples {
                    let Some((u, _, a)) = series.floor(i, k) else { break };
                    let below = if i > 0 { series.floor(i - 1, k).map_or(0.0, |b| b.0) } else { 0.0 };
                    f.peak_displacement = f.peak_displacement.max(u.abs());
                    f.peak_drift = f.peak_drift.max((u - below).abs());
                    f.peak_acceleration = f.peak_acceleration.max(a.abs());
                    sum += u * u;
                }
                f.rms_displacement = if samples > 0 { (sum / samples as f64).sqrt() } else { 0.0 };
                f
            })
            .collect()
    }
}

/// One damper's share of a run of several: what its balls' impacts did.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DamperSummary {
    /// 1 for the first `[[damper]]`.
    pub damper: usize,
    /// The floor that carries it, 1 at the bottom.
    pub floor: usize,
    /// Its number of balls.
    pub balls: usize,
    /// Its impacts: between its balls, and of its balls on its walls.
    pub impacts: usize,
    /// Of which on its walls.
    pub wall_impacts: usize,
    /// The energy its impacts lost, J.
    pub impact_loss: f64,
}

impl DamperSummary {
    /// Each damper of `scene` in `run` (none for a scene of one damper, or a run that did not
    /// keep its impacts).
    pub fn of(scene: &crate::scene::Scene, run: &Run) -> Vec<DamperSummary> {
        if !scene.has_several_dampers() || run.counted_impacts.count > 0 {
            return Vec::new();
        }
        let mut out: Vec<DamperSummary> = scene
            .dampers
            .iter()
            .enumerate()
            .map(|(k, d)| DamperSummary {
                damper: k + 1,
                floor: d.floor + 1,
                balls: d.balls.len(),
                impacts: 0,
                wall_impacts: 0,
                impact_loss: 0.0,
            })
            .collect();
        for impact in &run.impacts {
            // Every impact has a ball; the other body is a ball of the same damper or a wall.
            let (ball, wall) = match (impact.a, impact.b) {
                (Body::Ball(i), Body::Ball(_)) => (i, false),
                (Body::Ball(i), _) | (_, Body::Ball(i)) => (i, true),
                _ => continue,
            };
            let d = &mut out[scene.damper_of(ball)];
            d.impacts += 1;
            d.wall_impacts += usize::from(wall);
            d.impact_loss += impact.energy_lost;
        }
        out
    }
}

impl RunSummary {
    /// The summary of `run`.
    pub fn of(run: &Run) -> Self {
        RunSummary {
            scene: run.scene.clone(),
            model: run.model,
            horizon: run.horizon,
            impact_count: run.impact_count(),
            impacts: run
                .impacts
                .iter()
                .map(|i| ImpactSummary {
                    t: i.t,
                    bodies: [i.a, i.b],
                    approach_speed: i.approach_speed,
                    energy_lost: i.energy_lost,
                    peak_force: i.peak_force,
                    contact_duration: i.contact_duration,
                })
                .collect(),
            impacts_not_kept: run.counted_impacts.count > 0,
            metrics: metrics(run),
            energy: EnergySummary {
                initial: run.energy.initial,
                final_: run.energy.final_,
                damping_loss: run.energy.damping_loss,
                impact_loss: run.energy.impact_loss,
                contact_loss: run.energy.contact_loss,
                forcing_work: run.energy.forcing_work,
                balance_error: run.energy.balance_error,
            },
            noise: noise(run),
            wall_time_s: run.wall_time_s,
            series_every: (run.series.every > 1).then_some(run.series.every),
            floors: FloorSummary::of(&run.series),
            floors_without_damper: vec![],
            dampers: vec![],
            stop: None,
        }
    }
}

/// The numbers of a run that studies tabulate, map and draw distributions of: its metrics and
/// its impact totals ([`Metric::ALL`]).
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
            impact_count: run.impact_count(),
            impact_loss: run.energy.impact_loss,
            impact_rate: crate::metrics::impact_rate(run),
        }
    }
    /// The headline of a run's summary.
    pub fn of_summary(s: &RunSummary) -> Self {
        Headline { metrics: s.metrics, impact_count: s.impact_count, impact_loss: s.energy.impact_loss, impact_rate: s.noise.impact_rate }
    }
    /// The value of `metric`; `None` when the run has none (not settled, no contact forces).
    pub fn value(&self, metric: Metric) -> Option<f64> {
        let m = &self.metrics;
        match metric {
            Metric::PeakDisplacement => Some(m.peak_displacement),
            Metric::PeakAcceleration => Some(m.peak_acceleration),
            Metric::RmsDisplacement => Some(m.rms_displacement),
            Metric::SettlingTime => m.settling_time,
            Metric::EnergyRemaining => m.energy_remaining,
            Metric::DissipationTime90 => m.dissipation_time_90,
            Metric::DissipationTime99 => m.dissipation_time_99,
            Metric::PeakContactForce => m.peak_contact_force,
            Metric::PeakTrueAcceleration => m.peak_true_acceleration,
            Metric::ImpactCount => Some(self.impact_count as f64),
            Metric::ImpactLoss => Some(self.impact_loss),
            Metric::ImpactRate => Some(self.impact_rate),
            Metric::PeakDrift => m.peak_drift,
            Metric::PeakRoofDisplacement => m.peak_roof_displacement,
            Metric::PeakFloorAcceleration => m.peak_floor_acceleration,
        }
    }
    /// Every metric, in [`Metric::ALL`] order.
    pub fn values(&self) -> Vec<Option<f64>> {
        Metric::ALL.iter().map(|&m| self.value(m)).collect()
    }
}
