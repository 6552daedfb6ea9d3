//! A ball striking a touching group from a gap, in the same step as a faster ball that Rapier
//! stopped against the same target, lost 40 % of the energy at e = 1 (issue 55). The strike is
//! kept out of Rapier's solve and acts at the speed its pair approaches with at its turn; it came
//! first (the two approached equally fast) and met the target in Rapier's plastic stop of the
//! other pair, half way between the velocities before and after that impact. Strikes kept out of
//! Rapier's solve now act after every impact Rapier stopped (docs/MODEL.md §9, "Impacts that meet
//! what an earlier impact of the step moved").

use lpc_damper::model::RunOptions;
use lpc_damper::rapier::spatial::simulate_spatial;

use crate::common::scene_from_toml;

/// The energy Rapier's f32 velocities may lose or gain in the run, relative to the initial
/// energy (as in the test of a ball meeting two balls in one step).
const F32_ENERGY: f64 = 1e-5;

#[test]
fn a_strike_on_a_touching_pair_meets_its_target_after_rapiers_stop_is_a_bounce() {
    // No gravity or friction, e = 1, steps of 1 ms, a frame too heavy to move. T1 and T2 touch
    // across the box at rest; along x, S (0.5 m/s from the left) reaches T1 at 20.5 ms and F
    // (1 m/s from the right) at 20.3 ms, in the same step. In order: F stops and T1 leaves at
    // 1 m/s, S and T1 exchange at 1.5 m/s, T1 strikes F: S -1, T1 0, F 0.5 m/s.
    let mass = 0.004f64;
    let ball = |x: f64, y: f64, v: f64| {
        format!("[[ball]]\nposition = [{x}, {y}, 0.0]\nmass = {mass}\nradius = 0.005\nvelocity = [{v}, 0.0, 0.0]\n")
    };
    let text = format!(
        "[frame]\nmass = 100.0\nstiffness = 1000.0\ndamping = 0.0\ninitial_displacement = 0.0\n\
         [container]\nlength = 0.1\nwidth = 0.1\nheight = 0.1\n\
         [world]\ngravity = [0.0, 0.0, 0.0]\nrestitution = 1.0\nfriction = 0.0\n\
         [rapier]\ndt = 0.001\n{}{}{}{}\
         [run]\nhorizon = 0.025\nsample_dt = 0.001\n",
        ball(0.02975, 0.0, 0.5),
        ball(0.05, 0.0, 0.0),
        ball(0.05, 0.01, 0.0),
        ball(0.0803, 0.0, -1.0)
    );
    let run = simulate_spatial(&scene_from_toml(&text), &RunOptions::default()).unwrap();
    let (lost, initial) = (run.energy.contact_loss, run.energy.initial);
    assert!(lost.abs() <= F32_ENERGY * initial, "{lost} J lost of {initial} J at e = 1");
    // The balls' velocities along x, to Rapier's single precision.
    let expected = [-1.0, 0.0, 0.0, 0.5];
    for (i, (v, want)) in run.final_velocities.iter().zip(expected).enumerate() {
        assert!((v - want).abs() <= 1e-6, "ball {i} at {v} m/s, the sequence gives {want} m/s");
    }
}
