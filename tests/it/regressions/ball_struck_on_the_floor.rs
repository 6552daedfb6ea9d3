//! Issue 31: `planar-bed` stopped at 0.083 s with "more than 10 000 events at one instant". A
//! large ball struck a small one resting on the floor along a normal pointing down into it; the
//! impact was resolved between the free balls and the floor then took the small ball's velocity
//! into it, which left the pair closing again, at the same instant, without end. The fix
//! resolves such an impact with the floor's reaction at once (the resting ball moves only along
//! the floor, so along the normal it weighs `m / (1 - n_z^2)`, docs/MODEL.md §14): the pair
//! separates at `e` times its approach in one impact.

use crate::common::{reference, scene_from_toml};

#[test]
fn a_ball_struck_on_the_floor_separates_in_one_impact() {
    // A large ball (7 mm) slides at 0.1 m/s on the smooth floor into a small one (4 mm) resting
    // 20 mm ahead; their centres are 3 mm apart in height, so the normal points down into the
    // floor at the small ball.
    let (rl, rs, e, v) = (0.007f64, 0.004f64, 0.8f64, 0.1f64);
    let (ml, ms) = (0.0112, 0.0021);
    let floor = -0.05;
    let text = format!(
        "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.0\n\
         [container]\nlength = 0.1\nwidth = 0.06\nheight = 0.1\n\
         [world]\ngravity = [0.0, 0.0, -9.81]\nrestitution = {e}\n\
         [[ball]]\nposition = [0.02, 0.0, {zl}]\nmass = {ml}\nradius = {rl}\nvelocity = [{v}, 0.0, 0.0]\n\
         [[ball]]\nposition = [0.05, 0.0, {zs}]\nmass = {ms}\nradius = {rs}\n\
         [run]\nhorizon = 0.3\n",
        zl = floor + rl,
        zs = floor + rs,
    );
    let scene = scene_from_toml(&text);
    let run = reference(&scene).expect("the run goes on past the impact");
    let first = run.impacts.iter().find(|i| matches!(i.b, lpc_damper::scene::Body::Ball(_))).expect("the balls meet");
    // Along the normal n = (cos, 0, -sin), sin = 3 mm / 11 mm, the sliding ball approaches at
    // v cos; the resting one weighs ms / cos^2 (1 - n_z^2 = cos^2). Eq. 9-10 with these masses
    // lose (1 - e^2) mu u^2 / 2.
    let sin = (rl - rs) / (rl + rs);
    let cos = (1.0 - sin * sin).sqrt();
    let u = v * cos;
    let mu = ml * (ms / (cos * cos)) / (ml + ms / (cos * cos));
    let lost = 0.5 * (1.0 - e * e) * mu * u * u;
    assert!((first.approach_speed - u).abs() <= 1e-15, "approach {} m/s, expected {u}", first.approach_speed);
    assert!((first.energy_lost - lost).abs() <= 1e-12 * lost, "lost {} J, expected {lost} J", first.energy_lost);
    // One impact between the balls at that instant, and the small ball stays on the floor.
    assert_eq!(run.impacts.iter().filter(|i| i.t == first.t).count(), 1);
    let last = run.series.len() - 1;
    assert!((run.series.across(1, last)[1] - (floor + rs)).abs() <= 1e-15);
    assert!(run.energy.balance_error.abs() <= 1e-12, "{:?}", run.energy);
}
