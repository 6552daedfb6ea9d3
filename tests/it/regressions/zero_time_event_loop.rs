//! Two stress scenes stalled the reference at one instant: on a stiff frame at rest the
//! acceleration is round-off, the root finder and `resolve` judged its sign differently, and a
//! contact that `resolve` did not see as one kept its cached time (nothing marked the pair
//! for a new search). Both judge the sign alike now, and an event's pair is always searched
//! again.

use lpc_damper::studies::stress::{judge_run, random_scene_file};
use lpc_damper::Model;

#[test]
fn stiff_frames_at_rest_do_not_stall() {
    for seed in [1557, 1977] {
        let file = random_scene_file(seed, 100.0, false);
        let scene = lpc_damper::scene::from_file(file, "stress", "stress").unwrap().scene.unwrap();
        if let Err(f) = judge_run(Model::Reference, &scene, None) {
            panic!("seed {seed}: {} ({})", f.check, f.detail);
        }
    }
}
