//! Issue 30 (beds in the contact model), found by `lpc stress --beds --models rapier` (seed
//! 1183): a row of 15 balls that a wall accelerating at thousands of g presses sank the ball at
//! the wall 0.12 mm into it, 5.5 % of its radius, and the run went on with the ball outside the
//! container. No step or iteration count tried bounds that sink (docs/BENCHMARKS.md, "Stress
//! beyond one line"), so the spatial path now stops such a run with the reason: the ball, the
//! wall, the sink and the load.

use crate::common::scene_from_toml;
use lpc_damper::model::{ModelError, RunOptions};
use lpc_damper::rapier::spatial::wall_sink_limit;
use lpc_damper::Model;

#[test]
fn a_row_pressed_into_a_wall_deeper_than_rapier_holds_stops_the_run() {
    let scene = scene_from_toml(
        r#"
name = "stress-1183"
[frame]
mass = 1.35
stiffness = 12748316.43108801
damping = 1156.917643743632
initial_displacement = 0.0028445676778359316
[run]
horizon = 0.007961928017429423
sample_dt = 0.00001
[container]
length = 0.07034651327183818
width = 0.041477690802265696
height = 0.041477690802265696
[world]
gravity = [0.0, 0.0, -9.81]
friction = 0.21831470982459156
restitution = 0.31792019949380723
[bed]
count = 18
radii = [0.0022815011442390374]
density = 7800.0
placement = "lattice"
seed = 1183
"#,
    );
    match Model::Rapier.simulate(&scene, &RunOptions::default()) {
        Err(ModelError::Unstable { t, reason, .. }) => {
            assert!(t < scene.horizon, "{reason}");
            assert!(reason.contains("into the right wall"), "{reason}");
            // The sink stated is beyond the limit, which is 5 % of the radius and a micrometre.
            let sunk: f64 =
                reason.split(" has sunk ").nth(1).and_then(|r| r.split(' ').next()).and_then(|s| s.parse().ok()).expect(&reason);
            assert!(sunk > wall_sink_limit(&scene), "{reason}");
            assert!((wall_sink_limit(&scene) - (0.05 * 0.0022815011442390374 + 1e-6)).abs() < 1e-15);
        }
        other => panic!("the run should stop with the ball sunk into the wall: {:?}", other.map(|r| r.horizon)),
    }
}
