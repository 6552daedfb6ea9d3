//! Scene description and validation: the only place where a scene file is parsed and checked.
//! Every model receives a [`Scene`] that is already known to be valid (docs/MODEL.md §1-2, §8).

pub mod format;

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

pub use format::{Arrangement, Distribution, ForcingKind, Length, SceneFile, Stepping};

/// Default simulated time, s (docs/MODEL.md §8).
pub const DEFAULT_HORIZON: f64 = 5.0;
/// Default output sampling step, s.
pub const DEFAULT_SAMPLE_DT: f64 = 1e-3;
/// Most output samples one run may hold (about 1 GB of series for ten balls).
pub const MAX_SAMPLES: f64 = 2e7;
/// Horizon used for chain experiments; the reference stops earlier, once no pair approaches.
pub const CHAIN_HORIZON: f64 = 0.05;

/// A scene that cannot exist, or a file that cannot be read: names the file, the field and the rule.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{file}: cannot read scene file: {message}")]
    Io {
        /// The path given.
        file: String,
        /// Why.
        message: String,
    },
    /// The file is not valid TOML, or has unknown keys or wrong types.
    #[error("{file}: {message}")]
    Parse {
        /// The path given.
        file: String,
        /// The TOML parser's message (it names the key and line).
        message: String,
    },
    /// A value breaks a rule of the model.
    #[error("{file}: `{field}` {rule}")]
    Invalid {
        /// The path given.
        file: String,
        /// Dotted field name, e.g. `balls.restitution`.
        field: String,
        /// The rule broken, with the value.
        rule: String,
    },
}

/// The spring-damped primary structure (docs/MODEL.md §1, Eq. 5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// `ms`, kg.
    pub mass: f64,
    /// `ks`, N/m.
    pub stiffness: f64,
    /// `cs`, N s/m.
    pub damping: f64,
}

impl Frame {
    /// The bare frame's damped angular frequency, or `None` when it does not oscillate.
    pub fn damped_omega(&self) -> Option<f64> {
        let sigma = self.damping / (2.0 * self.mass);
        let w0sq = self.stiffness / self.mass;
        let wd2 = w0sq - sigma * sigma;
        (wd2 > 0.0).then(|| wd2.sqrt())
    }
    /// The frame's acceleration without impulses and contact forces, `-(cs vs + ks xs)/ms`
    /// (docs/MODEL.md §6, free vibration), as every model reports it.
    pub fn acceleration(&self, xs: f64, vs: f64) -> f64 {
        -(self.damping * vs + self.stiffness * xs) / self.mass
    }
    /// The frame's kinetic plus spring energy.
    pub fn energy(&self, xs: f64, vs: f64) -> f64 {
        0.5 * self.mass * vs * vs + 0.5 * self.stiffness * xs * xs
    }
    /// The natural frequency (Hz) at which driving this frame has no steady state: an undamped
    /// frame's, when it lies in `[from, to]` Hz (within 1e-12 relative, the round-off of
    /// `ks - ms w^2`); `None` otherwise. The one statement of that rule, for a scene's forcing
    /// (`from == to`) and a frequency sweep alike.
    pub fn resonance_without_steady_state(&self, from: f64, to: f64) -> Option<f64> {
        if self.damping != 0.0 || self.stiffness <= 0.0 {
            return None;
        }
        let natural = (self.stiffness / self.mass).sqrt() / (2.0 * PI);
        let slack = 0.5e-12 * natural;
        (from - slack <= natural && natural <= to + slack).then_some(natural)
    }
    /// `T = 2 pi / omega_d`, or 0 when the bare frame does not oscillate.
    pub fn damped_period(&self) -> f64 {
        self.damped_omega().map_or(0.0, |w| 2.0 * PI / w)
    }
}

/// Size class of a ball, for reports and colours.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BallKind {
    /// `L`.
    Large,
    /// `S`.
    Small,
    /// From an explicit list.
    Custom,
}

/// One ball.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ball {
    /// kg.
    pub mass: f64,
    /// m, from mass and density.
    pub radius: f64,
    /// Size class.
    pub kind: BallKind,
}

/// The container fixed on the frame: inner walls at `xs` and `xs + length`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Container {
    /// `Le`, m.
    pub length: f64,
    /// `Delta`, m.
    pub gap: f64,
    /// `Lc`, m.
    pub clearance: f64,
}

/// Settings of the Rapier model that a scene may fix.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RapierSettings {
    /// How steps are chosen.
    pub stepping: Option<Stepping>,
    /// Fixed step (longest step when aligned), s.
    pub dt: Option<f64>,
    /// Solver iterations.
    pub solver_iterations: Option<u32>,
    /// Rapier's swept CCD on the balls.
    pub ccd: Option<bool>,
}

/// Material of balls and walls for the compliant contact model (docs/MODEL.md §9; steel by
/// default), and the error tolerance of its integration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompliantSettings {
    /// Young's modulus `E`, Pa.
    pub youngs_modulus: f64,
    /// Poisson's ratio `nu`.
    pub poisson_ratio: f64,
    /// Error tolerance per step, relative to the contact scales.
    pub tolerance: f64,
}

/// The compliant model's error tolerance when the scene sets none.
pub const DEFAULT_COMPLIANT_TOLERANCE: f64 = 1e-9;

impl Default for CompliantSettings {
    fn default() -> Self {
        CompliantSettings { youngs_modulus: 200e9, poisson_ratio: 0.3, tolerance: DEFAULT_COMPLIANT_TOLERANCE }
    }
}

/// Harmonic excitation of the frame. Either way the frame obeys
/// `ms xs'' + cs xs' + ks xs = P sin(w t) + Q cos(w t)` ([`Forcing::harmonic_load`]), and its
/// smooth force is [`Scene::frame_force`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Forcing {
    /// Force on the frame, or motion of the ground.
    pub kind: ForcingKind,
    /// `F0`, N (force) or `Y`, m (base).
    pub amplitude: f64,
    /// Hz.
    pub frequency: f64,
}

