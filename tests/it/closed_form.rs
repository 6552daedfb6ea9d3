//! The reference against problems solved by hand: the bare frame's free vibration, a single
//! ball on a free frame bouncing between the walls, and the first wall impact on a spring frame.

use crate::common;

use crate::common::reference;
use approx::assert_relative_eq;
use common::*;
use lpc_damper::scene::{Body, Frame};

/// Round-off bound for quantities built from a few dozen floating operations on O(1) data.
const ROUND_OFF: f64 = 1e-12;

#[test]
fn no_damper_follows_the_damped_oscillator() {
    let scene = lpc_damper::scene::load_scene(lpc_damper::scene::scenes_dir().join("no-damper.toml")).unwrap();
    let run = reference(&scene).unwrap();
    let f = scene.frame.unwrap();
    let sigma = f.damping / (2.0 * f.mass);
    let wd = (f.stiffness / f.mass - sigma * sigma).sqrt();
    let xs0 = scene.initial_displacement;
    assert_eq!(run.series.len(), 5001);
    for (k, &t) in run.series.t().iter().enumerate() {
        let x = xs0 * (-sigma * t).exp() * ((wd * t).cos() + sigma / wd * (wd * t).sin());
        let v = -xs0 * (-sigma * t).exp() * (sigma * sigma / wd + wd) * (wd * t).sin();
        assert!((run.series.xs()[k] - x).abs() <= ROUND_OFF * xs0, "xs at t = {t}");
        assert!((run.series.vs()[k] - v).abs() <= ROUND_OFF * xs0 * wd, "vs at t = {t}");
        let a = -(f.damping * v + f.stiffness * x) / f.mass;
        assert!((run.series.a()[k] - a).abs() <= ROUND_OFF * xs0 * wd * wd, "a at t = {t}");
    }
    assert!(run.impacts.is_empty());
    assert!(run.energy.balance_error.abs() <= ROUND_OFF);
    // Energy left after 5 s is exp(-2 sigma t) times the initial, up to the oscillating term.
    let e_ratio = run.energy.final_ / run.energy.initial;
    assert!(e_ratio > (-2.0 * sigma * 5.0).exp() * 0.9 && e_ratio < (-2.0 * sigma * 5.0).exp() * 1.1);
}

#[test]
fn one_ball_on_a_free_frame_bounces_as_worked_out_by_hand() {
    // Free frame (ks = cs = 0): between impacts both move uniformly, so every impact time and
    // velocity follows from Eq. 9-10 and distances alone.
    let (m_frame, m, e) = (1.35, 0.11, 0.9);
    let frame = Frame { mass: m_frame, stiffness: 0.0, damping: 0.0 };
    let (gap, clearance) = (0.004, 0.01);
    let mut scene = damper(frame, 0.0, &[m], e, gap, clearance, 1.0);
    let v0 = 0.5;
    scene.initial_velocities[0] = v0;
    let run = reference(&scene).unwrap();
    let r = scene.balls[0].radius;
    let free_path = scene.container.unwrap().length - 2.0 * r;

    // By hand: relative speed is multiplied by e at each impact; momentum m v0 is shared.
    let mut t = clearance / v0;
    let (mut vb, mut vf) = (v0, 0.0);
    for (k, imp) in run.impacts.iter().enumerate().take(6) {
        let expected_wall = if k % 2 == 0 { Body::RightWall } else { Body::LeftWall };
        let pair = if k % 2 == 0 { (Body::Ball(0), expected_wall) } else { (expected_wall, Body::Ball(0)) };
        assert_eq!((imp.a, imp.b), pair, "impact {k}");
        assert_relative_eq!(imp.t, t, max_relative = ROUND_OFF);
        let rel = (vb - vf).abs();
        assert_relative_eq!(imp.approach_speed, rel, max_relative = ROUND_OFF);
        let mu = m * m_frame / (m + m_frame);
        assert_relative_eq!(imp.energy_lost, 0.5 * (1.0 - e * e) * mu * rel * rel, max_relative = ROUND_OFF);
        let vcm = (m * vb + m_frame * vf) / (m + m_frame);
        let sign = if vb > vf { 1.0 } else { -1.0 };
        vb = vcm - sign * e * rel * m_frame / (m + m_frame);
        vf = vcm + sign * e * rel * m / (m + m_frame);
        t += free_path / (e * rel);
    }
    assert!(run.impacts.len() >= 6);
    // Total momentum m v0 is conserved exactly (no spring, no damper).
    let vs_end = *run.series.vs().last().unwrap();
    let vb_end = *run.series.v(0).last().unwrap();
    assert_relative_eq!(m * vb_end + m_frame * vs_end, m * v0, max_relative = ROUND_OFF);
}

#[test]
fn first_wall_impact_on_an_undamped_spring_frame() {
    // cs = 0: xs = xs0 cos(w t); the ball rests until the right wall reaches it:
    // xs(t1) + Le = x_ball + R  =>  t1 = acos((x_ball + R - Le) / xs0) / w.
    let frame = Frame { mass: 1.35, stiffness: 865.0, damping: 0.0 };
    let xs0 = 0.0185;
    let scene = damper(frame, xs0, &[0.11], 0.9, 0.004, 0.02, 0.2);
    let run = reference(&scene).unwrap();
    let w = (frame.stiffness / frame.mass).sqrt();
    let (x_ball, r, le) = (scene.initial_positions[0], scene.balls[0].radius, scene.container.unwrap().length);
    let t1 = ((x_ball + r - le) / xs0).acos() / w;
    let first = run.impacts[0];
    assert_eq!((first.a, first.b), (Body::Ball(0), Body::RightWall));
    assert_relative_eq!(first.t, t1, max_relative = ROUND_OFF);
    let vs = -xs0 * w * (w * t1).sin();
    assert_relative_eq!(first.approach_speed, -vs, max_relative = 1e-10);
    // Eq. 9: the ball (at rest) leaves with (1 + e) ms vs / (m + ms).
    let k = run.series.t().partition_point(|&t| t <= t1);
    let expected = (1.0 + 0.9) * frame.mass * vs / (0.11 + frame.mass);
    assert_relative_eq!(run.series.v(0)[k], expected, max_relative = 1e-10);
}
