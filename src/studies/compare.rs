//! Errors of a model's [`Run`] against the reference's, on the same scene and samples.

use serde::{Deserialize, Serialize};

use crate::metrics::metrics;
use crate::run::Run;

/// Span of the early error window, s.
pub const EARLY_WINDOW: f64 = 0.5;

/// How far a run is from the reference (the JSON contract of `lpc compare`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Errors {
    /// RMS of `xs - xs_ref` over the horizon, m.
    pub rms_xs: f64,
    /// max |xs - xs_ref| over the first 0.5 s, m.
    pub max_xs_early: f64,
    /// `settling_time - settling_time_ref`, s; `null` when either run has not settled.
    pub settling_time_diff: Option<f64>,
    /// `(impact_loss - impact_loss_ref) / energy put in` (the initial energy, plus the
    /// reference's forcing work when forced).
    pub impact_loss_diff: f64,
    /// `impact_count - impact_count_ref`.
    pub impact_count_diff: i64,
}

/// Errors of `run` against `reference`; both must be sampled at the same times.
pub fn errors(run: &Run, reference: &Run) -> Errors {
    let (a, r) = (&run.series, &reference.series);
    let len = a.len().min(r.len());
    assert!(
        (0..len).all(|k| (a.t[k] - r.t[k]).abs() <= 1e-9 * run.sample_dt),
        "runs sampled at different times"
    );
    let mut sq = 0.0;
    let mut early: f64 = 0.0;
    for k in 0..len {
        let d = a.xs[k] - r.xs[k];
        sq += d * d;
        if r.t[k] <= EARLY_WINDOW {
            early = early.max(d.abs());
        }
    }
    let (ma, mr) = (metrics(run), metrics(reference));
    let put_in = reference.energy.initial.abs() + reference.energy.forcing_work.abs();
    let initial = if put_in != 0.0 { put_in } else { 1.0 };
    Errors {
        rms_xs: if len > 0 { (sq / len as f64).sqrt() } else { 0.0 },
        max_xs_early: early,
        settling_time_diff: ma.settling_time.zip(mr.settling_time).map(|(a, r)| a - r),
        impact_loss_diff: (run.energy.impact_loss - reference.energy.impact_loss) / initial,
        impact_count_diff: run.impacts.len() as i64 - reference.impacts.len() as i64,
    }
}
