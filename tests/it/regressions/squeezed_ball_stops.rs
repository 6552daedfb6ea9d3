//! Issue 6: a light ball squeezed between a heavy one and a wall (mass ratio 660) was pushed
//! through the wall by Rapier's iterative solver, and the run came back looking valid. The
//! contact model now checks every step and stops with the reason instead. Since issue 14 the
//! plug-in resolves the squeeze's impacts itself and runs the scene (at any mass ratio); since
//! issue 29 it also puts back a ball Rapier's solver pushed into a wall at any depth, so a
//! frame at 38 m/s striking a light ball (`FAST_FRAME`, stress seed 91211), which used to stop,
//! runs to its end and passes every check. A packed chain whose simultaneous contact solve
//! gains energy (`GAINING_CHAIN`, stress seed 96013) still stops with the reason.

use crate::common;
use lpc_damper::model::ModelError;
use lpc_damper::model::RunOptions;
use lpc_damper::Model;

/// A light ball squeezed between a heavy one and the wall (mass ratio 660, e = 0.9).
pub const SCENE: &str = r#"
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

/// Ten balls packed with no gaps into a container 1 mm longer than they are, two of them 665
/// times lighter than the rest: Rapier's simultaneous solve of the pressed chain gains energy.
pub const GAINING_CHAIN: &str = r#"
name = "stress-96013"
[frame]
mass = 1.35
stiffness = 219574.05227100817
damping = 9.834679833061172
initial_displacement = "-0.8074134139912366 Rr"
[balls]
arrangement = "SLSLLLLLLL"
large_mass = 0.11
mass_ratio = 665.4747166986969
density = 8000.0
restitution = 0.2702545013409512
gap = "0 Rr"
clearance = "0.06548396558159056 Rr"
[run]
horizon = 0.11195641528421493
sample_dt = 0.0001
"#;

#[test]
fn the_contact_model_puts_back_a_ball_pushed_through_and_runs_to_the_end() {
    let s = common::scene_from_toml(FAST_FRAME);
    let run = Model::Rapier.simulate(&s, &RunOptions::default()).unwrap();
    assert!((run.horizon - s.horizon).abs() <= 1e-12 * s.horizon);
    lpc_damper::studies::stress::judge(Model::Rapier, &s, &run).unwrap();
    let reference = Model::Reference.simulate(&s, &RunOptions::default()).unwrap();
    lpc_damper::studies::stress::judge(Model::Reference, &s, &reference).unwrap();
}

#[test]
fn the_contact_model_stops_with_the_reason_instead_of_a_wrong_run() {
    let s = common::scene_from_toml(GAINING_CHAIN);
    match Model::Rapier.simulate(&s, &RunOptions::default()) {
        Err(e @ ModelError::Unstable { .. }) => {
            let reason = e.to_string();
            assert!(reason.contains("stress-96013") && reason.contains("gained"), "{reason}");
            assert!(reason.contains("simultaneous contact solve"), "{reason}");
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
    settings.safeguards = false;
    let run = lpc_damper::rapier::simulate_with(&s, settings, &RunOptions::default()).unwrap();
    let failure = lpc_damper::studies::stress::judge(Model::Rapier, &s, &run).unwrap_err();
    assert_eq!(failure.check, "outside");
}