impl Forcing {
    /// `w = 2 pi f`, rad/s.
    pub fn omega(&self) -> f64 {
        2.0 * PI * self.frequency
    }
    /// The external force `Fe(t)` on the frame (0 for base excitation), N.
    pub fn force(&self, t: f64) -> f64 {
        match self.kind {
            ForcingKind::Force => self.amplitude * (self.omega() * t).sin(),
            ForcingKind::Base => 0.0,
        }
    }
    /// The ground's displacement and velocity `(y, y')` (zero for a force), m and m/s.
    pub fn ground(&self, t: f64) -> (f64, f64) {
        match self.kind {
            ForcingKind::Force => (0.0, 0.0),
            ForcingKind::Base => {
                let w = self.omega();
                let (s, c) = (w * t).sin_cos();
                (self.amplitude * s, self.amplitude * w * c)
            }
        }
    }
    /// `(P, Q)` of the load `P sin(w t) + Q cos(w t)` on a frame with damping `c` and
    /// stiffness `k`: `(F0, 0)` for a force, `(k Y, c w Y)` for base motion.
    pub fn harmonic_load(&self, damping: f64, stiffness: f64) -> (f64, f64) {
        match self.kind {
            ForcingKind::Force => (self.amplitude, 0.0),
            ForcingKind::Base => (stiffness * self.amplitude, damping * self.omega() * self.amplitude),
        }
    }
}

/// A validated system: what every model simulates.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// Name used in outputs.
    pub name: String,
    /// `None` for free balls on a line (the chain experiment).
    pub frame: Option<Frame>,
    /// Present exactly when `frame` is.
    pub container: Option<Container>,
    /// Left to right.
    pub balls: Vec<Ball>,
    /// `e`.
    pub restitution: f64,
    /// `xs0`, m (0 without a frame).
    pub initial_displacement: f64,
    /// Initial ball centres, m.
    pub initial_positions: Vec<f64>,
    /// Initial ball velocities, m/s.
    pub initial_velocities: Vec<f64>,
    /// Simulated time, s.
    pub horizon: f64,
    /// Output sampling step, s.
    pub sample_dt: f64,
    /// Rapier model settings from the file.
    pub rapier: RapierSettings,
    /// Compliant model material.
    pub compliant: CompliantSettings,
    /// Harmonic forcing; `None` for free vibration.
    pub forcing: Option<Forcing>,
    /// Reference radius `Rr`, m (radius of a large ball).
    pub reference_radius: f64,
}

/// Radius of a solid sphere of mass `m` and density `rho`: `(3 m / (4 pi rho))^(1/3)`.
pub fn ball_radius(mass: f64, density: f64) -> f64 {
    (3.0 * mass / (4.0 * PI * density)).cbrt()
}

impl Scene {
    /// Samples every model writes: at `k sample_dt` for every `k` with `k sample_dt` within
    /// the horizon (a relative 1e-12 of slack, so a horizon that is a whole number of steps
    /// in exact arithmetic keeps its last sample after rounding).
    pub fn sample_count(&self) -> usize {
        ((self.horizon / self.sample_dt * (1.0 + 1e-12)).floor() as usize).saturating_add(1)
    }

    /// Initial mechanical energy: spring energy plus balls' kinetic energy.
    pub fn initial_energy(&self) -> f64 {
        let spring = self.frame.map_or(0.0, |f| f.energy(self.initial_displacement, 0.0));
        spring
            + self
                .balls
                .iter()
                .zip(&self.initial_velocities)
                .map(|(b, v)| 0.5 * b.mass * v * v)
                .sum::<f64>()
    }

    /// The fastest motion the scene sets going, m/s: the frame's free swing from its initial
    /// displacement (`w0 |xs0|`), its steady forced response (`w X`, plus `w Y` of a moving
    /// base) and the balls' initial speeds. Impacts can add to it; models scale their
    /// tolerances by it.
    pub fn motion_speed(&self) -> f64 {
        let frame = self.frame.map_or(0.0, |f| {
            let osc = crate::oscillator::Oscillator::new(f.mass, f.damping, f.stiffness);
            let forced = self.harmonic_load().map_or(0.0, |(p, q, w)| {
                let base = self.forcing.filter(|g| g.kind == ForcingKind::Base).map_or(0.0, |g| g.omega() * g.amplitude);
                osc.harmonic_response(p, q, w).amplitude() * w + base
            });
            (osc.w0sq.sqrt() * self.initial_displacement.abs()).max(forced)
        });
        self.initial_velocities.iter().fold(frame, |m: f64, v| m.max(v.abs()))
    }

    /// The frame's harmonic load `(P, Q, w)` (see [`Forcing::harmonic_load`]), when forced.
    pub fn harmonic_load(&self) -> Option<(f64, f64, f64)> {
        let (f, g) = (self.frame?, self.forcing?);
        let (p, q) = g.harmonic_load(f.damping, f.stiffness);
        Some((p, q, g.omega()))
    }

