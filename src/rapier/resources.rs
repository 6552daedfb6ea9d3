//! The resources the plug-ins share, in one place: the scene, its bodies, how steps are taken,
//! the frame's exact state, the clock and the recording. Systems import these; nothing here
//! imports a system, so the plug-in's modules form no cycle.

use bevy::prelude::*;

use std::sync::{Mutex, PoisonError};

use crate::floor_motion::FloorMotion;
use crate::oscillator::Driven;
use crate::run::{Impact, Record, Recorder};
use crate::scene::{Scene, Stepping};

/// Rapier's length unit: the balls are centimetres, so are the tolerances.
pub const LENGTH_UNIT: f32 = 0.01;

/// How the contact model steps.
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct StepSettings {
    /// How steps are chosen.
    pub stepping: Stepping,
    /// Physics step (the longest one with aligned stepping), s.
    pub dt: f64,
    /// Rapier solver iterations per step.
    pub solver_iterations: usize,
    /// Rapier's swept CCD on the balls.
    pub ccd: bool,
    /// Contacts are predicted as far ahead as the scene's speed scale carries a ball in two
    /// steps (the plug-in's choice), rather than Rapier's fixed 0.02 length units (only the
    /// stability map turns this off, to show why it is needed).
    pub speculative_margin: bool,
    /// The plug-in's safeguards: a ball that Rapier's solver pushed into a wall deeper than a
    /// quarter of its radius is put back by the plug-in (shallower ones always are), and a step
    /// whose contacts gained energy stops the run with [`crate::model::ModelError::Unstable`]
    /// rather than return a wrong run. Only the stability map turns them off, to measure
    /// Rapier's raw behaviour.
    pub safeguards: bool,
}

impl StepSettings {
    /// Fixed steps of `dt` with the plug-in's other defaults.
    pub fn fixed(dt: f64, solver_iterations: usize) -> Self {
        StepSettings { stepping: Stepping::Fixed, dt, solver_iterations, ccd: false, speculative_margin: true, safeguards: true }
    }
}

/// The scene being simulated.
#[derive(Resource, Debug, Clone)]
pub struct DamperScene(pub Scene);

/// Entities of the scene, balls left to right.
#[derive(Resource, Debug, Clone, Default)]
pub struct Bodies {
    /// The kinematic frame carrying the walls.
    pub frame: Option<Entity>,
    /// Left and right wall colliders.
    pub walls: Option<(Entity, Entity)>,
    /// Ball bodies (each is its own collider).
    pub balls: Vec<Entity>,
}

/// Marks the frame's kinematic body.
#[derive(Component, Debug)]
pub struct FrameBody;

/// The frame's exact state (f64), advanced in closed form; impacts arrive as velocity jumps.
/// On a structure of several storeys the frame is the carrying floor, and the structure's
/// floors move it in place of the oscillator.
#[derive(Resource, Debug)]
pub struct FrameState {
    /// The bare frame's oscillator, with the scene's harmonic load.
    pub bare: Driven,
    /// This step's motion: the bare frame's, or the frame carrying the balls it holds.
    pub motion: Driven,
    /// Balls held against the left and the right wall this step (counted from each wall): they
    /// ride the frame, their mass part of its oscillator, as in the reference's persistent
    /// contact (docs/MODEL.md §4).
    pub held: [usize; 2],
    /// Time at the start of the current step, s.
    pub t_start: f64,
    /// Displacement and velocity at the start of the current step.
    pub start: (f64, f64),
    /// Displacement and velocity at the end of the step, before the impact impulses.
    pub before_impulses: (f64, f64),
    /// Displacement and velocity now (end of the last step, impulses included).
    pub now: (f64, f64),
    /// Energy dissipated by `cs` so far, J.
    pub damping_loss: f64,
    /// Work done by the excitation so far, J.
    pub forcing_work: f64,
    /// A structure's floors since the last impulse on the carrying floor (or change of what it
    /// holds), in closed form. The lock is there only so that the state can be a resource: the
    /// systems that hold it run one at a time.
    pub floors: Option<Mutex<FloorMotion>>,
    /// Why the frame cannot move on: its floors have no modes with the balls they hold.
    pub failure: Option<String>,
    /// The mass of balls the floors' current closed form carries on the carrying floor, kg.
    pub floors_held: f64,
}

