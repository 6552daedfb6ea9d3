//! The Bevy plug-in group: spawns a scene as Rapier bodies, drives the kinematic spring-damped
//! frame, feeds impacts back into it and records what happened. Each small plug-in owns its
//! systems; the resources they share are in `resources`; [`DamperSchedulePlugin`] states the
//! order of a step once, for the lean [`DamperStep`] schedule and for Bevy's main schedules.

use bevy::app::PluginGroupBuilder;
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier3d::rapier::dynamics::IntegrationParameters;

use super::phases::drive::{drive_frame, init_frame};
use super::phases::feedback::feedback;
use super::phases::impacts::resolve_impacts;
use super::phases::plan::plan_step;
use super::phases::record::{init_recording, record_samples};
use super::resources::*;
use super::spawn::spawn_scene;
use crate::run::Record;
use crate::scene::Scene;

/// A lean schedule holding one physics step and nothing else: the plug-in's systems and
/// Rapier's step, without Bevy's main schedule or bevy_rapier's ECS synchronisation
/// (transform propagation, change detection, writeback), which only a renderer needs.
/// Headless runs call it directly after one `app.update()` has spawned and initialised the
/// bodies; rendered runs use `app.update()` throughout.
#[derive(bevy::ecs::schedule::ScheduleLabel, Debug, Clone, PartialEq, Eq, Hash)]
pub struct DamperStep;

/// The phases of one physics step, in order. [`DamperSchedulePlugin`] configures the order
/// once, for the lean [`DamperStep`] schedule and for Bevy's main schedules.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DamperSet {
    /// Before the Rapier step: resolve the impacts of touching pairs that approach.
    Impacts,
    /// Before the Rapier step: choose its length.
    Plan,
    /// Before the Rapier step: move the kinematic frame to where the oscillator will be.
    DriveFrame,
    /// Rapier's step (in [`DamperStep`]; in the main schedules bevy_rapier's own
    /// [`PhysicsSet`]s run it in `PostUpdate`).
    Step,
    /// After the step: measure the balls' velocity jumps and feed the impulse to the frame.
    Feedback,
    /// After the feedback: write samples.
    Record,
}

/// Everything the contact model needs, as one group of small plug-ins.
pub struct LpcDamperPlugins {
    /// The scene to spawn.
    pub scene: Scene,
    /// Stepping.
    pub settings: StepSettings,
    /// What the run keeps besides its metrics.
    pub record: Record,
}

impl PluginGroup for LpcDamperPlugins {
    fn build(self) -> PluginGroupBuilder {
        PluginGroupBuilder::start::<Self>()
            .add(DamperSchedulePlugin)
            .add(ContactPhysicsPlugin { scene: self.scene.clone(), settings: self.settings })
            .add(SceneSpawnPlugin { scene: self.scene.clone() })
            .add(FramePlugin)
            .add(RecordPlugin { record: self.record })
    }
}

/// The order of a step's phases, stated once: [`DamperSet`] chained in the lean [`DamperStep`]
/// schedule, and around bevy_rapier's [`PhysicsSet`]s in the main schedules (plan and drive in
/// `Update`, before `PostUpdate` where Rapier steps; feedback and recording after its
/// writeback). Each plug-in below only puts its own systems into its sets, in both.
pub struct DamperSchedulePlugin;

impl Plugin for DamperSchedulePlugin {
    fn build(&self, app: &mut App) {
        use DamperSet::*;
        app.init_schedule(DamperStep)
            .configure_sets(DamperStep, (Impacts, Plan, DriveFrame, Step, Feedback, Record).chain())
            .configure_sets(Update, (Impacts, Plan, DriveFrame).chain())
            .configure_sets(PostUpdate, (Feedback, Record).chain().after(PhysicsSet::Writeback));
    }
}

