//! Issue 6: a light ball squeezed between a heavy one and a wall (mass ratio 660) was pushed
//! through the wall by Rapier's iterative solver, and the run came back looking valid. The
//! contact model now checks every step and stops with the reason instead. Since issue 14 the
//! plug-in resolves the squeeze's impacts itself and runs the scene; Rapier's solver still
//! fails at a mass ratio of 1e9, and the check still stops that run.

use lpc_damper::model::ModelError;
use crate::common;
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

/// The scene with the small ball `ratio` times lighter.
fn squeezed(ratio: f64) -> lpc_damper::scene::Scene {
    common::scene_from_toml(&SCENE.replace("661.7318540906778", &ratio.to_string()))
}

#[test]
fn the_contact_model_runs_the_squeeze_and_passes_every_check() {
    let s = squeezed(661.7318540906778);
    let run = Model::Rapier.simulate(&s).unwrap();
    lpc_damper::studies::stress::judge(Model::Rapier, &s, &run).unwrap();
}

#[test]
fn the_contact_model_stops_with_the_reason_instead_of_a_wrong_run() {
    let s = squeezed(1e9);
    match Model::Rapier.simulate(&s) {
        Err(ModelError::Unstable(reason)) => {
            assert!(reason.contains("stress-174") && reason.contains("right wall"), "{reason}");
            assert!(reason.contains("mass ratio 1000000000"), "{reason}");
        }
        other => panic!("expected the run to stop as unstable, got {:?}", other.map(|r| r.impacts.len())),
    }
    let reference = Model::Reference.simulate(&s).unwrap();
    lpc_damper::studies::stress::judge(Model::Reference, &s, &reference).unwrap();
}

#[test]
fn the_stability_map_still_sees_the_raw_behaviour() {
    // With the self-check off the same scene runs to the end (and shows the ball outside).
    let s = squeezed(1e9);
    let mut settings = lpc_damper::rapier::settings(&s);
    settings.self_check = false;
    let run = lpc_damper::rapier::simulate_with(&s, settings).unwrap();
    let failure = lpc_damper::studies::stress::judge(Model::Rapier, &s, &run).unwrap_err();
    assert_eq!(failure.check, "outside");
}
