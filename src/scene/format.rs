//! The TOML scene file as written by people: every table and key, with lengths that may be
//! given in metres or as multiples of the reference radius (`"0.25 Rr"`). Nothing here is
//! checked beyond syntax and types; `validate` turns a [`SceneFile`] into a [`super::Scene`].

use serde::{Deserialize, Serialize};

/// A whole scene file. `[frame]` + `[balls]` describe a damper; `[chain]` describes the
/// chain experiment of docs/MODEL.md §8 instead.
#[derive(Debug, Clone, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Scene name used in outputs; defaults to the file stem.
    pub name: Option<String>,
    /// The primary structure.
    pub frame: Option<FrameFile>,
    /// A primary structure of several storeys, instead of `[frame]`.
    pub structure: Option<StructureFile>,
    /// The damper's balls and container.
    pub balls: Option<BallsFile>,
    /// Run settings.
    #[serde(default)]
    pub run: RunFile,
    /// Settings of the reference model.
    #[serde(default)]
    pub reference: ReferenceFile,
    /// Settings of the Rapier model.
    #[serde(default)]
    pub rapier: RapierFile,
    /// Settings of the compliant (Hertz + Hunt-Crossley) model.
    #[serde(default)]
    pub compliant: CompliantFile,
    /// Harmonic forcing of the frame (free vibration without it).
    pub forcing: Option<ForcingFile>,
    /// A parameter sweep over this scene.
    pub sweep: Option<SweepFile>,
    /// The chain experiment (KER), instead of a damper.
    pub chain: Option<ChainFile>,
    /// Manufacturing tolerances: how an ensemble's members scatter about this scene.
    pub tolerances: Option<TolerancesFile>,
    /// The container's size across the frame's motion (and its length for a bed).
    pub container: Option<ContainerFile>,
    /// Gravity, friction, and the restitution of balls not given by `[balls]`.
    pub world: Option<WorldFile>,
    /// A generated bed of balls: a count or fill fraction of given sizes, placed on a lattice
    /// or at random.
    pub bed: Option<BedFile>,
    /// Explicit balls, one `[[ball]]` table each.
    #[serde(rename = "ball")]
    pub explicit_balls: Option<Vec<ExplicitBallFile>>,
    /// Several dampers, one `[[damper]]` table each, instead of one `[container]` with its
    /// balls.
    #[serde(rename = "damper")]
    pub dampers: Option<Vec<DamperFile>>,
}

/// `[[damper]]`: one of several dampers, a container with its own balls (given as the scene
/// gives one damper's: `[damper.balls]`, `[damper.bed]` or `[[damper.ball]]`, with
/// `[damper.container]`) on a floor of its choice. `[world]` acts on all of them.
#[derive(Debug, Clone, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct DamperFile {
    /// The floor that carries it, 1 at the bottom (default the top floor; 1 on a `[frame]`).
    pub floor: Option<u32>,
    /// Its container.
    pub container: Option<ContainerFile>,
    /// Its balls on a line, as `[balls]`.
    pub balls: Option<BallsFile>,
    /// Its generated bed, as `[bed]`.
    pub bed: Option<BedFile>,
    /// Its balls placed by hand, as `[[ball]]`.
    #[serde(rename = "ball")]
    pub explicit_balls: Option<Vec<ExplicitBallFile>>,
}

/// `[container]`: the container's inner size. Its axis (y = z = 0) runs along the frame's
/// motion through the middle of its cross-section; its left wall is at x = 0.
#[derive(Debug, Clone, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct ContainerFile {
    /// Inner length along x, m (for `[bed]` and `[[ball]]`; `[balls]` sets it by Eq. 11).
    pub length: Option<Length>,
    /// Inner width along y, m (default: each chain's channel as wide as its largest ball).
    pub width: Option<Length>,
    /// Inner height along z, m (default: as high as the largest ball).
    pub height: Option<Length>,
}

