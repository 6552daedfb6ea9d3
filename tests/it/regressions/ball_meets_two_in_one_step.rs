//! A ball meeting two free balls within one step of the contact model lost energy at e = 1
//! (and a gas of such balls lost 10 to 40 % of its energy in half a second, or gained some and
//! stopped). Rapier solved both contacts at once, stopping the ball short of both and passing
//! momentum between pairs that never touch, and the impact law then started each pair from
//! velocities the other pair's contact had changed. The whole step of such a group in flight
//! is now undone and its impacts act one after the other on free flight's velocities
//! (docs/MODEL.md §9, "Groups in flight").

use lpc_damper::model::RunOptions;
use lpc_damper::rapier::spatial::simulate_spatial;

use crate::common::scene_from_toml;

/// The energy Rapier's f32 velocities may lose or gain in the run, relative to the initial
/// energy (as in the test of balls meeting in flight).
const F32_ENERGY: f64 = 1e-5;

#[test]
fn a_ball_meeting_two_balls_in_one_step_keeps_its_energy_at_e_1() {
    // No gravity or friction, far from the walls. The first ball, at 0.5 m/s along x, touches
    // the second (6 mm off its path) at 20.1 ms and would touch the third (6.2 mm off it on the
    // other side) 0.7 ms later in free flight: both closings fall within the step from 20 to
    // 21 ms. The second and third never touch each other.
    let mass = 0.00408f64;
    let text = format!(
        "[frame]\nmass = 100.0\nstiffness = 1000.0\ndamping = 0.0\ninitial_displacement = 0.0\n\
         [container]\nlength = 0.1\nwidth = 0.1\nheight = 0.1\n\
         [world]\ngravity = [0.0, 0.0, 0.0]\nrestitution = 1.0\nfriction = 0.0\n\
         [rapier]\ndt = 0.001\n\
         [[ball]]\nposition = [0.02995, 0.0, 0.0]\nmass = {mass}\nradius = 0.005\nvelocity = [0.5, 0.0, 0.0]\n\
         [[ball]]\nposition = [0.048, 0.006, 0.0]\nmass = {mass}\nradius = 0.005\nvelocity = [0.0, 0.0, 0.0]\n\
         [[ball]]\nposition = [0.0482, -0.0062, 0.0]\nmass = {mass}\nradius = 0.005\nvelocity = [0.0, 0.0, 0.0]\n\
         [run]\nhorizon = 0.04\nsample_dt = 0.001\n"
    );
    let run = simulate_spatial(&scene_from_toml(&text), &RunOptions::default()).unwrap();
    let (lost, initial) = (run.energy.contact_loss, run.energy.initial);
    assert!(lost.abs() <= F32_ENERGY * initial, "{lost} J lost of {initial} J at e = 1");
    assert!(run.impact_count() >= 2, "{} impacts", run.impact_count());
    // Momentum along x stays with the balls (the frame, at rest and a hundred kilograms, takes
    // nothing from impacts among them).
    let px: f64 = run.final_velocities.iter().map(|v| mass * v).sum();
    assert!((px - mass * 0.5).abs() <= 4e-6 * mass * 0.5, "momentum {px} against {}", mass * 0.5);
}