    /// The smooth force on the frame at time `t` (spring, damper and excitation; impulses and
    /// contact forces excluded): `Fe(t) - cs (xs' - y') - ks (xs - y)`, N. 0 without a frame.
    pub fn frame_force(&self, t: f64, xs: f64, vs: f64) -> f64 {
        let Some(f) = self.frame else { return 0.0 };
        match self.forcing {
            None => -(f.damping * vs + f.stiffness * xs),
            Some(g) => {
                let (y, yd) = g.ground(t);
                g.force(t) - f.damping * (vs - yd) - f.stiffness * (xs - y)
            }
        }
    }
    /// The frame's reported acceleration `frame_force / ms` (docs/MODEL.md §6), m/s^2.
    pub fn frame_acceleration(&self, t: f64, xs: f64, vs: f64) -> f64 {
        match (self.frame, self.forcing) {
            (None, _) => 0.0,
            (Some(f), None) => f.acceleration(xs, vs),
            (Some(f), Some(_)) => self.frame_force(t, xs, vs) / f.mass,
        }
    }
    /// The frame's kinetic energy plus the energy in its spring, `ks (xs - y)^2 / 2`, J.
    pub fn frame_energy(&self, t: f64, xs: f64, vs: f64) -> f64 {
        let Some(f) = self.frame else { return 0.0 };
        match self.forcing {
            None => f.energy(xs, vs),
            Some(g) => {
                let (y, _) = g.ground(t);
                0.5 * f.mass * vs * vs + 0.5 * f.stiffness * (xs - y).powi(2)
            }
        }
    }
    /// Power dissipated in the frame's damper, `cs (xs' - y')^2`, W.
    pub fn damping_power(&self, t: f64, vs: f64) -> f64 {
        let Some(f) = self.frame else { return 0.0 };
        let yd = self.forcing.map_or(0.0, |g| g.ground(t).1);
        f.damping * (vs - yd).powi(2)
    }
    /// Power the excitation puts into the frame and its spring: `Fe xs'` for a force,
    /// `-y' (cs (xs' - y') + ks (xs - y))` for base motion (the ground pushing the spring's
    /// and damper's far ends), W. With [`Scene::frame_energy`] and [`Scene::damping_power`]
    /// this closes the energy balance.
    pub fn forcing_power(&self, t: f64, xs: f64, vs: f64) -> f64 {
        let (Some(f), Some(g)) = (self.frame, self.forcing) else { return 0.0 };
        match g.kind {
            ForcingKind::Force => g.force(t) * vs,
            ForcingKind::Base => {
                let (y, yd) = g.ground(t);
                -yd * (f.damping * (vs - yd) + f.stiffness * (xs - y))
            }
        }
    }

    /// The same frame without its damper: no container, no balls (the paper's "without
    /// damper" curves of Figs. 8-11).
    pub fn without_damper(&self) -> Scene {
        Scene {
            name: format!("{} without damper", self.name),
            container: None,
            balls: vec![],
            initial_positions: vec![],
            initial_velocities: vec![],
            ..self.clone()
        }
    }

    /// Names of bodies in outputs: `left-wall`, `right-wall`, `ball1`..`ballN`.
    pub fn body_name(body: Body) -> String {
        match body {
            Body::LeftWall => "left-wall".into(),
            Body::RightWall => "right-wall".into(),
            Body::Ball(i) => format!("ball{}", i + 1),
        }
    }
}

/// A body that takes part in an impact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Body {
    /// The container's left wall (the frame).
    LeftWall,
    /// Ball `i` (0-based, left to right).
    Ball(usize),
    /// The container's right wall (the frame).
    RightWall,
}

/// A loaded scene file: the scene, and the sweep or chain experiment it may describe.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The file as parsed (kept so sweeps can vary one parameter and re-validate).
    pub file: SceneFile,
    /// The path it came from.
    pub path: String,
    /// The damper scene, when the file has `[frame]`.
    pub scene: Option<Scene>,
    /// The chain experiment, when the file has `[chain]`.
    pub chain: Option<Vec<ChainCase>>,
    /// The damper's manufacturing tolerances, when the file has `[tolerances]`.
    pub tolerances: Option<Tolerances>,
}

/// The validated `[tolerances]` of a damper scene: what an ensemble draws.
#[derive(Debug, Clone, PartialEq)]
pub struct Tolerances {
    /// Each parameter given, in [`SWEEP_PARAMETERS`] order, with its spread in the parameter's
    /// unit (lengths in metres): the half-width, or the standard deviation when normal.
    pub spreads: Vec<(&'static str, f64)>,
    /// How the spreads are drawn.
    pub distribution: Distribution,
    /// Seed of the draws.
    pub seed: u64,
}

/// Parameters measured in metres (a value or a spread may be written `"<k> Rr"`).
pub const LENGTH_PARAMETERS: &[&str] = &["clearance", "gap", "initial_displacement"];

fn tolerances(t: &format::TolerancesFile, parsed: &SceneFile, scene: &Scene, v: &Validator) -> Result<Tolerances, SceneError> {
    let mut spreads = vec![];
    for (name, spread) in t.spreads() {
        let Some(spread) = spread else { continue };
        let field = format!("tolerances.{name}");
        let x = match spread {
            Length::Rr(k) if LENGTH_PARAMETERS.contains(&name) => k * scene.reference_radius,
            Length::Rr(_) => return Err(v.err(&field, &format!("is not a length: `{name}`'s spread must be a plain number"))),
            Length::Metres(x) => x,
        };
        v.non_negative(&field, x)?;
        apply_sweep_value(parsed, name, Length::Metres(0.0)).map_err(|rule| v.err(&field, &rule))?;
        spreads.push((name, x));
    }
    Ok(Tolerances { spreads, distribution: t.distribution, seed: t.seed.unwrap_or(1) })
}

/// One chain of the KER experiment.
#[derive(Debug, Clone)]
pub struct ChainCase {
    /// Number of large balls `N_L` (the incident ball is extra).
    pub large: u32,
    /// Whether a small ball sits between each two large balls.
    pub small: bool,
    /// The system: incident ball first, then the chain.
    pub scene: Scene,
}

/// Reads, parses and validates a scene file.
pub fn load(path: impl AsRef<Path>) -> Result<Loaded, SceneError> {
    let path = path.as_ref();
    let file_name = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| SceneError::Io { file: file_name.clone(), message: e.to_string() })?;
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    parse(&text, &file_name, &stem)
}

