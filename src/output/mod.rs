//! Output of runs: the JSON contract ([`RunSummary`]), a readable text summary, and the files
//! of `--out DIR` (`series.csv`, `impacts.csv`, `summary.json`), each written atomically.

pub mod figures;
pub mod parquet;
pub mod plot;
mod run_dir;

use crate::metrics::{Noise, RunSummary};

pub use run_dir::{impacts_csv, series_csv, table_csv, write_impacts_csv, write_run_dir, write_run_dir_with};

fn noise_line(n: &Noise) -> String {
    let Some(e) = n.energy_lost else {
        // A run that counted its impacts without keeping them has their rate but no spreads.
        return if n.impact_rate > 0.0 {
            format!("{:.1} impacts/s (counted, not kept: no spreads)", n.impact_rate)
        } else {
            "no impacts".into()
        };
    };
    let mut line =
        format!("{:.1} impacts/s; energy lost per impact mean {:.3e} J, p95 {:.3e} J, max {:.3e} J", n.impact_rate, e.mean, e.p95, e.max);
    if let Some(f) = n.peak_force {
        line += &format!("; peak force mean {:.1} N, p95 {:.1} N, max {:.1} N", f.mean, f.p95, f.max);
    }
    line
}

/// The energy left at the end as a share of the initial energy, or, where that means nothing
/// (an excitation puts energy in as it goes, or there was none at the start), the share of the
/// energy dissipated that the damper's impacts and contacts took.
fn energy_remaining(remaining: Option<f64>, e: &crate::metrics::EnergySummary) -> String {
    if let Some(x) = remaining {
        return format!("{:.4} %", x * 100.0);
    }
    let why = if e.forcing_work != 0.0 { "- (driven: energy is put in as it goes)" } else { "- (no energy at the start)" };
    let dissipated = e.damping_loss + e.impact_loss + e.contact_loss;
    if dissipated > 0.0 {
        format!("{why}; the damper took {:.1} % of the energy dissipated", 100.0 * (e.impact_loss + e.contact_loss) / dissipated)
    } else {
        why.into()
    }
}

/// A readable multi-line summary of a run.
pub fn text_summary(s: &RunSummary) -> String {
    let m = &s.metrics;
    let opt = |x: Option<f64>, unit: &str, scale: f64| x.map_or("not reached".to_string(), |v| format!("{:.4} {unit}", v * scale));
    let e = &s.energy;
    format!(
        "scene {} | model {} | horizon {} s | computed in {:.3} ms\n\
         impacts            {}{}\n\
         peak displacement  {:.4} mm (t >= T)\n\
         peak acceleration  {:.4} m/s^2 (t >= T){}\n\
         rms displacement   {:.4} mm\n\
         settling time      {}\n\
         energy remaining   {}\n\
         energy (J)         initial {:.6e}{} = final {:.6e} + damping {:.6e} + impacts {:.6e}{} (balance error {:.1e})\n\
         noise proxy        {}\n",
        s.scene,
        s.model,
        s.horizon,
        s.wall_time_s * 1e3,
        s.impact_count,
        if s.impacts_not_kept { " (counted, not kept)" } else { "" },
        m.peak_displacement * 1e3,
        m.peak_acceleration,
        match (m.peak_true_acceleration, m.peak_contact_force) {
            (Some(a), Some(f)) => format!("; with contact forces {a:.4} m/s^2; peak contact force {f:.1} N"),
            (Some(a), None) => format!("; with contact forces {a:.4} m/s^2"),
            _ => String::new(),
        },
        m.rms_displacement * 1e3,
        opt(m.settling_time, "s", 1.0),
        energy_remaining(m.energy_remaining, e),
        e.initial,
        if e.forcing_work != 0.0 { format!(" + forcing {:.6e}", e.forcing_work) } else { String::new() },
        e.final_,
        e.damping_loss,
        e.impact_loss,
        if e.contact_loss != 0.0 { format!(" + contacts {:.6e}", e.contact_loss) } else { String::new() },
        e.balance_error,
        noise_line(&s.noise),
    ) + &floors_table(s)
        + &dampers_table(s)
}

/// Each damper's impacts and losses, when the run has several.
fn dampers_table(s: &RunSummary) -> String {
    if s.dampers.is_empty() {
        return String::new();
    }
    let mut out = String::from("damper  floor  balls  impacts  on walls  impact loss (J)\n");
    for d in &s.dampers {
        out += &format!(
            "{:<6}  {:>5}  {:>5}  {:>7}  {:>8}  {:>15.6e}\n",
            d.damper, d.floor, d.balls, d.impacts, d.wall_impacts, d.impact_loss
        );
    }
    out
}

/// A structure's floors, with and without the damper when both are known.
fn floors_table(s: &RunSummary) -> String {
    if s.floors.is_empty() {
        return String::new();
    }
    let mut out = String::from("floor  peak disp (mm)  peak drift (mm)  peak abs accel (m/s^2)  rms disp (mm)\n");
    let row = |f: &crate::metrics::FloorSummary, label: &str| {
        format!(
            "{:<5}  {:>14.4}  {:>15.4}  {:>22.4}  {:>13.4}{label}\n",
            f.floor,
            f.peak_displacement * 1e3,
            f.peak_drift * 1e3,
            f.peak_acceleration,
            f.rms_displacement * 1e3
        )
    };
    for (i, f) in s.floors.iter().enumerate() {
        out += &row(f, "");
        if let Some(bare) = s.floors_without_damper.get(i) {
            out += &row(bare, "  (without damper)");
        }
    }
    out
}
