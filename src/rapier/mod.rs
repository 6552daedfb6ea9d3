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

use bevy::prelude::*;

use crate::model::{Checks, Meter, Model, ModelError, OverBudget, RunOptions, Setting, Simulator};
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

/// The contact model.
#[derive(Debug, Clone, Copy)]
pub struct Rapier;

impl Simulator for Rapier {
    fn model(&self) -> Model {
        Model::Rapier
    }

    fn supports(&self, _scene: &Scene) -> Result<(), String> {
        Ok(())
    }

    fn simulate(&self, scene: &Scene, options: &RunOptions) -> Result<Run, ModelError> {
        simulate_with(scene, settings(scene), options)
    }

    fn checks(&self, _scene: &Scene, _run: &Run) -> Checks {
        // f32 velocities, one rounding per impulse; Rapier's contacts sink by up to its allowed
        // overlap before it corrects them, and balls deform nothing it could bound otherwise.
        Checks {
            energy_gain: ENERGY_GAIN_TOLERANCE,
            balance: None,
            impact_gain: ENERGY_GAIN_TOLERANCE,
            exact_impacts: false,
            momentum: 1e-5,
            wall_overlap: ALLOWED_OVERLAP + 1e-6,
            ball_overlap: None,
            stall_by_rate: true,
        }
    }

    fn settings(&self) -> &'static [Setting] {
        &[Setting::Stepping, Setting::Dt, Setting::SolverIterations]
    }

    fn stepping(&self, scene: &Scene) -> &'static str {
        settings(scene).stepping.name()
    }
}

/// Steps between two looks at the budgets and two reports of progress.
const BUDGET_STEPS: u64 = 256;

/// Runs the contact model on `scene` with the plug-in's `settings` as given (no step bound
/// applied): for studies of the contact model itself, which vary what the scene does not say.
pub fn simulate_with(scene: &Scene, settings: StepSettings, options: &RunOptions) -> Result<Run, ModelError> {
    let meter = Meter::new(options, BUDGET_STEPS);
    let mut app = headless_app_recording(scene, settings, options.record);
    // The first update spawns the scene, lets bevy_rapier create its bodies and takes the
    // first step; the rest run the lean step schedule alone.
    app.update();
    let world = app.world_mut();
    loop {
        let clock = *world.resource::<StepClock>();
        if clock.t >= scene.horizon * (1.0 - 1e-12) {
            break;
        }
        if let Some(budget) = meter.look(clock.t, clock.steps) {
            let wall_s = meter.elapsed();
            let cost = format!("{} impacts so far; the last step was {} s", world.resource::<Recording>().impacts.len(), crate::scene::human(world.resource::<StepPlan>().h));
            let mut partial = collect(world, scene, clock.t, clock.steps);
            partial.wall_time_s = wall_s;
            return Err(ModelError::OverBudget(Box::new(OverBudget {
                scene: scene.name.clone(),
                model: Model::Rapier,
                t: clock.t,
                horizon: scene.horizon,
                steps: clock.steps,
                wall_s,
                budget,
                limit: meter.limit(budget),
                cost,
                partial,
            })));
        }
        world.run_schedule(DamperStep);
        if let Some(reason) = world.resource::<Recording>().failure.clone() {
            let t = world.resource::<StepClock>().t;
            return Err(ModelError::Unstable {
                scene: scene.name.clone(),
                model: Model::Rapier,
                t,
                reason: format!("{reason}; the reference and compliant models can run it"),
            });
        }
    }
    let steps = app.world().resource::<StepClock>().steps;
    meter.finish(scene.horizon, steps);
    let mut run = collect(app.world_mut(), scene, scene.horizon, steps);
    run.wall_time_s = meter.elapsed();
    Ok(run)
}

/// The [`Run`] recorded in `world`, up to time `t` (the horizon, or where a budget stopped it).
pub fn collect(world: &mut World, scene: &Scene, t: f64, steps: u64) -> Run {
    let rec = world.remove_resource::<Recording>().expect("recording");
    let frame = world.get_resource::<FrameState>().copied();
    let (xs, vs) = frame.map_or((0.0, 0.0), |f| f.now);
    let f = scene.frame;
    let final_ = scene.frame_energy(t, xs, vs)
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
        model: Model::Rapier,
        horizon: t,
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
