//! The compliant model beyond one line (docs/MODEL.md §15): Hertz contacts with Hunt-Crossley
//! damping and a Coulomb-capped tangential force, balls free in 3D, against closed forms, the
//! one-line compliant model and the stress checks.

use crate::common::scene_from_toml;
use lpc_damper::compliant::spatial::STEPS_PER_CONTACT;
use lpc_damper::model::RunOptions;
use lpc_damper::scene::{load_scene, scenes_dir, Body, Scene};
use lpc_damper::studies::stress::judge;
use lpc_damper::Model;

/// A steel ball of radius 5 mm in a 5 cm box on a frame so heavy and stiff that its contacts
/// cannot move it: at `[x, y, z]` (m, x from the left wall, z from the box's middle) with
/// velocity `v`, under `gravity`, with restitution `e` and friction `mu`.
fn one_ball(p: [f64; 3], v: [f64; 3], gravity: f64, e: f64, mu: f64, horizon: f64) -> Scene {
    let [x, y, z] = p;
    let [vx, vy, vz] = v;
    scene_from_toml(&format!(
        r#"
[frame]
mass = 1e9
stiffness = 1e9
damping = 0.0
initial_displacement = 0.0
[container]
length = 0.05
width = 0.05
height = 0.05
[world]
gravity = [0.0, 0.0, {gravity}]
restitution = {e}
friction = {mu}
[[ball]]
position = [{x}, {y}, {z}]
velocity = [{vx}, {vy}, {vz}]
mass = 0.0040841
radius = 0.005
[run]
horizon = {horizon}
sample_dt = 0.0005
"#
    ))
}

/// Velocity Verlet errs in an impact's restitution by about the square of its phase step,
/// `(pi / STEPS_PER_CONTACT)^2`.
fn verlet_error() -> f64 {
    (std::f64::consts::PI / STEPS_PER_CONTACT).powi(2)
}

/// A ball bouncing between the end walls without gravity leaves each impact with `e` times its
/// approach speed, at any speed (the Hunt-Crossley damping is set from each approach speed).
#[test]
fn an_impact_has_the_scenes_restitution_at_any_speed() {
    let e = 0.6;
    for speed in [0.01, 1.0, 10.0] {
        // Friction (with no sliding) sends the scene to the spatial path.
        let horizon = 0.04 * (1.0 + 1.0 / e + 1.0 / (e * e)) / speed;
        let scene = one_ball([0.025, 0.0, 0.0], [speed, 0.0, 0.0], 0.0, e, 0.3, horizon);
        let run = Model::Compliant.simulate(&scene, &RunOptions::default()).unwrap();
        let speeds: Vec<f64> = run.impacts.iter().map(|i| i.approach_speed).collect();
        assert!(speeds.len() >= 3, "v = {speed}: {:?}", run.impacts);
        for w in speeds.windows(2) {
            assert!((w[1] / w[0] / e - 1.0).abs() <= verlet_error(), "v = {speed}: {} then {}", w[0], w[1]);
        }
        assert!((speeds[0] / speed - 1.0).abs() <= verlet_error(), "{}", speeds[0]);
        judge(Model::Compliant, &scene, &run).unwrap();
    }
}

/// A ball sliding on the floor with friction ends rolling at 5/7 of its speed: friction acts at
/// the contact point only, so the angular momentum about it is conserved (to round-off in
/// velocity Verlet, whose kicks change the linear and angular momenta by the same impulse).
/// What friction took is the run's contact loss.
#[test]
fn a_sliding_ball_ends_rolling_at_five_sevenths_of_its_speed() {
    let (v0, mu, g) = (1.0, 0.3, 9.81);
    let rolls_after = 2.0 * v0 / (7.0 * mu * g);
    let scene = one_ball([0.005, 0.0, -0.02], [v0, 0.0, 0.0], -g, 0.6, mu, 0.03);
    let mut scene = scene;
    scene.container.as_mut().unwrap().length = 0.5;
    scene.horizon = 1.5 * rolls_after;
    let run = Model::Compliant.simulate(&scene, &RunOptions::default()).unwrap();
    let v = run.final_velocities[0];
    assert!((v / (5.0 / 7.0 * v0) - 1.0).abs() <= 1e-9, "{v}");
    // Until it rolls it slides, decelerated by mu g: its weight rests on the floor within the
    // static overlap's tremble, whose share of the normal force is below the restitution error.
    let s = &run.series;
    let k = (0.5 * rolls_after / scene.sample_dt) as usize;
    let sliding = v0 - mu * g * s.t()[k];
    assert!((s.v(0)[k] - sliding).abs() <= verlet_error() * (v0 - sliding), "{} vs {sliding}", s.v(0)[k]);
    // Friction took 2/7 of the kinetic energy (rolling keeps 5/7 of it, spin included): the
    // run's contact loss, to the balance's stated integration error; the normal damping of
    // the resting contact took next to nothing.
    let e0 = 0.5 * scene.balls[0].mass * v0 * v0;
    let friction = run.energy.contact_loss;
    assert!((friction - 2.0 / 7.0 * e0).abs() <= verlet_error() * e0, "friction took {friction} J of {e0} J");
    assert!(run.energy.impact_loss.abs() <= verlet_error() * e0, "{:?}", run.energy);
    judge(Model::Compliant, &scene, &run).unwrap();
}

