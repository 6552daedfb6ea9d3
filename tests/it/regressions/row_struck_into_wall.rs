//! A row of two touching balls flying into a wall at e = 1 lost half its energy at steps of 0.2
//! and 0.3 ms (issue 55, item 4): Rapier's plastic solve of the step stopped the row as one
//! block at the wall, and the impact law then gave the first ball its bounce but left the
//! second with what Rapier's solve left it, so the knock-on came at 0.77 of its speed. A
//! touching group that rested on no wall and of which a ball strikes a wall now has its step
//! undone, as a group in flight has (docs/MODEL.md §9, "Groups in flight").

use lpc_damper::model::RunOptions;
use lpc_damper::rapier::spatial::simulate_spatial;

use crate::common::scene_from_toml;

/// Rapier keeps velocities in f32: a velocity's relative rounding over a run of a few hundred
/// steps, and the energy that rounding may make or lose, relative to the initial energy.
const F32_VELOCITY: f64 = 1e-6;
const F32_ENERGY: f64 = 1e-5;

#[test]
fn a_touching_row_struck_into_a_wall_leaves_at_its_speed() {
    let r = 0.00675;
    for dt in [0.0002, 0.0003] {
        // Two touching balls fly at 1 m/s towards the left wall of a frame too heavy to move,
        // without gravity; the first is 5 mm from the wall. The sequence of §3 at e = 1: the
        // first bounces, passes its speed to the second, bounces again; both leave at 1 m/s.
        let mut text = format!(
            "[frame]\nmass = 1e6\nstiffness = 1e6\ndamping = 0.0\ninitial_displacement = 0.0\n\
             [container]\nlength = 1.0\nwidth = 0.05\nheight = 0.05\n\
             [world]\nrestitution = 1.0\nfriction = 0.1\n\
             [rapier]\ndt = {dt}\n\
             [run]\nhorizon = 0.03\nsample_dt = 0.001\n"
        );
        for k in 0..2 {
            let x = r + 0.005 + 2.0 * r * k as f64;
            text += &format!("[[ball]]\nposition = [{x}, 0.0, 0.0]\nmass = 0.01\nradius = {r}\nvelocity = [-1.0, 0.0, 0.0]\n");
        }
        let run = simulate_spatial(&scene_from_toml(&text), &RunOptions::default()).expect("the row keeps its energy");
        for (i, v) in run.final_velocities.iter().enumerate() {
            assert!((v - 1.0).abs() <= F32_VELOCITY, "dt {dt}: ball {i} leaves at {v} m/s");
        }
        let (lost, initial) = (run.energy.contact_loss, run.energy.initial);
        assert!(lost.abs() <= F32_ENERGY * initial, "dt {dt}: {lost} J lost of {initial} J at e = 1");
    }
}
