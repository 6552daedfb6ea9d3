//! The Bevy plug-in group: spawns a scene as Rapier bodies, drives the kinematic spring-damped
//! frame, feeds impacts back into it and records what happened. Each small plug-in owns its
//! systems; the resources they share are in `resources`; [`DamperSchedulePlugin`] states the
//! order of a step once, for the lean [`DamperStep`] schedule and for Bevy's main schedules.

use bevy::app::PluginGroupBuilder;
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier3d::rapier::dynamics::IntegrationParameters;

use super::impacts::resolve_impacts;
use super::record::{feedback, record_samples};
use super::resources::*;
use super::stepping::plan_step;
use crate::oscillator::{gauss_legendre, Driven, Oscillator};
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
                (
                    plan_step.in_set(DamperSet::Plan),
                    bevy_rapier3d::plugin::systems::step_simulation::<()>.in_set(DamperSet::Step),
                ),
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

/// How much smaller Rapier's balls are than the scene's, m: four f32 steps of the largest
/// coordinate. Balls that touch in the scene then do not overlap in f32, where Rapier would push
/// them apart and make energy from round-off (a packed column at rest started moving). Impacts
/// are found and resolved on the scene's radii (`super::stepping`, `super::impacts`); only
/// Rapier's resting contacts sit this much deeper.
pub fn collider_skin(scene: &Scene) -> f64 {
    let extent = scene.container.map_or(0.0, |c| c.length) + scene.initial_displacement.abs();
    let reach = scene.initial_positions.iter().zip(&scene.balls).map(|(x, b)| x.abs() + b.radius).fold(extent, f64::max);
    4.0 * f32::EPSILON as f64 * reach
}

/// Every contact Rapier solves is plastic: the plug-in gives the bounces (`super::impacts`).
const PLASTIC: Restitution = Restitution { coefficient: 0.0, combine_rule: CoefficientCombineRule::Max };

fn spawn_scene(mut commands: Commands, scene: Res<DamperScene>, settings: Res<StepSettings>) {
    let scene = &scene.0;
    let mut bodies = Bodies::default();
    let r_max = scene.balls.iter().map(|b| b.radius).fold(0.0, f64::max) as f32;
    if let (Some(_), Some(c)) = (scene.frame, scene.container) {
        // Thick walls, so that no ball can tunnel through one in a step.
        let half = (0.5 * c.length as f32).max(4.0 * r_max).max(0.01);
        let side = 2.0 * r_max.max(0.005);
        let mut walls = Vec::new();
        let frame = commands
            .spawn((
                FrameBody,
                RigidBody::KinematicPositionBased,
                Transform::from_xyz(scene.initial_displacement as f32, 0.0, 0.0),
                Sleeping::disabled(),
            ))
            .with_children(|p| {
                for centre in [-half, c.length as f32 + half] {
                    walls.push(
                        p.spawn((
                            Transform::from_xyz(centre, 0.0, 0.0),
                            Collider::cuboid(half, side, side),
                            Friction { coefficient: 0.0, combine_rule: CoefficientCombineRule::Min },
                            PLASTIC,
                        ))
                        .id(),
                    );
                }
            })
            .id();
        bodies.frame = Some(frame);
        bodies.walls = Some((walls[0], walls[1]));
    }
    let skin = collider_skin(scene);
    for (ball, (&x, &v)) in scene.balls.iter().zip(scene.initial_positions.iter().zip(&scene.initial_velocities)) {
        let id = commands
            .spawn((
                RigidBody::Dynamic,
                Transform::from_xyz(x as f32, 0.0, 0.0),
                Velocity::linear(Vec3::new(v as f32, 0.0, 0.0)),
                Collider::ball((ball.radius - skin) as f32),
                ColliderMassProperties::Mass(ball.mass as f32),
                Friction { coefficient: 0.0, combine_rule: CoefficientCombineRule::Min },
                LockedAxes::ROTATION_LOCKED | LockedAxes::TRANSLATION_LOCKED_Y | LockedAxes::TRANSLATION_LOCKED_Z,
                Sleeping::disabled(),
                PLASTIC,
            ))
            .id();
        if settings.ccd {
            commands.entity(id).insert(Ccd::enabled());
        }
        bodies.balls.push(id);
    }
    commands.insert_resource(bodies);
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

fn init_frame(mut commands: Commands, scene: Res<DamperScene>) {
    if let Some(f) = scene.0.frame {
        let x0 = (scene.0.initial_displacement, 0.0);
        commands.insert_resource(FrameState {
            bare: Driven::new(Oscillator::new(f.mass, f.damping, f.stiffness), scene.0.harmonic_load()),
            motion: Driven::new(Oscillator::new(f.mass, f.damping, f.stiffness), scene.0.harmonic_load()),
            held: [0, 0],
            t_start: 0.0,
            start: x0,
            before_impulses: x0,
            now: x0,
            damping_loss: 0.0,
            forcing_work: 0.0,
        });
    }
}

/// Moves the frame to where the closed form puts it at the end of the coming step; Rapier
/// gives it the step's mean velocity for its contacts. (Before the first step Rapier has not
/// created the body yet: that step is `MIN_STEP` long, see `stepping::plan_step`.)
pub fn drive_frame(
    plan: Res<StepPlan>,
    clock: Res<StepClock>,
    scene: Res<DamperScene>,
    frame: Option<ResMut<FrameState>>,
    bodies: Option<Res<Bodies>>,
    mut sets: Query<&mut RapierRigidBodySet>,
) {
    let (Some(mut frame), Some(bodies)) = (frame, bodies) else { return };
    let (x, v) = frame.now;
    let (t0, t1) = (clock.t, clock.t + plan.h);
    frame.start = (x, v);
    frame.t_start = t0;
    // Balls held against a wall ride the frame: their mass joins its oscillator for the step.
    let held_mass: f64 = held_balls(frame.held, scene.0.balls.len()).map(|i| scene.0.balls[i].mass).sum();
    // Made again only when what the frame carries changes.
    if frame.motion.osc.mass != frame.bare.osc.mass + held_mass {
        frame.motion = match scene.0.frame {
            Some(f) if held_mass > 0.0 => Driven::new(Oscillator::new(f.mass + held_mass, f.damping, f.stiffness), scene.0.harmonic_load()),
            _ => frame.bare,
        };
    }
    let motion = frame.motion;
    frame.before_impulses = motion.state(x, v, t0, t1);
    if motion.xp.is_none() {
        frame.damping_loss += motion.osc.dissipated(x, v, plan.h);
    } else {
        // A step is a small fraction of both periods: one Gauss-Legendre piece is exact.
        let scene = &scene.0;
        let [damping, work] = gauss_legendre(t0, t1, plan.h, |t| {
            let (xs, vs) = motion.state(x, v, t0, t);
            [scene.damping_power(t, vs), scene.forcing_power(t, xs, vs)]
        });
        frame.damping_loss += damping;
        frame.forcing_work += work;
    }
    let (Some(entity), Ok(mut set)) = (bodies.frame, sets.single_mut()) else { return };
    if let Some(&h) = set.entity2body().get(&entity) {
        set.bodies[h].set_next_kinematic_translation(Vec3::new(frame.before_impulses.0 as f32, 0.0, 0.0));
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

fn init_recording(mut commands: Commands, scene: Res<DamperScene>, settings: Res<StepSettings>, record: Record) {
    commands.insert_resource(StepClock::default());
    commands.insert_resource(Recording::new(&scene.0, record, settings.dt));
}