/// `[world]`: what acts on every ball.
#[derive(Debug, Clone, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct WorldFile {
    /// `[gx, gy, gz]`, m/s^2 (default none).
    pub gravity: Option<[f64; 3]>,
    /// Coulomb friction coefficient of every contact (default 0).
    pub friction: Option<f64>,
    /// Coefficient of restitution `e` of every impact, for balls from `[bed]` or `[[ball]]`.
    pub restitution: Option<f64>,
}

/// How a bed's balls are placed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Placement {
    /// On a cubic lattice as wide as the largest ball, filled from the floor (z low) up.
    #[default]
    Lattice,
    /// At random positions without overlaps (seeded).
    Random,
    /// Settled under gravity into a pile at rest from the lattice, nudged at random (seeded).
    Settled,
}

/// `[bed]`: a generated bed of balls.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BedFile {
    /// Number of balls. Give this or `fill_fraction`.
    pub count: Option<u32>,
    /// Solid fraction of the container's volume the balls fill.
    pub fill_fraction: Option<f64>,
    /// Radii of the ball sizes, m.
    pub radii: Vec<f64>,
    /// Relative numbers of balls of each size (default equal).
    pub proportions: Option<Vec<f64>>,
    /// kg/m^3.
    pub density: f64,
    /// `"lattice"` (default), `"random"` or `"settled"`.
    #[serde(default)]
    pub placement: Placement,
    /// Seed of a random or settled placement (default 1).
    pub seed: Option<u64>,
}

/// `[[ball]]`: one ball placed by hand.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ExplicitBallFile {
    /// Centre `[x, y, z]`, m, in the container's frame.
    pub position: [f64; 3],
    /// kg.
    pub mass: f64,
    /// m. Give this or `density`.
    pub radius: Option<f64>,
    /// kg/m^3. Give this or `radius`.
    pub density: Option<f64>,
    /// Initial velocity `[vx, vy, vz]`, m/s, relative to the ground (default at rest).
    pub velocity: Option<[f64; 3]>,
}

/// `[tolerances]`: the spread of each parameter an ensemble draws (the `[sweep]` parameters),
/// a half-width in the parameter's unit (lengths may be `"0.02 Rr"`), or the standard
/// deviation when `distribution = "normal"`.
#[derive(Debug, Clone, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct TolerancesFile {
    /// Each ball's initial gap, drawn independently; the container length is held (the
    /// clearance takes up the sum).
    pub gap: Option<Length>,
    /// `Lc`.
    pub clearance: Option<Length>,
    /// `xs0`.
    pub initial_displacement: Option<Length>,
    /// `e`, one per member.
    pub restitution: Option<Length>,
    /// `m_L / m_S`.
    pub mass_ratio: Option<Length>,
    /// `m_L`, kg.
    pub large_mass: Option<Length>,
    /// kg/m^3.
    pub density: Option<Length>,
    /// `ms`, kg.
    pub frame_mass: Option<Length>,
    /// `ks`, N/m.
    pub stiffness: Option<Length>,
    /// `cs`, N s/m.
    pub damping: Option<Length>,
    /// Forcing amplitude, in its unit.
    pub forcing_amplitude: Option<Length>,
    /// Forcing frequency, Hz.
    pub forcing_frequency: Option<Length>,
    /// Each ball's centre in a `[bed]` or `[[ball]]` scene, drawn independently along x, y and
    /// z (across gravity only, so that a ball resting on the floor stays on it), m.
    pub position: Option<Length>,
    /// `"uniform"` (default; the value is the half-width) or `"normal"` (the standard deviation).
    #[serde(default)]
    pub distribution: Distribution,
    /// Seed of the draws (default 1); `--seed` overrides it.
    pub seed: Option<u64>,
}

/// How a tolerance spreads a parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Distribution {
    /// Uniform over nominal +- the value.
    #[default]
    Uniform,
    /// Normal about the nominal with the value as standard deviation.
    Normal,
}

