//! The compliant (Hertz + Hunt-Crossley) model against closed forms and the reference: single
//! impacts give the scene's restitution with momentum kept, elastic impacts last and peak as
//! Hertz says, a wall of a free frame bounces a ball as Eq. 9-10 do, a wall carries a resting
//! ball, the energy balance closes to the integration error, the paper scene follows the
//! reference to within what finite contact durations explain, touching chains work, and runs
//! are repeatable.
//!
//! Tolerances: the integrator keeps each step's error below `tol = 1e-9` of the scene's
//! scales (the Hertz length at its speed scale, and that speed); an impact takes about 10^2
//! steps, so quantities set by one impact at the scene's speed are good to about 1e-7 relative
//! and are checked at 1e-6.
//!
//! Issue 18: packed and pressed contacts cost what their motion needs (the packed column and a
//! plastic light ball between heavy ones, each once stopped by millions of explicit steps).

use crate::common;
use crate::common::compliant;
use lpc_damper::compliant::contact;
use lpc_damper::impact_law::impact_law;
use lpc_damper::model::{Limits, ModelError, OverBudget, RunOptions};
use lpc_damper::run::Run;
use lpc_damper::scene::DEFAULT_COMPLIANT_TOLERANCE as DEFAULT_TOLERANCE;
use lpc_damper::scene::{
    ball_radius, load_scene, parse, scenes_dir, Ball, BallKind, CompliantSettings, Container, Forcing, ForcingKind, Frame, RapierSettings,
    Scene,
};
use lpc_damper::studies::compare::errors;
use lpc_damper::Model;

const STEEL: f64 = 8000.0;
/// Quantities set by one impact (see the module docs).
const ONE_IMPACT: f64 = 1e-6;

fn ball(m: f64) -> Ball {
    Ball { mass: m, radius: ball_radius(m, STEEL), kind: BallKind::Custom }
}

/// Hertz stiffness of two steel bodies of radii `r1` and `r2` (`None`: a flat wall).
fn hertz(r1: f64, r2: Option<f64>) -> f64 {
    let e_star = contact::effective_modulus(&CompliantSettings::default());
    contact::stiffness(e_star, contact::effective_radius(r1, r2))
}

/// Free balls on a line: `masses` left to right, `gap` apart, the first moving right at `v`.
fn free_balls(masses: &[f64], gap: f64, v: f64, e: f64, horizon: f64) -> Scene {
    let mut speeds = vec![0.0; masses.len()];
    speeds[0] = v;
    let gaps = vec![gap; masses.len().saturating_sub(1)];
    common::free_chain(masses.iter().map(|&m| ball(m)).collect(), &gaps, &speeds, e, horizon, horizon / 10.0)
}

/// One ball of mass `m` in a container on `frame`, `clearance` from the wall it moves towards
/// at `v` (right wall for `v > 0`), 10 mm from the other.
fn ball_in_frame(frame: Frame, xs0: f64, m: f64, v: f64, clearance: f64, e: f64, horizon: f64) -> Scene {
    let b = ball(m);
    let far = 0.01;
    let (left, right) = if v > 0.0 { (far, clearance) } else { (clearance, far) };
    Scene {
        name: "ball-in-frame".into(),
        frame: Some(frame),
        container: Some(Container { length: left + 2.0 * b.radius + right, gap: left, clearance: right }),
        reference_radius: b.radius,
        space: lpc_damper::scene::Space::line(1),
        balls: vec![b],
        restitution: e,
        initial_displacement: xs0,
        initial_positions: vec![xs0 + left + b.radius],
        initial_velocities: vec![v],
        horizon,
        sample_dt: horizon / 10.0,
        reference: lpc_damper::scene::ReferenceSettings::default(),
        rapier: RapierSettings::default(),
        compliant: CompliantSettings::default(),
        forcing: None,
        structure: None,
        dampers: vec![],
    }
}

fn run(scene: &Scene) -> Run {
    compliant(scene).unwrap()
}

/// Elastic Hertz impact of reduced mass `m` at speed `v`: (duration, peak force).
fn hertz_closed_form(m: f64, v: f64, k: f64) -> (f64, f64) {
    let d_max = (5.0 * m * v * v / (4.0 * k)).powf(0.4);
    (contact::ELASTIC_DURATION * contact::length_scale(m, v, k) / v, k * d_max.powf(1.5))
}

