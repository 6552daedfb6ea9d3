//! The common output of every model: sampled series, impact list, energy account and wall
//! time. Metrics, comparison and output read only this type, so models stay interchangeable.

mod memory;
mod series;
mod tally;

pub use memory::{
    available_memory, bytes_for_people, check_memory, fits_in_memory, refuse_beyond_memory, series_bytes, series_every, MAX_SERIES_EVERY,
    MEMORY_SHARE,
};
pub use series::{BallPath, Record, Recorder, Series};
pub use tally::{MotionMetrics, SampleTally, DISSIPATION_LEVELS, SETTLING_FRACTION};

use crate::scene::Body;

/// Declares the models the tool has, one line each: the label in outputs and on the command
/// line, how messages name it, what its budget counts and what its bound on memory counts.
/// Each is mapped to its implementation above this module, where the models are.
macro_rules! models {
    ($($(#[$doc:meta])* $variant:ident = $name:literal, $title:literal, $unit:literal, $kept:literal;)*) => {
        /// A model of the damper.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
        #[serde(rename_all = "lowercase")]
        pub enum Model {
            $($(#[$doc])* $variant,)*
        }

        impl Model {
            /// Every model, in report order.
            pub const ALL: &'static [Model] = &[$(Model::$variant),*];

            /// Name used on the command line and in outputs.
            pub fn name(self) -> &'static str {
                match self {
                    $(Model::$variant => $name,)*
                }
            }

            /// How messages name the model (`the reference`).
            pub fn title(self) -> &'static str {
                match self {
                    $(Model::$variant => $title,)*
                }
            }

            /// What its step budget counts (`events`, `steps`).
            pub fn step_unit(self) -> &'static str {
                match self {
                    $(Model::$variant => $unit,)*
                }
            }

            /// What its bound on the impacts it keeps in memory counts (`events`, `impacts`).
            pub fn kept_unit(self) -> &'static str {
                match self {
                    $(Model::$variant => $kept,)*
                }
            }
        }
    };
}

models! {
    /// The exact event-driven impulse solver.
    Reference = "reference", "the reference", "events", "events";
    /// Rapier colliders in a headless Bevy app.
    Rapier = "rapier", "the contact model", "steps", "impacts";
    /// Hertz contacts with Hunt-Crossley damping, integrated through every contact.
    Compliant = "compliant", "the compliant model", "steps", "impacts";
}

impl std::fmt::Display for Model {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Model {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Model::ALL.iter().copied().find(|m| m.name() == s).ok_or_else(|| {
            format!("unknown model `{s}`; choose one of {}", Model::ALL.iter().map(|m| m.name()).collect::<Vec<_>>().join(", "))
        })
    }
}

/// One impact between two neighbouring bodies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Impact {
    /// s.
    pub t: f64,
    /// The left body of the pair.
    pub a: Body,
    /// The right body of the pair.
    pub b: Body,
    /// Relative speed of approach just before, m/s.
    pub approach_speed: f64,
    /// Kinetic energy lost, J.
    pub energy_lost: f64,
    /// Momentum exchanges this impact stands for (sequential impulses at one instant, or the
    /// bodies of a merged run): each rounds momentum once, which bounds round-off.
    pub impulses: u32,
    /// Largest contact force during the impact, N (compliant contact only; impulse models
    /// have none).
    pub peak_force: Option<f64>,
    /// Time the bodies stay in contact, s (compliant contact only).
    pub contact_duration: Option<f64>,
}

/// What a run keeps of its impacts. Their energy is in its account either way.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ImpactRecord {
    /// Every impact, in time order (`impacts.csv`, the noise proxy's spreads, pictures).
    #[default]
    Every,
    /// Their count and largest contact force only: a long run of a pile makes hundreds of
    /// millions of impacts, more than memory holds.
    Count,
}

impl ImpactRecord {
    /// Every choice, as the command line and the Python binding name them.
    pub const ALL: [(ImpactRecord, &'static str); 2] = [(ImpactRecord::Every, "every"), (ImpactRecord::Count, "count")];
}

impl std::str::FromStr for ImpactRecord {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL.iter().find(|(_, name)| *name == s).map(|(r, _)| *r).ok_or_else(|| format!("must be `every` or `count` (got `{s}`)"))
    }
}

/// The impacts a run counted without keeping them ([`ImpactRecord::Count`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CountedImpacts {
    /// How many.
    pub count: usize,
    /// The largest contact force among them, N (compliant contact only).
    pub peak_force: Option<f64>,
}

