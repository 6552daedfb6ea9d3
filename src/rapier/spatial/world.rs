//! The scene as Rapier worlds, one per damper: a kinematic body carrying the container's six
//! walls (and the dividers between chains), and a dynamic sphere per ball of that damper, free
//! in 3D, under the scene's gravity and friction. Every contact Rapier solves is plastic: the
//! stepper gives the bounces. Dampers never touch each other, so each is solved alone, and
//! nothing one damper does (how far ahead its contacts are predicted, the order of its
//! constraints) reaches another's solve.

use bevy_rapier3d::rapier::prelude::*;

use crate::scene::{Chamber, Scene, Wall};

/// The Rapier worlds of a scene and the handles the stepper reads.
pub struct SpatialWorld {
    /// Each damper's world, in the scene's order.
    pub dampers: Vec<DamperWorld>,
    /// Each ball's body and collider in its damper's world, in the scene's order.
    pub balls: Vec<BallHandles>,
}

/// One damper's Rapier world.
pub struct DamperWorld {
    /// Rapier's state.
    pub physics: PhysicsWorld,
    /// The kinematic body that carries the container (the frame's, or its floor's).
    pub frame: RigidBodyHandle,
    /// The container's walls and their colliders.
    pub walls: Vec<(Wall, ColliderHandle)>,
}

/// Where a ball lives.
#[derive(Debug, Clone, Copy)]
pub struct BallHandles {
    /// Its damper, the index of its world.
    pub damper: usize,
    /// Its dynamic body there.
    pub body: RigidBodyHandle,
    /// Its sphere there.
    pub collider: ColliderHandle,
}

impl SpatialWorld {
    /// The body of ball `i`.
    pub fn ball(&self, i: usize) -> &RigidBody {
        let h = self.balls[i];
        &self.dampers[h.damper].physics.bodies[h.body]
    }
    /// The body of ball `i`, to change.
    pub fn ball_mut(&mut self, i: usize) -> &mut RigidBody {
        let h = self.balls[i];
        &mut self.dampers[h.damper].physics.bodies[h.body]
    }
    /// The sphere of ball `i`, to change.
    pub fn collider_mut(&mut self, i: usize) -> &mut Collider {
        let h = self.balls[i];
        &mut self.dampers[h.damper].physics.colliders[h.collider]
    }
}

/// How stiff Rapier's contacts are and how it steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// Step, s.
    pub dt: f64,
    /// Rapier's length unit, m (the largest ball's diameter).
    pub length_unit: f64,
    /// Solver iterations per step.
    pub solver_iterations: usize,
    /// Natural frequency of Rapier's contact springs, Hz.
    pub contact_frequency: f64,
    /// Their damping ratio.
    pub contact_damping: f64,
}

/// The walls are this many largest radii thick: no ball crosses one in a step.
const WALL_THICKNESS_RADII: f64 = 4.0;

