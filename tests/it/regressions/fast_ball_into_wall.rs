//! Issue 30 (beds in the contact model), found by `lpc stress --beds --models rapier` (seed
//! 1089): a small ball that larger balls had struck (e = 1) flew at four times the scene's speed
//! scale and sank 0.19 mm, 11 % of its radius, into a wall. Rapier stops a pair at contact only
//! when it predicts the contact, and it predicted contacts only as far as the scene's speed
//! scale carries a body in a step. The prediction now also covers what the fastest ball can
//! close in the step.

use crate::common::scene_from_toml;
use lpc_damper::model::RunOptions;
use lpc_damper::rapier::spatial::{simulate_spatial_with, solver_settings, wall_sink_limit};
use lpc_damper::studies::stress::judge;
use lpc_damper::Model;

#[test]
fn a_ball_faster_than_the_frame_stops_at_the_wall() {
    let scene = scene_from_toml(
        r#"
[frame]
mass = 1.35
stiffness = 833.7144457365974
damping = 13.85424920385595
initial_displacement = -0.008337617698384453
[container]
length = 0.05185144304934277
width = 0.03767188747734873
height = 0.03767188747734873
[world]
gravity = [0.0, 0.0, -9.81]
friction = 0.09817469949420976
restitution = 1.0
[bed]
count = 43
radii = [0.003729889849242449, 0.00167989900501353]
density = 7800.0
placement = "lattice"
[run]
horizon = 0.43220398255554093
sample_dt = 0.00021610199127777046
"#,
    );
    let (run, report) = simulate_spatial_with(&scene, solver_settings(&scene), &RunOptions::default()).unwrap();
    // No ball sinks into a wall by more than Rapier's resting sink, 5 % of the largest radius
    // (0.19 mm, about 11 % of the small balls', before the fix), even before a sunk ball would
    // be put back; and the checks hold.
    assert!(report.deepest_wall_sink <= wall_sink_limit(&scene), "{report:?}");
    judge(Model::Rapier, &scene, &run).unwrap();
}