/// Parses and validates scene text; `file` names it in errors, `default_name` names the scene.
pub fn parse(text: &str, file: &str, default_name: &str) -> Result<Loaded, SceneError> {
    let parsed: SceneFile = toml::from_str(text)
        .map_err(|e| SceneError::Parse { file: file.into(), message: e.to_string().trim_end().to_string() })?;
    from_file(parsed, file, default_name)
}

/// Validates an already parsed file.
pub fn from_file(parsed: SceneFile, file: &str, default_name: &str) -> Result<Loaded, SceneError> {
    let v = Validator { file, flags: &[] };
    let name = parsed.name.clone().unwrap_or_else(|| default_name.to_string());
    if parsed.chain.is_some() && (parsed.frame.is_some() || parsed.balls.is_some()) {
        return Err(v.err("chain", "cannot be combined with [frame] or [balls]: a chain file describes only the KER experiment"));
    }
    let scene = match (&parsed.frame, &parsed.chain) {
        (Some(_), _) => Some(build_damper(&parsed, &name, &v)?),
        (None, None) => return Err(v.err("frame", "is missing: a scene needs a [frame] table (or a [chain] table)")),
        (None, Some(_)) => None,
    };
    let chain = match &parsed.chain {
        Some(c) => Some(build_chain(c, &parsed.run, &name, &v)?),
        None => None,
    };
    if let (Some(sweep), Some(_)) = (&parsed.sweep, &scene) {
        if sweep.values.is_empty() {
            return Err(v.err("sweep.values", "is empty: give at least one value"));
        }
        let second = match (&sweep.parameter_y, &sweep.values_y) {
            (Some(p), Some(values)) if !values.is_empty() => Some((p, values)),
            (Some(_), Some(_)) => return Err(v.err("sweep.values_y", "is empty: give at least one value")),
            (None, None) => None,
            (Some(_), None) => return Err(v.err("sweep.values_y", "is missing: `parameter_y` needs its values")),
            (None, Some(_)) => return Err(v.err("sweep.parameter_y", "is missing: `values_y` needs its parameter")),
        };
        // Each value alone must make a valid scene (a grid's combinations are checked when run).
        let axes = std::iter::once(("sweep.parameter", "sweep.values", &sweep.parameter, &sweep.values))
            .chain(second.map(|(p, values)| ("sweep.parameter_y", "sweep.values_y", p, values)));
        for (parameter_field, values_field, parameter, values) in axes {
            for (i, value) in values.iter().enumerate() {
                let varied =
                    apply_sweep_value(&parsed, parameter, *value).map_err(|rule| v.err(parameter_field, &rule))?;
                build_damper(&varied, &name, &v).map_err(|e| match e {
                    SceneError::Invalid { file, field, rule } => SceneError::Invalid {
                        file,
                        field: format!("{values_field}[{i}] (as {field})"),
                        rule,
                    },
                    other => other,
                })?;
            }
        }
    } else if parsed.sweep.is_some() {
        return Err(v.err("sweep", "needs a damper scene ([frame] and [balls])"));
    }
    let tolerances = match (&parsed.tolerances, &scene) {
        (Some(t), Some(s)) => Some(tolerances(t, &parsed, s, &v)?),
        (Some(_), None) => return Err(v.err("tolerances", "needs a damper scene ([frame] and [balls])")),
        (None, _) => None,
    };
    Ok(Loaded { file: parsed, path: file.to_string(), scene, chain, tolerances })
}

/// Parameters a `[sweep]` may vary.
pub const SWEEP_PARAMETERS: &[&str] = &[
    "clearance",
    "gap",
    "mass_ratio",
    "restitution",
    "large_mass",
    "density",
    "frame_mass",
    "stiffness",
    "damping",
    "initial_displacement",
    "forcing_amplitude",
    "forcing_frequency",
];

/// The scene file with one parameter set to `value`.
pub fn apply_sweep_value(file: &SceneFile, parameter: &str, value: Length) -> Result<SceneFile, String> {
    let mut f = file.clone();
    f.sweep = None;
    let number = || match value {
        Length::Metres(x) => Ok(x),
        Length::Rr(_) => Err(format!("`{parameter}` is not a length: its values must be plain numbers")),
    };
    let frame = f.frame.as_mut().ok_or("needs a [frame] table")?;
    match parameter {
        "frame_mass" => frame.mass = number()?,
        "stiffness" => frame.stiffness = number()?,
        "damping" => frame.damping = number()?,
        "initial_displacement" => frame.initial_displacement = value,
        "forcing_amplitude" | "forcing_frequency" => {
            let x = number()?;
            let g = f.forcing.as_mut().ok_or("needs a [forcing] table")?;
            if parameter == "forcing_amplitude" {
                g.amplitude = x;
            } else {
                g.frequency = x;
            }
        }
        _ => {
            let balls = f.balls.as_mut().ok_or("needs a [balls] table")?;
            match parameter {
                "clearance" => {
                    balls.clearance = Some(value);
                    balls.container_length = None;
                }
                "gap" => balls.gap = value,
                "mass_ratio" => balls.mass_ratio = number()?,
                "restitution" => balls.restitution = number()?,
                "large_mass" => balls.large_mass = number()?,
                "density" => balls.density = number()?,
                other => {
                    return Err(format!(
                        "`{other}` cannot be swept; choose one of {}",
                        SWEEP_PARAMETERS.join(", ")
                    ))
                }
            }
        }
    }
    Ok(f)
}

