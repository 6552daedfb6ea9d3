//! A ball striking an end wall bounced not at all when the frame had rung down hard earlier in
//! the run: the contact model took a contact as resting when it closed slower than twice what
//! the frame's largest acceleration over the whole run builds in a step, so on the driven box
//! (a 100 Hz frame released from 20 mm, 7900 m/s^2 at the start) every end-wall impact slower
//! than some 8 m/s was left to Rapier's plastic solve for the whole run, and the gas the drive
//! should have kept warm died. The resting speed now takes the walls' acceleration over the
//! step (docs/MODEL.md §9).

use lpc_damper::model::RunOptions;
use lpc_damper::rapier::spatial::simulate_spatial;

use crate::common::scene_from_toml;

/// Velocities live in f32 inside Rapier (as in the struck-group tests).
const F32_SOLVE: f64 = 2e-6;

#[test]
fn a_ball_bounces_off_a_wall_that_rang_down_before() {
    // The frame rings down from 20 mm at 100 Hz with half its critical damping: its motion is
    // below a nanometre by 50 ms. The ball starts 30 mm from the left wall, which the frame
    // carries 20 mm back as it comes to rest: at 0.5 m/s it strikes the wall at 90 ms and
    // leaves at e times its speed, less the frame's share of the recoil.
    let (e, speed, ball_mass, frame_mass) = (0.6f64, 0.5f64, 0.004f64, 50.0f64);
    let stiffness = 19739208.8f64;
    let damping = 2.0 * 0.5 * (stiffness * frame_mass).sqrt();
    let text = format!(
        "[frame]\nmass = {frame_mass}\nstiffness = {stiffness}\ndamping = {damping}\ninitial_displacement = 0.02\n\
         [container]\nlength = 0.1\nwidth = 0.03\nheight = 0.03\n\
         [world]\nrestitution = {e}\nfriction = 0.1\n\
         [[ball]]\nposition = [0.03, 0.0, 0.0]\nmass = {ball_mass}\nradius = 0.005\nvelocity = [-{speed}, 0.0, 0.0]\n\
         [run]\nhorizon = 0.12\nsample_dt = 0.001\n"
    );
    let run = simulate_spatial(&scene_from_toml(&text), &RunOptions::default()).unwrap();
    let recoil = (1.0 + e) * speed * ball_mass / (ball_mass + frame_mass);
    let expected = e * speed;
    let v = run.final_velocities[0];
    assert!((v - expected).abs() <= recoil + 4.0 * F32_SOLVE * speed, "the ball leaves at {v} m/s, expected {expected}");
    assert_eq!(run.impact_count(), 1);
}
