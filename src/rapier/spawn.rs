//! The scene as Rapier bodies: a kinematic frame carrying both walls, and a dynamic ball per
//! ball of the scene, every contact plastic (the plug-in gives the bounces).

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;

use super::resources::{Bodies, DamperScene, FrameBody, StepSettings};
use crate::scene::Scene;

/// How much smaller Rapier's balls are than the scene's, m: four f32 steps of the largest
/// coordinate. Balls that touch in the scene then do not overlap in f32, where Rapier would push
/// them apart and make energy from round-off (a packed column at rest would start moving). Impacts
/// are found and resolved on the scene's radii (`super::phases::plan`, `super::contacts`); only
/// Rapier's resting contacts sit this much deeper.
pub fn collider_skin(scene: &Scene) -> f64 {
    let extent = scene.container.map_or(0.0, |c| c.length) + scene.initial_displacement.abs();
    let reach = scene.initial_positions.iter().zip(&scene.balls).map(|(x, b)| x.abs() + b.radius).fold(extent, f64::max);
    4.0 * f32::EPSILON as f64 * reach
}

/// Every contact Rapier solves is plastic: the plug-in gives the bounces (`super::contacts`).
const PLASTIC: Restitution = Restitution { coefficient: 0.0, combine_rule: CoefficientCombineRule::Max };

/// Spawns the frame (a kinematic body carrying both walls) and the balls, and records their
/// entities in [`Bodies`].
pub fn spawn_scene(mut commands: Commands, scene: Res<DamperScene>, settings: Res<StepSettings>) {
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
