//! The common output of every model: sampled series, impact list, energy account and wall
//! time. Metrics, comparison and output read only this type, so models stay interchangeable.

use crate::metrics::{MotionMetrics, SampleTally};
use crate::scene::{Body, Scene};

/// A model of the damper.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Model {
    /// The exact event-driven impulse solver.
    Reference,
    /// Rapier colliders in a headless Bevy app.
    Rapier,
    /// Hertz contacts with Hunt-Crossley damping, integrated through every contact.
    Compliant,
}

impl Model {
    /// Every model, in report order.
    pub const ALL: &'static [Model] = &[Model::Reference, Model::Rapier, Model::Compliant];

    /// Name used on the command line and in outputs.
    pub fn name(self) -> &'static str {
        match self {
            Model::Reference => "reference",
            Model::Rapier => "rapier",
            Model::Compliant => "compliant",
        }
    }
}

impl std::fmt::Display for Model {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Model {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Model::ALL
            .iter()
            .copied()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown model `{s}`; choose one of {}", Model::ALL.iter().map(|m| m.name()).collect::<Vec<_>>().join(", ")))
    }
}

/// Series sampled every `sample_dt` from `t = 0` to the horizon (inclusive where it falls on a sample).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Series {
    /// s.
    pub t: Vec<f64>,
    /// Frame displacement, m.
    pub xs: Vec<f64>,
    /// Frame velocity, m/s.
    pub vs: Vec<f64>,
    /// Frame acceleration without impulses and contact forces, `(Fe - cs vs - ks xs)/ms`
    /// ([`crate::scene::Scene::frame_acceleration`]), m/s^2.
    pub a: Vec<f64>,
    /// Ball centres, `[ball][sample]`, m.
    pub x: Vec<Vec<f64>>,
    /// Ball velocities, `[ball][sample]`, m/s.
    pub v: Vec<Vec<f64>>,
    /// The series keeps every `every`-th sample of the run (1, or 0 for a series built by
    /// hand: all of them): more when the whole series would not fit in memory
    /// ([`series_every`]). The metrics always see every sample.
    pub every: usize,
}

impl Series {
    /// An empty series with room for `samples` samples of `balls` balls.
    pub fn with_capacity(balls: usize, samples: usize) -> Self {
        Series {
            t: Vec::with_capacity(samples),
            xs: Vec::with_capacity(samples),
            vs: Vec::with_capacity(samples),
            a: Vec::with_capacity(samples),
            x: (0..balls).map(|_| Vec::with_capacity(samples)).collect(),
            v: (0..balls).map(|_| Vec::with_capacity(samples)).collect(),
            every: 1,
        }
    }
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }
    /// True when no sample was taken.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
}

/// What a run keeps of its motion besides the metrics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Record {
    /// The sampled series (`series.csv`, plots, comparisons of trajectories).
    #[default]
    Series,
    /// Nothing but the metrics: a run that feeds only statistics (an ensemble member) builds
    /// no series, so it needs no memory per sample.
    MetricsOnly,
}

/// Where a model writes each sample: into the series when they are kept, and always into the
/// [`SampleTally`], so that [`crate::metrics::metrics`] is the same, bit for bit, whether the
/// series was kept or not.
#[derive(Debug, Clone)]
pub struct Recorder {
    series: Option<Series>,
    /// Samples taken so far (kept in the series or not).
    taken: usize,
    /// `None` when the model computes the metrics itself ([`Recorder::untallied`]).
    tally: Option<SampleTally>,
    masses: Vec<f64>,
}

