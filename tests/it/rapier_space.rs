//! The contact model's spatial path (docs/MODEL.md §9, "Rapier"): balls free in 3D under
//! gravity and friction, bounced by the impact law along each contact's normal, against
//! closed forms, Eq. 9-10 and the one-line reference.

use crate::common::{reference, scene_from_toml, LSL_TOML};
use lpc_damper::model::RunOptions;
use lpc_damper::rapier::spatial::{
    self, energy_gain_allowance, simulate_spatial, simulate_spatial_with, solver_settings, RESTING_SINK_FRACTION, SPATIAL_ENERGY_GAIN,
};
use lpc_damper::scene::{load_scene, scenes_dir, Body, Scene};
use lpc_damper::studies::compare::errors;
use lpc_damper::Model;

/// Ball velocities live in f32 inside Rapier: a few roundings of 6e-8 relative each, and the
/// solver's f32 arithmetic, stay below 2e-6 relative (as on the one-line path).
const F32_SOLVE: f64 = 2e-6;

/// A steel ball of radius 5 mm dropped from rest at height `drop` (m, from its lowest point
/// to the floor) in a 0.6 m high box on a frame so heavy and stiff that impacts cannot move it,
/// under gravity, with restitution `e`, at steps of `dt`.
fn drop_scene(drop: f64, e: f64, dt: f64, horizon: f64) -> Scene {
    let (height, r) = (0.6, 0.005);
    let z = -0.5 * height + r + drop;
    scene_from_toml(&format!(
        r#"
[frame]
mass = 1e6
stiffness = 1e6
damping = 0.0
initial_displacement = 0.0
[container]
length = 0.05
width = 0.05
height = {height}
[world]
gravity = [0.0, 0.0, -9.81]
restitution = {e}
[[ball]]
position = [0.025, 0.0, {z}]
mass = 0.0040841
radius = {r}
[rapier]
dt = {dt}
[run]
horizon = {horizon}
sample_dt = 0.001
"#
    ))
}

/// A ball dropped on the floor rebounds with the scene's `e`: successive bounce heights
/// `v_k^2 / 2g` (v_k the approach speed of the k-th impact) are in ratio `e^2`.
///
/// Tolerance: each approach speed is reconstructed from the gap and velocity at the start of
/// the step in which the ball lands, assuming the exact parabola. Rapier's symplectic Euler
/// flight is an exact parabola whose velocity at each step's end is off by `g h / 2` from the
/// parabola through its positions, so each speed is within `g h / 2` (plus f32 round-off),
/// and a ratio of two speeds `v1, v2` within `g h / 2 (1/v1 + 1/v2)` relatively; the height
/// ratio, a square, within twice that.
#[test]
fn a_dropped_ball_rebounds_with_the_scenes_restitution() {
    let (e, g, h) = (0.6, 9.81, 1e-4);
    for speed in [0.1, 0.3, 1.0, 3.0] {
        let drop = speed * speed / (2.0 * g);
        // Three bounces: the fall, then flights of 2 e^k v / g.
        let horizon = speed / g + 2.0 * speed * (e + e * e + e * e * e) / g + 0.01;
        let scene = drop_scene(drop, e, h, horizon);
        assert!(spatial::needs_spatial(&scene));
        let run = Model::Rapier.simulate(&scene, &RunOptions::default()).unwrap();
        let floor: Vec<f64> = run.impacts.iter().filter(|i| i.b == Body::Floor).map(|i| i.approach_speed).collect();
        assert!(floor.len() >= 4, "v0 = {speed}: {:?}", run.impacts);
        let first = floor[0];
        assert!((first - speed).abs() <= 0.5 * g * h + F32_SOLVE * speed, "v0 = {speed}: first approach {first}: {:?}", run.impacts);
        for k in 0..3 {
            let (v1, v2) = (floor[k], floor[k + 1]);
            let ratio = (v2 / v1).powi(2);
            let tolerance = 2.0 * (0.5 * g * h * (1.0 / v1 + 1.0 / v2) + 2.0 * F32_SOLVE);
            assert!(
                (ratio / (e * e) - 1.0).abs() <= tolerance,
                "v0 = {speed}: bounce {k}: height ratio {ratio} vs e^2 = {}, tolerance {tolerance}",
                e * e
            );
        }
    }
}