#[test]
fn ball_ball_impact_has_the_scene_restitution_and_keeps_momentum() {
    for (m1, m2) in [(0.11, 0.11), (0.11, 0.011), (0.011, 0.11)] {
        let k = hertz(ball(m1).radius, Some(ball(m2).radius));
        let mu = m1 * m2 / (m1 + m2);
        for v in [0.05, 1.4, 5.0] {
            let (t_c, _) = hertz_closed_form(mu, v, k);
            let gap = 1e-5;
            for e in [1.0, 0.94, 0.5, 0.1] {
                // Long enough for the slowest (most damped) contact to end.
                let scene = free_balls(&[m1, m2], gap, v, e, gap / v + 20.0 * t_c);
                let r = run(&scene);
                let [v1, v2] = r.final_velocities[..] else { panic!() };
                let cor = (v2 - v1) / v;
                assert!((cor - e).abs() <= ONE_IMPACT, "m {m1}/{m2} v {v} e {e}: COR {cor}");
                let p0 = m1 * v;
                assert!((m1 * v1 + m2 * v2 - p0).abs() <= 1e-12 * p0, "momentum {} vs {p0}", m1 * v1 + m2 * v2);
                assert_eq!(r.impacts.len(), 1, "{:?}", r.impacts);
                let imp = r.impacts[0];
                assert!((imp.approach_speed / v - 1.0).abs() <= 1e-12, "approach speed {}", imp.approach_speed);
                let lost = 0.5 * (1.0 - e * e) * mu * v * v;
                assert!((imp.energy_lost - lost).abs() <= ONE_IMPACT * 0.5 * mu * v * v, "lost {} vs {lost}", imp.energy_lost);
                assert!(r.energy.balance_error.abs() <= ONE_IMPACT, "balance {:e}", r.energy.balance_error);
            }
        }
    }
}

#[test]
fn elastic_impact_lasts_and_peaks_as_hertz_says() {
    let (m1, m2) = (0.11, 0.011);
    let (r1, r2) = (ball(m1).radius, ball(m2).radius);
    let k = hertz(r1, Some(r2));
    let mu = m1 * m2 / (m1 + m2);
    let e_star = contact::effective_modulus(&CompliantSettings::default());
    for v in [0.05, 1.4, 5.0] {
        let (t_c, f_max) = hertz_closed_form(mu, v, k);
        let r = run(&free_balls(&[m1, m2], 1e-5, v, 1.0, 1e-5 / v + 5.0 * t_c));
        let imp = r.impacts[0];
        let duration = imp.contact_duration.unwrap();
        let peak = imp.peak_force.unwrap();
        assert!((duration / t_c - 1.0).abs() <= ONE_IMPACT, "v {v}: duration {duration} vs {t_c}");
        assert!((peak / f_max - 1.0).abs() <= ONE_IMPACT, "v {v}: peak {peak} vs {f_max}");
        // The textbook form, whose constant 2.87 is rounded (exact: 2.868).
        let r_star = r1 * r2 / (r1 + r2);
        let textbook = 2.87 * (mu * mu / (r_star * e_star * e_star * v)).powf(0.2);
        assert!((duration / textbook - 1.0).abs() <= 1e-3, "v {v}: {duration} vs {textbook}");
    }
}

