//! Scene description and validation: the only place where a scene file is parsed and checked.
//! Every model receives a [`Scene`] that is already known to be valid (docs/MODEL.md §1-2, §8).

mod chamber;
mod dampers;
mod excitation;
pub mod format;
mod geometry;
mod overrides;
mod parameters;
mod placement;
pub mod record;
mod rules;
mod settings;
mod settle;
mod space;
mod structure;
mod validator;

use std::path::{Path, PathBuf};

pub use chamber::{Chamber, Wall};
pub use dampers::Damper;
pub use excitation::Forcing;
pub use format::{Arrangement, Distribution, ForcingKind, Length, SceneFile, Stepping};
pub use geometry::{ball_radius, pair_bodies, pair_gap, pair_range, Ball, BallKind, Body, Container, Pairs};
pub use overrides::{with_settings_of, Overrides};
pub use parameters::{Parameter, Tolerances};
pub use placement::{move_placed_balls, MAX_BED_BALLS};
pub use record::GroundRecord;
pub use rules::from_file;
pub use settings::{CompliantSettings, RapierSettings, ReferenceSettings, DEFAULT_COMPLIANT_TOLERANCE, DEFAULT_CONTACT_DURATION};
pub use space::Space;
pub use structure::{FloorForce, Frame, Structure};
pub use validator::validate_sample_dt;

/// Default simulated time, s (docs/MODEL.md §8).
pub const DEFAULT_HORIZON: f64 = 5.0;
/// Default output sampling step, s.
pub const DEFAULT_SAMPLE_DT: f64 = 1e-3;
/// Most output samples one run may hold (about 1 GB of series for ten balls).
pub const MAX_SAMPLES: f64 = 2e7;
/// Horizon used for chain experiments; the reference stops earlier, once no pair approaches.
pub const CHAIN_HORIZON: f64 = 0.05;
/// The time in which a scene at rest covers its length at its speed scale
/// ([`Scene::speed_scale`]), s: the smallest scale a scene has, whatever its horizon.
pub const REST_TIME: f64 = 1000.0;

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
    /// Reference model settings from the file.
    pub reference: ReferenceSettings,
    /// Rapier model settings from the file.
    pub rapier: RapierSettings,
    /// Compliant model material.
    pub compliant: CompliantSettings,
    /// Harmonic forcing; `None` for free vibration.
    pub forcing: Option<Forcing>,
    /// Reference radius `Rr`, m (radius of a large ball).
    pub reference_radius: f64,
    /// The chains, the balls' places across the motion, gravity and friction.
    pub space: Space,
    /// A structure of several storeys or a ground-motion record, which `frame` alone cannot
    /// describe; `None` for a frame in free vibration or under a sine.
    pub structure: Option<std::sync::Arc<Structure>>,
    /// Every damper, each with its container, balls and floor, when the scene carries more
    /// than one; empty for one damper, which `container`, `space` and the structure's `floor`
    /// describe (and which they describe as the first of several).
    pub dampers: Vec<Damper>,
}

impl Scene {
    /// Samples every model writes: at `k sample_dt` for every `k` with `k sample_dt` within
    /// the horizon (a relative 1e-12 of slack, so a horizon that is a whole number of steps
    /// in exact arithmetic keeps its last sample after rounding).
    pub fn sample_count(&self) -> usize {
        ((self.horizon / self.sample_dt * (1.0 + 1e-12)).floor() as usize).saturating_add(1)
    }

    /// Whether a run's clock at `t` has reached the horizon: within a relative 1e-12, the slack
    /// of [`Scene::sample_count`], since a clock that adds its steps gathers round-off.
    pub fn reached_horizon(&self, t: f64) -> bool {
        t >= self.horizon * (1.0 - 1e-12)
    }

    /// Whether the sample at `ts` falls on the end `t_end` of a step of length `h`: within
    /// round-off of the step, or anywhere within the horizon's slack once the run has reached
    /// it (so the row at the horizon is never lost to the clock's round-off).
    pub fn sample_at_step_end(&self, ts: f64, t_end: f64, h: f64) -> bool {
        (ts - t_end).abs() <= 1e-9 * h || (self.reached_horizon(t_end) && self.reached_horizon(ts))
    }

    /// Whether something drives the structure (a sine or a moving ground): then energy is put
    /// in, and dissipation times mean nothing.
    pub fn is_driven(&self) -> bool {
        self.forcing.is_some() || self.structure.as_ref().is_some_and(|s| s.is_recorded())
    }