/// The value of `parameter` (one of [`SWEEP_PARAMETERS`]) in `scene`, built from `file`: in
/// the file's unit, lengths in metres; `None` when the scene has no such part (no forcing).
pub fn parameter_value(file: &SceneFile, scene: &Scene, parameter: &str) -> Option<f64> {
    let balls = file.balls.as_ref();
    match parameter {
        "clearance" => scene.container.map(|c| c.clearance),
        "gap" => scene.container.map(|c| c.gap),
        "initial_displacement" => Some(scene.initial_displacement),
        "restitution" => Some(scene.restitution),
        "mass_ratio" => balls.map(|b| b.mass_ratio),
        "large_mass" => balls.map(|b| b.large_mass),
        "density" => balls.map(|b| b.density),
        "frame_mass" => scene.frame.map(|f| f.mass),
        "stiffness" => scene.frame.map(|f| f.stiffness),
        "damping" => scene.frame.map(|f| f.damping),
        "forcing_amplitude" => scene.forcing.map(|g| g.amplitude),
        "forcing_frequency" => scene.forcing.map(|g| g.frequency),
        _ => None,
    }
}

/// The parameter (one of [`SWEEP_PARAMETERS`]) whose value a scene field holds, for the
/// fields that [`apply_sweep_value`] sets.
pub fn parameter_of_field(field: &str) -> Option<&'static str> {
    Some(match field {
        "balls.gap" => "gap",
        "balls.clearance" | "balls.container_length" => "clearance",
        "balls.restitution" => "restitution",
        "balls.mass_ratio" => "mass_ratio",
        "balls.large_mass" => "large_mass",
        "balls.density" => "density",
        "frame.mass" => "frame_mass",
        "frame.stiffness" => "stiffness",
        "frame.damping" => "damping",
        "frame.initial_displacement" => "initial_displacement",
        "forcing.amplitude" => "forcing_amplitude",
        "forcing.frequency" => "forcing_frequency",
        _ => return None,
    })
}

/// Checks values against the scene's rules and names what broke one.
struct Validator<'a> {
    file: &'a str,
    /// Fields whose value came from a command-line flag, and that flag (`run.horizon` ->
    /// `--horizon`): an error names what the user typed.
    flags: &'a [(&'static str, &'static str)],
}

impl Validator<'_> {
    fn err(&self, field: &str, rule: &str) -> SceneError {
        let field = self.flags.iter().find(|(f, _)| *f == field).map_or(field, |(_, flag)| flag);
        SceneError::Invalid { file: self.file.into(), field: field.into(), rule: rule.into() }
    }
    fn finite(&self, field: &str, x: f64) -> Result<f64, SceneError> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.err(field, &format!("must be a finite number (got {})", human(x))))
        }
    }
    fn positive(&self, field: &str, x: f64) -> Result<f64, SceneError> {
        self.finite(field, x)?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(self.err(field, &format!("must be positive (got {})", human(x))))
        }
    }
    fn non_negative(&self, field: &str, x: f64) -> Result<f64, SceneError> {
        self.finite(field, x)?;
        if x >= 0.0 {
            Ok(x)
        } else {
            Err(self.err(field, &format!("must not be negative (got {})", human(x))))
        }
    }
    fn restitution(&self, field: &str, e: f64) -> Result<f64, SceneError> {
        self.finite(field, e)?;
        if (0.0..=1.0).contains(&e) {
            Ok(e)
        } else {
            Err(self.err(field, &format!("is a coefficient of restitution and must lie in [0, 1] (got {})", human(e))))
        }
    }
    fn run(&self, run: &format::RunFile, default_horizon: f64) -> Result<(f64, f64), SceneError> {
        let horizon = self.positive("run.horizon", run.horizon.unwrap_or(default_horizon))?;
        let dt = self.positive("run.sample_dt", run.sample_dt.unwrap_or(DEFAULT_SAMPLE_DT))?;
        validate_sample_dt(horizon, dt).map_err(|rule| self.err("run.sample_dt", &rule))?;
        Ok((horizon, dt))
    }
}

/// Values typed on the command line that replace a scene's (ripgrep's low and high
/// arguments: the flags are collected as plain values, then validated here by the very rules
/// of the file's fields, so no rule is written twice and a validated [`Scene`] is never
/// changed afterwards, only replaced by a new validated one).
#[derive(Debug, Clone, Copy, Default)]
pub struct Overrides {
    /// `--horizon`: simulated time, s.
    pub horizon: Option<f64>,
    /// `--sample-dt`: output sampling step, s.
    pub sample_dt: Option<f64>,
    /// `--stepping`: how the Rapier model chooses its steps.
    pub stepping: Option<Stepping>,
    /// `--dt`: the Rapier model's (longest) step, s.
    pub dt: Option<f64>,
    /// `--solver-iterations`: the Rapier model's solver iterations per step.
    pub solver_iterations: Option<u32>,
    /// `--ccd`: Rapier's swept CCD on the balls.
    pub ccd: bool,
    /// `--tolerance`: the compliant model's error tolerance.
    pub tolerance: Option<f64>,
    /// `--kind`: force or base motion (a scene without `[forcing]` gets one).
    pub forcing_kind: Option<ForcingKind>,
    /// `--amplitude`: the forcing's amplitude, N or m.
    pub forcing_amplitude: Option<f64>,
    /// The forcing frequency, Hz (a study that sweeps it gives where it starts).
    pub forcing_frequency: Option<f64>,
}

