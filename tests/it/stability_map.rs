//! The stability map's corner cells: Rapier's own contact prediction lets a fast ball tunnel
//! into a wall, the plug-in's speculative margin does not, and aligned stepping stays accurate
//! at a step far longer than the free space a ball crosses in it.

use lpc_damper::studies::stability::{cell, Case, CONFIGS};

fn config(name: &str) -> lpc_damper::studies::stability::Config {
    *CONFIGS.iter().find(|c| c.name == name).expect("config")
}

#[test]
fn rapier_default_prediction_tunnels_at_speed() {
    // 10 m/s for 1 ms: 10 mm per step, 50 times Rapier's 0.2 mm prediction distance.
    let c = cell(Case::BallWall, config("rapier-defaults"), 1e-3, 10.0);
    assert_eq!(c.outcome, "outside", "{c:?}");
}

#[test]
fn plug_in_margin_never_tunnels() {
    for (dt, speed) in [(1e-3, 10.0), (1e-2, 100.0), (1e-4, 100.0)] {
        let c = cell(Case::BallWall, config("plug-in-fixed"), dt, speed);
        assert!(c.outcome == "ok" || c.outcome == "inaccurate", "{c:?}");
    }
}

#[test]
fn aligned_stepping_is_accurate_across_the_map_corner() {
    // 100 m/s with a 10 ms longest step: a ball crosses its free space 70 times per step;
    // aligned steps still end at every contact, so the final energy matches the reference.
    for case in Case::ALL {
        let c = cell(case, config("plug-in-aligned"), 1e-2, 100.0);
        assert_eq!(c.outcome, "ok", "{c:?}");
        assert!(c.energy_error.abs() < 1e-3, "{c:?}");
    }
}