/// A ball sliding on the floor of a resting box with friction ends rolling at 5/7 of its
/// speed, and what the contact took, friction's `2/7` of its kinetic energy and the weight's
/// work as the ball sank into Rapier's soft floor, is booked as the run's contact loss, not its
/// impacts'.
///
/// Tolerance: the loss booked in a step is the step's energy change (spin included) less
/// gravity's work, so the sum is the energy the ball lost; what is left is the f32 rounding of
/// the velocities, [`F32_SOLVE`] relative in each of some `2 v0 / (7 mu g h)` steps, and the
/// final speed's own error, by which Rapier's iterative friction solve misses rolling. The
/// account then closes to its round-off: every step's loss is in it.
#[test]
fn a_sliding_balls_friction_loss_is_its_contact_loss() {
    let (v0, mu, g, h) = (1.0, 0.3, 9.81, 1e-3);
    let m = 0.0040841;
    let rolls_after = 2.0 * v0 / (7.0 * mu * g);
    let scene = scene_from_toml(&format!(
        r#"
[frame]
mass = 1e6
stiffness = 1e6
damping = 0.0
initial_displacement = 0.0
[container]
length = 0.5
width = 0.05
height = 0.05
[world]
gravity = [0.0, 0.0, -{g}]
friction = {mu}
restitution = 0.6
[[ball]]
position = [0.05, 0.0, -0.02]
mass = {m}
radius = 0.005
velocity = [{v0}, 0.0, 0.0]
[rapier]
dt = {h}
[run]
horizon = {horizon}
sample_dt = 0.001
"#,
        horizon = 1.5 * rolls_after
    ));
    let run = simulate_spatial(&scene, &RunOptions::default()).unwrap();
    let v = run.final_velocities[0];
    let rolling = 5.0 / 7.0 * v0;
    let speed_error = (v - rolling).abs() / v0;
    assert!(speed_error <= 1e-3, "ends at {v} m/s, rolling is {rolling} m/s");
    let e0 = 0.5 * m * v0 * v0;
    let steps = rolls_after / h + 1.0;
    let tolerance = (steps * F32_SOLVE + 2.0 * speed_error) * e0;
    let s = &run.series;
    let sunk = -0.02 - s.across(0, s.len() - 1)[1];
    assert!((0.0..=RESTING_SINK_FRACTION * 0.005).contains(&sunk), "sank {sunk} m");
    let expected = 2.0 / 7.0 * e0 + m * g * sunk;
    let loss = run.energy.contact_loss;
    assert!((loss - expected).abs() <= tolerance, "contact loss {loss} J against {expected} J (sank {sunk} m)");
    assert!(run.impacts.is_empty() && run.energy.impact_loss == 0.0, "{:?}", run.impacts);
    assert!(run.energy.balance_error.abs() <= tolerance / e0, "{:?}", run.energy);
}

/// Two equal balls on one line in a box without gravity or friction, the first at `v0`
/// towards the second at rest, with `e = 1`.
fn head_on(v0: f64) -> Scene {
    scene_from_toml(&format!(
        r#"
[frame]
mass = 1e6
stiffness = 1e6
damping = 0.0
initial_displacement = 0.0
[container]
length = 0.2
width = 0.02
height = 0.02
[world]
restitution = 1.0
[[ball]]
position = [0.02, 0.0, 0.0]
mass = 0.0040841
radius = 0.005
velocity = [{v0}, 0.0, 0.0]
[[ball]]
position = [0.06, 0.0, 0.0]
mass = 0.0040841
radius = 0.005
[run]
horizon = 0.1
sample_dt = 0.001
"#
    ))
}

/// With `e = 1` a ball striking a resting equal ball head-on passes on its whole momentum: the
/// striker stops and the struck ball leaves at the striker's speed (Eq. 9-10). A rigid-body
/// engine's restitution gets this wrong; the plug-in's impact law does not.
#[test]
fn an_elastic_head_on_impact_passes_the_whole_momentum() {
    let v0 = 0.5;
    let scene = head_on(v0);
    // On one line without gravity or friction: the one-line path's scene, forced through the
    // spatial path.
    assert!(!spatial::needs_spatial(&scene));
    let run = simulate_spatial(&scene, &RunOptions::default()).unwrap();
    let balls: Vec<_> = run.impacts.iter().filter(|i| i.a == Body::Ball(0) && i.b == Body::Ball(1)).collect();
    assert_eq!(balls.len(), 1, "{:?}", run.impacts);
    assert!((balls[0].approach_speed - v0).abs() <= F32_SOLVE * v0);
    let [striker, struck] = [run.final_velocities[0], run.final_velocities[1]];
    assert!(striker.abs() <= F32_SOLVE * v0, "striker keeps {striker} m/s");
    assert!((struck - v0).abs() <= F32_SOLVE * v0, "struck ball leaves at {struck} m/s");
    assert!(run.energy.impact_loss == 0.0);
}

