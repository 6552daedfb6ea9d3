//! Balls given at exactly touching positions (centres 0.05 and 0.06 m apart for radii 0.005 m)
//! were refused as overlapping: `0.06 - 0.05` is a few ulps short of 0.01 in floating point.
//! Touching within the round-off of the container's coordinates is now allowed; a real overlap
//! is still refused, naming the ball.

use lpc_damper::model::{Model, RunOptions};

use crate::common::scene_from_toml;

/// A scene of two balls of radius 5 mm at `x1` and `x2` on the container's axis, the first
/// moving at 0.1 m/s towards the second, elastic, without gravity.
fn two_balls(x1: f64, x2: f64) -> String {
    format!(
        "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.0\n\
         [container]\nlength = 0.1\nwidth = 0.02\nheight = 0.02\n\
         [world]\nrestitution = 1.0\n\
         [[ball]]\nposition = [{x1}, 0.0, 0.0]\nmass = 0.004\nradius = 0.005\nvelocity = [0.1, 0.0, 0.0]\n\
         [[ball]]\nposition = [{x2}, 0.0, 0.0]\nmass = 0.004\nradius = 0.005\n\
         [run]\nhorizon = 0.05\n"
    )
}

#[test]
fn balls_at_touching_positions_are_accepted_and_strike_at_once() {
    let scene = scene_from_toml(&two_balls(0.05, 0.06));
    // Equal balls, elastic: the first stops and the second leaves at its speed, at once.
    let run = Model::Reference.simulate(&scene, &RunOptions::default()).unwrap();
    let first = run.impacts.first().expect("the balls strike");
    assert_eq!(first.t, 0.0, "{:?}", run.impacts);
    let last = run.series.len() - 1;
    let (v1, v2) = (run.series.v(0)[last], run.series.v(1)[last]);
    assert!(v1.abs() <= 1e-15 && (v2 - 0.1).abs() <= 1e-15, "velocities {v1} and {v2}");
    for model in [Model::Rapier, Model::Compliant] {
        model.simulate(&scene, &RunOptions::default()).unwrap_or_else(|e| panic!("{model}: {e}"));
    }
}

#[test]
fn overlapping_balls_are_still_refused_naming_the_ball() {
    let text = two_balls(0.05, 0.0599);
    let Err(err) = lpc_damper::scene::parse(&text, "test.toml", "test") else { panic!("an overlap is refused") };
    let err = err.to_string();
    assert!(err.contains("ball[1].position") && err.contains("overlap"), "{err}");
}