/// Builds the worlds of `scene` (validated for the spatial path by `super::refusal`), each
/// damper's container from `chambers`.
pub fn build(scene: &Scene, chambers: &[Chamber], solver: SolverSettings) -> SpatialWorld {
    let [gx, gy, gz] = scene.space.gravity;
    let lu = solver.length_unit as f32;
    let parameters = IntegrationParameters {
        dt: solver.dt as f32,
        length_unit: lu,
        num_solver_iterations: solver.solver_iterations,
        contact_softness: SpringCoefficients::new(solver.contact_frequency as f32, solver.contact_damping as f32),
        // The walls are kinematic, not fixed: the same stiffness applies to them.
        static_contact_softness: SpringCoefficients::new(solver.contact_frequency as f32, solver.contact_damping as f32),
        // The default clamps every body at 400 length units per second.
        normalized_max_linear_velocity: f32::MAX,
        // The stepper sets how far ahead contacts are found before each step, from how fast
        // its balls move.
        normalized_prediction_distance: super::LEAST_PREDICTION,
        // Coulomb's law at each contact point: a sphere touches at one point, so Rapier's
        // default (one friction constraint per manifold plus a "twist" constraint that stops
        // spin about the normal) would add a torque Coulomb friction has not.
        friction_model: FrictionModel::Coulomb,
        ..IntegrationParameters::default()
    };
    let plastic = |b: ColliderBuilder| {
        b.friction(scene.space.friction as f32)
            .friction_combine_rule(CoefficientCombineRule::Max)
            .restitution(0.0)
            .restitution_combine_rule(CoefficientCombineRule::Min)
    };
    let mut dampers: Vec<DamperWorld> = scene
        .damper_list()
        .iter()
        .zip(chambers)
        .map(|(damper, geometry)| {
            let mut physics = PhysicsWorld::new();
            physics.gravity = Vector::new(gx as f32, gy as f32, gz as f32);
            physics.integration_parameters = parameters;
            let start = scene.damper_start(damper);
            let frame = physics.insert_body(
                RigidBodyBuilder::kinematic_position_based().translation(Vector::new(start as f32, 0.0, 0.0)).can_sleep(false),
            );
            let thick = WALL_THICKNESS_RADII * geometry.largest_radius;
            let walls = geometry
                .walls()
                .map(|wall| {
                    let (centre, half) = wall_box(geometry, wall, thick);
                    let collider = plastic(ColliderBuilder::cuboid(half[0] as f32, half[1] as f32, half[2] as f32))
                        .translation(Vector::new(centre[0] as f32, centre[1] as f32, centre[2] as f32));
                    (wall, physics.insert_collider(collider, Some(frame)))
                })
                .collect();
            DamperWorld { physics, frame, walls }
        })
        .collect();
    let mut balls = Vec::with_capacity(scene.balls.len());
    for (i, ball) in scene.balls.iter().enumerate() {
        let [y, z] = scene.space.lateral_of(i);
        let [vy, vz] = scene.space.lateral_velocity_of(i);
        let body = RigidBodyBuilder::dynamic()
            .translation(Vector::new(scene.initial_positions[i] as f32, y as f32, z as f32))
            .linvel(Vector::new(scene.initial_velocities[i] as f32, vy as f32, vz as f32))
            .can_sleep(false);
        let collider = plastic(ColliderBuilder::ball(ball.radius as f32)).mass(ball.mass as f32);
        let damper = scene.damper_of(i);
        let (body, collider) = dampers[damper].physics.insert(body, collider);
        balls.push(BallHandles { damper, body, collider });
    }
    SpatialWorld { dampers, balls }
}

/// The box of a wall in the frame's coordinates (origin at the left wall's inner face on the
/// axis): its centre and half-extents. The six walls overlap at the edges so that no corner
/// is open; dividers span the container's inside.
fn wall_box(g: &Chamber, wall: Wall, t: f64) -> ([f64; 3], [f64; 3]) {
    let [l, w, h] = [g.length, g.width, g.height];
    let (hl, hw, hh) = (0.5 * l + 2.0 * t, 0.5 * w + 2.0 * t, 0.5 * h + 2.0 * t);
    match wall {
        Wall::Left => ([-t, 0.0, 0.0], [t, hw, hh]),
        Wall::Right => ([l + t, 0.0, 0.0], [t, hw, hh]),
        Wall::Front => ([0.5 * l, -0.5 * w - t, 0.0], [hl, t, hh]),
        Wall::Back => ([0.5 * l, 0.5 * w + t, 0.0], [hl, t, hh]),
        Wall::Floor => ([0.5 * l, 0.0, -0.5 * h - t], [hl, hw, t]),
        Wall::Ceiling => ([0.5 * l, 0.0, 0.5 * h + t], [hl, hw, t]),
        Wall::Divider(k) => ([0.5 * l, g.divider_y(k), 0.0], [0.5 * l, g.divider_half_thickness, 0.5 * h]),
    }
}
