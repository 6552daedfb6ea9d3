//! Issue 31: a bed with restitution 0 (`lpc stress --beds`, seed 59) stopped with "more than
//! 10 000 events at one instant": two balls side by side on the floor slid together, their
//! velocities one ulp apart, so they closed by 3e-17 m/s; no impact can part them by less than
//! an ulp, and the pair was found touching and closing again at the same instant. The fix: a
//! touching pair that closes no faster than the round-off of its velocities does not close.

use crate::common::{min_gap, reference, scene_from_toml};

#[test]
fn balls_sliding_together_after_a_plastic_impact_go_on() {
    // The shrunk scene: two touching balls on the floor of a box on a stiff frame swinging far
    // beyond the box, every impact plastic. It stalled at 0.2118 s.
    let scene = scene_from_toml(
        "[frame]\nmass = 1.35\nstiffness = 98728.16715274591\ndamping = 101.01125414154335\n\
         initial_displacement = 0.17136367826630192\n\
         [run]\nhorizon = 0.22\nsample_dt = 0.0001612091933123357\n\
         [container]\nlength = 0.09134059028799765\nwidth = 0.051903554856232145\nheight = 0.051903554856232145\n\
         [world]\ngravity = [0.0, 0.0, -9.81]\nfriction = 0.0\nrestitution = 0.0\n\
         [bed]\ncount = 2\nradii = [0.005138965827349717]\ndensity = 7800.0\nplacement = \"lattice\"\nseed = 59\n",
    );
    let run = reference(&scene).expect("the run never stalls");
    assert!(run.energy.balance_error.abs() <= 1e-12, "{:?}", run.energy);
    assert!(min_gap(&scene, &run) >= -1e-12);
}