/// Rapier with fixed steps, centimetre tolerances and no gravity; it plans each step and
/// takes it.
pub struct ContactPhysicsPlugin {
    /// For the speed scale of the prediction distance and the frame mass of the hook.
    pub scene: Scene,
    /// Stepping.
    pub settings: StepSettings,
}

impl Plugin for ContactPhysicsPlugin {
    fn build(&self, app: &mut App) {
        let integration_parameters = integration_parameters(&self.scene, self.settings);
        let rapier_configuration = RapierConfiguration { gravity: Vec3::ZERO, ..RapierConfiguration::new(LENGTH_UNIT) };
        app.insert_resource(TimestepMode::Fixed { dt: self.settings.dt as f32, substeps: 1 })
            .insert_resource(self.settings)
            .add_plugins(RapierPhysicsPlugin::<()>::default().with_custom_initialization(
                RapierContextInitialization::InitializeDefaultRapierContext { integration_parameters, rapier_configuration },
            ))
            .insert_resource(StepPlan { h: self.settings.dt, horizon: self.scene.horizon })
            .add_systems(Update, plan_step.in_set(DamperSet::Plan))
            .add_systems(
                DamperStep,
                (plan_step.in_set(DamperSet::Plan), bevy_rapier3d::plugin::systems::step_simulation::<()>.in_set(DamperSet::Step)),
            );
    }
}

/// Rapier's integration parameters for `scene`: centimetre length unit, the solver
/// iterations asked for, a prediction distance that sees contacts before they close, and no
/// speed clamp.
pub fn integration_parameters(scene: &Scene, settings: StepSettings) -> IntegrationParameters {
    let dt = settings.dt as f32;
    // Contacts must be found before they close: at least twice the closing distance of one
    // step at the fastest speed the scene can reach.
    let speed = speed_scale(scene) as f32;
    let prediction = if settings.speculative_margin { (4.0 * speed * dt).max(0.02 * LENGTH_UNIT) } else { 0.02 * LENGTH_UNIT };
    IntegrationParameters {
        dt,
        length_unit: LENGTH_UNIT,
        num_solver_iterations: settings.solver_iterations,
        normalized_prediction_distance: prediction / LENGTH_UNIT,
        // The default clamps every body at 400 length units per second (4 m/s here).
        normalized_max_linear_velocity: f32::MAX,
        ..IntegrationParameters::default()
    }
}

/// Spawns the frame (a kinematic body carrying both walls) and the balls.
pub struct SceneSpawnPlugin {
    /// The scene to spawn.
    pub scene: Scene,
}

impl Plugin for SceneSpawnPlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(DamperScene(self.scene.clone())).add_systems(Startup, spawn_scene);
    }
}

/// Advances the kinematic frame with the exact damped-oscillator step.
pub struct FramePlugin;

impl Plugin for FramePlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Startup, init_frame)
            .add_systems(Update, drive_frame.in_set(DamperSet::DriveFrame))
            .add_systems(DamperStep, drive_frame.in_set(DamperSet::DriveFrame));
    }
}

/// Measures impacts, feeds them back into the frame and records the series.
pub struct RecordPlugin {
    /// What the run keeps besides its metrics.
    pub record: Record,
}

impl Plugin for RecordPlugin {
    fn build(&self, app: &mut App) {
        // Passed in the system, not as a resource: adding a resource reorders what Bevy
        // iterates, and the contact model's chaotic runs follow any change of order.
        let record = self.record;
        app.add_systems(Startup, move |commands: Commands, scene: Res<DamperScene>, settings: Res<StepSettings>| {
            init_recording(commands, scene, settings, record)
        })
        .add_systems(PostUpdate, (feedback.in_set(DamperSet::Feedback), record_samples.in_set(DamperSet::Record)))
        .add_systems(DamperStep, (feedback.in_set(DamperSet::Feedback), record_samples.in_set(DamperSet::Record)))
        .add_systems(Update, resolve_impacts.in_set(DamperSet::Impacts))
        .add_systems(DamperStep, resolve_impacts.in_set(DamperSet::Impacts));
    }
}