/// Two light balls that heavy ones strike towards each other (`e = 1`) leave at nearly twice
/// the heavy balls' speed and meet in the next step, closer than Rapier's broad phase boxed them
/// for at the end of the step before (it boxes colliders as far ahead as that step predicted,
/// from the heavy balls' speed). The boxes are made anew for the faster step, so Rapier stops
/// the pair at contact and the impact law bounces it, and no energy is lost. Missed, the pair
/// would sink into each other and Rapier's soft contact would part them, taking their energy.
#[test]
fn light_balls_kicked_towards_each_other_meet_without_loss() {
    // Steps of 0.4 ms, heavy balls (1 kg) at 2 m/s 0.4 mm from light ones (1 g): each strikes
    // its light ball half-way through the first step, which leaves the light balls 2.8 mm apart,
    // approaching at 8 m/s. The first step predicted 1.6 mm ahead (twice 2 m/s over the step),
    // and Rapier's boxes reach 0.04 length units (0.4 mm) beyond that each: pairs 2.4 mm apart.
    let (v, h, r) = (2.0, 0.0004, 0.005);
    let gap = 0.5 * v * h;
    let apart = 2.8e-3 + 2.0 * gap;
    let ball = |x: f64, mass: f64, v: f64| {
        format!("[[ball]]\nposition = [{x}, 0.0, 0.0]\nmass = {mass}\nradius = {r}\nvelocity = [{v}, 0.0, 0.0]\n")
    };
    let x = [0.05, 0.05 + 2.0 * r + gap, 0.05 + 4.0 * r + gap + apart, 0.05 + 6.0 * r + 2.0 * gap + apart];
    let scene = scene_from_toml(&format!(
        "[frame]\nmass = 1e6\nstiffness = 1e6\ndamping = 0.0\ninitial_displacement = 0.0\n\
         [container]\nlength = 0.2\nwidth = 0.02\nheight = 0.02\n[world]\nrestitution = 1.0\n[rapier]\ndt = {h}\n\
         [run]\nhorizon = {}\nsample_dt = {h}\n{}{}{}{}",
        2.0 * h,
        ball(x[0], 1.0, v),
        ball(x[1], 0.001, 0.0),
        ball(x[2], 0.001, 0.0),
        ball(x[3], 1.0, -v)
    ));
    assert_eq!(solver_settings(&scene).dt, h);
    let run = simulate_spatial(&scene, &RunOptions::default()).unwrap();
    let light = run.impacts.iter().find(|i| (i.a, i.b) == (Body::Ball(1), Body::Ball(2)));
    let light = light.unwrap_or_else(|| panic!("the light balls never struck each other: {:?}", run.impacts));
    assert!(light.approach_speed > 3.9 * v, "{light:?}");
    // Velocities in f32 (F32_SOLVE relative) on the heavy balls' energy.
    assert!(run.energy.contact_loss.abs() <= 2.0 * F32_SOLVE * run.energy.initial, "{:?}", run.energy);
}

/// A ball striking a resting row of two touching equal balls on the floor with `e = 1`
/// (Newton's cradle): §3's one pair at a time passes the whole momentum down the row, the
/// striker and the middle ball stopping and the last leaving at the striker's speed. Rapier's
/// speculative contact stops the striker at contact at the end of a step, before it touches the
/// row, so its solve moves no ball of the row, and the impact law and its knock-on then resolve
/// the row one pair at a time.
#[test]
fn a_ball_striking_a_touching_row_passes_the_momentum_down_the_row() {
    let v0 = 0.5;
    let run = simulate_spatial(&cradle(0.02, v0), &RunOptions::default()).unwrap();
    let v = &run.final_velocities;
    assert!(v[0].abs() <= F32_SOLVE * v0 && v[1].abs() <= F32_SOLVE * v0, "striker and middle ball keep {v:?} m/s");
    assert!((v[2] - v0).abs() <= F32_SOLVE * v0, "the last ball leaves at {} m/s", v[2]);
}