impl Recorder {
    /// A recorder for a run of `scene` that keeps what `record` asks for.
    pub fn new(scene: &Scene, record: Record) -> Self {
        // A run that skipped check_memory and cannot fit thins as far as the rule goes.
        Self::thinned(scene, record, series_every(scene).unwrap_or(MAX_SERIES_EVERY))
    }
    /// [`Recorder::new`] keeping every `every`-th sample in the series.
    fn thinned(scene: &Scene, record: Record, every: usize) -> Self {
        let series = (record == Record::Series)
            .then(|| Series { every, ..Series::with_capacity(scene.balls.len(), scene.sample_count().div_ceil(every)) });
        Recorder {
            series,
            taken: 0,
            tally: Some(SampleTally::new(scene)),
            masses: scene.balls.iter().map(|b| b.mass).collect(),
        }
    }
    /// This recorder keeping the series only: for a model that computes the metrics itself
    /// (the reference, exactly, in free vibration).
    pub fn untallied(self) -> Self {
        Recorder { tally: None, ..self }
    }
    /// Whether the series is kept.
    pub fn keeps_series(&self) -> bool {
        self.series.is_some()
    }
    /// The sample at `t`: the frame's state, and each ball's `(x, v)` from `ball(i)`. The
    /// acceleration is the one every model reports, [`Scene::frame_acceleration`].
    #[inline]
    pub fn sample(&mut self, scene: &Scene, t: f64, xs: f64, vs: f64, ball: impl Fn(usize) -> (f64, f64)) {
        let a = scene.frame_acceleration(t, xs, vs);
        let wants_energy = self.tally.as_ref().is_some_and(|t| t.wants_energy());
        let mut kinetic = 0.0;
        let kept = self.series.as_mut().filter(|s| self.taken % s.every.max(1) == 0);
        self.taken += 1;
        if let Some(s) = kept {
            s.t.push(t);
            s.xs.push(xs);
            s.vs.push(vs);
            s.a.push(a);
            for (i, m) in self.masses.iter().enumerate() {
                let (x, v) = ball(i);
                s.x[i].push(x);
                s.v[i].push(v);
                kinetic += 0.5 * m * v * v;
            }
        } else if wants_energy {
            for (i, m) in self.masses.iter().enumerate() {
                let v = ball(i).1;
                kinetic += 0.5 * m * v * v;
            }
        }
        let energy = if wants_energy { scene.frame_energy(t, xs, vs) + kinetic } else { 0.0 };
        if let Some(tally) = &mut self.tally {
            tally.add(t, xs, a, energy);
        }
    }
    /// The series (empty when not kept) and the metrics tallied at the samples (the default
    /// when untallied).
    pub fn finish(self) -> (Series, MotionMetrics) {
        (self.series.unwrap_or_default(), self.tally.map(|t| t.finish()).unwrap_or_default())
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

/// Where the energy went.
/// `balance_error = (initial + forcing_work - final - damping_loss - impact_loss) / (|initial| + |forcing_work|)`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EnergyAccount {
    /// Mechanical energy at t = 0, J.
    pub initial: f64,
    /// Mechanical energy at the horizon, J.
    pub final_: f64,
    /// Dissipated by the frame damper `cs`, J.
    pub damping_loss: f64,
    /// Lost in impacts, J.
    pub impact_loss: f64,
    /// Work done by the excitation, J (0 in free vibration).
    pub forcing_work: f64,
    /// Relative balance error.
    pub balance_error: f64,
}

impl EnergyAccount {
    /// An account with its balance error computed.
    pub fn new(initial: f64, final_: f64, damping_loss: f64, impact_loss: f64) -> Self {
        Self::forced(initial, final_, damping_loss, impact_loss, 0.0)
    }
    /// An account of a forced run, the excitation having done `forcing_work`.
    pub fn forced(initial: f64, final_: f64, damping_loss: f64, impact_loss: f64, forcing_work: f64) -> Self {
        let scale = initial.abs() + forcing_work.abs();
        let scale = if scale != 0.0 { scale } else { 1.0 };
        EnergyAccount {
            initial,
            final_,
            damping_loss,
            impact_loss,
            forcing_work,
            balance_error: (initial + forcing_work - final_ - damping_loss - impact_loss) / scale,
        }
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
    /// Every impact, in time order.
    pub impacts: Vec<Impact>,
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
            energy: EnergyAccount::default(),
            events: 0,
            final_velocities: vec![],
            peak_true_acceleration: None,
            wall_time_s: 0.0,
        }
    }
}