#[test]
fn wall_of_a_free_frame_bounces_a_ball_as_eq_9_10() {
    // No spring, no damper: nothing but the contact acts during the impact, so the two-body
    // law holds to the integration error.
    let frame = Frame { mass: 1.35, stiffness: 0.0, damping: 0.0 };
    let m = 0.11;
    for v in [0.5f64, -0.5, 2.0] {
        for e in [1.0, 0.9, 0.3] {
            let k = hertz(ball(m).radius, None);
            let mu = m * frame.mass / (m + frame.mass);
            let (t_c, _) = hertz_closed_form(mu, v.abs(), k);
            let clearance = 1e-5;
            let scene = ball_in_frame(frame, 0.0, m, v, clearance, e, clearance / v.abs() + 20.0 * t_c);
            let r = run(&scene);
            let (vb, vf, _) = impact_law(m, v, frame.mass, 0.0, e);
            let vs = *r.series.vs().last().unwrap();
            assert!((r.series.t().last().unwrap() - scene.horizon).abs() < 1e-12);
            assert!((r.final_velocities[0] - vb).abs() <= ONE_IMPACT * v.abs(), "v {v} e {e}: ball {} vs {vb}", r.final_velocities[0]);
            assert!((vs - vf).abs() <= ONE_IMPACT * v.abs(), "v {v} e {e}: frame {vs} vs {vf}");
            assert_eq!(r.impacts.len(), 1);
            let imp = r.impacts[0];
            let wall = if v > 0.0 { lpc_damper::scene::Body::RightWall } else { lpc_damper::scene::Body::LeftWall };
            assert!(imp.a == wall || imp.b == wall, "{imp:?}");
            // Momentum of ball and frame together, to round-off.
            assert!((m * r.final_velocities[0] + frame.mass * vs - m * v).abs() <= 1e-12 * m * v.abs());
            // With no spring and no damper the frame's true acceleration is the wall force over
            // its mass; sampled at step ends, about 40 a contact, so within (pi/40)^2/2 of the
            // peak (and never above it).
            let true_peak = r.peak_true_acceleration.unwrap();
            let force_peak = imp.peak_force.unwrap() / frame.mass;
            assert!(true_peak <= force_peak * (1.0 + 1e-9), "v {v} e {e}: {true_peak} > {force_peak}");
            assert!(
                true_peak >= force_peak * (1.0 - 0.5 * (std::f64::consts::PI / 40.0).powi(2)),
                "v {v} e {e}: {true_peak} vs {force_peak}"
            );
        }
    }
}

#[test]
fn a_wall_that_pushes_carries_a_resting_ball() {
    // The paper's frame released from xs0 < 0 accelerates right; its left wall touches a ball
    // at rest and pushes it for a quarter period. The ball rides on a Hertz spring of natural
    // frequency ~1e4 rad/s, so it follows the wall to within a / omega ~ 1e-3 m/s.
    let frame = Frame { mass: 1.35, stiffness: 865.0, damping: 1.092 };
    let mut scene = ball_in_frame(frame, -0.0185, 0.11, -1e-9, 0.0, 0.9, 0.06);
    scene.initial_velocities[0] = 0.0;
    scene.sample_dt = 1e-3;
    let r = run(&scene);
    let s = &r.series;
    let vmax = s.vs().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(vmax > 0.3, "the frame should swing: {vmax}");
    for k in 0..s.len() {
        assert!((s.v(0)[k] - s.vs()[k]).abs() <= 1e-2 * vmax, "t {}: ball {} frame {}", s.t()[k], s.v(0)[k], s.vs()[k]);
    }
    assert!(r.energy.balance_error.abs() <= r.events as f64 * DEFAULT_TOLERANCE, "balance {:e}", r.energy.balance_error);
}

#[test]
fn paper_scene_balances_energy_to_the_integration_error() {
    let scene = load_scene(scenes_dir().join("lpc-lsl.toml")).unwrap();
    let mut last = f64::INFINITY;
    for tol in [1e-9, 1e-10] {
        let r = compliant(&with_tolerance(&scene, tol)).unwrap();
        let err = r.energy.balance_error.abs();
        // Each step errs by at most tol of the contact's scales; the errors add up at worst.
        assert!(err <= r.events as f64 * tol, "tol {tol:e}: balance {err:e} after {} steps", r.events);
        // And it is integration error: it falls with the tolerance (about tenfold per decade).
        assert!(err < last / 3.0, "tol {tol:e}: balance {err:e}, was {last:e}");
        last = err;
        assert!(r.impacts.iter().all(|i| i.energy_lost >= -1e-12 * r.energy.initial));
        let listed: f64 = r.impacts.iter().map(|i| i.energy_lost).sum();
        assert!((listed - r.energy.impact_loss).abs() <= r.events as f64 * tol * r.energy.initial);
    }
    // With an excitation the forcing work joins the account.
    for kind in [ForcingKind::Force, ForcingKind::Base] {
        let mut forced = scene.clone();
        forced.horizon = 2.0;
        forced.forcing = Some(Forcing { kind, amplitude: if kind == ForcingKind::Force { 2.0 } else { 2e-3 }, frequency: 4.0 });
        let r = run(&forced);
        assert!(r.energy.forcing_work.abs() > 1e-3 * r.energy.initial, "{kind:?}: work {}", r.energy.forcing_work);
        assert!(
            r.energy.balance_error.abs() <= r.events as f64 * DEFAULT_TOLERANCE,
            "{kind:?}: balance {:e} after {} steps",
            r.energy.balance_error,
            r.events
        );
    }
}

