//! Property tests: every impact conserves momentum and never gains energy, for random masses,
//! speeds and restitution; whole random free chains conserve momentum and balance energy.

use crate::common;

use crate::common::reference;
use lpc_damper::impact_law::impact_law;
use lpc_damper::scene::{ball_radius, Ball, BallKind, Scene};
use proptest::prelude::*;

proptest! {
    #![proptest_config(common::proptest_config(2000))]

    #[test]
    fn impact_law_conserves_momentum_and_loses_what_it_reports(
        m1 in 1e-4f64..10.0, m2 in 1e-4f64..10.0, v1 in -5.0f64..5.0, v2 in -5.0f64..5.0, e in 0.0f64..=1.0,
    ) {
        let (a, b, lost) = impact_law(m1, v1, m2, v2, e);
        let p_scale = m1 * v1.abs() + m2 * v2.abs() + 1e-300;
        // A handful of roundings on each side: a few ulps of the largest momentum involved.
        prop_assert!((m1 * a + m2 * b - (m1 * v1 + m2 * v2)).abs() <= 1e-14 * p_scale);
        prop_assert!(lost >= 0.0);
        let ke = |x: f64, y: f64| 0.5 * m1 * x * x + 0.5 * m2 * y * y;
        let k_scale = ke(v1, v2) + 1e-300;
        prop_assert!((ke(v1, v2) - ke(a, b) - lost).abs() <= 1e-13 * k_scale);
        // Kinematic COR: the separation speed is e times the approach speed.
        prop_assert!(((b - a) + e * (v2 - v1)).abs() <= 1e-13 * (v1.abs() + v2.abs() + 1e-300));
    }
}

fn free_chain(masses: &[f64], gaps: &[f64], speeds: &[f64], e: f64) -> Scene {
    let balls = masses.iter().map(|&m| Ball { mass: m, radius: ball_radius(m, 8000.0), kind: BallKind::Custom }).collect();
    common::free_chain(balls, gaps, speeds, e, 1.0, 1e-2)
}

proptest! {
    #![proptest_config(common::proptest_config(300))]

    #[test]
    fn random_free_chains_conserve_momentum_and_balance_energy(
        balls in prop::collection::vec((1e-3f64..1.0, 0.0f64..0.01, -2.0f64..2.0), 2..12),
        e in 0.0f64..=1.0,
    ) {
        let masses: Vec<f64> = balls.iter().map(|b| b.0).collect();
        let gaps: Vec<f64> = balls.iter().map(|b| b.1).collect();
        let speeds: Vec<f64> = balls.iter().map(|b| b.2).collect();
        let scene = free_chain(&masses, &gaps, &speeds, e);
        let run = reference(&scene).unwrap();
        let p0: f64 = masses.iter().zip(&speeds).map(|(m, v)| m * v).sum();
        let p1: f64 = masses.iter().zip(&run.final_velocities).map(|(m, v)| m * v).sum();
        let scale: f64 = masses.iter().zip(&speeds).map(|(m, v)| m * v.abs()).sum::<f64>() + 1e-300;
        // Each momentum exchange rounds the momenta it touches by a few ulps (< 1e-15 of the
        // total); allow that per exchange on top of 1e-14 for the sums.
        let exchanges: u32 = run.impacts.iter().map(|i| i.impulses).sum();
        let bound = (1e-14 + 1e-15 * exchanges as f64) * scale;
        prop_assert!((p1 - p0).abs() <= bound, "momentum {p0} -> {p1}");
        prop_assert!(run.impacts.iter().all(|i| i.energy_lost >= 0.0));
        let roundoff = common::balance_roundoff(masses.len(), exchanges);
        prop_assert!(run.energy.balance_error.abs() <= roundoff, "balance {} after {exchanges} exchanges", run.energy.balance_error);
        prop_assert!(run.energy.final_ <= run.energy.initial * (1.0 + roundoff));
        prop_assert!(common::min_gap(&scene, &run) >= -1e-12);
    }
}