    /// Ball `i`'s height energy at its centre `p` (`x` in the ground's frame, `y` and `z` in
    /// the container's), J: gravity's potential, measured across the motion from the lowest
    /// place the ball can reach (its centre one radius from the wall gravity presses it
    /// against) and along the motion from where the ball starts. A ball resting on the floor
    /// has none, so a bed at rest has only its pile's height (docs/MODEL.md §6).
    pub fn height_energy(&self, i: usize, p: [f64; 3]) -> f64 {
        let g = self.space.gravity;
        let (radius, start, section) = (self.balls[i].radius, self.space.lateral_of(i), self.section_of(i));
        let across = |a: usize| {
            let half = 0.5 * section[a - 1];
            // A scene on one line has no walls across: its balls stay where they start.
            let lowest = if half <= 0.0 {
                start[a - 1]
            } else if g[a] < 0.0 {
                radius - half
            } else {
                half - radius
            };
            -g[a] * (p[a] - lowest)
        };
        let along = if g[0] == 0.0 { 0.0 } else { -g[0] * (p[0] - self.initial_positions[i]) };
        self.balls[i].mass * (along + across(1) + across(2))
    }

    /// The balls' height energy as they start ([`Scene::height_energy`]), J: what a model whose
    /// potential counts from the start adds to it.
    pub fn height_energy_at_start(&self) -> f64 {
        if self.space.gravity == [0.0; 3] {
            return 0.0;
        }
        (0..self.balls.len())
            .map(|i| {
                let [y, z] = self.space.lateral_of(i);
                self.height_energy(i, [self.initial_positions[i], y, z])
            })
            .sum()
    }

    /// Initial mechanical energy: spring energy, the balls' kinetic energy and their height
    /// energy ([`Scene::height_energy`]).
    pub fn initial_energy(&self) -> f64 {
        let spring = match &self.structure {
            // The floors start at their velocities relative to a ground that may move (a sine
            // base starts at `Y w`).
            Some(s) => {
                let ground = self.forcing.filter(|g| g.kind == ForcingKind::Base).map_or(0.0, |g| g.ground(0.0).1);
                s.energy(&s.initial_displacements, &s.initial_velocities, ground)
            }
            None => self.frame.map_or(0.0, |f| f.energy(self.initial_displacement, 0.0)),
        };
        let across: f64 = (0..self.balls.len())
            .map(|i| {
                let [vy, vz] = self.space.lateral_velocity_of(i);
                0.5 * self.balls[i].mass * (vy * vy + vz * vz)
            })
            .sum();
        spring
            + self.balls.iter().zip(&self.initial_velocities).map(|(b, v)| 0.5 * b.mass * v * v).sum::<f64>()
            + across
            + self.height_energy_at_start()
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
        // A structure: the carrying floor's speed with all the structure's energy, and a
        // record's fastest ground velocity plus the response of a fundamental-period
        // oscillator to its peak acceleration.
        let structure = self.structure.as_ref().map_or(0.0, |s| {
            let own = (2.0 * s.energy(&s.initial_displacements, &s.initial_velocities, 0.0) / s.building.masses[s.floor]).sqrt();
            let ground = s.ground.as_ref().map_or(0.0, |g| {
                let fastest = g.ground.iter().fold(0.0, |m: f64, (_, v)| m.max(v.abs()));
                let (omegas, _) = s.building.undamped_modes();
                fastest + g.peak() / omegas[0]
            });
            // A recorded force: the static drift it gives the fundamental mode, at its rate.
            let force = s.force.as_ref().map_or(0.0, |f| {
                let (omegas, _) = s.building.undamped_modes();
                f.record.peak() / (s.building.masses[f.floor] * omegas[0])
            });
            own + ground + force
        });
        let across = self.space.lateral_velocities.iter().fold(0.0, |m: f64, [vy, vz]| m.max(vy.hypot(*vz)));
        self.initial_velocities.iter().fold(frame.max(across).max(structure), |m: f64, v| m.max(v.abs()))
    }

    /// The scene's length scale, m: the container's length (or a free chain's span), the
    /// initial displacement or the largest ball's radius, whichever is largest, and at least a
    /// nanometre. Models scale their length tolerances by it.
    pub fn length_scale(&self) -> f64 {
        let extent = match (self.longest_container(), self.initial_positions.first(), self.initial_positions.last()) {
            (Some(length), _, _) => length,
            (None, Some(a), Some(b)) => b - a,
            _ => 0.0,
        };
        let largest = self.balls.iter().map(|b| b.radius).fold(0.0, f64::max);
        let across =
            self.dampers.iter().map(|d| d.section).fold(self.space.section[0].max(self.space.section[1]), |m, [w, h]| m.max(w).max(h));
        extent.max(self.initial_displacement.abs()).max(largest).max(across).max(1e-9)
    }