#[test]
fn paper_scene_follows_the_reference_within_what_contact_durations_explain() {
    // An impact lasts t_c ~ 5e-5 s (ball-ball) to 1.2e-4 s (ball-wall) instead of an instant,
    // and the bodies leave it about t_c later than the reference's impulse. The delays add up
    // along a ball's impacts: the first 0.5 s has 4 wall impacts, each after some 6 ball-ball
    // impacts, so each lands ~3e-4 s off, and its jump of the frame's velocity,
    // (1 + e) m_L u / (ms + m_L) ~ 0.12 m/s at u ~ 0.85 m/s, moves xs by ~0.12 x 3e-4 = 36 um;
    // the four, with growing delays, give ~0.1-0.2 mm. Bound: 0.25 mm (1.4 % of xs0).
    let scene = load_scene(scenes_dir().join("lpc-lsl.toml")).unwrap();
    let mut early = scene.clone();
    early.horizon = 0.5;
    let reference = Model::Reference.simulate(&early, &RunOptions::default()).unwrap();
    let soft = errors(&run(&early), &reference).max_xs_early;
    assert!(soft <= 0.25e-3, "max |xs - xs_ref| over 0.5 s: {soft:e} m");
    // And the difference is that duration: t_c ~ E^(-2/5), so 100 times stiffer balls shrink
    // it 100^(2/5) = 6.3 times (the impact sequence being the same).
    let mut stiff = early.clone();
    stiff.compliant.youngs_modulus *= 100.0;
    let stiff_err = errors(&run(&stiff), &reference).max_xs_early;
    let ratio = soft / stiff_err;
    assert!((4.5..9.0).contains(&ratio), "error {soft:e} -> {stiff_err:e} (ratio {ratio})");
    let full = run(&scene);
    let count = Model::Reference.simulate(&scene, &RunOptions::default()).unwrap().impacts.len() as f64;
    assert!((full.impacts.len() as f64 - count).abs() <= 0.1 * count, "{} impacts vs {count}", full.impacts.len());
}

#[test]
fn touching_chain_passes_momentum_and_balances_energy() {
    // Gap 0: the chain's balls touch at rest, and the incident ball's pulse squeezes each pair
    // from zero overlap rate. With e = 1 nothing is lost; with e < 1 what is lost is booked.
    for e in [1.0, 0.94] {
        let text = format!(
            "[chain]\nlarge_counts = [3]\nsmall_balls = [false, true]\nlarge_mass = 0.11\nmass_ratio = 10.0\n\
             density = 8000.0\nrestitution = {e}\ngap = 0.0\nincident_speed = 1.4\n[run]\nhorizon = 0.01\nsample_dt = 0.0001\n"
        );
        let loaded = parse(&text, "touching", "touching").unwrap();
        for case in loaded.chain.unwrap() {
            let s = &case.scene;
            let r = run(s);
            let p: f64 = s.balls.iter().zip(&r.final_velocities).map(|(b, v)| b.mass * v).sum();
            let p0 = s.balls[0].mass * 1.4;
            assert!((p - p0).abs() <= 1e-12 * p0, "{}: momentum {p} vs {p0}", s.name);
            assert!(r.energy.balance_error.abs() <= r.events as f64 * DEFAULT_TOLERANCE, "{}: {:e}", s.name, r.energy.balance_error);
            let ker = lpc_damper::studies::chain::ker(s, &r);
            if e == 1.0 {
                assert!((ker - 1.0).abs() <= 1e-6, "{}: KER {ker}", s.name);
            } else {
                assert!(ker < 1.0 && ker > 0.3, "{}: KER {ker}", s.name);
            }
            // Everything separates: no pair still approaches at the end.
            for i in 1..s.balls.len() {
                assert!(r.final_velocities[i] >= r.final_velocities[i - 1] - 1e-9, "{}: {:?}", s.name, r.final_velocities);
            }
        }
    }
}

