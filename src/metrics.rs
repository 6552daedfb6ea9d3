//! Headline metrics of docs/MODEL.md §7, computed from a [`Run`]'s samples once, the same way for
//! every model: peaks after one bare period, RMS, settling time, energy remaining.

use crate::run::Run;

/// Fraction of `|xs0|` that counts as settled.
pub const SETTLING_FRACTION: f64 = 0.05;

/// The headline metrics of one run.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Metrics {
    /// max |xs| for t >= T, m.
    pub peak_displacement: f64,
    /// max |a| for t >= T, m/s^2.
    pub peak_acceleration: f64,
    /// RMS of xs over the horizon, m.
    pub rms_displacement: f64,
    /// Last time |xs| >= 5 % of |xs0|; `None` when that still holds at the horizon.
    pub settling_time: Option<f64>,
    /// Mechanical energy at the horizon / initial energy (`None` when the initial energy is 0).
    pub energy_remaining: Option<f64>,
    /// Largest contact force over all impacts, N (`None` for impulse models).
    #[serde(default)]
    pub peak_contact_force: Option<f64>,
    /// max |a| for t >= T with contact forces included, m/s^2 (`None` for impulse models).
    #[serde(default)]
    pub peak_true_acceleration: Option<f64>,
}

/// Mean, 95th percentile and largest of a set of per-impact values.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Spread {
    /// Mean.
    pub mean: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
    /// Largest.
    pub max: f64,
}

impl Spread {
    /// The spread of `values` (`None` when there are none).
    pub fn of(mut values: Vec<f64>) -> Option<Spread> {
        if values.is_empty() {
            return None;
        }
        values.sort_by(f64::total_cmp);
        let n = values.len();
        let rank = ((0.95 * n as f64).ceil() as usize).clamp(1, n);
        Some(Spread { mean: values.iter().sum::<f64>() / n as f64, p95: values[rank - 1], max: values[n - 1] })
    }
}

/// A noise proxy (the paper names noise as impact dampers' weak point): how often, how hard
/// and how loud the damper hits. Sound radiated by an impact grows with the energy it
/// releases and with the peak force (which sets its frequency content), so dampers are
/// compared on those statistics. Only wall impacts excite the structure directly, so they
/// are also given alone.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Noise {
    /// Impacts per simulated second.
    pub impact_rate: f64,
    /// Energy lost per impact, J.
    pub energy_lost: Option<Spread>,
    /// Energy lost per impact on a container wall, J.
    pub wall_energy_lost: Option<Spread>,
    /// Approach speed per impact, m/s.
    pub approach_speed: Option<Spread>,
    /// Peak contact force per impact, N (compliant contact only).
    pub peak_force: Option<Spread>,
}

/// The noise proxy of `run`.
pub fn noise(run: &Run) -> Noise {
    use crate::scene::Body;
    let i = &run.impacts;
    let on_wall = |b: Body| matches!(b, Body::LeftWall | Body::RightWall);
    Noise {
        impact_rate: if run.horizon > 0.0 { i.len() as f64 / run.horizon } else { 0.0 },
        energy_lost: Spread::of(i.iter().map(|x| x.energy_lost).collect()),
        wall_energy_lost: Spread::of(i.iter().filter(|x| on_wall(x.a) || on_wall(x.b)).map(|x| x.energy_lost).collect()),
        approach_speed: Spread::of(i.iter().map(|x| x.approach_speed).collect()),
        peak_force: Spread::of(i.iter().filter_map(|x| x.peak_force).collect()),
    }
}

/// Computes the metrics of `run`.
pub fn metrics(run: &Run) -> Metrics {
    let s = &run.series;
    let after_period = s.t.partition_point(|&t| t < run.damped_period);
    let peak = |v: &[f64]| v[after_period.min(v.len())..].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let rms = if s.is_empty() { 0.0 } else { (s.xs.iter().map(|x| x * x).sum::<f64>() / s.len() as f64).sqrt() };
    Metrics {
        peak_displacement: peak(&s.xs),
        peak_acceleration: peak(&s.a),
        rms_displacement: rms,
        settling_time: settling_time(&s.t, &s.xs, run.initial_displacement),
        energy_remaining: (run.energy.initial != 0.0).then(|| run.energy.final_ / run.energy.initial),
        peak_contact_force: run.impacts.iter().filter_map(|i| i.peak_force).reduce(f64::max),
        peak_true_acceleration: run.peak_true_acceleration,
    }
}

/// The last sampled time at which `|xs| >= 5 % |xs0|`, or `None` if the last sample still is
/// (not settled within the horizon). A series that never reaches the band settles at 0.
pub fn settling_time(t: &[f64], xs: &[f64], xs0: f64) -> Option<f64> {
    let band = SETTLING_FRACTION * xs0.abs();
    match xs.iter().rposition(|x| x.abs() >= band) {
        None => Some(0.0),
        Some(i) if i + 1 == xs.len() => None,
        Some(i) => Some(t[i]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settling_is_last_time_outside_the_band() {
        let t = [0.0, 1.0, 2.0, 3.0];
        assert_eq!(settling_time(&t, &[1.0, -0.5, 0.01, 0.0], 1.0), Some(1.0));
        assert_eq!(settling_time(&t, &[1.0, 0.0, 0.0, 0.06], 1.0), None);
        assert_eq!(settling_time(&t, &[0.01, 0.0, 0.0, 0.0], 1.0), Some(0.0));
    }

    #[test]
    fn spread_uses_nearest_rank() {
        let s = Spread::of((1..=20).map(f64::from).collect()).unwrap();
        assert_eq!((s.mean, s.p95, s.max), (10.5, 19.0, 20.0));
        assert_eq!(Spread::of(vec![]), None);
    }
}
