//! After the feedback: the samples that fall in the step just taken, the frame in closed form
//! and the balls along their straight paths.

use bevy::prelude::*;

use crate::rapier::resources::{DamperScene, FrameState, Recording, StepClock, StepPlan, StepSettings};
use crate::run::Record;

/// Inserts the clock and the recording of a run that keeps what `record` asks for.
pub fn init_recording(mut commands: Commands, scene: Res<DamperScene>, settings: Res<StepSettings>, record: Record) {
    commands.insert_resource(StepClock::default());
    commands.insert_resource(Recording::new(&scene.0, record, settings.dt));
}

/// Writes the samples that fall in the step just taken: the frame exactly (closed form from the
/// step's start; impulses land at its end), the balls along their straight path within the step.
pub fn record_samples(
    clock: Res<StepClock>,
    plan: Res<StepPlan>,
    scene: Res<DamperScene>,
    mut frame: Option<ResMut<FrameState>>,
    mut rec: ResMut<Recording>,
) {
    let scene = &scene.0;
    let dt = plan.h;
    let t1 = clock.t;
    let t0 = t1 - dt;
    let rec: &mut Recording = &mut rec;
    while rec.next_sample < rec.sample_count {
        let k = rec.next_sample;
        let ts = k as f64 * scene.sample_dt;
        // A sample on the step's end (within round-off) belongs to this step, after impulses.
        let at_end = scene.sample_at_step_end(ts, t1, dt);
        if ts > t1 && !at_end {
            break;
        }
        let (x, v, prev_x, prev_v) = (&rec.x, &rec.v, &rec.prev_x, &rec.prev_v);
        let ball = |i: usize| {
            if k == 0 {
                (scene.initial_positions[i], scene.initial_velocities[i])
            } else if at_end {
                (x[i], v[i])
            } else {
                // Impulses land at the step's end: inside it, balls keep their old velocity.
                let w = ((ts - t0) / dt).clamp(0.0, 1.0);
                (prev_x[i] + w * (x[i] - prev_x[i]), prev_v[i])
            }
        };
        match (frame.as_deref_mut(), scene.structure.as_deref()) {
            (Some(fr), Some(s)) if fr.floors.is_some() => {
                // The floors relative to the ground: as they start, as the closed form moves
                // them inside the step, or with the carrying floor's impulses at its end.
                let (z, ground) = if k == 0 {
                    let z = s.initial_displacements.iter().chain(&s.initial_velocities).copied().collect();
                    let (xg, vg, _) = scene.ground_motion(0.0);
                    (z, (xg, vg))
                } else if at_end {
                    fr.floors_now(ts).expect("a structure has floors")
                } else {
                    let from = fr.t_start;
                    fr.floors_mut().expect("a structure has floors").floors(ts.max(from))
                };
                let (u, v) = z.split_at(z.len() / 2);
                rec.recorder.sample_floors(scene, ts, (u, v), ground, ball);
            }
            (fr, _) => {
                let (xs, vs) = match fr {
                    Some(_) if k == 0 => (scene.initial_displacement, 0.0),
                    Some(fr) if at_end => fr.now,
                    Some(fr) => fr.motion.state(fr.start.0, fr.start.1, fr.t_start, ts.max(fr.t_start)),
                    None => (0.0, 0.0),
                };
                rec.recorder.sample(scene, ts, xs, vs, ball);
            }
        }
        rec.next_sample += 1;
    }
}
