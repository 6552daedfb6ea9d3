//! The four walls across the motion were all called `side-wall` in impacts, so a reader could
//! not tell a ball bouncing on the floor from one striking the ceiling or the front. They are
//! now `floor` (z = -height / 2), `ceiling`, `front-wall` (y = -width / 2) and `back-wall`.

use lpc_damper::model::{Model, RunOptions};
use lpc_damper::scene::Body;

use crate::common::scene_from_toml;

/// One elastic ball without gravity in a 0.1 m cube, from its centre at `velocity`.
fn thrown(velocity: [f64; 3]) -> lpc_damper::scene::Scene {
    let [vx, vy, vz] = velocity;
    scene_from_toml(&format!(
        "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.0\n\
         [container]\nlength = 0.1\nwidth = 0.1\nheight = 0.1\n\
         [world]\nrestitution = 1.0\n\
         [[ball]]\nposition = [0.05, 0.0, 0.0]\nmass = 0.004\nradius = 0.005\nvelocity = [{vx}, {vy}, {vz}]\n\
         [run]\nhorizon = 0.3\n"
    ))
}

#[test]
fn each_wall_across_the_motion_is_named_in_impacts() {
    // Straight across at 1 m/s, the ball strikes the wall 45 mm ahead after 45 ms, then the
    // opposite one 90 mm later: each wall in turn, by its name.
    for (velocity, walls) in [
        ([0.0, 0.0, -1.0], [Body::Floor, Body::Ceiling]),
        ([0.0, 0.0, 1.0], [Body::Ceiling, Body::Floor]),
        ([0.0, -1.0, 0.0], [Body::FrontWall, Body::BackWall]),
        ([0.0, 1.0, 0.0], [Body::BackWall, Body::FrontWall]),
    ] {
        let scene = thrown(velocity);
        for model in [Model::Reference, Model::Compliant, Model::Rapier] {
            let run = model.simulate(&scene, &RunOptions::default()).unwrap();
            let struck: Vec<Body> = run.impacts.iter().map(|i| i.b).take(2).collect();
            assert_eq!(struck, walls, "{model}, thrown at {velocity:?}: {:?}", run.impacts);
        }
    }
    let names: Vec<String> = [Body::Floor, Body::Ceiling, Body::FrontWall, Body::BackWall].iter().map(|b| b.name()).collect();
    assert_eq!(names, ["floor", "ceiling", "front-wall", "back-wall"]);
}
