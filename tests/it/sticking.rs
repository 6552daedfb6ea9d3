//! Persistent contact: balls resting on an accelerating wall, perfectly inelastic impacts,
//! many balls and zero gaps finish in a bounded number of events with the balance intact and
//! no ball outside the container.

use crate::common;

use crate::common::reference;
use common::*;
use lpc_damper::run::Run;
use lpc_damper::scene::Scene;

/// Checks common to every sticking scene; `max_events` is a generous bound on the events a
/// collapse-free solver needs (each impact plus a few holds and releases).
fn check(scene: &Scene, max_events: u64) -> Run {
    let run = reference(scene).unwrap();
    assert!(run.events <= max_events, "{} events (bound {max_events})", run.events);
    assert!(run.energy.balance_error.abs() <= 1e-12, "balance error {:e}", run.energy.balance_error);
    assert!(min_gap(scene, &run) >= -1e-12, "overlap {:e}", min_gap(scene, &run));
    assert!(run.series.xs().iter().all(|x| x.is_finite()));
    run
}

#[test]
fn ball_resting_on_an_accelerating_wall_moves_with_it() {
    // Delta = 0 and xs0 < 0: the left wall starts by pushing the ball, which must ride on it
    // (same velocity) while the wall accelerates to the right, then fly off.
    let scene = damper(PAPER_FRAME, -0.0185, &[0.11], 0.9, 0.0, 0.03, 1.0);
    let run = check(&scene, 10_000);
    // Until the frame's acceleration reverses (a quarter period, ~0.062 s), the ball and the
    // wall move together: same velocity at every sample.
    let quarter = 0.25 * PAPER_FRAME.damped_period();
    for k in 0..run.series.len() {
        if run.series.t()[k] < 0.9 * quarter {
            assert_eq!(run.series.v(0)[k], run.series.vs()[k], "t = {}", run.series.t()[k]);
        }
    }
    // And it leaves the wall afterwards.
    let k = run.series.t().partition_point(|&t| t < 1.5 * quarter);
    assert!(run.series.x(0)[k] - scene.balls[0].radius - run.series.xs()[k] > 1e-4);
}

#[test]
fn perfectly_inelastic_balls_collapse_without_stalling() {
    let scene = damper(PAPER_FRAME, 0.0185, &[0.11, 0.011, 0.11], 0.0, 0.0037, 0.0297, 5.0);
    check(&scene, 100_000);
}

#[test]
fn twenty_balls_with_zero_gaps() {
    let masses: Vec<f64> = (0..20).map(|i| if i % 2 == 0 { 0.11 } else { 0.011 }).collect();
    for e in [0.0, 0.5, 0.9, 1.0] {
        let scene = damper(PAPER_FRAME, 0.0185, &masses, e, 0.0, 0.01, 5.0);
        check(&scene, 200_000);
    }
}

#[test]
fn packed_container_moves_as_one_body() {
    // No gaps and no clearance: the balls fill the container; the system is a single oscillator
    // of mass ms + sum(m), which loses energy only through cs.
    let masses = [0.11, 0.011, 0.11];
    let scene = damper(PAPER_FRAME, 0.0185, &masses, 0.9, 0.0, 0.0, 2.0);
    let run = check(&scene, 1_000);
    let total = PAPER_FRAME.mass + masses.iter().sum::<f64>();
    let sigma = PAPER_FRAME.damping / (2.0 * total);
    let wd = (PAPER_FRAME.stiffness / total - sigma * sigma).sqrt();
    for (k, &t) in run.series.t().iter().enumerate() {
        let x = 0.0185 * (-sigma * t).exp() * ((wd * t).cos() + sigma / wd * (wd * t).sin());
        assert!((run.series.xs()[k] - x).abs() < 1e-12, "t = {t}");
    }
    assert!(run.impact_loss_is_zero());
}

trait ImpactLoss {
    fn impact_loss_is_zero(&self) -> bool;
}
impl ImpactLoss for Run {
    fn impact_loss_is_zero(&self) -> bool {
        self.energy.impact_loss.abs() < 1e-15
    }
}

#[test]
fn elastic_ball_chattering_on_a_wall_is_bounded() {
    // e = 1 and a ball starting on the wall the frame pushes: grazing contacts repeat, but the
    // stick rule turns them into riding, so the event count stays small.
    let scene = damper(PAPER_FRAME, -0.0185, &[0.11], 1.0, 0.0, 0.03, 5.0);
    check(&scene, 100_000);
}

#[test]
fn stiff_and_soft_frames() {
    use lpc_damper::scene::Frame;
    for frame in [
        Frame { mass: 1.35, stiffness: 865.0 * 1e4, damping: 1.092 }, // period 2.5 ms
        Frame { mass: 1.35, stiffness: 0.0, damping: 1.092 },         // no spring
        Frame { mass: 1.35, stiffness: 865.0, damping: 200.0 },       // over-damped
        Frame { mass: 1.35, stiffness: 865.0, damping: 2.0 * (865.0f64 * 1.35).sqrt() }, // critical
    ] {
        let scene = damper(frame, 0.0185, &[0.11, 0.011, 0.11], 0.9, 0.0037, 0.0297, 5.0);
        check(&scene, 1_000_000);
    }
}

#[test]
fn a_longer_contact_duration_merges_a_squeeze_sooner() {
    // A light ball (660 times lighter) between a heavy one and the wall (the regression scene of
    // issue 6) bounces ever faster as the heavy one closes in; a pair that strikes again within
    // the contact duration `t_c` is merged (docs/MODEL.md §4). Up to the first repeat within the
    // longer duration the two runs are the same impacts; there the longer one merges and the
    // default goes on bouncing.
    let short = scene_from_toml(crate::regressions::squeezed_ball_stops::SCENE);
    let mut long = short.clone();
    long.reference.contact_duration = 1e-4;
    let (by_default, by_long) = (check(&short, 10_000), check(&long, 10_000));
    let first_repeat = (1..by_default.impacts.len())
        .find(|&k| {
            let i = &by_default.impacts[k];
            by_default.impacts[..k].iter().rev().find(|p| (p.a, p.b) == (i.a, i.b)).is_some_and(|p| i.t - p.t < 1e-4)
        })
        .expect("the squeeze repeats within 0.1 ms");
    assert!(by_long.impacts.len() < by_default.impacts.len());
    assert_eq!(by_long.impacts[..first_repeat], by_default.impacts[..first_repeat]);
}