impl CountedImpacts {
    /// Counts `impact`.
    pub fn add(&mut self, impact: &Impact) {
        self.count += 1;
        if let Some(f) = impact.peak_force {
            self.peak_force = Some(self.peak_force.map_or(f, |p| p.max(f)));
        }
    }
}

/// Most impacts a run keeps in memory (96 bytes each, some 2 GB with the list's spare room):
/// a run that keeps every impact stops past it with the run so far; one that counts them goes on.
pub const MAX_KEPT_IMPACTS: usize = 20_000_000;

/// A run's impacts as the model makes them: every one kept, or only counted
/// ([`ImpactRecord`]).
#[derive(Debug, Default)]
pub struct Impacts {
    counts_only: bool,
    /// The impacts kept.
    pub kept: Vec<Impact>,
    /// The impacts counted.
    pub counted: CountedImpacts,
}

impl Impacts {
    /// An empty record that keeps or counts as `record` asks.
    pub fn new(record: ImpactRecord) -> Self {
        Impacts { counts_only: record == ImpactRecord::Count, ..Impacts::default() }
    }

    /// Keeps or counts `impact`.
    pub fn push(&mut self, impact: Impact) {
        if self.counts_only {
            self.counted.add(&impact);
        } else {
            self.kept.push(impact);
        }
    }

    /// How many so far.
    pub fn len(&self) -> usize {
        self.kept.len() + self.counted.count
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether the impacts kept have passed [`MAX_KEPT_IMPACTS`].
    pub fn beyond_memory(&self) -> bool {
        self.kept.len() > MAX_KEPT_IMPACTS
    }
}

/// Where the energy went, every entry in J with the mechanical energy's zero of
/// docs/MODEL.md §6 (the frame at rest unstretched, every ball at rest at its lowest place).
/// `balance_error = (initial + forcing_work - final - damping_loss - impact_loss - contact_loss)
/// / (|initial| + |forcing_work|)`: the share of the energy put in that the account does not
/// explain; divided by 1 J instead when nothing was put in (a scene at rest), so that it is
/// then the residual in J.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EnergyAccount {
    /// Mechanical energy at t = 0, J.
    pub initial: f64,
    /// Mechanical energy at the horizon, J.
    pub final_: f64,
    /// Dissipated by the frame damper `cs`, J.
    pub damping_loss: f64,
    /// Lost in impacts, J: along the contacts' normals, by the impact law (the compliant
    /// model's normal damping).
    pub impact_loss: f64,
    /// Lost in contacts besides the impacts, J: friction, and what the contact model's plastic
    /// solve takes from resting and pushed contacts (0 where every contact is an impact).
    pub contact_loss: f64,
    /// Work done by the excitation, J (0 in free vibration).
    pub forcing_work: f64,
    /// The residual relative to the energy put in (see the type's documentation).
    pub balance_error: f64,
}

impl EnergyAccount {
    /// An account with its balance error computed.
    pub fn new(initial: f64, final_: f64, damping_loss: f64, impact_loss: f64) -> Self {
        Self::forced(initial, final_, damping_loss, impact_loss, 0.0)
    }
    /// An account of a forced run, the excitation having done `forcing_work`.
    pub fn forced(initial: f64, final_: f64, damping_loss: f64, impact_loss: f64, forcing_work: f64) -> Self {
        EnergyAccount { initial, final_, damping_loss, impact_loss, contact_loss: 0.0, forcing_work, balance_error: 0.0 }.balanced()
    }
    /// The account with `contact_loss` booked besides the impacts' loss.
    pub fn with_contact_loss(self, contact_loss: f64) -> Self {
        EnergyAccount { contact_loss, ..self }.balanced()
    }
    /// The energy the account does not explain, J: what was put in less what is held and lost.
    pub fn residual(&self) -> f64 {
        self.initial + self.forcing_work - self.final_ - self.damping_loss - self.impact_loss - self.contact_loss
    }
    /// The account with its balance error computed from its entries.
    fn balanced(self) -> Self {
        let scale = self.initial.abs() + self.forcing_work.abs();
        let scale = if scale != 0.0 { scale } else { 1.0 };
        EnergyAccount { balance_error: self.residual() / scale, ..self }
    }
}

