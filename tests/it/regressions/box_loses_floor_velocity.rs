//! The contact model's spatial path started the carrying floor of a structure at rest: the
//! impacts before the first step restarted the floors' closed form from a velocity of zero plus
//! their impulses, so a building whose top floor starts moving lost that floor's kinetic energy
//! unaccounted. The path now starts from the carrier's own state.

use lpc_damper::model::{Model, RunOptions};

use crate::common::scene_from_toml;

#[test]
fn a_box_on_a_moving_floor_keeps_the_floors_energy() {
    let scene = scene_from_toml(
        "[structure]\nmasses = [1.35, 1.35, 1.35]\nstiffnesses = [4364.0, 4364.0, 4364.0]\n\
         damping_ratios = [0.016, 0.016, 0.016]\ninitial_velocities = [0.0, 0.0, 0.1]\ndamper_floor = 3\n\
         [container]\nlength = 0.06\nwidth = 0.04\nheight = 0.05\n\
         [world]\ngravity = [0.0, 0.0, -9.81]\nrestitution = 0.6\n\
         [bed]\ncount = 6\nradii = [0.005]\ndensity = 7800.0\nplacement = \"lattice\"\n\
         [run]\nhorizon = 0.1\n",
    );
    for model in [Model::Rapier, Model::Compliant] {
        let run = model.simulate(&scene, &RunOptions::default()).unwrap();
        // The top floor starts at 0.1 m/s and is still moving so a millisecond later (its
        // springs take less than 1e-4 m/s from it by then), and the energy balance closes.
        assert!((run.series.vs()[0] - 0.1).abs() < 1e-12, "{model}: {}", run.series.vs()[0]);
        assert!(run.series.vs()[1] > 0.099, "{model}: {}", run.series.vs()[1]);
        assert!(run.energy.balance_error.abs() < 1e-3, "{model}: {:?}", run.energy);
        lpc_damper::studies::stress::judge(model, &scene, &run).unwrap_or_else(|f| panic!("{model}: {} {}", f.check, f.detail));
    }
}
