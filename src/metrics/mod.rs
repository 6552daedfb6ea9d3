//! Headline metrics of docs/MODEL.md §7, the same way for every model: peaks after one bare
//! period, RMS, settling time, energy remaining, dissipation times. Those that read the sampled
//! motion are tallied sample by sample as a model runs ([`crate::run::SampleTally`]), so a run that keeps no
//! series (an ensemble member) has exactly the metrics of one that does.

mod summary;

pub use summary::{DamperSummary, EnergySummary, FloorSummary, Headline, ImpactSummary, RunSummary};

use crate::run::Run;

/// Declares the metrics of a run's summary, each with the name it has in outputs, on the command
/// line and in Python, in report order.
macro_rules! metrics {
    ($($(#[$doc:meta])* $variant:ident = $name:literal,)*) => {
        /// A number of a run's summary that studies tabulate, map, rank and draw distributions of.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Metric {
            $($(#[$doc])* $variant,)*
        }

        impl Metric {
            /// Every metric, in report order.
            pub const ALL: &'static [Metric] = &[$(Metric::$variant),*];

            /// Its name in outputs (`settling_time`).
            pub fn name(self) -> &'static str {
                match self {
                    $(Metric::$variant => $name,)*
                }
            }
        }
    };
}

metrics! {
    /// max `|xs|` for `t >= T`, m.
    PeakDisplacement = "peak_displacement",
    /// max `|a|` for `t >= T`, m/s^2.
    PeakAcceleration = "peak_acceleration",
    /// RMS of `xs` over the horizon, m.
    RmsDisplacement = "rms_displacement",
    /// Last time `|xs| >= 5 % |xs0|`, s.
    SettlingTime = "settling_time",
    /// Mechanical energy at the horizon over the initial.
    EnergyRemaining = "energy_remaining",
    /// First time the energy has fallen to 10 %, s.
    DissipationTime90 = "dissipation_time_90",
    /// First time the energy has fallen to 1 %, s.
    DissipationTime99 = "dissipation_time_99",
    /// Largest contact force, N (compliant contact).
    PeakContactForce = "peak_contact_force",
    /// max `|a|` for `t >= T` with contact forces, m/s^2 (compliant contact).
    PeakTrueAcceleration = "peak_true_acceleration",
    /// Impacts.
    ImpactCount = "impact_count",
    /// Energy lost in impacts, J.
    ImpactLoss = "impact_loss",
    /// Impacts per simulated second.
    ImpactRate = "impact_rate",
    /// A structure's largest interstorey drift for `t >= T`, m.
    PeakDrift = "peak_drift",
    /// A structure's top floor's largest displacement relative to the ground for `t >= T`, m.
    PeakRoofDisplacement = "peak_roof_displacement",
    /// The largest absolute acceleration of any of a structure's floors for `t >= T`, m/s^2.
    PeakFloorAcceleration = "peak_floor_acceleration",
}

impl std::fmt::Display for Metric {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Metric {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Metric::ALL
            .iter()
            .copied()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("`{s}` is not one of {}", Metric::ALL.iter().map(|m| m.name()).collect::<Vec<_>>().join(", ")))
    }
}

impl serde::Serialize for Metric {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for Metric {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        name.parse().map_err(serde::de::Error::custom)
    }
}

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
    /// Mechanical energy at the horizon / initial energy (`None` when an excitation drives the
    /// run, which puts energy in as it goes, or when the initial energy is 0).
    pub energy_remaining: Option<f64>,
    /// First time at which the mechanical energy has fallen to 10 % of its initial value
    /// (`None` when forced, when the initial energy is 0, or not reached).
    #[serde(default)]
    pub dissipation_time_90: Option<f64>,
    /// The same for 1 %.
    #[serde(default)]
    pub dissipation_time_99: Option<f64>,
    /// Largest contact force over all impacts, N (`None` for impulse models).
    #[serde(default)]
    pub peak_contact_force: Option<f64>,
    /// max |a| for t >= T with contact forces included, m/s^2 (`None` for impulse models).
    #[serde(default)]
    pub peak_true_acceleration: Option<f64>,
    /// A structure's largest interstorey drift over its floors for t >= T, m (`None` without
    /// a structure).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_drift: Option<f64>,
    /// A structure's top floor's largest displacement relative to the ground for t >= T, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_roof_displacement: Option<f64>,
    /// The largest absolute acceleration (without impulses) of any floor for t >= T, m/s^2.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_floor_acceleration: Option<f64>,
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

/// Impacts per simulated second of `run` (0 for a run of no time).
pub fn impact_rate(run: &Run) -> f64 {
    if run.horizon > 0.0 {
        run.impact_count() as f64 / run.horizon
    } else {
        0.0
    }
}

/// The noise proxy of `run`.
pub fn noise(run: &Run) -> Noise {
    use crate::scene::Body;
    let i = &run.impacts;
    let on_wall = |b: Body| matches!(b, Body::LeftWall | Body::RightWall);
    Noise {
        impact_rate: impact_rate(run),
        energy_lost: Spread::of(i.iter().map(|x| x.energy_lost).collect()),
        wall_energy_lost: Spread::of(i.iter().filter(|x| on_wall(x.a) || on_wall(x.b)).map(|x| x.energy_lost).collect()),
        approach_speed: Spread::of(i.iter().map(|x| x.approach_speed).collect()),
        peak_force: Spread::of(i.iter().filter_map(|x| x.peak_force).collect()),
    }
}

/// Computes the metrics of `run`.
pub fn metrics(run: &Run) -> Metrics {
    let m = &run.motion;
    Metrics {
        peak_displacement: m.peak_displacement,
        peak_acceleration: m.peak_acceleration,
        rms_displacement: m.rms_displacement,
        settling_time: m.settling_time,
        energy_remaining: (!m.driven && run.energy.initial != 0.0).then(|| run.energy.final_ / run.energy.initial),
        dissipation_time_90: m.dissipation_times[0],
        dissipation_time_99: m.dissipation_times[1],
        peak_contact_force: run.peak_contact_force(),
        peak_true_acceleration: run.peak_true_acceleration,
        peak_drift: m.peak_drift,
        peak_roof_displacement: m.peak_roof_displacement,
        peak_floor_acceleration: m.peak_floor_acceleration,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_uses_nearest_rank() {
        let s = Spread::of((1..=20).map(f64::from).collect()).unwrap();
        assert_eq!((s.mean, s.p95, s.max), (10.5, 19.0, 20.0));
        assert_eq!(Spread::of(vec![]), None);
    }
}