/// A ball dropped on the floor of a resting box lands at the free fall's time, and each bounce
/// leaves with `e` times its approach speed, less what gravity takes during the contact
/// (`g T_c`), and returns after the flight `2 v / g`.
#[test]
fn a_dropped_ball_bounces_at_the_closed_form_times() {
    let (e, g, drop): (f64, f64, f64) = (0.8, 9.81, 0.01);
    let z = -0.025 + 0.005 + drop;
    let fall = (2.0 * drop / g).sqrt();
    let scene = one_ball([0.025, 0.0, z], [0.0; 3], -g, e, 0.0, fall * (1.0 + 2.0 * e + 2.0 * e * e) + 0.002);
    let run = Model::Compliant.simulate(&scene, &RunOptions::default()).unwrap();
    let floor: Vec<_> = run.impacts.iter().filter(|i| i.b == Body::Floor).collect();
    assert_eq!(floor.len(), 3, "{:?}", run.impacts);
    // Onsets and ends are extrapolated from the steps either side: a step each at most.
    let step = |i: &lpc_damper::run::Impact| i.contact_duration.unwrap() / STEPS_PER_CONTACT;
    assert!((floor[0].t - fall).abs() <= step(floor[0]), "{} vs {fall}", floor[0].t);
    assert!((floor[0].approach_speed / (g * fall) - 1.0).abs() <= verlet_error(), "{}", floor[0].approach_speed);
    for w in floor.windows(2) {
        let (a, b) = (w[0], w[1]);
        let contact = a.contact_duration.unwrap();
        let leaves = e * a.approach_speed - g * contact;
        assert!((b.approach_speed - leaves).abs() <= verlet_error() * a.approach_speed, "{} then {}", a.approach_speed, b.approach_speed);
        let returns = a.t + contact + 2.0 * b.approach_speed / g;
        assert!((b.t - returns).abs() <= 2.0 * step(a), "{} vs {returns}", b.t);
    }
    judge(Model::Compliant, &scene, &run).unwrap();
}

/// Balls on one line without gravity (friction, with nothing sliding, sends the scene to the
/// spatial path): the one-line model's impacts and frame motion, early in the run, to the
/// integration error: each impact's speed within the restitution's error of one impact, its
/// onset within its contact's duration, and the frame within that error of its swing.
#[test]
fn balls_on_one_line_give_the_one_line_compliant_model() {
    let mut scene = load_scene(scenes_dir().join("lpc-lsl.toml")).unwrap();
    scene.horizon = 0.3;
    let line = Model::Compliant.simulate(&scene, &RunOptions::default()).unwrap();
    scene.space.section = [0.05, 0.05];
    scene.space.friction = 0.3;
    let spatial = Model::Compliant.simulate(&scene, &RunOptions::default()).unwrap();
    assert!(line.impacts.len() >= 15, "{}", line.impacts.len());
    assert_eq!(spatial.impacts.len(), line.impacts.len());
    for (a, b) in spatial.impacts.iter().zip(&line.impacts) {
        assert_eq!((a.a, a.b), (b.a, b.b), "at {} s", b.t);
        assert!((a.t - b.t).abs() <= b.contact_duration.unwrap(), "{} s against {} s", a.t, b.t);
        assert!((a.approach_speed / b.approach_speed - 1.0).abs() <= verlet_error(), "at {} s", b.t);
    }
    let (fa, fb) = (spatial.series.xs(), line.series.xs());
    let worst = fa.iter().zip(fb).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(worst <= verlet_error() * scene.initial_displacement, "frame apart by {worst} m");
    judge(Model::Compliant, &scene, &spatial).unwrap();
}

/// The shipped beds, shortened: the stress checks hold (energy balance to the integration
/// error, no ball outside beyond the contacts' deformation).
#[test]
fn shipped_beds_pass_the_stress_checks() {
    for name in ["planar-bed", "particle-box"] {
        let mut scene = load_scene(scenes_dir().join(format!("{name}.toml"))).unwrap();
        scene.horizon = 0.02;
        let run = Model::Compliant.simulate(&scene, &RunOptions::default()).unwrap();
        assert!(!run.impacts.is_empty(), "{name}");
        judge(Model::Compliant, &scene, &run).unwrap();
    }
}