/// `[frame]`: the spring-damped primary structure.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FrameFile {
    /// `ms`, kg.
    pub mass: f64,
    /// `ks`, N/m.
    pub stiffness: f64,
    /// `cs`, N s/m.
    pub damping: f64,
    /// `xs0`, the initial displacement (m or Rr).
    pub initial_displacement: Length,
}

/// `[structure]`: a shear building of several storeys (docs/MODEL.md §16).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct StructureFile {
    /// Floor masses, bottom to top, kg.
    pub masses: Vec<f64>,
    /// Storey stiffnesses, bottom to top (storey `i` joins floor `i - 1` to floor `i`), N/m.
    pub stiffnesses: Vec<f64>,
    /// Rayleigh damping `C = a0 M + a1 K`, as `[a0, a1]`.
    pub rayleigh: Option<[f64; 2]>,
    /// Damping ratios of the undamped modes, lowest first (instead of `rayleigh`).
    pub damping_ratios: Option<Vec<f64>>,
    /// Each floor's initial displacement relative to the ground, m (default 0).
    pub initial_displacements: Option<Vec<f64>>,
    /// Each floor's initial velocity relative to the ground, m/s (default 0).
    pub initial_velocities: Option<Vec<f64>>,
    /// The floor that carries the container, 1 at the bottom (default the top floor).
    pub damper_floor: Option<u32>,
}

/// `[balls]`: the balls in the container and the container geometry.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BallsFile {
    /// `"LSL"` (L = large, S = small) or an explicit list of balls.
    pub arrangement: Arrangement,
    /// `m_L`, kg.
    pub large_mass: f64,
    /// `m_L / m_S`.
    #[serde(default = "one")]
    pub mass_ratio: f64,
    /// Steel density, kg/m^3.
    pub density: f64,
    /// Coefficient of restitution `e` of every impact.
    pub restitution: f64,
    /// `Delta`: left gap and gap between neighbouring balls.
    pub gap: Length,
    /// `Lc`: clearance between the last ball and the right wall. Give either this or
    /// `container_length`.
    pub clearance: Option<Length>,
    /// `Le`: inner container length; the clearance then follows from Eq. 11.
    pub container_length: Option<Length>,
    /// Number of copies of the arrangement side by side, each in its own channel (default 1).
    pub chains: Option<u32>,
}

/// The order of balls, left to right.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(untagged)]
pub enum Arrangement {
    /// One letter per ball: `L` large, `S` small.
    Letters(String),
    /// One table per ball.
    List(Vec<BallFile>),
}

/// One ball of an explicit arrangement.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BallFile {
    /// kg.
    pub mass: f64,
    /// kg/m^3; defaults to the scene's density.
    pub density: Option<f64>,
}

/// `[run]`: horizon and output sampling.
#[derive(Debug, Clone, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct RunFile {
    /// Simulated time, s (default 5).
    pub horizon: Option<f64>,
    /// Output sampling step, s (default 1 ms).
    pub sample_dt: Option<f64>,
}

/// `[reference]`: settings of the exact event-driven model.
#[derive(Debug, Clone, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct ReferenceFile {
    /// The collapse rule's contact duration `t_c`, s (default 1e-6).
    pub contact_duration: Option<f64>,
}

/// `[rapier]`: settings of the contact model.
#[derive(Debug, Clone, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct RapierFile {
    /// `"aligned"` (steps end at contacts) or `"fixed"`.
    pub stepping: Option<Stepping>,
    /// Fixed physics step (the longest step when aligned), s.
    pub dt: Option<f64>,
    /// Solver iterations per step.
    pub solver_iterations: Option<u32>,
    /// Rapier's swept continuous collision detection on the balls (off by default: the
    /// plug-in's speculative margin already finds every contact, see docs/BENCHMARKS.md).
    pub ccd: Option<bool>,
}

