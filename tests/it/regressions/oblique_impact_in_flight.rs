//! Two balls meeting in flight off their line of centres lost energy at e = 1 in the contact
//! model (6 % of it at a 1 ms step, with the normal at 53 degrees to their paths), and a gas of
//! such balls lost a third of its energy in 0.2 s. Rapier pushed the pair apart along a line of
//! its own, near the line of their centres at the step's start, the impact law acted along the
//! line at the step's end, and the part of Rapier's push off the second line stayed. The impact
//! now acts along the line the balls touch along in free flight, after Rapier's push on the
//! pair is undone (docs/MODEL.md §9, "Balls meeting in flight").

use lpc_damper::model::RunOptions;
use lpc_damper::rapier::spatial::simulate_spatial;

use crate::common::scene_from_toml;

/// Velocities live in f32 inside Rapier (as in the struck-group tests).
const F32_SOLVE: f64 = 2e-6;

#[test]
fn balls_meeting_in_flight_off_their_line_bounce_elastically() {
    // Equal balls, no gravity or friction, far from the walls: the second sits 8 mm off the
    // first's path, so they touch along n = (0.6, 0.8, 0) and exchange their normal velocities.
    let (v_a, v_b, mass) = (0.5f64, -0.3f64, 0.00408f64);
    for dt in [1e-3, 5e-4, 1e-4] {
        let text = format!(
            "[frame]\nmass = 100.0\nstiffness = 1000.0\ndamping = 0.0\ninitial_displacement = 0.0\n\
             [container]\nlength = 0.1\nwidth = 0.1\nheight = 0.1\n\
             [world]\ngravity = [0.0, 0.0, 0.0]\nrestitution = 1.0\nfriction = 0.0\n\
             [rapier]\ndt = {dt}\n\
             [[ball]]\nposition = [0.03, 0.0, 0.0]\nmass = {mass}\nradius = 0.005\nvelocity = [{v_a}, 0.0, 0.0]\n\
             [[ball]]\nposition = [0.05, 0.008, 0.0]\nmass = {mass}\nradius = 0.005\nvelocity = [{v_b}, 0.0, 0.0]\n\
             [run]\nhorizon = 0.03\nsample_dt = 0.001\n"
        );
        let run = simulate_spatial(&scene_from_toml(&text), &RunOptions::default()).unwrap();
        let n = [0.6f64, 0.8];
        let approach = (v_a - v_b) * n[0];
        let expected = [v_a - approach * n[0], v_b + approach * n[0]];
        for (k, want) in expected.iter().enumerate() {
            let got = run.final_velocities[k];
            assert!((got - want).abs() <= 4.0 * F32_SOLVE * v_a, "dt {dt}: ball {k} leaves at {got} m/s along x, expected {want}");
        }
        let lost = run.energy.contact_loss;
        assert!(lost.abs() <= 1e-5 * run.energy.initial, "dt {dt}: {lost} J lost of {} J at e = 1", run.energy.initial);
        assert_eq!(run.impact_count(), 1);
    }
}
