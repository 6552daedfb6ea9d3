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

/// Errors of `run` against `reference` at the samples both series hold: every sample of the
/// scene, or, when a series had to keep only every k-th of them to fit in memory (each run
/// judges that for itself), the ones they share.
pub fn errors(run: &Run, reference: &Run) -> Errors {
    let (a, r) = (&run.series, &reference.series);
    let (at, axs, rt, rxs) = (a.t(), a.xs(), r.t(), r.xs());
    let tol = 1e-9 * run.sample_dt;
    let (mut i, mut j) = (0, 0);
    let (mut sq, mut shared) = (0.0, 0usize);
    let mut early: f64 = 0.0;
    while i < a.len() && j < r.len() {
        if at[i] < rt[j] - tol {
            i += 1;
        } else if rt[j] < at[i] - tol {
            j += 1;
        } else {
            let d = axs[i] - rxs[j];
            sq += d * d;
            shared += 1;
            if rt[j] <= EARLY_WINDOW {
                early = early.max(d.abs());
            }
            i += 1;
            j += 1;
        }
    }
    let (ma, mr) = (metrics(run), metrics(reference));
    let put_in = reference.energy.initial.abs() + reference.energy.forcing_work.abs();
    let initial = if put_in != 0.0 { put_in } else { 1.0 };
    Errors {
        rms_xs: if shared > 0 { (sq / shared as f64).sqrt() } else { 0.0 },
        max_xs_early: early,
        settling_time_diff: ma.settling_time.zip(mr.settling_time).map(|(a, r)| a - r),
        impact_loss_diff: (run.energy.impact_loss - reference.energy.impact_loss) / initial,
        impact_count_diff: run.impact_count() as i64 - reference.impact_count() as i64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::Series;

    /// A run of `samples` samples of `xs = k` (k the sample index), keeping every `every`-th.
    fn thinned(samples: usize, every: usize, offset: f64) -> Run {
        let kept: Vec<usize> = (0..samples).step_by(every).collect();
        let t = kept.iter().map(|&k| k as f64 * 1e-3).collect();
        let xs = kept.iter().map(|&k| k as f64 + offset).collect();
        let mut series = Series::from_columns(t, xs, vec![0.0; kept.len()], vec![0.0; kept.len()], vec![], vec![]);
        series.every = every;
        Run { series, sample_dt: 1e-3, ..Run::empty("thinned", crate::run::Model::Reference) }
    }

    /// Runs thinned by different factors (each judges its memory for itself) are compared
    /// at the samples they share, not index by index.
    #[test]
    fn thinned_runs_compare_at_their_shared_samples() {
        let e = errors(&thinned(1001, 2, 0.5), &thinned(1001, 3, 0.0));
        // Shared: every 6th sample, each off by 0.5.
        assert_eq!(e.rms_xs, 0.5);
        assert_eq!(e.max_xs_early, 0.5);
        let same = errors(&thinned(1001, 1, 0.0), &thinned(1001, 1, 0.0));
        assert_eq!(same.rms_xs, 0.0);
    }
}
