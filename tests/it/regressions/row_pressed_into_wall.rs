//! Issue 30 (beds in the contact model), found by `lpc stress --beds --models rapier` (seed
//! 1183): a row of 15 balls that a wall accelerating at thousands of g presses sank the ball at
//! the wall 0.12 mm into it, 5.5 % of its radius, and the run went on with the ball outside the
//! container. No step or iteration count tried bounds that sink (docs/BENCHMARKS.md, "Stress
//! beyond one line"), so the spatial path now stops such a run with the reason: the ball, the
//! wall, the sink and the load. (Since Rapier's contacts are as stiff as its substeps allow,
//! that row is held; the bed of seed 1102, which walls at 2300 g press into a side wall, is the
//! scene here.)

use crate::common::scene_from_toml;
use lpc_damper::model::{ModelError, RunOptions};
use lpc_damper::rapier::spatial::wall_sink_limit;
use lpc_damper::Model;

#[test]
fn a_ball_pressed_into_a_wall_deeper_than_rapier_holds_stops_the_run() {
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
    match Model::Rapier.simulate(&scene, &RunOptions::default()) {
        Err(ModelError::Unstable { t, reason, .. }) => {
            assert!(t < scene.horizon, "{reason}");
            assert!(reason.contains("into the front wall"), "{reason}");
            // The sink stated is beyond the limit, which is 5 % of the radius and a micrometre.
            let sunk: f64 =
                reason.split(" has sunk ").nth(1).and_then(|r| r.split(' ').next()).and_then(|s| s.parse().ok()).expect(&reason);
            assert!(sunk > wall_sink_limit(&scene), "{reason}");
            assert!((wall_sink_limit(&scene) - (0.05 * 0.0053537346490156335 + 1e-6)).abs() < 1e-15);
        }
        other => panic!("the run should stop with the ball sunk into the wall: {:?}", other.map(|r| r.horizon)),
    }
}
