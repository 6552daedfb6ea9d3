//! A 2 s contact-model run at `--dt 0.0001` had 2000 samples instead of 2001: its clock adds up
//! 20 000 steps and ends 2e-13 s short of the horizon, within the slack that ends the run but
//! outside the one that puts a sample on a step's end, so the row at the horizon was never
//! written. Once a run has reached its horizon, the samples within the same slack are now
//! taken at its end.

use lpc_damper::model::{Model, RunOptions};

use crate::common::{scene_from_toml, LSL_TOML};

#[test]
fn every_model_writes_the_row_at_the_horizon() {
    // A ball resting on the floor of a box: the balls' own path, with Rapier's step of 0.1 ms.
    let in_space = scene_from_toml(
        "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.01\n\
         [container]\nlength = 0.1\nwidth = 0.06\nheight = 0.1\n\
         [world]\ngravity = [0.0, 0.0, -9.81]\nrestitution = 0.8\n\
         [[ball]]\nposition = [0.05, 0.0, -0.045]\nmass = 0.004\nradius = 0.005\n\
         [rapier]\ndt = 0.0001\n\
         [run]\nhorizon = 2.0\n",
    );
    // The paper's damper on one line, stepped at a fixed 0.1 ms.
    let on_a_line =
        scene_from_toml(&format!("{LSL_TOML}\n[rapier]\nstepping = \"fixed\"\ndt = 0.0001\n").replace("horizon = 5.0", "horizon = 2.0"));
    for (what, scene, models) in
        [("in space", &in_space, &[Model::Rapier, Model::Compliant, Model::Reference][..]), ("on a line", &on_a_line, &[Model::Rapier][..])]
    {
        for &model in models {
            let run = model.simulate(scene, &RunOptions::default()).unwrap();
            assert_eq!(run.series.len(), 2001, "{model} {what}: samples every 1 ms over 2 s");
            assert_eq!(run.series.t().last(), Some(&2.0), "{model} {what}");
        }
    }
}
