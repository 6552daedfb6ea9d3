//! Issue 31: a run whose horizon fell while the frame pressed a ball against an end wall
//! stopped with "more than 10 000 events at one instant" just before the horizon (an ensemble
//! of the frictionless particle box at the default contact duration, run to 0.05 s; shrunk, a
//! lone ball pressed against the right wall stalled at one horizon in seven between 6 and 60 ms).
//! The collapse rule opens a pressed contact by less than the contact tolerance. Struck within
//! a contact duration of the horizon, the ball was still separating when the search's window
//! ended there, and the search took the window's end, where the gap was within the tolerance, for
//! a contact: struck there, the ball was found touching there again. The fix: a touching ball
//! that still separates at the end of a piece of the frame's motion does not meet the wall on
//! that piece.

use crate::common::{min_gap, reference, scene_from_toml};
use lpc_damper::scene::Body;

#[test]
fn a_ball_pressed_against_a_wall_at_the_horizon_runs_to_it() {
    // The ball of `a_ball_pressed_against_a_wall_of_the_frame_is_struck_once_a_contact_duration`
    // (struck by the right wall at 5.6 ms, pressed until 62 ms), at horizons that stalled.
    for (e, horizon) in [(0.0, 0.0525), (0.0, 0.0565), (0.6, 0.025), (0.6, 0.059)] {
        let scene = scene_from_toml(&format!(
            "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.01\n\
             [container]\nlength = 0.1\nwidth = 0.06\nheight = 0.1\n\
             [world]\ngravity = [0.0, 0.0, -9.81]\nrestitution = {e}\n\
             [[ball]]\nposition = [0.0949, 0.0, -0.045]\nmass = 0.004\nradius = 0.005\n\
             [run]\nhorizon = {horizon}\n"
        ));
        let run = reference(&scene).unwrap_or_else(|err| panic!("e {e}, horizon {horizon}: {err}"));
        // Still pressed at the horizon: struck up to a contact duration before it.
        let last = run.impacts.iter().rev().find(|i| i.b == Body::RightWall).expect("the wall strikes the ball");
        let t_c = scene.reference.contact_duration;
        assert!(last.t < horizon && horizon - last.t <= t_c, "e {e}: last struck at {} s of {horizon} s", last.t);
        let roundoff = 8.0 * f64::EPSILON * run.impacts.len() as f64;
        assert!(run.energy.balance_error.abs() <= roundoff, "e {e}: {:?}", run.energy);
        assert!(min_gap(&scene, &run) >= -1e-12);
    }
}