impl Overrides {
    /// `scene` with these values, validated by the file's rules; an error names the flag when
    /// the value came from one, and `file`.
    pub fn apply(&self, scene: Scene, file: &str) -> Result<Scene, SceneError> {
        let given = [
            ("run.horizon", "--horizon", self.horizon.is_some()),
            ("run.sample_dt", "--sample-dt", self.sample_dt.is_some()),
            ("rapier.dt", "--dt", self.dt.is_some()),
            ("rapier.solver_iterations", "--solver-iterations", self.solver_iterations.is_some()),
            ("compliant.tolerance", "--tolerance", self.tolerance.is_some()),
            ("forcing.amplitude", "--amplitude", self.forcing_amplitude.is_some()),
            ("forcing.frequency", "--freq", self.forcing_frequency.is_some()),
        ];
        let flags: Vec<_> = given.iter().filter(|g| g.2).map(|&(field, flag, _)| (field, flag)).collect();
        let v = Validator { file, flags: &flags };
        let run = format::RunFile { horizon: self.horizon.or(Some(scene.horizon)), sample_dt: self.sample_dt.or(Some(scene.sample_dt)) };
        let (horizon, sample_dt) = v.run(&run, scene.horizon)?;
        let r = &scene.rapier;
        let rapier = rapier_settings(
            &format::RapierFile {
                stepping: self.stepping.or(r.stepping),
                dt: self.dt.or(r.dt),
                solver_iterations: self.solver_iterations.or(r.solver_iterations),
                ccd: if self.ccd { Some(true) } else { r.ccd },
            },
            &v,
        )?;
        let c = &scene.compliant;
        let compliant = compliant_settings(
            &format::CompliantFile {
                youngs_modulus: Some(c.youngs_modulus),
                poisson_ratio: Some(c.poisson_ratio),
                tolerance: Some(self.tolerance.unwrap_or(c.tolerance)),
            },
            &v,
        )?;
        let given = self.forcing_kind.is_some() || self.forcing_amplitude.is_some() || self.forcing_frequency.is_some();
        let forcing = match (given, scene.frame) {
            (false, _) => scene.forcing,
            (true, None) => {
                let flag = if self.forcing_kind.is_some() { "--kind" } else { "--amplitude" };
                return Err(v.err(flag, "needs a damper scene (one with a [frame] to force)"));
            }
            (true, Some(frame)) => {
                let old = scene.forcing;
                let g = format::ForcingFile {
                    kind: self.forcing_kind.or(old.map(|g| g.kind)).unwrap_or(ForcingKind::Force),
                    amplitude: self.forcing_amplitude.or(old.map(|g| g.amplitude)).unwrap_or(0.0),
                    frequency: self.forcing_frequency.or(old.map(|g| g.frequency)).unwrap_or(1.0),
                };
                Some(forcing(&g, &frame, &v)?)
            }
        };
        Ok(Scene { horizon, sample_dt, rapier, compliant, forcing, ..scene })
    }
    /// The models' settings alone against the file's rules (for commands that take lists of
    /// them before any scene is loaded); an error names the flag.
    pub fn validate_settings(&self) -> Result<(), SceneError> {
        let flags = [("rapier.dt", "--dt"), ("rapier.solver_iterations", "--solver-iterations"), ("compliant.tolerance", "--tolerance")];
        let v = Validator { file: "(command line)", flags: &flags };
        let r = format::RapierFile { stepping: self.stepping, dt: self.dt, solver_iterations: self.solver_iterations, ccd: Some(self.ccd) };
        rapier_settings(&r, &v)?;
        compliant_settings(&format::CompliantFile { tolerance: self.tolerance, ..Default::default() }, &v).map(drop)
    }
}

/// `file` with the run, Rapier, compliant and forcing settings of `scene` (built from it, perhaps with
/// [`Overrides`]): what a study that varies the file's other parameters rebuilds from, so that
/// the command line's settings hold for every variant.
pub fn with_settings_of(file: &SceneFile, scene: &Scene) -> SceneFile {
    let r = scene.rapier;
    SceneFile {
        run: format::RunFile { horizon: Some(scene.horizon), sample_dt: Some(scene.sample_dt) },
        rapier: format::RapierFile { stepping: r.stepping, dt: r.dt, solver_iterations: r.solver_iterations, ccd: r.ccd },
        compliant: format::CompliantFile {
            youngs_modulus: Some(scene.compliant.youngs_modulus),
            poisson_ratio: Some(scene.compliant.poisson_ratio),
            tolerance: Some(scene.compliant.tolerance),
        },
        forcing: scene.forcing.map(|g| format::ForcingFile { kind: g.kind, amplitude: g.amplitude, frequency: g.frequency }),
        ..file.clone()
    }
}

/// The rule an output step must keep: no longer than the horizon, at most [`MAX_SAMPLES`] samples.
pub fn validate_sample_dt(horizon: f64, dt: f64) -> Result<(), String> {
    if !(dt.is_finite() && dt > 0.0) {
        return Err(format!("must be a positive finite step (got {})", human(dt)));
    }
    if dt > horizon {
        return Err(format!(
            "({} s) is longer than the horizon ({} s): no sample would be written",
            human(dt),
            human(horizon)
        ));
    }
    if horizon / dt > MAX_SAMPLES {
        return Err(format!(
            "({} s) would write {} samples over {} s; at most {} are allowed",
            human(dt),
            human(horizon / dt),
            human(horizon),
            human(MAX_SAMPLES)
        ));
    }
    Ok(())
}

/// A number as a person reads it in a message: plain from 1e-4 to 1e7 (`0.001`, `25000`),
/// in scientific notation with at most four significant digits beyond (`1e300`, `5.06e302`),
/// never three hundred digits.
pub fn human(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || !x.is_finite() || (1e-4..1e7).contains(&a) {
        // Twelve significant digits: what was typed, not its binary expansion.
        let rounded: f64 = format!("{x:.11e}").parse().unwrap_or(x);
        return format!("{rounded}");
    }
    let text = format!("{x:.3e}");
    let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
    let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
    format!("{mantissa}e{exponent}")
}

