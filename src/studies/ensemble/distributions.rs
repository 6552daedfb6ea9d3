//! Distributions of an ensemble's metrics: quantiles and spreads, the band of the members'
//! motion, two samples told apart (Kolmogorov-Smirnov, medians against bands) and bootstrap
//! bands of a quantile.

use std::collections::BTreeMap;

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::Ensemble;
use crate::metrics::Metric;
use crate::model::Model;

/// A distribution's summary: median, 5-95 % band, mean, standard deviation and range of the
/// members that define the value (`null` when none does), and how many do not.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Stats {
    /// 50 % quantile.
    pub median: Option<f64>,
    /// 5 % quantile.
    pub p05: Option<f64>,
    /// 95 % quantile.
    pub p95: Option<f64>,
    /// Mean.
    pub mean: Option<f64>,
    /// Sample standard deviation (0 for one member).
    pub std: Option<f64>,
    /// Smallest.
    pub min: Option<f64>,
    /// Largest.
    pub max: Option<f64>,
    /// Members for which the value is undefined (a run that never settled, say).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub undefined: usize,
}

fn is_zero(k: &usize) -> bool {
    *k == 0
}

impl Stats {
    /// The summary of `values` (`None` for an undefined value).
    pub fn of(values: impl IntoIterator<Item = Option<f64>>) -> Stats {
        let mut undefined = 0;
        let mut v: Vec<f64> = values
            .into_iter()
            .filter_map(|x| {
                undefined += x.is_none() as usize;
                x
            })
            .collect();
        if v.is_empty() {
            return Stats { undefined, ..Stats::default() };
        }
        v.sort_by(f64::total_cmp);
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = if v.len() > 1 { v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0) } else { 0.0 };
        Stats {
            median: Some(quantile(&v, 0.5)),
            p05: Some(quantile(&v, 0.05)),
            p95: Some(quantile(&v, 0.95)),
            mean: Some(mean),
            std: Some(var.sqrt()),
            min: v.first().copied(),
            max: v.last().copied(),
            undefined,
        }
    }
}

/// The `q` quantile of sorted values, interpolated linearly between order statistics (the
/// usual definition: `q = 0` is the least, `q = 1` the largest). NaN when empty.
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let h = q.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let (lo, frac) = (h.floor() as usize, h - h.floor());
    let hi = (lo + 1).min(sorted.len() - 1);
    // Exactly on an order statistic, or between equal ones (infinite ones too: a run that
    // never settled ranks last), there is nothing to interpolate.
    if frac == 0.0 || sorted[lo] == sorted[hi] {
        return sorted[lo];
    }
    sorted[lo] + frac * (sorted[hi] - sorted[lo])
}

/// `lpc run --ensemble`'s JSON (`ensemble.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EnsembleSummary {
    /// Scene name.
    pub scene: String,
    /// Model.
    pub model: Model,
    /// Number of members.
    pub members: usize,
    /// Draws thrown away as invalid.
    pub redraws: u64,
    /// Seed of the draws.
    pub seed: u64,
    /// Each metric of the single-run summary over the members.
    pub metrics: BTreeMap<String, Stats>,
    /// Computing time of the whole ensemble, s.
    pub wall_time_s: f64,
}

impl EnsembleSummary {
    /// The summary of `members` of scene `scene` run with `model`, whose metrics are `metrics`
    /// (`[member][metric]`), computed in `wall_time_s`.
    pub fn of(scene: &str, model: Model, members: &Ensemble, metrics: &[Vec<Option<f64>>], wall_time_s: f64) -> Self {
        EnsembleSummary {
            scene: scene.to_string(),
            model,
            members: members.members.len(),
            redraws: members.redraws,
            seed: members.seed,
            metrics: metric_stats(metrics),
            wall_time_s,
        }
    }
}

/// Each metric's distribution over `metrics` (`[member][metric]`, [`Metric::ALL`] order).
pub fn metric_stats(metrics: &[Vec<Option<f64>>]) -> BTreeMap<String, Stats> {
    Metric::ALL.iter().enumerate().map(|(j, metric)| (metric.name().to_string(), Stats::of(metrics.iter().map(|m| m[j])))).collect()
}

/// Each metric's `q` quantile over the members that define it (`None` when none does).
pub fn metric_quantiles(metrics: &[Vec<Option<f64>>], q: f64) -> BTreeMap<String, Option<f64>> {
    Metric::ALL
        .iter()
        .enumerate()
        .map(|(j, metric)| {
            let mut v: Vec<f64> = metrics.iter().filter_map(|m| m[j]).collect();
            v.sort_by(f64::total_cmp);
            (metric.name().to_string(), (!v.is_empty()).then(|| quantile(&v, q)))
        })
        .collect()
}

/// Checks a quantile given on the command line as `field`.
pub fn check_quantile(q: f64) -> Result<f64, String> {
    if (0.0..=1.0).contains(&q) {
        Ok(q)
    } else {
        Err(format!("must lie in [0, 1] (got {})", crate::scene::human(q)))
    }
}