#[test]
fn runs_are_bitwise_repeatable() {
    let scene = load_scene(scenes_dir().join("lpc-lslsl.toml")).unwrap();
    let a = run(&scene);
    let b = run(&scene);
    assert_eq!(a.series, b.series);
    assert_eq!(a.impacts, b.impacts);
    assert_eq!(a.energy, b.energy);
}

#[test]
fn a_step_limit_stops_the_run_and_keeps_it_so_far() {
    let scene = load_scene(scenes_dir().join("lpc-lsl.toml")).unwrap();
    let err = Model::Compliant.simulate(&scene, &RunOptions::limited(Limits { max_steps: Some(3000), ..Limits::NONE })).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("lpc-lsl") && msg.contains("--max-steps"), "{msg}");
    let ModelError::OverBudget(stop) = err else { panic!("{msg}") };
    let OverBudget { t, steps, partial, .. } = *stop;
    assert_eq!(steps, 3000);
    assert!(t > 0.0 && t < scene.horizon);
    // The run so far is a run: its samples end by `t`, and its energy balance closes to the
    // integration tolerance as a finished run's does.
    assert_eq!(partial.horizon, t);
    assert!(!partial.series.t().is_empty() && *partial.series.t().last().unwrap() <= t);
    assert!(partial.energy.balance_error.abs() < 1e-6, "{:?}", partial.energy);
    let mut bad = scene.clone();
    bad.compliant.tolerance = 0.0;
    let refused = Model::Compliant.simulate(&bad, &RunOptions::default());
    assert!(refused.is_err_and(|e| e.to_string().contains("tolerance")));
}

/// Issue 18's packed column (45 balls, no gaps, e = 0.07): the budget stops it and says what
/// its steps cost (its open contacts and the stiffest of them).
const PACKED_COLUMN: &str = include_str!("../../examples/scenes/packed-column.toml");

#[test]
fn a_budget_says_what_the_steps_cost() {
    let scene = lpc_damper::scene::parse(PACKED_COLUMN, "packed.toml", "packed").unwrap().scene.unwrap();
    let err = Model::Compliant.simulate(&scene, &RunOptions::limited(Limits { max_steps: Some(20_000), ..Limits::NONE })).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("packed-column") && msg.contains("contacts open, the stiffest ball") && msg.contains("Hertz period"), "{msg}");
    // A wall-time budget of a nanosecond stops at the meter's first look, before the first step.
    let err = Model::Compliant.simulate(&scene, &RunOptions::limited(Limits { max_wall_s: Some(1e-9), ..Limits::NONE })).unwrap_err();
    let ModelError::OverBudget(stop) = err else { panic!("not a budget stop") };
    assert_eq!(stop.steps, 0);
    assert!(stop.budget_text().contains("--max-wall-time"), "{}", stop.budget_text());
}

#[test]
fn lpc_run_writes_the_run_a_budget_stopped() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let scene = scenes_dir().join("lpc-lsl.toml");
    let o = crate::common::lpc([
        "run".as_ref(),
        scene.as_os_str(),
        "--model".as_ref(),
        "compliant".as_ref(),
        "--max-steps".as_ref(),
        "5000".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("wrote the run up to t = ") && err.contains("--max-steps"), "{err}");
    let series = std::fs::read_to_string(out.join("series.csv")).unwrap();
    assert!(series.lines().count() > 10);
    // Every model takes the budgets: the reference stops at its event budget likewise.
    let o = crate::common::lpc(["run".as_ref(), scene.as_os_str(), "--max-steps".as_ref(), "50".as_ref()]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("the reference stopped") && err.contains("50 events (--max-steps)"), "{err}");
}

/// `scene` with the compliant model's error tolerance `tolerance`.
fn with_tolerance(scene: &Scene, tolerance: f64) -> Scene {
    let mut scene = scene.clone();
    scene.compliant.tolerance = tolerance;
    scene
}

