//! The contact model: the balls are Rapier colliders in a headless Bevy app, the frame is a
//! kinematic body moved by the exact damped-oscillator step, and every ball-wall impact is fed
//! back into the frame as the opposite of the balls' momentum change.
//!
//! Where it departs from the impulse model (docs/MODEL.md §3-4, "Rapier"), and why:
//! - Rapier only keeps bodies apart (every contact plastic); the plug-in resolves impacts with
//!   Eq. 9-10 and the frame's finite mass, one pair at a time (`impacts`), because Rapier
//!   bounces a contact only in the step it is new, solves a touching chain at once, and sees
//!   the kinematic frame as infinitely heavy.
//! - Steps end as pairs come into contact (`stepping`); with fixed steps an impact lands at the
//!   end of the step in which it happens, up to `dt` late. The frame's motion between impulses
//!   is exact.
//! - Velocities are f32.

pub mod impacts;
pub mod plugin;
pub mod record;
pub mod resources;
pub mod stepping;

use std::time::Instant;

use bevy::prelude::*;

use crate::model::ModelError;
use crate::run::{EnergyAccount, Record, Run};
use crate::scene::Scene;
pub use plugin::{DamperSet, DamperStep, LpcDamperPlugins};
pub use resources::{Bodies, DamperScene, FrameState, Recording, StepClock, StepPlan, StepSettings};
pub use crate::scene::Stepping;

/// Default stepping (from the accuracy study in docs/BENCHMARKS.md).
pub const DEFAULT_STEPPING: Stepping = Stepping::Aligned;
/// Default longest step, s.
pub const DEFAULT_DT: f64 = 2e-3;
/// Default solver iterations.
pub const DEFAULT_SOLVER_ITERATIONS: usize = 4;

/// Steps per period of the frame at least: Rapier sees the walls move in a straight line over
/// a step, which must stay close to the frame's true path.
pub const STEPS_PER_FRAME_PERIOD: f64 = 40.0;

/// Rapier's allowed contact overlap (`0.005 length_unit`), m: what a contact may sink before
/// Rapier corrects it.
pub const ALLOWED_OVERLAP: f64 = 0.005 * resources::LENGTH_UNIT as f64;
/// Energy a step's contacts may gain, relative to the energy put in (f32 velocities, one
/// rounding per impulse): beyond it the run stops as unstable.
pub const ENERGY_GAIN_TOLERANCE: f64 = 1e-3;

/// Largest gap between the straight path Rapier gives the walls over a step and the frame's
/// true path, m: a fifth of [`ALLOWED_OVERLAP`], so that the
/// walls a ball meets are where the frame is.
pub const WALL_CHORD_ERROR: f64 = 1e-5;

/// The frame's largest acceleration to expect: its spring at the larger of the initial
/// displacement and the steady forced amplitude, plus the excitation's load, m/s^2.
pub fn peak_frame_acceleration(scene: &Scene) -> f64 {
    let Some(f) = scene.frame else { return 0.0 };
    let (steady, load) = scene.harmonic_load().map_or((0.0, 0.0), |(p, q, w)| {
        let osc = crate::oscillator::Oscillator::new(f.mass, f.damping, f.stiffness);
        (osc.harmonic_response(p, q, w).amplitude(), p.hypot(q))
    });
    (f.stiffness * scene.initial_displacement.abs().max(steady) + load) / f.mass
}

/// The stepping a scene asks for, with the defaults filled in and the step kept inside the
/// stable region: at most a 40th of the frame's natural period and of the forcing period, and
/// short enough that the walls' straight path over a step stays within [`WALL_CHORD_ERROR`]
/// of the frame's (`a h^2 / 8`).
pub fn settings(scene: &Scene) -> StepSettings {
    let dt = scene.rapier.dt.unwrap_or(DEFAULT_DT);
    let a = peak_frame_acceleration(scene);
    let chord_bound = if a > 0.0 { (8.0 * WALL_CHORD_ERROR / a).sqrt() } else { f64::INFINITY };
    let forcing_bound = scene.forcing.map_or(f64::INFINITY, |g| 1.0 / (g.frequency * STEPS_PER_FRAME_PERIOD));
    let period_bound = scene
        .frame
        .filter(|f| f.stiffness > 0.0)
        .map_or(f64::INFINITY, |f| 2.0 * std::f64::consts::PI * (f.mass / f.stiffness).sqrt() / STEPS_PER_FRAME_PERIOD)
        .min(forcing_bound);
    StepSettings {
        stepping: scene.rapier.stepping.unwrap_or(DEFAULT_STEPPING),
        dt: dt.min(period_bound).min(chord_bound),
        solver_iterations: scene.rapier.solver_iterations.map_or_else(|| default_iterations(scene), |i| i as usize),
        ccd: scene.rapier.ccd.unwrap_or(false),
        speculative_margin: true,
        self_check: true,
    }
}

/// Solver iterations when the scene sets none: [`DEFAULT_SOLVER_ITERATIONS`] per decade of
/// the largest mass ratio of neighbouring balls. Rapier's iterative solver converges more
/// slowly the more unequal the masses it couples: a light ball squeezed between a heavy one
/// and a wall sinks into the wall with too few iterations (docs/BENCHMARKS.md, "Stress runs").
pub fn default_iterations(scene: &Scene) -> usize {
    // Past 16 decades the light ball's momentum is below the heavy one's round-off: more
    // iterations cannot couple them (and an infinite ratio must not ask for infinitely many).
    let decades = neighbour_mass_ratio(scene).log10().ceil();
    DEFAULT_SOLVER_ITERATIONS * if decades.is_nan() { 1 } else { decades.clamp(1.0, 16.0) as usize }
}

