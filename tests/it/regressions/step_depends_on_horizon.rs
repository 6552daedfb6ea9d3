//! The same 50 ms of a box of balls differed by 0.67 mm in a ball's position between
//! `--horizon 0.05` and `--horizon 2`: the speed scale every model takes its step bounds and
//! speed tolerances from was at least the scene's length over the horizon, so a short horizon
//! made the contact model's step smaller. The scale is now what the scene sets going, the fall
//! its balls start and floors of the scene's own (docs/MODEL.md §9): the horizon only says
//! where a run ends.

use lpc_damper::model::{Model, RunOptions};

use crate::common::scene_from_toml;

fn balls_in_a_box(horizon: f64) -> lpc_damper::scene::Scene {
    scene_from_toml(&format!(
        "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.01\n\
         [container]\nlength = 0.1\nwidth = 0.06\nheight = 0.1\n\
         [world]\ngravity = [0.0, 0.0, -9.81]\nrestitution = 0.8\n\
         [[ball]]\nposition = [0.03, 0.0, -0.02]\nmass = 0.004\nradius = 0.005\n\
         [[ball]]\nposition = [0.05, 0.01, -0.045]\nmass = 0.004\nradius = 0.005\n\
         [[ball]]\nposition = [0.07, -0.01, -0.03]\nmass = 0.004\nradius = 0.005\n\
         [reference]\ncontact_duration = 1e-5\n\
         [run]\nhorizon = {horizon}\nsample_dt = 0.001\n"
    ))
}

#[test]
fn the_first_50_ms_are_the_same_whatever_the_horizon() {
    let (short, long) = (balls_in_a_box(0.05), balls_in_a_box(0.4));
    assert_eq!(short.speed_scale(), long.speed_scale());
    for model in [Model::Rapier, Model::Compliant, Model::Reference] {
        let a = model.simulate(&short, &RunOptions::default()).unwrap();
        let b = model.simulate(&long, &RunOptions::default()).unwrap();
        assert_eq!(a.series.len(), 51, "{model}");
        // The compliant model's steps follow its contacts, so the short run's last step is cut
        // to end on its horizon: every sample before it is the same.
        let n = if model == Model::Compliant { 50 } else { 51 };
        assert_eq!(&a.series.t()[..n], &b.series.t()[..n], "{model}");
        assert_eq!(&a.series.xs()[..n], &b.series.xs()[..n], "{model}");
        for i in 0..3 {
            assert_eq!(&a.series.x(i)[..n], &b.series.x(i)[..n], "{model} ball {i}");
            for k in 0..n {
                assert_eq!(a.series.across(i, k), b.series.across(i, k), "{model} ball {i} at sample {k}");
            }
        }
    }
}
