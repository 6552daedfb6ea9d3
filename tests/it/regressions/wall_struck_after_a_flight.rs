//! A wall impact that came after, in the same step, a wall impact of a ball of a group in flight
//! met the frame as it was before that impact, and made or destroyed energy at e = 1 (issue 55;
//! 1.7e-4 J in one step of a 20-ball gas box). The group's wall impact moved the frame but did
//! not add that change to what the step's later wall impacts meet. It now does (docs/MODEL.md §9,
//! "Impacts that meet balls an earlier impact of the step moved").

use lpc_damper::model::RunOptions;
use lpc_damper::rapier::spatial::simulate_spatial;
use lpc_damper::scene::Body;

use crate::common::scene_from_toml;

/// The energy Rapier's f32 velocities may lose or gain in the run, relative to the initial
/// energy (as in the test of a ball meeting two balls in one step).
const F32_ENERGY: f64 = 1e-5;

#[test]
fn a_wall_impact_meets_the_frame_a_flying_group_moved_earlier_in_the_step() {
    // No gravity or friction, e = 1, steps of 1 ms, the frame at rest, 25 times a ball's mass
    // and on a spring soft enough (1 N/m) that it hardly accelerates in a step: the impulses
    // land on it at the step's end, which costs energy in proportion to its acceleration. In free flight from the start, B (0.8 m/s) catches A (0.4 m/s) at 20.3 ms, A would
    // reach the right wall at 20.6 ms and C (0.25 m/s, 20 mm aside) reaches it at 20.8 ms: all
    // in the step from 20 to 21 ms. A and B are a group in flight; C's is an ordinary impact.
    let mass = 0.004f64;
    let text = format!(
        "[frame]\nmass = 0.1\nstiffness = 1.0\ndamping = 0.0\ninitial_displacement = 0.0\n\
         [container]\nlength = 0.1\nwidth = 0.1\nheight = 0.1\n\
         [world]\ngravity = [0.0, 0.0, 0.0]\nrestitution = 1.0\nfriction = 0.0\n\
         [rapier]\ndt = 0.001\n\
         [[ball]]\nposition = [0.08676, 0.0, 0.0]\nmass = {mass}\nradius = 0.005\nvelocity = [0.4, 0.0, 0.0]\n\
         [[ball]]\nposition = [0.06864, 0.0, 0.0]\nmass = {mass}\nradius = 0.005\nvelocity = [0.8, 0.0, 0.0]\n\
         [[ball]]\nposition = [0.0898, 0.02, 0.0]\nmass = {mass}\nradius = 0.005\nvelocity = [0.25, 0.0, 0.0]\n\
         [run]\nhorizon = 0.025\nsample_dt = 0.001\n"
    );
    let run = simulate_spatial(&scene_from_toml(&text), &RunOptions::default()).expect("the run keeps its energy");
    // The premise: both balls' wall impacts are booked at the end of one step.
    let wall: Vec<(f64, Body)> = run.impacts.iter().filter(|i| i.b == Body::RightWall).map(|i| (i.t, i.a)).collect();
    assert!(wall.len() >= 2 && wall[0].0 == wall[1].0 && wall[0].1 != wall[1].1, "wall impacts {wall:?}");
    let (lost, initial) = (run.energy.contact_loss, run.energy.initial);
    assert!(lost.abs() <= F32_ENERGY * initial, "{lost} J lost of {initial} J at e = 1");
}
