//! Issue 55: a ball striking a touching pair from a gap on the spatial path left the three balls
//! at (-0.125, 0.25, 0.875) v at a step of 1 ms with e = 1, instead of (0, 0, v): Rapier's
//! plastic solve had passed part of the strike through the pair's touching contact before the
//! impact law was applied. The group now starts its impacts from its free flight over the step.

use crate::common::scene_from_toml;
use lpc_damper::model::RunOptions;
use lpc_damper::rapier::spatial::simulate_spatial;

#[test]
fn a_touching_pair_struck_from_a_gap_passes_the_momentum_on() {
    // Three 10 g balls on the axis without gravity, the striker 16.6 mm from the pair at 1 m/s;
    // friction, which a head-on row never calls on, puts them on the spatial path.
    let mut text = "[frame]\nmass = 1e6\nstiffness = 1e6\ndamping = 0.0\ninitial_displacement = 0.0\n\
                    [container]\nlength = 1.0\nwidth = 0.05\nheight = 0.05\n\
                    [world]\nrestitution = 1.0\nfriction = 0.1\n[rapier]\ndt = 0.001\n\
                    [run]\nhorizon = 0.05\nsample_dt = 0.001\n"
        .to_string();
    let r = 0.00675;
    for (x, v) in [(0.3 - 2.0 * r - 0.0166, 1.0), (0.3, 0.0), (0.3 + 2.0 * r, 0.0)] {
        text += &format!("[[ball]]\nposition = [{x}, 0.0, 0.0]\nmass = 0.01\nradius = {r}\nvelocity = [{v}, 0.0, 0.0]\n");
    }
    let run = simulate_spatial(&scene_from_toml(&text), &RunOptions::default()).unwrap();
    let v = &run.final_velocities;
    // Velocities live in f32 in Rapier, and the stopped balls stay touching for some 30 steps.
    let tolerance = 1e-5;
    assert!(v[0].abs() <= tolerance && v[1].abs() <= tolerance && (v[2] - 1.0).abs() <= tolerance, "{v:?}");
}
