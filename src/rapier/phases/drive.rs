//! Before each Rapier step: the kinematic frame moved to where its exact oscillator will be at
//! the step's end, carrying the balls its walls hold, with the damper's loss and the
//! excitation's work over the step booked.

use std::sync::Mutex;

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;

use crate::floor_motion::FloorMotion;
use crate::oscillator::{gauss_legendre, Driven, Oscillator};
use crate::rapier::resources::{held_balls, Bodies, DamperScene, FrameState, StepClock, StepPlan};
use crate::scene::Scene;

/// Inserts the frame's exact state at its initial displacement (on a structure, the carrying
/// floor's initial state, the ground's motion included).
pub fn init_frame(mut commands: Commands, scene: Res<DamperScene>) {
    if let Some(f) = scene.0.frame {
        let (floors, failure) = match scene.0.structure.as_ref().map(|s| FloorMotion::new(s.clone(), scene.0.forcing)) {
            Some(Ok(floors)) => (Some(floors), None),
            Some(Err(why)) => (None, Some(why)),
            None => (None, None),
        };
        let x0 = floors.as_ref().map_or((scene.0.initial_displacement, 0.0), |floors| floors.state(0.0));
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
            floors: floors.map(Mutex::new),
            failure,
            floors_held: 0.0,
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
    let t0 = clock.t;
    frame.start = frame.now;
    frame.t_start = t0;
    // Balls held against a wall ride the frame: their mass joins its oscillator for the step.
    let held_mass: f64 = held_balls(frame.held, scene.0.balls.len()).map(|i| scene.0.balls[i].mass).sum();
    if !frame.advance_floors(t0, plan.h, held_mass) {
        advance_oscillator(&mut frame, &scene.0, held_mass, (t0, plan.h));
    }
    let (Some(entity), Ok(mut set)) = (bodies.frame, sets.single_mut()) else { return };
    if let Some(&h) = set.entity2body().get(&entity) {
        set.bodies[h].set_next_kinematic_translation(Vec3::new(frame.before_impulses.0 as f32, 0.0, 0.0));
    }
}

/// Moves a frame of one storey over the step from `t0` to `t0 + h` with its exact oscillator,
/// carrying `held_mass` kg of balls, and books its damper's loss and the excitation's work.
fn advance_oscillator(frame: &mut FrameState, scene: &Scene, held_mass: f64, (t0, h): (f64, f64)) {
    let (x, v) = frame.now;
    // Made again only when what the frame carries changes.
    if frame.motion.osc.mass != frame.bare.osc.mass + held_mass {
        frame.motion = match scene.frame {
            Some(f) if held_mass > 0.0 => Driven::new(Oscillator::new(f.mass + held_mass, f.damping, f.stiffness), scene.harmonic_load()),
            _ => frame.bare,
        };
    }
    let motion = frame.motion;
    frame.before_impulses = motion.state(x, v, t0, t0 + h);
    if motion.xp.is_none() {
        frame.damping_loss += motion.osc.dissipated(x, v, h);
    } else {
        // A step is a small fraction of both periods: one Gauss-Legendre piece is exact.
        let [damping, work] = gauss_legendre(t0, t0 + h, h, |t| {
            let (xs, vs) = motion.state(x, v, t0, t);
            [scene.damping_power(t, vs), scene.forcing_power(t, xs, vs)]
        });
        frame.damping_loss += damping;
        frame.forcing_work += work;
    }
}