/// Bytes the series of a run of `scene` take in memory (and, as text, several times that in
/// `series.csv`): each sample holds `t`, `xs`, `vs`, `a` and every ball's `x` and `v`, eight
/// bytes each. Impacts add about 80 bytes each, which no scene's series comes near.
pub fn series_bytes(scene: &Scene) -> f64 {
    scene.sample_count() as f64 * (4.0 + 2.0 * scene.balls.len() as f64) * 8.0
}

/// Share of the memory available that a run's series may take: the rest is the model's own
/// state, the impacts and the outputs being written.
pub const MEMORY_SHARE: f64 = 0.8;

/// Memory this process can still take, bytes: the least of the machine's available memory,
/// what its control group's limit leaves, and what its address-space limit (`ulimit -v`)
/// leaves; `None` where none of them can be read (the check is then skipped).
pub fn available_memory() -> Option<f64> {
    let read = |path: &str| std::fs::read_to_string(path).ok();
    let field = |text: &str, key: &str| -> Option<f64> {
        let line = text.lines().find(|l| l.starts_with(key))?;
        line[key.len()..].split_whitespace().next()?.parse::<f64>().ok().map(|kb| kb * 1024.0)
    };
    let mut limits = vec![];
    if let Some(meminfo) = read("/proc/meminfo") {
        limits.extend(field(&meminfo, "MemAvailable:"));
    }
    if let (Some(max), Some(current)) = (read("/sys/fs/cgroup/memory.max"), read("/sys/fs/cgroup/memory.current")) {
        if let (Ok(max), Ok(current)) = (max.trim().parse::<f64>(), current.trim().parse::<f64>()) {
            limits.push((max - current).max(0.0));
        }
    }
    #[cfg(unix)]
    {
        let mut limit = libc::rlimit { rlim_cur: 0, rlim_max: 0 };
        // SAFETY: getrlimit writes into the struct it is given and reads nothing else.
        if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut limit) } == 0 && limit.rlim_cur != libc::RLIM_INFINITY {
            let used = read("/proc/self/status").and_then(|s| field(&s, "VmSize:")).unwrap_or(0.0);
            limits.push((limit.rlim_cur as f64 - used).max(0.0));
        }
    }
    limits.into_iter().reduce(f64::min)
}

/// Whether `need` bytes fit in the memory left: `Err` with what the process can still use
/// when they take more than [`MEMORY_SHARE`] of it ([`available_memory`]). Checked before
/// anything is allocated: otherwise the allocator aborts or the kernel kills the process
/// without a word. Below 100 MB every machine the tool runs on has room, and the many short
/// runs of a study skip reading /proc.
pub fn fits_in_memory(need: f64) -> Result<(), f64> {
    if need < 1e8 {
        return Ok(());
    }
    match available_memory() {
        Some(available) if need > MEMORY_SHARE * available => Err(available),
        _ => Ok(()),
    }
}

/// The rules a run's budgets keep (`--max-steps`, `--max-wall-time` and their Python
/// keywords): at least one step, a positive and finite number of seconds. The rule broken, for
/// the caller to name its field.
pub fn check_budgets(max_steps: Option<u64>, max_wall_s: Option<f64>) -> Result<(), (Budget, String)> {
    if max_steps == Some(0) {
        return Err((Budget::Steps, "must be at least 1".into()));
    }
    match max_wall_s {
        Some(w) if !(w > 0.0 && w.is_finite()) => Err((Budget::WallTime, format!("must be a positive number of seconds (got {w})"))),
        _ => Ok(()),
    }
}

/// Which budget a rule is about ([`check_budgets`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Budget {
    /// Integration steps.
    Steps,
    /// Seconds of computing.
    WallTime,
}

/// Most a series is thinned to fit in memory ([`series_every`]): a series thinner than a
/// hundredth of the one asked for is not that series any more, and a scene that needs more
/// is refused with the numbers, for its user to choose the sampling.
pub const MAX_SERIES_EVERY: usize = 100;

/// The decimation rule: the series of a run of `scene` keeps every `k`-th sample, `k` the
/// smallest that makes it fit in [`MEMORY_SHARE`] of the memory left ([`fits_in_memory`]);
/// 1 when the whole series fits. Its metrics still see every sample, and `lpc run` says so.
/// `Err` with the memory left when even `k` = [`MAX_SERIES_EVERY`] would not fit.
pub fn series_every(scene: &Scene) -> Result<usize, f64> {
    let need = series_bytes(scene);
    fits_in_memory(need).map(|()| 1).or_else(|available| thinning(need, available, scene.sample_count()))
}

