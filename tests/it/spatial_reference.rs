//! The reference beyond one line (docs/MODEL.md §14): closed-form flights under gravity, the
//! exact impact law along normals, the energy balance with gravity's work, and what it refuses.

use crate::common::{reference, scene_from_toml};
use lpc_damper::model::Model;

/// A container on a frame at rest, with `world` and `balls` tables.
fn box_scene(world: &str, balls: &str, horizon: f64) -> String {
    format!(
        "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.0\n\
         [container]\nlength = 0.1\nwidth = 0.06\nheight = 0.1\n[world]\n{world}\n{balls}\n[run]\nhorizon = {horizon}\n"
    )
}

#[test]
fn a_ball_dropped_on_the_floor_bounces_at_the_closed_form_times() {
    // From 40 mm above the floor (z = -0.05 m), e = 0.8: the k-th bounce comes 2 e^k v1 / g
    // after the one before, at e^k v1, v1 = sqrt(2 g h).
    let (g, h, e, r) = (9.81f64, 0.04f64, 0.8f64, 0.005f64);
    let z0 = -0.05 + r + h;
    let scene = scene_from_toml(&box_scene(
        &format!("gravity = [0.0, 0.0, -{g}]\nrestitution = {e}"),
        &format!("[[ball]]\nposition = [0.05, 0.0, {z0}]\nmass = 0.004\nradius = {r}\n"),
        1.0,
    ));
    let run = reference(&scene).unwrap();
    let v1 = (2.0 * g * h).sqrt();
    let (mut t, mut v) = ((2.0 * h / g).sqrt(), v1);
    assert!(run.impacts.len() > 8, "{} impacts", run.impacts.len());
    for (k, impact) in run.impacts.iter().take(8).enumerate() {
        // Round-off of the quadratics' roots and of the state carried from bounce to bounce.
        assert!((impact.t - t).abs() <= 1e-12, "bounce {k} at {} s, closed form {t} s", impact.t);
        assert!((impact.approach_speed - v).abs() <= 1e-12, "bounce {k} at {} m/s, closed form {v} m/s", impact.approach_speed);
        let lost = 0.5 * 0.004 * v * v * (1.0 - e * e);
        assert!((impact.energy_lost - lost).abs() <= 1e-15, "bounce {k} lost {} J, closed form {lost} J", impact.energy_lost);
        v *= e;
        t += 2.0 * v / g;
    }
    // The bounces shorten geometrically (about 1.13 s in all) and the ball comes to rest on the
    // floor within the horizon: what it had is all lost in impacts, gravity's work included.
    let total = (2.0 * h / g).sqrt() + 2.0 * e * v1 / g / (1.0 - e);
    assert!(total < 1.5);
    let long = scene_from_toml(&box_scene(
        &format!("gravity = [0.0, 0.0, -{g}]\nrestitution = {e}"),
        &format!("[[ball]]\nposition = [0.05, 0.0, {z0}]\nmass = 0.004\nradius = {r}\n"),
        1.5,
    ));
    let run = reference(&long).unwrap();
    let potential = 0.004 * g * h;
    assert!((run.energy.impact_loss - potential).abs() <= 1e-12 * potential, "{:?}", run.energy);
    assert!(run.energy.balance_error.abs() <= 1e-12, "{:?}", run.energy);
    let last = run.series.len() - 1;
    assert!((run.series.across(0, last)[1] - (-0.05 + r)).abs() <= 1e-15, "the ball rests on the floor");
}

#[test]
fn a_gas_in_a_box_on_the_frame_keeps_its_energy_balance() {
    // Twenty balls with random velocities in a box without gravity, struck by the frame's walls.
    let mut balls = String::new();
    for i in 0..20 {
        let (x, y, z) = (0.01 + 0.02 * (i % 4) as f64, -0.02 + 0.02 * ((i / 4) % 3) as f64, -0.04 + 0.02 * (i / 12) as f64);
        let v = [(i as f64 * 0.37).sin(), (i as f64 * 0.91).cos(), (i as f64 * 1.73).sin()];
        balls +=
            &format!("[[ball]]\nposition = [{x}, {y}, {z}]\nmass = 0.004\nradius = 0.005\nvelocity = [{}, {}, {}]\n", v[0], v[1], v[2]);
    }
    let mut text = box_scene("gravity = [0.0, 0.0, 0.0]\nrestitution = 0.9", &balls, 1.0);
    text = text.replace("initial_displacement = 0.0", "initial_displacement = 0.01");
    let scene = scene_from_toml(&text);
    let run = reference(&scene).unwrap();
    assert!(run.impacts.len() > 100, "{} impacts", run.impacts.len());
    // Exact impacts: each loses (1 - e^2) of its normal kinetic energy, none gains; the balance
    // of the whole run closes to round-off.
    assert!(run.impacts.iter().all(|i| i.energy_lost >= 0.0));
    assert!(run.energy.balance_error.abs() <= 1e-12, "{:?}", run.energy);
    assert!(run.impacts.iter().any(|i| i.a == lpc_damper::scene::Body::LeftWall || i.b == lpc_damper::scene::Body::RightWall));
}

