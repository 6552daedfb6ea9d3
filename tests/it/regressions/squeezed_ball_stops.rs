//! Issue 6: a light ball squeezed between a heavy one and a wall (mass ratio 660) was pushed
//! through the wall by Rapier's iterative solver, and the run came back looking valid. The
//! contact model now checks every step and stops with the reason instead. Since issue 14 the
//! plug-in resolves the squeeze's impacts itself and runs the scene (at any mass ratio); a
//! frame at 38 m/s striking a light ball still beats Rapier's solver (`FAST_FRAME`, stress
//! seed 91211), and the check still stops that run.

use crate::common;
use lpc_damper::model::ModelError;
use lpc_damper::model::RunOptions;
use lpc_damper::Model;

const SCENE: &str = r#"
name = "stress-174"
[frame]
mass = 1.35
stiffness = 3366.652256466029
damping = 0.0
initial_displacement = "-0.4986277621334814 Rr"

[balls]
arrangement = "LS"
large_mass = 0.11
mass_ratio = 661.7318540906778
density = 8000.0
restitution = 0.9
gap = "0.25 Rr"
clearance = "0 Rr"

[run]
horizon = 0.061902355482029985
sample_dt = 0.0001
"#;

/// A plastic damper on a frame of period 6.7 ms started 41 mm out (38 m/s through the
/// centre): the light ball is struck by the wall and pushed 1.2 mm into it.
const FAST_FRAME: &str = r#"
name = "stress-91211"
[frame]
mass = 1.35
stiffness = 1200747.0785199883
damping = 519.040508207179
initial_displacement = "2.740814523268277 Rr"
[balls]
arrangement = "SL"
large_mass = 0.11
mass_ratio = 348.46511909829263
density = 8000.0
restitution = 0.0
gap = "0.9846668383276259 Rr"
clearance = "2.2118896683748 Rr"
[run]
horizon = 0.11067409544051521
sample_dt = 0.0001
"#;

#[test]
fn the_contact_model_runs_the_squeeze_and_passes_every_check() {
    for ratio in ["661.7318540906778", "1e9"] {
        let s = common::scene_from_toml(&SCENE.replace("661.7318540906778", ratio));
        let run = Model::Rapier.simulate(&s, &RunOptions::default()).unwrap();
        lpc_damper::studies::stress::judge(Model::Rapier, &s, &run).unwrap();
    }
}

#[test]
fn the_contact_model_stops_with_the_reason_instead_of_a_wrong_run() {
    let s = common::scene_from_toml(FAST_FRAME);
    match Model::Rapier.simulate(&s, &RunOptions::default()) {
        Err(e @ ModelError::Unstable { .. }) => {
            let reason = e.to_string();
            assert!(reason.contains("stress-91211") && reason.contains("left wall"), "{reason}");
            assert!(reason.contains("mass ratio 348"), "{reason}");
        }
        other => panic!("expected the run to stop as unstable, got {:?}", other.map(|r| r.impacts.len())),
    }
    let reference = Model::Reference.simulate(&s, &RunOptions::default()).unwrap();
    lpc_damper::studies::stress::judge(Model::Reference, &s, &reference).unwrap();
}

#[test]
fn the_stability_map_still_sees_the_raw_behaviour() {
    // With the self-check off the same scene runs to the end (and shows the ball outside).
    let s = common::scene_from_toml(FAST_FRAME);
    let mut settings = lpc_damper::rapier::settings(&s);
    settings.self_check = false;
    let run = lpc_damper::rapier::simulate_with(&s, settings, &RunOptions::default()).unwrap();
    let failure = lpc_damper::studies::stress::judge(Model::Rapier, &s, &run).unwrap_err();
    assert_eq!(failure.check, "outside");
}
