//! The contact model of docs/MODEL.md §9: the balls are Rapier colliders in a Bevy app, the
//! frame a kinematic body moved by its exact oscillator, fed back the opposite of the balls'
//! momentum change. Rapier keeps bodies apart; the plug-in resolves the impacts with Eq. 9-10
//! and the frame's finite mass, one pair at a time (`contacts`), since Rapier bounces a contact
//! only in the step it is new, solves a touching chain at once and sees the kinematic frame as
//! infinitely heavy.
//!
//! The plug-in group (`plugin`) runs the phases of a step (`phases`) in one order; `spawn`
//! makes the bodies, `resources` holds what the phases share, `settings` the stepping rules.
//! Scenes beyond one line (several chains, balls across the axis, gravity, friction) go to
//! `spatial`, the same model with balls free in 3D, in a lean loop of its own.

mod contacts;
mod phases;
mod plugin;
mod resources;
mod settings;
pub mod spatial;
mod spawn;

use bevy::prelude::*;

use crate::model::{Checks, Meter, Model, ModelError, OverBudget, RunOptions, Setting, Simulator, STALL_EVENTS_PER_SIM_S};
use crate::run::{EnergyAccount, Record, Run};
use crate::scene::Scene;
pub use crate::scene::Stepping;
pub use phases::plan::{APPROACH_RATIO, APPROACH_STEP, MIN_STEP, TOUCHING};
pub use plugin::{
    integration_parameters, ContactPhysicsPlugin, DamperSchedulePlugin, DamperSet, DamperStep, FramePlugin, LpcDamperPlugins, RecordPlugin,
    SceneSpawnPlugin,
};
pub use resources::{Bodies, DamperScene, FrameState, Recording, StepClock, StepPlan, StepSettings};
pub use settings::*;

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

    fn supports(&self, scene: &Scene) -> Result<(), String> {
        // Several chains or dampers, or balls beyond lines, go to the spatial path (`spatial`).
        if spatial::needs_spatial(scene) {
            return spatial::refusal(scene).map_or(Ok(()), Err);
        }
        Ok(())
    }

    fn simulate(&self, scene: &Scene, options: &RunOptions) -> Result<Run, ModelError> {
        if spatial::needs_spatial(scene) {
            return spatial::simulate_spatial(scene, options);
        }
        simulate_with(scene, settings(scene), options)
    }

    fn checks(&self, scene: &Scene, run: &Run) -> Checks {
        if spatial::needs_spatial(scene) {
            return spatial::checks(scene, run);
        }
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
            stall_rate: Some(STALL_EVENTS_PER_SIM_S),
        }
    }

    fn settings(&self) -> &'static [Setting] {
        &[Setting::Stepping, Setting::Dt, Setting::SolverIterations]
    }

    fn stepping(&self, scene: &Scene) -> &'static str {
        if spatial::needs_spatial(scene) {
            return Stepping::Fixed.name();
        }
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
    if let Some(failure) = frame_failure(world, scene) {
        return Err(failure);
    }
    loop {
        let clock = *world.resource::<StepClock>();
        if scene.reached_horizon(clock.t) {
            break;
        }
        if let Some(budget) = meter.look(clock.t, clock.steps) {
            let wall_s = meter.elapsed();
            let cost = format!(
                "{} impacts so far; the last step was {} s",
                world.resource::<Recording>().impacts.len(),
                crate::scene::human(world.resource::<StepPlan>().h)
            );
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
        if let Some(failure) = frame_failure(world, scene) {
            return Err(failure);
        }
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

/// Why the frame cannot move on, when it cannot: a structure whose floors have no modes with
/// the balls they hold, which no model can run either.
fn frame_failure(world: &World, scene: &Scene) -> Option<ModelError> {
    let reason = world.get_resource::<FrameState>()?.failure.clone()?;
    Some(ModelError::Unstable { scene: scene.name.clone(), model: Model::Rapier, t: world.resource::<StepClock>().t, reason })
}

/// The [`Run`] recorded in `world`, up to time `t` (the horizon, or where a budget stopped it).
pub fn collect(world: &mut World, scene: &Scene, t: f64, steps: u64) -> Run {
    let rec = world.remove_resource::<Recording>().expect("recording");
    let (frame_energy, damping_loss, forcing_work) = match world.get_resource_mut::<FrameState>() {
        Some(mut frame) => (frame.energy(scene, t), frame.damping_loss, frame.forcing_work),
        None => (scene.frame_energy(t, 0.0, 0.0), 0.0, 0.0),
    };
    let f = scene.frame;
    let final_ = frame_energy + scene.balls.iter().zip(&rec.v).map(|(b, v)| 0.5 * b.mass * v * v).sum::<f64>();
    let energy = EnergyAccount::forced(scene.initial_energy(), final_, damping_loss, rec.impact_loss, forcing_work);
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
        counted_impacts: crate::run::CountedImpacts::default(),
        energy,
        events: steps,
        final_velocities: rec.v,
        peak_true_acceleration: None,
        wall_time_s: 0.0,
    }
}