impl FrameState {
    /// The structure's floors, when the frame is a structure's carrying floor.
    pub fn floors_mut(&mut self) -> Option<&mut FloorMotion> {
        self.floors.as_mut().map(|m| m.get_mut().unwrap_or_else(PoisonError::into_inner))
    }

    /// Moves a structure's floors over the step from `t0` to `t0 + h` from where the frame is
    /// now, the carrying floor holding `held` kg of balls: the frame's state at the step's end
    /// before its impulses, and the storeys' loss and the excitation's work over the step.
    /// Returns whether the frame is a structure's floor (otherwise nothing is done).
    pub fn advance_floors(&mut self, t0: f64, h: f64, held: f64) -> bool {
        let v = self.now.1;
        // The closed form goes on until an impulse changes the carrying floor's velocity or
        // what the floor holds changes.
        let (kept, held_before) = (self.now == self.before_impulses, self.floors_held);
        let Some(floors) = self.floors.as_mut().map(|m| m.get_mut().unwrap_or_else(PoisonError::into_inner)) else { return false };
        if !(kept && held == held_before) {
            if let Err(why) = floors.restart(t0, v, held) {
                self.failure.get_or_insert(why);
            }
            self.floors_held = held;
        }
        let t1 = t0 + h;
        self.before_impulses = floors.state(t1);
        let (damping, work) = floors.energy_between(t0, t1);
        self.damping_loss += damping;
        self.forcing_work += work;
        true
    }

    /// The floors' state `[u; u']` relative to the ground at `t` in the current step, with the
    /// carrying floor moving at the frame's velocity now (its impulses included) and the
    /// ground's displacement and velocity; `None` for a frame of one storey.
    pub fn floors_now(&mut self, t: f64) -> Option<(Vec<f64>, (f64, f64))> {
        let v = self.now.1;
        let floors = self.floors_mut()?;
        let (mut z, ground) = floors.floors(t);
        let d = floors.structure.floor;
        let n = z.len() / 2;
        z[n + d] = v - ground.1;
        Some((z, ground))
    }

    /// The smooth force on the frame at `t` as it is now (springs, dampers and excitation;
    /// impulses and contact forces excluded), N, and the mechanical energy of the frame (or of
    /// the structure it is a floor of), J: one evaluation of a structure's floors for both.
    pub fn force_and_energy(&mut self, scene: &Scene, t: f64) -> (f64, f64) {
        let (xs, vs) = self.now;
        match (self.floors_now(t), scene.structure.as_deref()) {
            (Some((z, (_, vg))), Some(s)) => {
                let (u, v) = z.split_at(z.len() / 2);
                (scene.floor_accelerations(t, u, v)[s.floor] * s.building.masses[s.floor], s.energy(u, v, vg))
            }
            _ => (scene.frame_force(t, xs, vs), scene.frame_energy(t, xs, vs)),
        }
    }

    /// The smooth force of [`FrameState::force_and_energy`], N.
    pub fn smooth_force(&mut self, scene: &Scene, t: f64) -> f64 {
        self.force_and_energy(scene, t).0
    }

    /// The mechanical energy of [`FrameState::force_and_energy`], J.
    pub fn energy(&mut self, scene: &Scene, t: f64) -> f64 {
        self.force_and_energy(scene, t).1
    }
}

/// The balls `held` (counted from the left and the right wall, as [`FrameState::held`]) of a
/// scene with `n` balls, by index.
pub fn held_balls(held: [usize; 2], n: usize) -> impl Iterator<Item = usize> + Clone {
    (0..held[0].min(n)).chain(n - held[1].min(n)..n)
}