/// `[compliant]`: material of the balls and walls for the compliant contact model.
#[derive(Debug, Clone, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct CompliantFile {
    /// Young's modulus `E`, Pa (default 200 GPa, steel).
    pub youngs_modulus: Option<f64>,
    /// Poisson's ratio `nu` (default 0.3).
    pub poisson_ratio: Option<f64>,
    /// Error tolerance per step, relative to the contact scales (default 1e-9).
    pub tolerance: Option<f64>,
}

/// What the harmonic forcing acts on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ForcingKind {
    /// A force `Fe(t) = F0 sin(w t)` on the frame; `amplitude` is `F0` in N.
    Force,
    /// The ground under the spring and damper moves as `y(t) = Y sin(w t)`; `amplitude` is `Y` in m.
    Base,
}

/// What drives the structure: a sine ([`ForcingKind`]) or a ground-motion record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum ExcitationKind {
    /// A sine force on the frame.
    #[default]
    Force,
    /// A sine motion of the ground.
    Base,
    /// The ground accelerates as a record read from `file` (docs/MODEL.md §17).
    Record,
    /// The ground accelerates as Kanai-Tajimi filtered white noise drawn from `seed`
    /// (docs/MODEL.md §17): each ensemble member draws its own.
    Random,
    /// A force recorded in `file` (time in s, force in N) acts on `floor` (docs/MODEL.md §17).
    #[serde(rename = "force_record")]
    ForceRecord,
}

impl From<ForcingKind> for ExcitationKind {
    fn from(k: ForcingKind) -> Self {
        match k {
            ForcingKind::Force => ExcitationKind::Force,
            ForcingKind::Base => ExcitationKind::Base,
        }
    }
}

/// `[forcing]`: harmonic excitation of the frame, or a ground-motion record.
#[derive(Debug, Clone, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct ForcingFile {
    /// `"force"`, `"base"`, `"record"`, `"random"` or `"force_record"`.
    pub kind: ExcitationKind,
    /// `F0` in N (force) or `Y` in m (base).
    pub amplitude: Option<f64>,
    /// Forcing frequency, Hz.
    pub frequency: Option<f64>,
    /// A record's file (relative to the scene file): two columns of time (s) and ground
    /// acceleration (m/s^2) separated by a comma or spaces, or a PEER `.AT2` file.
    pub file: Option<String>,
    /// A factor on the record's accelerations (default 1).
    pub scale: Option<f64>,
    /// A force record: the floor it acts on, 1 at the bottom (default: the damper's).
    pub floor: Option<u32>,
    /// Random ground motion: the soil's frequency `fg`, Hz.
    pub ground_frequency: Option<f64>,
    /// Random ground motion: the soil's damping ratio `zeta_g`.
    pub ground_damping: Option<f64>,
    /// Random ground motion: the white noise's two-sided spectral density `S0`, m^2/s^3.
    pub intensity: Option<f64>,
    /// Random ground motion: how long the ground shakes, s.
    pub duration: Option<f64>,
    /// Random ground motion: the step between its points, s (default 0.01).
    pub step: Option<f64>,
    /// Random ground motion: an envelope `[rise, strong, decay]`, rising as `(t / rise)^2` to
    /// 1, holding to `strong` s, then decaying as `exp(-decay (t - strong))` (none: 1).
    pub envelope: Option<[f64; 3]>,
    /// Random ground motion: the seed of its noise (default 1; an ensemble's members draw
    /// their own).
    pub seed: Option<u64>,
}

/// `[sweep]`: one parameter and its values.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// One of `clearance`, `gap`, `mass_ratio`, `restitution`, `large_mass`, `stiffness`,
    /// `damping`, `frame_mass`, `initial_displacement`.
    pub parameter: String,
    /// The values, in the parameter's unit (lengths may be `"1 Rr"`).
    pub values: Vec<Length>,
    /// A second parameter: the sweep becomes a grid (a design map).
    pub parameter_y: Option<String>,
    /// The second parameter's values.
    pub values_y: Option<Vec<Length>>,
}