/// The same cradle with the striker 0.1 um from the row when the run starts, closer than
/// touching: the pairs touching at the start strike before the first step, one at a time, so
/// the momentum still passes down the row and no energy goes to Rapier's plastic solve (which
/// would move the row as one block: `(-0.097, 0.194, 0.403)` m/s before).
#[test]
fn a_ball_touching_a_row_at_the_start_passes_the_momentum_down_the_row() {
    let v0 = 0.5;
    let run = simulate_spatial(&cradle(0.05 - 1e-7, v0), &RunOptions::default()).unwrap();
    let v = &run.final_velocities;
    assert!(v[0].abs() <= F32_SOLVE * v0 && v[1].abs() <= F32_SOLVE * v0, "striker and middle ball keep {v:?} m/s");
    assert!((v[2] - v0).abs() <= F32_SOLVE * v0, "the last ball leaves at {} m/s", v[2]);
    let at_start: Vec<_> = run.impacts.iter().filter(|i| i.t == 0.0).map(|i| (i.a, i.b)).collect();
    assert_eq!(at_start, [(Body::Ball(0), Body::Ball(1)), (Body::Ball(1), Body::Ball(2))]);
    assert_eq!(run.energy.impact_loss, 0.0);
}

/// A striker at `x` moving at `v0` towards two equal balls touching at rest on the floor
/// (`e = 1`, under gravity: the spatial path).
fn cradle(x: f64, v0: f64) -> Scene {
    let mut text = "[frame]\nmass = 1e6\nstiffness = 1e6\ndamping = 0.0\ninitial_displacement = 0.0\n\
                    [container]\nlength = 0.2\nwidth = 0.02\nheight = 0.02\n\
                    [world]\nrestitution = 1.0\ngravity = [0.0, 0.0, -9.81]\n\
                    [run]\nhorizon = 0.1\nsample_dt = 0.001\n"
        .to_string();
    for (x, v) in [(x, v0), (0.06, 0.0), (0.07, 0.0)] {
        text += &format!("[[ball]]\nposition = [{x}, 0.0, -0.005]\nmass = 0.0040841\nradius = 0.005\nvelocity = [{v}, 0.0, 0.0]\n");
    }
    let scene = scene_from_toml(&text);
    assert!(spatial::needs_spatial(&scene));
    scene
}

/// Steps of the chain scenes, s: fixed steps land an impact up to a step late, which moves
/// the balls by up to their speed (about 0.5 m/s) times the step: 0.05 mm at 0.1 ms, a
/// quarter of the bound the comparisons use.
const CHAIN_DT: f64 = 1e-4;

/// Fig. 9's LSL chain in a box 2.2 Rr square, short, at steps of [`CHAIN_DT`].
fn lsl_in_a_box(restitution: f64, damping: f64, horizon: f64) -> Scene {
    let text = LSL_TOML
        .replace("restitution = 0.9", &format!("restitution = {restitution}"))
        .replace("damping = 1.092", &format!("damping = {damping}"))
        .replace("horizon = 5.0", &format!("horizon = {horizon}"));
    scene_from_toml(&format!("{text}\n[container]\nwidth = \"2.2 Rr\"\nheight = \"2.2 Rr\"\n[rapier]\ndt = {CHAIN_DT}\n"))
}

/// A chain in a box without gravity or friction, run through the spatial path, follows the
/// reference: the frame's displacement within the bound the one-line contact model meets on
/// the paper's scenes over the first 0.5 s (0.2 mm, tests/it/rapier_model.rs).
#[test]
fn a_chain_in_a_box_follows_the_reference() {
    let scene = lsl_in_a_box(0.9, 1.092, 0.6);
    let run = simulate_spatial(&scene, &RunOptions::default()).unwrap();
    let e = errors(&run, &reference(&scene).unwrap());
    assert!(e.max_xs_early <= 0.2e-3, "early error {:e} m", e.max_xs_early);
}

/// Three LSL chains side by side in their channels (scenes/lpc-lsl-3chains.toml) are coupled
/// through the frame only: the reference runs them exactly, and the spatial path follows it
/// within the same bound.
#[test]
fn three_chains_follow_the_reference() {
    let mut scene = load_scene(scenes_dir().join("lpc-lsl-3chains.toml")).unwrap();
    scene.horizon = 0.6;
    scene.rapier.dt = Some(CHAIN_DT);
    assert!(spatial::needs_spatial(&scene));
    assert_eq!(Model::Rapier.supports(&scene), Ok(()));
    let run = Model::Rapier.simulate(&scene, &RunOptions::default()).unwrap();
    let e = errors(&run, &reference(&scene).unwrap());
    assert!(e.max_xs_early <= 0.2e-3, "early error {:e} m", e.max_xs_early);
}