/// Steps taken so far and the simulated time they cover.
#[derive(Resource, Debug, Clone, Copy, Default)]
pub struct StepClock {
    /// Steps taken.
    pub steps: u64,
    /// Time at the end of the last step, s.
    pub t: f64,
}

/// The fastest speed the contact model expects: the scene's speed scale
/// ([`Scene::speed_scale`]), doubled for what impacts can add.
pub fn speed_scale(scene: &Scene) -> f64 {
    2.0 * scene.speed_scale()
}

/// The length of the step about to be taken, s.
#[derive(Resource, Debug, Clone, Copy)]
pub struct StepPlan {
    /// Step length, s.
    pub h: f64,
    /// Time at which the run ends, s.
    pub horizon: f64,
}

/// What the contact model has recorded so far.
#[derive(Resource, Debug, Clone)]
pub struct Recording {
    /// Samples every `sample_dt`.
    pub recorder: Recorder,
    /// Impacts, in time order.
    pub impacts: Vec<Impact>,
    /// Kinetic energy lost in contacts, J.
    pub impact_loss: f64,
    /// Ball positions and velocities at the start of the current step.
    pub x: Vec<f64>,
    /// See `x`.
    pub v: Vec<f64>,
    /// Ball positions and velocities at the start of the last step taken.
    pub prev_x: Vec<f64>,
    /// See `prev_x`.
    pub prev_v: Vec<f64>,
    /// Impulse across each pair in the last step (pair `p` between body `p-1` and body `p`).
    pub last_impulse: Vec<f64>,
    /// Index in `impacts` of each pair's latest impact.
    pub last_impact: Vec<Option<usize>>,
    /// The step count at which the plug-in last resolved an impact of each pair: a pair struck
    /// again at the next step's start is one persistent contact, not a new impact.
    pub struck_at: Vec<Option<u64>>,
    /// Next sample to write.
    pub next_sample: usize,
    /// Number of samples over the horizon.
    pub sample_count: usize,
    /// Impulses below this are numerical noise (f32 velocities), N s.
    pub impulse_floor: f64,
    /// Why the run cannot go on (a ball pushed through a wall, contacts that gained energy),
    /// when the self-check found it.
    pub failure: Option<String>,
    /// The scene's mechanical energy at t = 0, J.
    pub initial_energy: f64,
    /// Energy that f32 positions cannot resolve, J: every ball moving by one f32 step of the
    /// container's extent per longest step. Rapier pushing apart balls that touch within
    /// round-off (a packed column at rest) makes about this much; energy checks are judged
    /// above it.
    pub energy_floor: f64,
}

impl Recording {
    /// An empty recording for `scene` that keeps what `record` asks for.
    pub fn new(scene: &Scene, record: Record, longest_step: f64) -> Self {
        let n = scene.balls.len();
        let samples = scene.sample_count();
        let m_min = scene.balls.iter().map(|b| b.mass).fold(f64::INFINITY, f64::min);
        Recording {
            recorder: Recorder::new(scene, record),
            impacts: Vec::new(),
            impact_loss: 0.0,
            x: scene.initial_positions.clone(),
            v: scene.initial_velocities.clone(),
            prev_x: scene.initial_positions.clone(),
            prev_v: scene.initial_velocities.clone(),
            last_impulse: vec![0.0; n + 1],
            last_impact: vec![None; n + 1],
            struck_at: vec![None; n + 1],
            next_sample: 0,
            sample_count: samples,
            impulse_floor: 1e-6 * m_min * speed_scale(scene).max(1e-6),
            failure: None,
            initial_energy: scene.initial_energy(),
            energy_floor: {
                let extent = scene.container.map_or(0.0, |c| c.length) + scene.initial_displacement.abs();
                let v = f32::EPSILON as f64 * extent / longest_step;
                0.5 * scene.balls.iter().map(|b| b.mass).sum::<f64>() * v * v
            },
        }
    }
}
