//! Issue 30 (beds in the contact model), found by `lpc stress --beds --models rapier` (seed
//! 1183): a row of 15 balls that a wall accelerating at thousands of g presses sank the ball at
//! the wall 0.12 mm into it, 5.5 % of its radius, and the run went on with the ball outside the
//! container. No step or iteration count tried bounds that sink (docs/BENCHMARKS.md, "Stress
//! beyond one line"). The spatial path first stopped such a run with the reason; it now puts a
//! ball sunk past the resting sink back to it, positions only, as the one-line path does, and
//! stops only a ball whose centre has crossed a wall. (Since Rapier's contacts are as stiff as
//! its substeps allow, that row is held; the bed of seed 1102, which walls at 2300 g press into
//! a side wall, is the scene here.)

use crate::common::scene_from_toml;
use lpc_damper::model::RunOptions;
use lpc_damper::rapier::spatial::{simulate_spatial_with, solver_settings, wall_sink_limit};
use lpc_damper::studies::stress::judge;
use lpc_damper::Model;

#[test]
fn a_ball_pressed_into_a_wall_deeper_than_rapier_holds_is_put_back() {
    let scene = scene_from_toml(
        r#"
name = "stress-1102"
[frame]
mass = 1.35
stiffness = 2895778.3225605777
damping = 125.8794684385986
initial_displacement = 0.03221495803693112
[run]
horizon = 0.07433721948630549
sample_dt = 0.0001
[container]
length = 0.07862679407868471
width = 0.04325817596404632
height = 0.04325817596404632
[world]
gravity = [0.0, 0.0, 0.0]
friction = 0.0
restitution = 1.0
[bed]
count = 20
radii = [0.0053537346490156335]
density = 7800.0
placement = "lattice"
seed = 1102
"#,
    );
    let (run, report) = simulate_spatial_with(&scene, solver_settings(&scene), &RunOptions::default()).unwrap();
    // The walls press a ball past the resting sink, and it is put back.
    assert!(report.sinks_put_back > 0 && report.deepest_wall_sink > wall_sink_limit(&scene), "{report:?}");
    assert!((wall_sink_limit(&scene) - (0.05 * 0.0053537346490156335 + 1e-6)).abs() < 1e-15);
    // Among the checks: no ball outside the container by more than that sink, no energy made.
    judge(Model::Rapier, &scene, &run).unwrap();
}