#[test]
fn a_ball_pressed_against_a_wall_of_the_frame_is_struck_once_a_contact_duration() {
    // One ball with e = 0 on the floor by the right wall of a box on a frame released from
    // 10 mm: the wall strikes it after 5.6 ms and then presses it until the frame passes its
    // rest position (62 ms). The collapse rule gives the pressed contact the separation speed
    // a t_c / 2, which keeps it open for a contact duration (docs/MODEL.md §14): the run goes on,
    // at the default contact duration and at the longer one a scene may set.
    for t_c in [lpc_damper::scene::DEFAULT_CONTACT_DURATION, 1e-4] {
        let mut text = box_scene(
            "gravity = [0.0, 0.0, -9.81]\nrestitution = 0.0",
            "[[ball]]\nposition = [0.0949, 0.0, -0.045]\nmass = 0.004\nradius = 0.005\n",
            0.2,
        );
        text = text.replace("initial_displacement = 0.0", "initial_displacement = 0.01");
        text.push_str(&format!("\n[reference]\ncontact_duration = {t_c:e}\n"));
        let scene = scene_from_toml(&text);
        assert_eq!(scene.reference.contact_duration, t_c);
        let run = reference(&scene).expect("a pressed ball never stalls the run");
        let wall: Vec<f64> = run.impacts.iter().filter(|i| i.b == lpc_damper::scene::Body::RightWall).map(|i| i.t).collect();
        let pressed = wall.last().unwrap() - wall[0];
        assert!(pressed > 0.05 && pressed < 0.062, "t_c {t_c:e}: pressed for {pressed} s");
        // The contact opens by a t_c^2 / 8 (1e-12 m at a microsecond, the order of the contact
        // tolerance), so the search may find it closed again half way: strikes come between
        // half a contact duration and one apart. The frame's pressing falls as it nears its rest
        // position, by some w0 t_c = 2.5e-3 of itself over a contact duration mid-way (w0 = 25
        // rad/s) and to nothing at the end, which lengthens the last strikes' intervals: the
        // median interval is a contact duration to a hundredth.
        let mut intervals: Vec<f64> = wall.windows(2).map(|w| w[1] - w[0]).collect();
        intervals.sort_by(f64::total_cmp);
        let (shortest, median) = (intervals[0], intervals[intervals.len() / 2]);
        assert!(shortest >= 0.5 * t_c * (1.0 - 1e-3), "t_c {t_c:e}: impacts {shortest:e} s apart");
        assert!(median <= t_c * (1.0 + 1e-2), "t_c {t_c:e}: impacts {median:e} s apart at the median");
        // What the rule puts in is booked: the balance closes to a few ulps of the energy at each
        // of the frame's restarts, and the ball stays in its box.
        let roundoff = 8.0 * f64::EPSILON * run.impacts.len() as f64;
        assert!(run.energy.balance_error.abs() <= roundoff, "t_c {t_c:e}: {:?}", run.energy);
        assert!(crate::common::min_gap(&scene, &run) >= -1e-12);
    }
}

#[test]
fn the_reference_refuses_friction_and_gravity_along_the_motion() {
    let ball = "[[ball]]\nposition = [0.05, 0.0, 0.0]\nmass = 0.004\nradius = 0.005\nvelocity = [0.0, 1.0, 0.0]\n";
    let rough = scene_from_toml(&box_scene("friction = 0.3\nrestitution = 0.6", ball, 0.1));
    assert!(Model::Reference.supports(&rough).unwrap_err().contains("friction"));
    let tilted = scene_from_toml(&box_scene("gravity = [1.0, 0.0, -9.81]\nrestitution = 0.6", ball, 0.1));
    assert!(Model::Reference.supports(&tilted).unwrap_err().contains("along the frame's motion"));
}