/// `scene` with its horizon cut to `horizon`.
fn cut(mut scene: Scene, horizon: f64) -> Scene {
    scene.horizon = horizon;
    scene
}

/// Two runs of one scene at tolerances `tol` and `tol / 10`: the coarser one's impact loss and
/// final state are integration error away from the finer one's. Chaos amplifies a step's error
/// over a long run, so these runs are short.
fn converges(scene: &Scene, tol: f64, max_steps: u64) -> (Run, Run) {
    let options = RunOptions::limited(Limits { max_steps: Some(max_steps), ..Limits::NONE });
    let coarse = Model::Compliant.simulate(&with_tolerance(scene, tol), &options).unwrap();
    let fine = Model::Compliant.simulate(&with_tolerance(scene, tol / 10.0), &options).unwrap();
    for r in [&coarse, &fine] {
        assert!(
            r.energy.balance_error.abs() <= r.events as f64 * tol,
            "{}: balance {:e} after {} steps",
            scene.name,
            r.energy.balance_error,
            r.events
        );
    }
    (coarse, fine)
}

/// The packed column (45 balls, no gaps, e = 0.07) pressed by its frame: its first 0.1 s took
/// more than 38 million explicit steps (the old run stopped at 50 million at t = 0.13 s),
/// every one held to nanoseconds by contacts damped at up to 1e9 per second. Now the steps
/// follow the motion; the answer is the same at a tenth of the tolerance.
#[test]
fn packed_column_costs_what_its_motion_needs() {
    let scene = cut(parse(PACKED_COLUMN, "packed.toml", "packed").unwrap().scene.unwrap(), 0.1);
    let (coarse, fine) = converges(&scene, DEFAULT_TOLERANCE, 2_000_000);
    assert!(coarse.events < 1_000_000, "{} steps", coarse.events);
    let e0 = coarse.energy.initial;
    assert!((coarse.energy.impact_loss - fine.energy.impact_loss).abs() <= 1e-6 * e0, "{:?} vs {:?}", coarse.energy, fine.energy);
    assert!((coarse.energy.damping_loss - fine.energy.damping_loss).abs() <= 1e-6 * e0);
    // A column trembling in place is a few contacts, not one impact per tremble.
    assert!(coarse.impacts.len() < 10 * scene.balls.len(), "{} impacts", coarse.impacts.len());
}

/// A plastic (e = 0) light ball (0.36 g) between two 110 g balls in a swinging frame (stress
/// seed 31368): 11.9 s of computing for 0.53 s before; a few hundred thousand steps now.
#[test]
fn plastic_light_ball_between_heavy_ones_is_cheap_and_converged() {
    let toml = r#"
name = "pressed-plastic"
[frame]
mass = 1.35
stiffness = 422.516621135352
damping = 1.1220729756471255
initial_displacement = "-7.289504835503309 Rr"
[balls]
arrangement = "LSLL"
large_mass = 0.11
mass_ratio = 302.82669420812323
density = 8000.0
restitution = 0.0
gap = "0.008351146603002789 Rr"
clearance = "0.8617691946490968 Rr"
[run]
horizon = 0.5318965555637503
sample_dt = 0.00026594827778187515
"#;
    let scene = parse(toml, "plastic.toml", "plastic").unwrap().scene.unwrap();
    let (coarse, fine) = converges(&scene, DEFAULT_TOLERANCE, 1_000_000);
    assert!(coarse.events < 500_000, "{} steps", coarse.events);
    let e0 = coarse.energy.initial;
    assert!((coarse.energy.impact_loss - fine.energy.impact_loss).abs() <= 1e-6 * e0, "{:?} vs {:?}", coarse.energy, fine.energy);
    assert_eq!(coarse.impacts.len(), fine.impacts.len());
    // Momentum passes through the plastic contacts: the heavy balls' final speeds agree.
    for (a, b) in coarse.final_velocities.iter().zip(&fine.final_velocities) {
        assert!((a - b).abs() <= 1e-5 * coarse.final_velocities.iter().fold(0.0f64, |m, v| m.max(v.abs())), "{a} vs {b}");
    }
}