/// The largest mass ratio of two neighbouring balls (1 for fewer than two balls).
pub fn neighbour_mass_ratio(scene: &Scene) -> f64 {
    scene.balls.windows(2).map(|w| (w[0].mass / w[1].mass).max(w[1].mass / w[0].mass)).fold(1.0, f64::max)
}

/// A headless app (no window, renderer or audio) simulating `scene`: one Rapier step per
/// `app.update()`, never paced to real time.
pub fn headless_app(scene: &Scene, settings: StepSettings) -> App {
    headless_app_recording(scene, settings, Record::Series)
}

/// [`headless_app`], keeping what `record` asks for.
pub fn headless_app_recording(scene: &Scene, settings: StepSettings, record: Record) -> App {
    let mut app = App::new();
    // Rapier reads `Time` although fixed steps never use its value.
    app.init_resource::<Time>();
    app.add_plugins(LpcDamperPlugins { scene: scene.clone(), settings, record });
    app.finish();
    app.cleanup();
    app
}

/// Runs the contact model on `scene`.
pub fn simulate(scene: &Scene) -> Result<Run, ModelError> {
    simulate_with(scene, settings(scene))
}

/// Runs the contact model on `scene` with `settings` as given (no step bound applied).
pub fn simulate_with(scene: &Scene, settings: StepSettings) -> Result<Run, ModelError> {
    run_app(scene, settings, Record::Series, None)
}

/// Runs the contact model on `scene`, keeping what `record` asks for.
pub fn simulate_recording(scene: &Scene, record: Record) -> Result<Run, ModelError> {
    run_app(scene, settings(scene), record, None)
}

/// [`simulate_recording`] within `max_wall_s` seconds of computing, if given
/// ([`ModelError::OverBudget`]).
pub fn simulate_within(scene: &Scene, record: Record, max_wall_s: Option<f64>) -> Result<Run, ModelError> {
    run_app(scene, settings(scene), record, max_wall_s)
}

/// Steps between two looks at the computing-time budget.
const BUDGET_STEPS: u64 = 256;

fn run_app(scene: &Scene, settings: StepSettings, record: Record, max_wall_s: Option<f64>) -> Result<Run, ModelError> {
    let start = Instant::now();
    let mut app = headless_app_recording(scene, settings, record);
    // The first update spawns the scene, lets bevy_rapier create its bodies and takes the
    // first step; the rest run the lean step schedule alone.
    app.update();
    let world = app.world_mut();
    while world.resource::<StepClock>().t < scene.horizon * (1.0 - 1e-12) {
        world.run_schedule(DamperStep);
        if let Some(budget) = max_wall_s {
            let clock = world.resource::<StepClock>();
            let wall_s = start.elapsed().as_secs_f64();
            if clock.steps % BUDGET_STEPS == 0 && wall_s > budget {
                return Err(ModelError::OverBudget(format!(
                    "scene `{}`: the contact model stopped at t = {} s after {} steps and {wall_s:.1} s of computing: more than {budget} s of computing",
                    scene.name,
                    crate::scene::human(clock.t),
                    clock.steps
                )));
            }
        }
        if let Some(reason) = world.resource::<Recording>().failure.clone() {
            return Err(ModelError::Unstable(format!(
                "scene `{}`: the contact model stopped: {reason}; the reference and compliant models can run it",
                scene.name
            )));
        }
    }
    let steps = app.world().resource::<StepClock>().steps;
    let mut run = collect(app.world_mut(), scene, steps);
    run.wall_time_s = start.elapsed().as_secs_f64();
    Ok(run)
}

/// The [`Run`] recorded in `world`.
pub fn collect(world: &mut World, scene: &Scene, steps: u64) -> Run {
    let rec = world.remove_resource::<Recording>().expect("recording");
    let frame = world.get_resource::<FrameState>().copied();
    let (xs, vs) = frame.map_or((0.0, 0.0), |f| f.now);
    let f = scene.frame;
    let final_ = scene.frame_energy(scene.horizon, xs, vs)
        + scene.balls.iter().zip(&rec.v).map(|(b, v)| 0.5 * b.mass * v * v).sum::<f64>();
    let energy = EnergyAccount::forced(
        scene.initial_energy(),
        final_,
        frame.map_or(0.0, |f| f.damping_loss),
        rec.impact_loss,
        frame.map_or(0.0, |f| f.forcing_work),
    );
    let (series, motion) = rec.recorder.finish();
    Run {
        scene: scene.name.clone(),
        model: crate::run::Model::Rapier,
        horizon: scene.horizon,
        sample_dt: scene.sample_dt,
        initial_displacement: scene.initial_displacement,
        damped_period: f.map_or(0.0, |f| f.damped_period()),
        series,
        motion,
        impacts: rec.impacts,
        energy,
        events: steps,
        final_velocities: rec.v,
        peak_true_acceleration: None,
        wall_time_s: 0.0,
    }
}