fn build_damper(f: &SceneFile, name: &str, v: &Validator) -> Result<Scene, SceneError> {
    let fr = f.frame.as_ref().expect("checked by caller");
    let frame = Frame {
        mass: v.positive("frame.mass", fr.mass)?,
        stiffness: v.non_negative("frame.stiffness", fr.stiffness)?,
        damping: v.non_negative("frame.damping", fr.damping)?,
    };
    let (horizon, sample_dt) = v.run(&f.run, DEFAULT_HORIZON)?;
    let rapier = rapier_settings(&f.rapier, v)?;
    let compliant = compliant_settings(&f.compliant, v)?;
    let forcing = match &f.forcing {
        None => None,
        Some(g) => Some(forcing(g, &frame, v)?),
    };
    let Some(b) = &f.balls else {
        let xs0 = v.finite("frame.initial_displacement", fr.initial_displacement.metres(0.0))?;
        if matches!(fr.initial_displacement, Length::Rr(_)) {
            return Err(v.err("frame.initial_displacement", "is given in Rr but the scene has no balls to define Rr"));
        }
        return Ok(Scene {
            name: name.into(),
            frame: Some(frame),
            container: None,
            balls: vec![],
            restitution: 1.0,
            initial_displacement: xs0,
            initial_positions: vec![],
            initial_velocities: vec![],
            horizon,
            sample_dt,
            rapier,
            compliant,
            forcing,
            reference_radius: 0.0,
        });
    };
    let large_mass = v.positive("balls.large_mass", b.large_mass)?;
    let mass_ratio = v.positive("balls.mass_ratio", b.mass_ratio)?;
    let density = v.positive("balls.density", b.density)?;
    let restitution = v.restitution("balls.restitution", b.restitution)?;
    let rr = ball_radius(large_mass, density);
    let balls = arrangement_balls(&b.arrangement, large_mass, mass_ratio, density, "balls.arrangement", v)?;
    let xs0 = v.finite("frame.initial_displacement", fr.initial_displacement.metres(rr))?;
    let gap = v.finite("balls.gap", b.gap.metres(rr))?;
    if gap < 0.0 {
        return Err(v.err("balls.gap", &format!("must not be negative: neighbouring balls would overlap (got {gap} m)")));
    }
    let sum_d: f64 = balls.iter().map(|b| 2.0 * b.radius).sum();
    let n = balls.len() as f64;
    let (length, clearance) = match (b.clearance, b.container_length) {
        (Some(_), Some(_)) => {
            return Err(v.err("balls.container_length", "and `balls.clearance` are both given: give one (Eq. 11 ties them)"))
        }
        (None, None) => return Err(v.err("balls.clearance", "is missing: give the clearance or the container length")),
        (Some(lc), None) => {
            let lc = v.non_negative("balls.clearance", lc.metres(rr))?;
            (n * gap + sum_d + lc, lc)
        }
        (None, Some(le)) => {
            let le = v.positive("balls.container_length", le.metres(rr))?;
            let lc = le - n * gap - sum_d;
            if lc < 0.0 {
                return Err(v.err(
                    "balls.container_length",
                    &format!(
                        "is {le} m but the balls and gaps need {} m: the balls cannot fit",
                        n * gap + sum_d
                    ),
                ));
            }
            (le, lc)
        }
    };
    if !length.is_finite() {
        return Err(v.err("balls.gap", &format!("and the clearance make the container {} m long, more than a number can hold", human(length))));
    }
    let mut positions = Vec::with_capacity(balls.len());
    let mut x = xs0 + gap;
    for ball in &balls {
        positions.push(x + ball.radius);
        x += 2.0 * ball.radius + gap;
    }
    Ok(Scene {
        name: name.into(),
        frame: Some(frame),
        container: Some(Container { length, gap, clearance }),
        initial_velocities: vec![0.0; balls.len()],
        balls,
        restitution,
        initial_displacement: xs0,
        initial_positions: positions,
        horizon,
        sample_dt,
        rapier,
        compliant,
        forcing,
        reference_radius: rr,
    })
}

fn compliant_settings(c: &format::CompliantFile, v: &Validator) -> Result<CompliantSettings, SceneError> {
    let d = CompliantSettings::default();
    let youngs_modulus = v.positive("compliant.youngs_modulus", c.youngs_modulus.unwrap_or(d.youngs_modulus))?;
    let poisson_ratio = v.finite("compliant.poisson_ratio", c.poisson_ratio.unwrap_or(d.poisson_ratio))?;
    if !(poisson_ratio > -1.0 && poisson_ratio < 0.5) {
        return Err(v.err("compliant.poisson_ratio", &format!("must lie in (-1, 0.5) for a stable solid (got {poisson_ratio})")));
    }
    let tolerance = v.positive("compliant.tolerance", c.tolerance.unwrap_or(d.tolerance))?;
    if tolerance > 1e-2 {
        return Err(v.err("compliant.tolerance", &format!("must lie in (0, 1e-2] (got {})", human(tolerance))));
    }
    Ok(CompliantSettings { youngs_modulus, poisson_ratio, tolerance })
}

fn forcing(g: &format::ForcingFile, frame: &Frame, v: &Validator) -> Result<Forcing, SceneError> {
    let amplitude = v.non_negative("forcing.amplitude", g.amplitude)?;
    let frequency = v.positive("forcing.frequency", g.frequency)?;
    let forcing = Forcing { kind: g.kind, amplitude, frequency };
    // An undamped frame driven exactly at resonance has no bounded particular solution.
    if frame.resonance_without_steady_state(frequency, frequency).is_some() {
        return Err(v.err(
            "forcing.frequency",
            &format!("({frequency} Hz) drives an undamped frame exactly at resonance: its amplitude grows without bound"),
        ));
    }
    Ok(forcing)
}

fn rapier_settings(r: &format::RapierFile, v: &Validator) -> Result<RapierSettings, SceneError> {
    if let Some(dt) = r.dt {
        v.positive("rapier.dt", dt)?;
        if dt > 0.1 {
            return Err(v.err("rapier.dt", &format!("({dt} s) is longer than 0.1 s: far too long for centimetre balls")));
        }
    }
    if let Some(it) = r.solver_iterations {
        if it == 0 || it > 1000 {
            return Err(v.err("rapier.solver_iterations", &format!("must lie in 1..=1000 (got {it})")));
        }
    }
    Ok(RapierSettings { stepping: r.stepping, dt: r.dt, solver_iterations: r.solver_iterations, ccd: r.ccd })
}

