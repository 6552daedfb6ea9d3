//! Choosing each physics step. `Fixed` takes steps of `dt`. `Aligned` ends a step at the
//! next contact, found with parry's time-of-impact queries, and otherwise takes steps of up to
//! `dt`. Between impacts balls fly freely and the frame moves in closed form, so long steps
//! lose nothing there, while each contact lands at a step boundary, where the plug-in resolves
//! it with the two-body law before Rapier's next step (`super::impacts`). With `Fixed` steps a
//! contact closes inside a step; Rapier holds it plastically and the plug-in adds the bounce
//! afterwards (`super::feedback`), the impact up to a step late.

use bevy::prelude::*;
use bevy_rapier3d::parry::math::Pose;
use bevy_rapier3d::parry::query::{cast_shapes, ShapeCastOptions};
use bevy_rapier3d::parry::shape::{Ball, HalfSpace};
use bevy_rapier3d::prelude::*;

use crate::rapier::resources::{DamperScene, FrameState, Recording, StepClock, StepPlan, StepSettings};
use crate::scene::Stepping;

/// Shortest step, s.
pub const MIN_STEP: f64 = 1e-6;
/// A wall contact is approached with a final step no longer than this, so that the wall's
/// mean velocity over that step (what Rapier's contact sees) is its velocity at the impact.
pub const APPROACH_STEP: f64 = 2e-5;
/// Steps before a contact leave at least `APPROACH_RATIO - 1` times their own length to go.
///
/// Rapier's speculative contact allows a closing speed of `gap / dt` for the whole step but
/// re-checks it at every solver substep, so a step that starts closer than about `2 u dt` to
/// a contact (`u` the approach speed) clamps the approach in a late substep, loads the contact
/// and bounces it before it touches. Approaching geometrically keeps every step clear of that
/// until the one that ends at the contact.
pub const APPROACH_RATIO: f64 = 2.2;
/// Pairs closer than this are touching, m: a step ends when a pair approaching comes within
/// half of it, and the plug-in resolves the impact before the next step (`super::impacts`).
pub const TOUCHING: f32 = 1e-6;

/// Sets the next step's length (and Rapier's fixed timestep to it).
#[allow(clippy::too_many_arguments)]
pub fn plan_step(
    settings: Res<StepSettings>,
    clock: Res<StepClock>,
    scene: Res<DamperScene>,
    frame: Option<Res<FrameState>>,
    rec: Option<Res<Recording>>,
    mut plan: ResMut<StepPlan>,
    mut timestep: ResMut<TimestepMode>,
) {
    let remaining = plan.horizon - clock.t;
    let mut h = settings.dt;
    if settings.stepping == Stepping::Aligned {
        if let Some(rec) = rec {
            h = aligned_step(&scene.0, &rec.x, &rec.v, frame.as_deref(), settings.dt);
        }
    }
    // bevy_rapier creates the bodies during the first update, after the frame is driven: the
    // walls stay where they start for that step. Keep it too short for the frame to move
    // (a ball that fits its container exactly would be struck by the walls' jump a step later).
    if clock.steps == 0 {
        h = MIN_STEP;
    }
    // Land exactly on the horizon rather than leave a sliver of a step.
    if remaining <= h * (1.0 + 1e-9) {
        h = remaining.max(MIN_STEP);
    }
    plan.h = h;
    *timestep = TimestepMode::Fixed { dt: h as f32, substeps: 1 };
}

/// The next step's length from the balls' positions `x` and velocities `v` (as Rapier holds
/// them, at the start of the step) and the frame's state.
fn aligned_step(scene: &crate::scene::Scene, x: &[f64], v: &[f64], frame: Option<&FrameState>, longest: f64) -> f64 {
    let n = x.len();
    let state = |i: usize| (Vec3::new(x[i] as f32, 0.0, 0.0), Vec3::new(v[i] as f32, 0.0, 0.0));
    // Look far enough ahead to start the geometric approach in time.
    // The time at which a pair comes within half the touching distance, so that the step
    // ends before Rapier's contact solve can touch the impact.
    let options = ShapeCastOptions {
        max_time_of_impact: (2.0 * APPROACH_RATIO * longest) as f32,
        target_distance: 0.5 * TOUCHING,
        ..Default::default()
    };
    let mut ball_toi = f64::INFINITY;
    for i in 1..n {
        let ((p1, v1), (p2, v2)) = (state(i - 1), state(i));
        let (r1, r2) = (scene.balls[i - 1].radius as f32, scene.balls[i].radius as f32);
        if (p2.x - p1.x) - (r1 + r2) <= TOUCHING {
            continue;
        }
        let hit = cast_shapes(&Pose::from_translation(p1), v1, &Ball::new(r1), &Pose::from_translation(p2), v2, &Ball::new(r2), options);
        if let Ok(Some(hit)) = hit {
            ball_toi = ball_toi.min(hit.time_of_impact as f64);
        }
    }
    let mut wall_toi = f64::INFINITY;
    if let (Some(frame), Some(c)) = (frame, scene.container) {
        let (xs, vs) = frame.now;
        let vw = Vec3::new(vs as f32, 0.0, 0.0);
        // Walls as half-spaces moving with the frame's current velocity (its change over the
        // step is why the last approach is a short step).
        let walls = [(0, xs as f32, Vec3::X), (n.saturating_sub(1), (xs + c.length) as f32, -Vec3::X)];
        for (i, surface, normal) in walls.into_iter().filter(|_| n > 0) {
            let (p, v) = state(i);
            let r = scene.balls[i].radius as f32;
            if (p.x - surface) * normal.x - r <= TOUCHING {
                continue;
            }
            let hit = cast_shapes(
                &Pose::from_translation(Vec3::new(surface, 0.0, 0.0)),
                vw,
                &HalfSpace::new(normal),
                &Pose::from_translation(p),
                v,
                &Ball::new(r),
                options,
            );
            if let Ok(Some(hit)) = hit {
                wall_toi = wall_toi.min(hit.time_of_impact as f64);
            }
        }
    }
    let (toi, limit) = if wall_toi < ball_toi { (wall_toi, APPROACH_STEP.min(longest)) } else { (ball_toi, longest) };
    let h = if toi <= limit { toi } else { (toi / APPROACH_RATIO).min(longest) };
    // On a frame stiffer than about 1e10 N/m per kg^(1/2) the longest stable step (a 40th of
    // the period) is itself shorter than MIN_STEP: the period's bound wins.
    h.max(MIN_STEP).min(longest)
}