/// `[chain]`: the KER experiment of docs/MODEL.md §8.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ChainFile {
    /// Numbers of large balls, e.g. `[3, 4, 5, 6, 7]`.
    pub large_counts: Vec<u32>,
    /// Run each count without and/or with small balls between the large ones.
    #[serde(default = "both")]
    pub small_balls: Vec<bool>,
    /// kg.
    pub large_mass: f64,
    /// `m_L / m_S`.
    pub mass_ratio: f64,
    /// kg/m^3.
    pub density: f64,
    /// `e`.
    pub restitution: f64,
    /// Gap between neighbouring balls (m or Rr).
    pub gap: Length,
    /// Speed of the incident ball, m/s.
    pub incident_speed: f64,
}

fn one() -> f64 {
    1.0
}
fn both() -> Vec<bool> {
    vec![false, true]
}

/// A length in metres, or a multiple of the reference radius written `"<k> Rr"`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "LengthRepr", into = "LengthRepr")]
pub enum Length {
    /// Metres.
    Metres(f64),
    /// Multiples of the reference radius.
    Rr(f64),
}

#[derive(Deserialize, Serialize)]
#[serde(untagged)]
enum LengthRepr {
    Number(f64),
    Int(i64),
    Text(String),
}

impl TryFrom<LengthRepr> for Length {
    type Error = String;
    fn try_from(r: LengthRepr) -> Result<Self, String> {
        match r {
            LengthRepr::Number(x) => Ok(Length::Metres(x)),
            LengthRepr::Int(i) => Ok(Length::Metres(i as f64)),
            LengthRepr::Text(s) => parse_rr(&s).ok_or_else(|| format!("`{s}` is not a length: write metres as a number or `<k> Rr`")),
        }
    }
}

impl From<Length> for LengthRepr {
    fn from(l: Length) -> Self {
        match l {
            Length::Metres(x) => LengthRepr::Number(x),
            Length::Rr(k) => LengthRepr::Text(format!("{k} Rr")),
        }
    }
}

fn parse_rr(s: &str) -> Option<Length> {
    let t = s.trim();
    let k = t.strip_suffix("Rr")?.trim();
    let k = if k.is_empty() { 1.0 } else { k.parse::<f64>().ok()? };
    Some(Length::Rr(k))
}

impl std::fmt::Display for Length {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Length::Metres(m) => write!(f, "{m} m"),
            Length::Rr(k) => write!(f, "{k} Rr"),
        }
    }
}

impl Length {
    /// Parses `"<k> Rr"` (or `"<k>Rr"`).
    pub fn try_from_text(s: &str) -> Option<Length> {
        parse_rr(s)
    }
    /// The length in metres for reference radius `rr`.
    pub fn metres(self, rr: f64) -> f64 {
        match self {
            Length::Metres(x) => x,
            Length::Rr(k) => k * rr,
        }
    }
    /// The number as written (metres or Rr multiple), for reports.
    pub fn raw(self) -> f64 {
        match self {
            Length::Metres(x) | Length::Rr(x) => x,
        }
    }
}

/// How the Rapier model chooses its steps (a setting of the scene, read by that model).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Stepping {
    /// Every step is `dt` long.
    Fixed,
    /// Steps end at contacts; `dt` is the longest step.
    Aligned,
}

impl Stepping {
    /// Name on the command line and in outputs.
    pub fn name(self) -> &'static str {
        match self {
            Stepping::Fixed => "fixed",
            Stepping::Aligned => "aligned",
        }
    }
}

impl std::str::FromStr for Stepping {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "fixed" => Ok(Stepping::Fixed),
            "aligned" => Ok(Stepping::Aligned),
            other => Err(format!("unknown stepping `{other}`; choose fixed or aligned")),
        }
    }
}