    /// The scene's speed scale, m/s: the fastest motion it sets going
    /// ([`Scene::motion_speed`]) or the fastest fall its balls start ([`Scene::fall_speed`]),
    /// and at least the speed of a fall through the smallest ball's radius under gravity and
    /// the scene's length covered in [`REST_TIME`] (a scene at rest still has a scale). The one
    /// speed every model scales its speed tolerances, floors and step bounds by; it depends on
    /// what the scene is, never on how long it is run (docs/MODEL.md §9).
    pub fn speed_scale(&self) -> f64 {
        let g = self.space.gravity.iter().map(|a| a * a).sum::<f64>().sqrt();
        let smallest = self.balls.iter().map(|b| b.radius).fold(f64::INFINITY, f64::min);
        let settling = if smallest.is_finite() { (g * smallest).sqrt() } else { 0.0 };
        self.motion_speed().max(self.fall_speed()).max(settling).max(self.length_scale() / REST_TIME)
    }

    /// The fastest speed gravity alone can give a ball from where it starts, m/s: its fall
    /// to the lowest place it can reach across the motion ([`Scene::height_energy`]) and, with
    /// gravity along the motion, through the container's length. 0 without gravity.
    pub fn fall_speed(&self) -> f64 {
        if self.space.gravity == [0.0; 3] {
            return 0.0;
        }
        let along = self.space.gravity[0].abs() * self.longest_container().unwrap_or(0.0);
        (0..self.balls.len())
            .map(|i| {
                let [y, z] = self.space.lateral_of(i);
                // Along the motion the height energy counts from the start, so at the start it
                // is the fall across the motion alone.
                let across = self.height_energy(i, [self.initial_positions[i], y, z]) / self.balls[i].mass;
                (2.0 * (across.max(0.0) + along)).sqrt()
            })
            .fold(0.0, f64::max)
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

    /// The ground's displacement, velocity and acceleration under a structure at `t`: its
    /// record's exact integrals plus a sine base motion `Y sin w t`, m, m/s and m/s^2 (zero when
    /// neither moves it). The ground every model moves a structure's floors against.
    pub fn ground_motion(&self, t: f64) -> (f64, f64, f64) {
        let (mut x, mut v, mut a) = match self.structure.as_ref().and_then(|s| s.ground.as_ref()) {
            Some(record) => {
                let stretch = record.stretch(t);
                stretch.at(t - stretch.start)
            }
            None => (0.0, 0.0, 0.0),
        };
        if let Some(g) = self.forcing.filter(|g| g.kind == ForcingKind::Base) {
            let (y, yd) = g.ground(t);
            x += y;
            v += yd;
            a -= g.omega() * g.omega() * y;
        }
        (x, v, a)
    }
    /// A structure's floors' absolute accelerations at `t` without impulses and contact
    /// forces, with the floors at `u` and moving at `v` relative to the ground: the storeys'
    /// `-M^-1 (C v + K u)` plus a sine force on the carrying floor and a recorded force on its
    /// floor, m/s^2.
    pub fn floor_accelerations(&self, t: f64, u: &[f64], v: &[f64]) -> Vec<f64> {
        let Some(s) = self.structure.as_deref() else { return Vec::new() };
        let mut a = s.accelerations(u, v);
        if let Some(g) = self.forcing.filter(|g| g.kind == ForcingKind::Force) {
            a[s.floor] += g.force(t) / s.building.masses[s.floor];
        }
        if let Some(f) = &s.force {
            a[f.floor] += s.recorded_force(t) / s.building.masses[f.floor];
        }
        a
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
            space: Space::line(0),
            dampers: vec![],
            ..self.clone()
        }
    }
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
    let text = std::fs::read_to_string(path).map_err(|e| SceneError::Io { file: file_name.clone(), message: e.to_string() })?;
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    parse(&text, &file_name, &stem)
}

/// Parses and validates scene text; `file` names it in errors, `default_name` names the scene.
pub fn parse(text: &str, file: &str, default_name: &str) -> Result<Loaded, SceneError> {
    let parsed: SceneFile =
        toml::from_str(text).map_err(|e| SceneError::Parse { file: file.into(), message: e.to_string().trim_end().to_string() })?;
    from_file(parsed, file, default_name)
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