/// Without gravity, friction or damping and with `e = 1`, no energy is made: the final
/// energy stays within the model's stated tolerance of the initial, and no step's contacts
/// gained more than it.
#[test]
fn elastic_chains_gain_no_energy() {
    let scene = lsl_in_a_box(1.0, 0.0, 1.0);
    let (run, report) = simulate_spatial_with(&scene, solver_settings(&scene), &RunOptions::default()).unwrap();
    let e0 = run.energy.initial;
    assert!(run.energy.final_ <= e0 * (1.0 + SPATIAL_ENERGY_GAIN), "{:?}", run.energy);
    assert!(report.worst_step_gain <= SPATIAL_ENERGY_GAIN * e0, "{report:?}");
    assert!(run.impacts.len() > 20);
}

/// With gravity and friction (the particle box, shortened), the energy never grows beyond
/// the stated allowance, and the contacts' own loss is never negative beyond it.
#[test]
fn a_shaken_bed_gains_no_energy() {
    for name in ["particle-box", "planar-bed"] {
        let mut scene = load_scene(scenes_dir().join(format!("{name}.toml"))).unwrap();
        scene.horizon = 0.3;
        assert!(spatial::needs_spatial(&scene));
        let (run, report) = simulate_spatial_with(&scene, solver_settings(&scene), &RunOptions::default()).unwrap();
        let put_in = run.energy.initial + run.energy.forcing_work;
        assert!(run.energy.final_ <= put_in + energy_gain_allowance(&scene, put_in), "{name}: {:?}", run.energy);
        assert!(report.contact_loss >= -energy_gain_allowance(&scene, put_in), "{name}: {report:?}");
        // The particle box's bed rests on its floor: it sinks by a few percent of a radius
        // at most. (The planar bed's balls collide at speed; their deepest overlap is that
        // of a fast pair Rapier's speculative margin caught late, not of a resting bed.)
        if name == "particle-box" {
            assert!(report.deepest_overlap <= RESTING_SINK_FRACTION * 0.005, "{name}: {report:?}");
        }
    }
}

/// The one-line scenes still go to the one-line path: Rapier's `supports` accepts the
/// spatial scenes it can run and refuses a spatial scene without a frame.
#[test]
fn dispatch_sends_only_spatial_scenes_to_the_spatial_path() {
    for name in ["lpc-lsl", "lpc-lslsl", "conventional", "chain-lll"] {
        let scene = load_scene(scenes_dir().join(format!("{name}.toml"))).unwrap();
        assert!(!spatial::needs_spatial(&scene), "{name}");
    }
    for name in ["particle-box", "planar-bed", "lpc-lsl-3chains"] {
        let scene = load_scene(scenes_dir().join(format!("{name}.toml"))).unwrap();
        assert!(spatial::needs_spatial(&scene), "{name}");
        assert_eq!(Model::Rapier.supports(&scene), Ok(()), "{name}");
    }
}

/// A free frame (no spring, no dashpot) and balls moving across the container with friction
/// exchange x momentum through the walls only: the total, `ms vs + sum m vx`, stays what it
/// was at every sample. Tolerance: velocities are f32 inside Rapier, each impact rounds a
/// ball's velocity once (6e-8 relative) where the frame's is f64; a random walk over the
/// run's impacts stays below the one-line path's stated momentum drift (1e-5 of the scale).
#[test]
fn a_free_frame_and_its_balls_keep_their_momentum() {
    let scene = scene_from_toml(
        r#"
[frame]
mass = 0.2
stiffness = 0.0
damping = 0.0
initial_displacement = 0.0
[container]
length = 0.06
width = 0.04
height = 0.04
[world]
friction = 0.3
restitution = 0.8
[[ball]]
position = [0.01, -0.005, 0.0]
mass = 0.0040841
radius = 0.005
velocity = [0.4, 0.3, 0.1]
[[ball]]
position = [0.03, 0.005, 0.002]
mass = 0.0040841
radius = 0.005
velocity = [-0.2, -0.1, 0.25]
[[ball]]
position = [0.05, 0.0, -0.01]
mass = 0.0040841
radius = 0.005
velocity = [0.1, 0.2, -0.3]
[run]
horizon = 0.5
sample_dt = 0.001
"#,
    );
    assert!(spatial::needs_spatial(&scene));
    let run = Model::Rapier.simulate(&scene, &RunOptions::default()).unwrap();
    assert!(run.impacts.len() > 10, "{} impacts", run.impacts.len());
    let s = &run.series;
    let momentum = |k: usize| 0.2 * s.vs()[k] + (0..3).map(|i| 0.0040841 * s.v(i)[k]).sum::<f64>();
    let scale = 0.0040841 * (0.4 + 0.2 + 0.1);
    for k in 0..s.len() {
        assert!((momentum(k) - momentum(0)).abs() <= 1e-5 * scale, "t = {}: {} vs {}", s.t()[k], momentum(k), momentum(0));
    }
}