/// The 5 %, 50 % and 95 % quantiles of the members' displacement at each sample, and the
/// 95 % quantile of its magnitude: rows `t, xs_p05, xs_median, xs_p95, env_p95`.
pub fn band(t: &[f64], xs: &[Vec<f64>]) -> Vec<[f64; 5]> {
    let len = xs.iter().map(Vec::len).min().unwrap_or(0).min(t.len());
    (0..len)
        .into_par_iter()
        .map(|k| {
            let mut v: Vec<f64> = xs.iter().map(|m| m[k]).collect();
            v.sort_by(f64::total_cmp);
            let mut env: Vec<f64> = v.iter().map(|x| x.abs()).collect();
            env.sort_by(f64::total_cmp);
            [t[k], quantile(&v, 0.05), quantile(&v, 0.5), quantile(&v, 0.95), quantile(&env, 0.95)]
        })
        .collect()
}

/// The two-sample Kolmogorov-Smirnov statistic: the largest distance between the empirical
/// distribution functions of `a` and `b` (0 when either is empty).
pub fn ks_statistic(a: &[f64], b: &[f64]) -> f64 {
    if a.is_empty() || b.is_empty() {
        return 0.0;
    }
    let (mut a, mut b) = (a.to_vec(), b.to_vec());
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    let (mut i, mut j, mut d) = (0, 0, 0.0f64);
    while i < a.len() && j < b.len() {
        let x = a[i].min(b[j]);
        while i < a.len() && a[i] <= x {
            i += 1;
        }
        while j < b.len() && b[j] <= x {
            j += 1;
        }
        d = d.max((i as f64 / a.len() as f64 - j as f64 / b.len() as f64).abs());
    }
    d
}

/// How one metric's distribution under a model stands against the reference's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Agreement {
    /// Model's median minus the reference's (`null` when either has no defined value).
    pub median_diff: Option<f64>,
    /// Whether the model's median lies inside the reference's 5-95 % band.
    pub median_inside_reference_band: Option<bool>,
    /// Two-sample Kolmogorov-Smirnov statistic between the defined values.
    pub ks: Option<f64>,
    /// Whether that statistic says the two distributions differ at 5 % significance
    /// (`D > 1.358 sqrt((n + m) / (n m))`, the asymptotic critical value).
    pub differ_at_5_percent: Option<bool>,
}

/// Each metric's [`Agreement`] of `model` with `reference` (`[member][metric]` each,
/// [`Metric::ALL`] order).
pub fn agreement(model: &[Vec<Option<f64>>], reference: &[Vec<Option<f64>>]) -> BTreeMap<String, Agreement> {
    Metric::ALL
        .iter()
        .enumerate()
        .map(|(j, metric)| {
            let values = |runs: &[Vec<Option<f64>>]| runs.iter().filter_map(|m| m[j]).collect::<Vec<f64>>();
            let (m, r) = (values(model), values(reference));
            let (sm, sr) = (Stats::of(m.iter().map(|&x| Some(x))), Stats::of(r.iter().map(|&x| Some(x))));
            let both = !m.is_empty() && !r.is_empty();
            let ks = both.then(|| ks_statistic(&m, &r));
            let (n, k) = (m.len() as f64, r.len() as f64);
            let a = Agreement {
                median_diff: sm.median.zip(sr.median).map(|(a, b)| a - b),
                median_inside_reference_band: sm.median.zip(sr.p05.zip(sr.p95)).map(|(x, (lo, hi))| lo <= x && x <= hi),
                ks,
                differ_at_5_percent: ks.map(|d| d > 1.358 * ((n + k) / (n * k)).sqrt()),
            };
            (metric.name().to_string(), a)
        })
        .collect()
}

/// Resamples of a bootstrap.
pub const BOOTSTRAP_RESAMPLES: usize = 1000;

/// The 5-95 % band of the `q` quantile of `values` by bootstrap ([`BOOTSTRAP_RESAMPLES`]
/// resamples with replacement, drawn from `seed`): how well the members pin the quantile.
pub fn bootstrap_band(values: &[f64], q: f64, seed: u64) -> Option<(f64, f64)> {
    if values.is_empty() {
        return None;
    }
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut estimates: Vec<f64> = (0..BOOTSTRAP_RESAMPLES)
        .map(|_| {
            let mut r: Vec<f64> = (0..values.len()).map(|_| values[rng.random_range(0..values.len())]).collect();
            r.sort_by(f64::total_cmp);
            quantile(&r, q)
        })
        .collect();
    estimates.sort_by(f64::total_cmp);
    Some((quantile(&estimates, 0.05), quantile(&estimates, 0.95)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_interpolate_between_order_statistics() {
        let v = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!((quantile(&v, 0.0), quantile(&v, 0.5), quantile(&v, 1.0)), (1.0, 3.0, 5.0));
        assert_eq!(quantile(&v, 0.05), 1.2);
        let s = Stats::of([Some(2.0), None, Some(4.0)]);
        assert_eq!((s.median, s.mean, s.undefined), (Some(3.0), Some(3.0), 1));
        assert_eq!(s.std, Some(2f64.sqrt()));
    }

    #[test]
    fn ks_statistic_of_identical_and_disjoint_samples() {
        assert_eq!(ks_statistic(&[1.0, 2.0, 3.0], &[3.0, 1.0, 2.0]), 0.0);
        assert_eq!(ks_statistic(&[1.0, 2.0], &[3.0, 4.0]), 1.0);
        assert_eq!(ks_statistic(&[1.0, 2.0, 3.0, 4.0], &[2.5]), 0.5);
    }
}
