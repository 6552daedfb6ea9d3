//! Balls placed on the floor under gravity logged an impact at t = 0 with an approach speed of
//! -0 in the reference: a ball that only touches the wall it rests on was booked as striking
//! it. It now settles on the floor without an impact, and no model books an impact that does
//! not approach.

use lpc_damper::model::{Model, RunOptions};

use crate::common::scene_from_toml;

#[test]
fn balls_resting_on_the_floor_log_no_impact() {
    // Two balls on the smooth floor of a frame at rest, apart, under gravity: nothing strikes.
    let floor = -0.05;
    let scene = scene_from_toml(&format!(
        "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.0\n\
         [container]\nlength = 0.1\nwidth = 0.06\nheight = 0.1\n\
         [world]\ngravity = [0.0, 0.0, -9.81]\nrestitution = 0.8\n\
         [[ball]]\nposition = [0.02, 0.0, {z}]\nmass = 0.004\nradius = 0.005\n\
         [[ball]]\nposition = [0.06, 0.0, {z}]\nmass = 0.004\nradius = 0.005\n\
         [run]\nhorizon = 0.05\n",
        z = floor + 0.005
    ));
    let run = Model::Reference.simulate(&scene, &RunOptions::default()).unwrap();
    assert!(run.impacts.is_empty(), "{:?}", run.impacts);
    assert_eq!(run.energy.impact_loss, 0.0);
}

#[test]
fn no_model_books_an_impact_that_does_not_approach() {
    let scene = lpc_damper::scene::load_scene(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/planar-bed.toml")).unwrap();
    let scene = lpc_damper::scene::Scene { horizon: 0.02, ..scene };
    for model in [Model::Reference, Model::Compliant, Model::Rapier] {
        let run = model.simulate(&scene, &RunOptions::default()).unwrap();
        let still: Vec<_> = run.impacts.iter().filter(|i| i.approach_speed <= 0.0 || i.approach_speed.is_nan()).collect();
        assert!(still.is_empty(), "{model}: {still:?}");
    }
}