fn arrangement_balls(
    a: &Arrangement,
    large_mass: f64,
    mass_ratio: f64,
    density: f64,
    field: &str,
    v: &Validator,
) -> Result<Vec<Ball>, SceneError> {
    let small_mass = large_mass / mass_ratio;
    let balls: Vec<Ball> = match a {
        Arrangement::Letters(s) => s
            .chars()
            .filter(|c| !c.is_whitespace() && *c != '-')
            .map(|c| match c.to_ascii_uppercase() {
                'L' => Ok(Ball { mass: large_mass, radius: ball_radius(large_mass, density), kind: BallKind::Large }),
                'S' => Ok(Ball { mass: small_mass, radius: ball_radius(small_mass, density), kind: BallKind::Small }),
                other => Err(v.err(field, &format!("has the unknown letter `{other}`: use L (large) and S (small)"))),
            })
            .collect::<Result<_, _>>()?,
        Arrangement::List(list) => list
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let m = v.positive(&format!("{field}[{i}].mass"), b.mass)?;
                let rho = v.positive(&format!("{field}[{i}].density"), b.density.unwrap_or(density))?;
                Ok(Ball { mass: m, radius: ball_radius(m, rho), kind: BallKind::Custom })
            })
            .collect::<Result<_, _>>()?,
    };
    // What the typed values make must be numbers too: a mass below the smallest normal f64,
    // or a radius beyond the largest, is not a ball any model can move.
    if balls.iter().any(|b| b.kind == BallKind::Small) && !small_mass.is_normal() {
        return Err(v.err(
            "balls.mass_ratio",
            &format!("makes the small balls' mass large_mass / mass_ratio = {} kg, too small for a number to hold", human(small_mass)),
        ));
    }
    if let Some(b) = balls.iter().find(|b| !(b.mass.is_normal() && b.radius.is_normal())) {
        return Err(v.err(
            field,
            &format!("has a ball of mass {} kg and radius {} m (from its density): not a size a number can hold", human(b.mass), human(b.radius)),
        ));
    }
    Ok(balls)
}

fn build_chain(c: &format::ChainFile, run: &format::RunFile, name: &str, v: &Validator) -> Result<Vec<ChainCase>, SceneError> {
    let large_mass = v.positive("chain.large_mass", c.large_mass)?;
    let mass_ratio = v.positive("chain.mass_ratio", c.mass_ratio)?;
    let density = v.positive("chain.density", c.density)?;
    let restitution = v.restitution("chain.restitution", c.restitution)?;
    let speed = v.positive("chain.incident_speed", c.incident_speed)?;
    let rr = ball_radius(large_mass, density);
    let gap = v.non_negative("chain.gap", c.gap.metres(rr))?;
    let (horizon, sample_dt) = v.run(run, CHAIN_HORIZON)?;
    if c.large_counts.is_empty() {
        return Err(v.err("chain.large_counts", "is empty"));
    }
    if c.small_balls.is_empty() {
        return Err(v.err("chain.small_balls", "is empty: give [false], [true] or both"));
    }
    let mut cases = Vec::new();
    for &small in &c.small_balls {
        for &nl in &c.large_counts {
            if !(1..=1000).contains(&nl) {
                return Err(v.err("chain.large_counts", &format!("must lie in 1..=1000 (got {nl})")));
            }
            let mut letters = String::from("L");
            for i in 0..nl {
                if i > 0 && small {
                    letters.push('S');
                }
                letters.push('L');
            }
            let balls = arrangement_balls(&Arrangement::Letters(letters), large_mass, mass_ratio, density, "chain", v)?;
            let mut positions = Vec::with_capacity(balls.len());
            let mut x = 0.0;
            for (i, b) in balls.iter().enumerate() {
                if i > 0 {
                    x += gap + b.radius;
                }
                positions.push(x);
                x += b.radius;
            }
            let mut velocities = vec![0.0; balls.len()];
            velocities[0] = speed;
            cases.push(ChainCase {
                large: nl,
                small,
                scene: Scene {
                    name: format!("{name}-{nl}L{}", if small { format!("-{}S", nl - 1) } else { String::new() }),
                    frame: None,
                    container: None,
                    balls,
                    restitution,
                    initial_displacement: 0.0,
                    initial_positions: positions,
                    initial_velocities: velocities,
                    horizon,
                    sample_dt,
                    rapier: RapierSettings::default(),
                    compliant: CompliantSettings::default(),
                    forcing: None,
                    reference_radius: rr,
                },
            });
        }
    }
    Ok(cases)
}

/// Loads a file that must describe a damper scene.
pub fn load_scene(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
    let loaded = load(path)?;
    loaded.damper().cloned()
}

impl Loaded {
    /// The damper scene, or an error saying the file describes a chain experiment.
    pub fn damper(&self) -> Result<&Scene, SceneError> {
        self.scene.as_ref().ok_or(SceneError::Invalid {
            file: self.path.clone(),
            field: "frame".into(),
            rule: "is missing: this command needs a damper scene, not a chain experiment".into(),
        })
    }
}

/// The scenes directory shipped with the crate, for tests and `lpc check`.
pub fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

#[cfg(test)]
mod tests {
    use super::human;

    #[test]
    fn numbers_in_messages_read_as_typed() {
        assert_eq!(human(0.001), "0.001");
        assert_eq!(human(865.0), "865");
        assert_eq!(human(0.1 + 0.2), "0.3");
        assert_eq!(human(-2.5), "-2.5");
        assert_eq!(human(1e300), "1e300");
        assert_eq!(human(1e300 / 1.975e-3), "5.063e302");
        assert_eq!(human(2e7), "2e7");
        assert_eq!(human(1.5e-9), "1.5e-9");
        assert_eq!(human(f64::NAN), "NaN");
        assert_eq!(human(f64::INFINITY), "inf");
    }
}