/// The rule of [`series_every`] for a series of `samples` samples taking `need` bytes, with
/// `available` bytes left.
fn thinning(need: f64, available: f64, samples: usize) -> Result<usize, f64> {
    let k = (need / (MEMORY_SHARE * available)).ceil();
    if k <= MAX_SERIES_EVERY as f64 {
        Ok((k as usize).clamp(1, samples.max(1)))
    } else {
        Err(available)
    }
}

/// Refuses, with the numbers, a run whose series would not fit in the memory left even
/// thinned as far as [`series_every`] goes.
pub fn check_memory(scene: &Scene) -> Result<(), String> {
    let need = series_bytes(scene);
    series_every(scene).map(|_| ()).map_err(|available| {
        format!(
            "scene `{}`: its series would take {} of memory ({} samples x {} balls, {} bytes each), more than {:.0} % \
             of the {} this process can still use even keeping one sample in {MAX_SERIES_EVERY}; raise run.sample_dt, \
             shorten the horizon or use fewer balls",
            scene.name,
            bytes_for_people(need),
            crate::scene::human(scene.sample_count() as f64),
            scene.balls.len(),
            (4 + 2 * scene.balls.len()) * 8,
            100.0 * MEMORY_SHARE,
            bytes_for_people(available)
        )
    })
}

/// `3.2 GB`, `512 MB`, `40 kB`.
pub fn bytes_for_people(b: f64) -> String {
    match b {
        b if b >= 1e12 => format!("{:.1} TB", b / 1e12),
        b if b >= 1e9 => format!("{:.1} GB", b / 1e9),
        b if b >= 1e6 => format!("{:.0} MB", b / 1e6),
        b => format!("{:.0} kB", b / 1e3),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The thinning rule: the smallest factor that fits, never past the samples there are,
    /// and a refusal past [`MAX_SERIES_EVERY`].
    #[test]
    fn a_series_thins_by_the_smallest_factor_that_fits() {
        let gb = 1e9;
        // 2.5 GB into 80 % of 1 GB: a third of the samples (0.83 GB).
        assert_eq!(thinning(2.5 * gb, gb, 5001), Ok(4));
        assert_eq!(thinning(2.4 * gb, gb, 5001), Ok(3));
        assert_eq!(thinning(80.0 * gb, gb, 5001), Ok(100));
        assert_eq!(thinning(80.1 * gb, gb, 5001), Err(gb));
        assert_eq!(thinning(10.0 * gb, gb, 3), Ok(3));
    }

    /// A thinned series keeps samples 0, k, 2k, ... and its metrics are those of every sample.
    #[test]
    fn a_thinned_series_keeps_every_kth_sample_and_all_the_metrics() {
        let scene = crate::scene::load_scene(crate::scene::scenes_dir().join("lpc-lsl.toml")).unwrap();
        let feed = |mut r: Recorder| {
            for k in 0..scene.sample_count() {
                let t = k as f64 * scene.sample_dt;
                let (xs, vs) = (0.01 * (9.0 * t).cos() * (-0.3 * t).exp(), -0.09 * (9.0 * t).sin() * (-0.3 * t).exp());
                r.sample(&scene, t, xs, vs, |i| (0.1 * i as f64 + xs, vs));
            }
            r.finish()
        };
        let (all, all_metrics) = feed(Recorder::thinned(&scene, Record::Series, 1));
        let (thin, thin_metrics) = feed(Recorder::thinned(&scene, Record::Series, 7));
        assert_eq!(thin.every, 7);
        assert_eq!(thin.len(), scene.sample_count().div_ceil(7));
        for (j, k) in (0..all.len()).step_by(7).enumerate() {
            assert_eq!((thin.t[j], thin.xs[j], thin.x[2][j]), (all.t[k], all.xs[k], all.x[2][k]));
        }
        assert_eq!(thin_metrics, all_metrics);
    }
}
