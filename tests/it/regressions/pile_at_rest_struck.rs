//! A pile at rest booked impacts at every step in the contact model: three balls wedged in a
//! box (two on the floor between the front and back walls, one resting on both) struck each
//! other and the walls some ten times a step, 9504 impacts in 0.1 s at 0.1 ms steps, and a
//! settled bed some 16 million a simulated second. A contact was resting when it closed slower
//! than gravity builds along its normal in two steps, which is nothing along a horizontal
//! normal, so every tremor of Rapier's soft contacts there was an impact and set off knock-ons
//! through the pile. A ball in a pile carries weight along every contact, so gravity now
//! counts whole for each of its contacts (docs/MODEL.md §9).

use lpc_damper::model::{Model, RunOptions};

use crate::common::scene_from_toml;

#[test]
fn a_pile_at_rest_has_no_impacts() {
    // Each pair 0.1 um apart, which gravity closes in the first step.
    let (r, slack, height, length) = (0.005f64, 1e-7f64, 0.05f64, 0.05f64);
    let floor = -0.5 * height + r + slack;
    let side = r + slack;
    let rise = ((2.0 * r + slack).powi(2) - side * side).sqrt();
    let mut text = format!(
        "[frame]\nmass = 1000.0\nstiffness = 1000.0\ndamping = 0.0\ninitial_displacement = 0.0\n\
         [container]\nlength = {length}\nwidth = {width}\nheight = {height}\n\
         [world]\ngravity = [0.0, 0.0, -9.81]\nfriction = 0.0\nrestitution = 0.6\n\
         [rapier]\ndt = 0.0001\n[run]\nhorizon = 0.1\nsample_dt = 0.001\n",
        width = 4.0 * r + 4.0 * slack
    );
    for (y, z) in [(-side, floor), (side, floor), (0.0, floor + rise)] {
        text += &format!("[[ball]]\nposition = [{}, {y}, {z}]\nmass = 0.004\nradius = {r}\n", 0.5 * length);
    }
    let run = Model::Rapier.simulate(&scene_from_toml(&text), &RunOptions::default()).unwrap();
    assert_eq!(run.impact_count(), 0, "a pile at rest struck {} times", run.impact_count());
    assert_eq!(run.energy.impact_loss, 0.0);
}