/// A model's result for one scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// Scene name.
    pub scene: String,
    /// Model name (`reference`, `rapier`, ...).
    pub model: Model,
    /// Simulated time actually covered, s.
    pub horizon: f64,
    /// Output step, s.
    pub sample_dt: f64,
    /// Initial frame displacement (for the settling threshold).
    pub initial_displacement: f64,
    /// Bare frame's damped period, s (0 when it does not oscillate).
    pub damped_period: f64,
    /// Sampled motion (empty when the run kept only its metrics, [`Record::MetricsOnly`]).
    pub series: Series,
    /// The metrics of the motion (tallied at the samples, or exact where a model knows its
    /// motion in closed form).
    pub motion: MotionMetrics,
    /// Every impact, in time order (none when the run only counted them,
    /// [`ImpactRecord::Count`]).
    pub impacts: Vec<Impact>,
    /// The impacts counted but not kept.
    pub counted_impacts: CountedImpacts,
    /// Energy account.
    pub energy: EnergyAccount,
    /// Events processed (impacts, sticks, releases); for stall detection.
    pub events: u64,
    /// Final ball velocities (exact, not sampled), m/s.
    pub final_velocities: Vec<f64>,
    /// Largest |acceleration| of the frame for t >= T with contact forces included, m/s^2
    /// (compliant contact only: impulse models have infinite acceleration at impacts).
    pub peak_true_acceleration: Option<f64>,
    /// Computing time, s.
    pub wall_time_s: f64,
}

/// A sampling step for a run to be shown at `fps` frames per second, and the samples per
/// frame: the largest step no longer than `sample_dt` that divides `1 / fps`, so that every
/// frame falls on a sample.
pub fn frame_sampling(fps: f64, sample_dt: f64) -> (f64, usize) {
    let per_frame = (1.0 / (fps * sample_dt)).ceil().max(1.0) as usize;
    (1.0 / (fps * per_frame as f64), per_frame)
}

impl Run {
    /// A run of nothing: no samples, no impacts, no energy (a stand-in for a refused scene,
    /// or a shell to hold a series read back from a file).
    pub fn empty(scene: &str, model: Model) -> Self {
        Run {
            scene: scene.into(),
            model,
            horizon: 0.0,
            sample_dt: 0.0,
            initial_displacement: 0.0,
            damped_period: 0.0,
            series: Series::default(),
            motion: MotionMetrics::default(),
            impacts: vec![],
            counted_impacts: CountedImpacts::default(),
            energy: EnergyAccount::default(),
            events: 0,
            final_velocities: vec![],
            peak_true_acceleration: None,
            wall_time_s: 0.0,
        }
    }

    /// How many impacts the run made, kept or only counted.
    pub fn impact_count(&self) -> usize {
        self.impacts.len() + self.counted_impacts.count
    }

    /// The largest contact force of any impact, N (compliant contact only).
    pub fn peak_contact_force(&self) -> Option<f64> {
        self.impacts.iter().filter_map(|i| i.peak_force).chain(self.counted_impacts.peak_force).reduce(f64::max)
    }

    /// Keeps of the run's impacts what `record` asks: under [`ImpactRecord::Count`] the list
    /// goes into the count.
    pub fn keep_impacts(&mut self, record: ImpactRecord) {
        if record == ImpactRecord::Count {
            for i in std::mem::take(&mut self.impacts) {
                self.counted_impacts.add(&i);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::EnergyAccount;

    /// The balance error is the residual over the energy put in, or over 1 J when none was.
    #[test]
    fn the_balance_error_is_the_residual_over_the_energy_put_in() {
        let a = EnergyAccount::forced(2.0, 1.0, 0.5, 0.25, 1.0).with_contact_loss(0.125);
        assert_eq!(a.residual(), 2.0 + 1.0 - 1.0 - 0.5 - 0.25 - 0.125);
        assert_eq!(a.balance_error, a.residual() / 3.0);
        let drained = EnergyAccount::forced(-2.0, -1.0, 0.5, 0.0, -1.0);
        assert_eq!(drained.balance_error, drained.residual() / 3.0);
        let at_rest = EnergyAccount::new(0.0, -1e-3, 0.0, 0.0);
        assert_eq!(at_rest.balance_error, 1e-3);
    }
}
