//! Before each Rapier step: the impacts of touching pairs that approach, resolved by the
//! plug-in ([`crate::rapier::contacts`]), the balls a wall holds merged with the frame, and the
//! new velocities written into Rapier's bodies.
//!
//! Pairs that carried a contact impulse in the last step and approach slower than the frame's
//! acceleration can explain over a step are persistent contacts (a ball riding the wall, a
//! squeezed pack): Rapier holds them plastically, which is the reference's persistent-contact
//! rule (docs/MODEL.md §4) at the scale of a step.

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier3d::rapier::dynamics::RigidBodyHandle;

use crate::rapier::contacts::{approach_floor, book, resolve_touching, sticking_speed, write_velocities, Instant, Ledger, PairImpact};
use crate::rapier::resources::{held_balls, Bodies, DamperScene, FrameState, Recording, StepClock, StepPlan};

/// The system: resolves the impacts of the touching pairs at the start of the step, writes
/// the new velocities into Rapier's bodies and the balls' `Velocity`, the frame's into its
/// state, and books the impacts.
#[allow(clippy::too_many_arguments)]
pub fn resolve_impacts(
    clock: Res<StepClock>,
    plan: Res<StepPlan>,
    scene: Res<DamperScene>,
    mut frame: Option<ResMut<FrameState>>,
    bodies: Option<Res<Bodies>>,
    mut rec: ResMut<Recording>,
    mut sets: Query<&mut RapierRigidBodySet>,
    mut velocities: Query<&mut Velocity>,
    mut resolved: Local<Vec<PairImpact>>,
    mut handles: Local<Vec<RigidBodyHandle>>,
) {
    let Some(bodies) = bodies else { return };
    let scene = &scene.0;
    let n = scene.balls.len();
    let floor = approach_floor(scene);
    // What the frame's acceleration now builds over the last step: a slower approach of a
    // loaded pair is the wall or the chain pressing on, not a new impact.
    let acceleration = frame.as_deref_mut().zip(scene.frame).map_or(0.0, |(f, sf)| f.smooth_force(scene, clock.t) / sf.mass);
    let stick = sticking_speed(scene, acceleration, plan.h);
    let Recording { x, v, last_impulse, impulse_floor, impacts, last_impact, struck_at, impact_loss, .. } = &mut *rec;
    // Pairs within a run the walls hold ride the frame: persistent too.
    let [left, right] = frame.as_deref().map_or([0, 0], |f| f.held);
    let in_held = |p: usize| p < left.min(n) || p > n - right.min(n);
    let threshold = |p: usize| if last_impulse[p] > *impulse_floor || in_held(p) { stick } else { floor };
    let walls = frame.as_deref_mut().zip(scene.frame).zip(scene.container);
    let mut now = Instant { x, v, frame: walls.map(|((f, sf), c)| (f.now.0, &mut f.now.1, sf.mass, c.length)) };
    resolve_touching(scene, &mut now, threshold, &mut resolved);
    // A struck held run is free again: the feedback decides afresh what the walls hold.
    let touches_held = |p: usize| in_held(p) || (left > 0 && p == left) || (right > 0 && p == n - right);
    if resolved.iter().any(|hit| touches_held(hit.pair)) {
        if let Some(f) = frame.as_deref_mut() {
            f.held = [0, 0];
        }
    }
    // A held run rides the frame: it takes the frame's velocity now, momentum kept (the balls
    // were within the sticking speed of it), the kinetic energy given up booked.
    let mut merged = false;
    if let (Some(f), Some(sf)) = (frame.as_deref_mut(), scene.frame) {
        let carried = held_balls(f.held, n);
        let (mass, momentum) =
            carried.clone().fold((sf.mass, sf.mass * f.now.1), |(m, p), i| (m + scene.balls[i].mass, p + scene.balls[i].mass * v[i]));
        if mass > sf.mass {
            let common = momentum / mass;
            let ke = |m: f64, u: f64| 0.5 * m * u * u;
            let mut lost = ke(sf.mass, f.now.1) - ke(sf.mass, common);
            for i in carried {
                lost += ke(scene.balls[i].mass, v[i]) - ke(scene.balls[i].mass, common);
                v[i] = common;
            }
            f.now.1 = common;
            *impact_loss += lost;
            let wall_pair = if f.held[0] > 0 { 0 } else { n };
            if let Some(k) = last_impact[wall_pair] {
                impacts[k].energy_lost += lost;
            }
            merged = true;
        }
    }
    if resolved.is_empty() && !merged {
        return;
    }
    for hit in resolved.iter() {
        *impact_loss += hit.energy_lost;
        // The steps end just short of contact: the impact is when the gap closes, within the
        // last step's length (a slow approach closes a gap of a micrometre late).
        let t = clock.t + (hit.gap.max(0.0) / hit.approach_speed).min(plan.h);
        book(Ledger { impacts, last_impact, struck_at }, n, hit, t, clock.steps);
    }
    // Before the first step bevy_rapier has not made the bodies yet: it will from `Velocity`.
    if let Ok(mut set) = sets.single_mut() {
        if handles.len() != n {
            handles.clear();
            handles.extend(bodies.balls.iter().map_while(|e| set.entity2body().get(e).copied()));
        }
        if handles.len() == n {
            write_velocities(&mut set, &handles, &bodies.balls, &mut velocities, v);
            return;
        }
    }
    for (ball, &vi) in bodies.balls.iter().zip(v.iter()) {
        if let Ok(mut velocity) = velocities.get_mut(*ball) {
            velocity.linear.x = vi as f32;
        }
    }
}
