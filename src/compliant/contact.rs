//! The contact law: Hertz's elastic force between spheres (or a sphere and a flat wall) with
//! Hunt-Crossley damping, `F = K d^(3/2) (1 + alpha d')`, never pulling (`F >= 0`), and the
//! choice of `alpha` that gives each impact the scene's coefficient of restitution.
//!
//! With `d = L u`, `t = (L / v0) s` and `L = (m v0^2 / K)^(2/5)` an isolated impact at approach
//! speed `v0` becomes `u'' = -u^(3/2) (1 + c u')`, `u(0) = 0`, `u'(0) = 1`, whose only
//! parameter is `c = alpha v0`: the coefficient of restitution is a function of `c` alone
//! ([`restitution`]). It is decreasing, from 1 at `c = 0` towards 0 as `c` grows, so for a
//! given `e` one `c` is found once by bracketing ([`damping_for`]) and every impact uses
//! `alpha = c / v0`.

use super::integrator::{bracketed_root, next_step, Dopri5};
use crate::scene::CompliantSettings;

/// Smallest coefficient of restitution the law is asked for. The restitution of the
/// Hunt-Crossley law reaches 0 only as `alpha v0` goes to infinity, so a scene with a smaller
/// `e` (down to 0) gets this one: it loses `1 - 1e-6` of the relative kinetic energy instead
/// of all of it, and its contacts stay integrable.
pub const MIN_RESTITUTION: f64 = 1e-3;

/// Contact duration of an elastic Hertz impact in units of `L / v0`:
/// `2 (5/4)^(2/5) sqrt(pi) Gamma(7/5) / Gamma(9/10)` (the integral of
/// `(1 - x^(5/2))^(-1/2)` over `[0, 1]` times `2 d_max / v0`).
pub const ELASTIC_DURATION: f64 = 2.0 * 1.0933620739432781 * 1.7724538509055159 * 0.8872638175030753 / 1.0686287021193193;

/// The effective modulus `E*` of two bodies of one material: `1/E* = 2 (1 - nu^2) / E`.
pub fn effective_modulus(m: &CompliantSettings) -> f64 {
    m.youngs_modulus / (2.0 * (1.0 - m.poisson_ratio * m.poisson_ratio))
}

/// Hertz's stiffness `K = 4/3 E* sqrt(R*)`, N/m^(3/2).
pub fn stiffness(effective_modulus: f64, effective_radius: f64) -> f64 {
    4.0 / 3.0 * effective_modulus * effective_radius.sqrt()
}

/// `R* = R1 R2 / (R1 + R2)`; a flat wall (`None`) gives `R1`.
pub fn effective_radius(r1: f64, r2: Option<f64>) -> f64 {
    r2.map_or(r1, |r2| r1 * r2 / (r1 + r2))
}

/// The contact force for overlap `d` growing at `rate`, or 0 when the bodies do not touch or
/// the damping would make the force pull.
#[inline]
pub fn force(k: f64, alpha: f64, d: f64, rate: f64) -> f64 {
    if d <= 0.0 {
        return 0.0;
    }
    (k * d * d.sqrt() * (1.0 + alpha * rate)).max(0.0)
}

/// The elastic energy stored at overlap `d`: `2/5 K d^(5/2)`.
#[inline]
pub fn elastic_energy(k: f64, d: f64) -> f64 {
    if d <= 0.0 {
        0.0
    } else {
        0.4 * k * d * d * d.sqrt()
    }
}

/// The length scale `L = (m v^2 / K)^(2/5)` of an impact of reduced mass `m` at speed `v`.
pub fn length_scale(m: f64, v: f64, k: f64) -> f64 {
    (m * v * v / k).powf(0.4)
}

/// Largest overlap of an elastic impact: `(5 m v^2 / (4 K))^(2/5)`.
pub fn max_overlap(m: f64, v: f64, k: f64) -> f64 {
    (1.25 * m * v * v / k).powf(0.4)
}

/// Restitution and duration (in units of `L / v0`) of the dimensionless impact with damping
/// `c = alpha v0`, integrated to about 1e-12.
pub fn impact(c: f64) -> (f64, f64) {
    let mut f = |_s: f64, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[1];
        dy[1] = -force(1.0, c, y[0], y[1]);
    };
    let scale = [1e-13, 1e-13];
    let mut rk = Dopri5::new(2);
    let mut y = [0.0, 1.0];
    let mut dy = [1.0, 0.0];
    let (mut s, mut h) = (0.0, 1e-3);
    // Overdamped contacts creep back at speed ~1/c over a distance ~c^(-2/5): bounded, but long.
    for _ in 0..10_000_000 {
        rk.step(&mut f, s, &y, &dy, h);
        let err = rk.error_norm(&scale);
        let h_next = next_step(h, err);
        if err <= 1.0 {
            if s > 0.0 && rk.y1[0] <= 0.0 {
                // The overlap is concave while the bodies touch: one crossing in this step.
                let theta = bracketed_root(|th| rk.dense_component(0, th), 0.0, 1.0, 1e-15);
                return (-rk.dense_component(1, theta), s + theta * h);
            }
            s += h;
            y.copy_from_slice(&rk.y1);
            dy.copy_from_slice(rk.last_derivative());
        }
        h = h_next;
    }
    panic!("dimensionless impact with c = {c} did not end");
}

/// The coefficient of restitution of the Hunt-Crossley law at `c = alpha v0`.
pub fn restitution(c: f64) -> f64 {
    impact(c).0
}

/// The `c = alpha v0` whose restitution is `e` (`e` below [`MIN_RESTITUTION`] is raised to it;
/// `e = 1` gives 0), to about 1e-10 in restitution.
pub fn damping_for(e: f64) -> f64 {
    let e = e.clamp(MIN_RESTITUTION, 1.0);
    if e >= 1.0 {
        return 0.0;
    }
    // Hunt and Crossley's linearisation, e = 1 - 2c/3, starts the bracket.
    let mut hi = 1.5 * (1.0 - e) / e;
    while restitution(hi) > e {
        hi *= 2.0;
    }
    bracketed_root(|c| restitution(c) - e, 0.0, hi, 1e-13 * hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elastic_impact_has_hertz_duration() {
        let (e, duration) = impact(0.0);
        assert!((e - 1.0).abs() < 1e-10, "{e}");
        assert!((duration / ELASTIC_DURATION - 1.0).abs() < 1e-9, "{duration} vs {ELASTIC_DURATION}");
    }

    #[test]
    fn light_damping_follows_hunt_crossley_linearisation() {
        let c = 1e-4;
        let e = restitution(c);
        assert!(((1.0 - e) / c / (2.0 / 3.0) - 1.0).abs() < 1e-3, "{e}");
    }

    #[test]
    fn inversion_recovers_restitution() {
        for e in [0.999, 0.94, 0.9, 0.5, 0.1, 0.0] {
            let c = damping_for(e);
            let got = restitution(c);
            assert!((got - e.max(MIN_RESTITUTION)).abs() < 1e-9, "e {e}: c {c} gives {got}");
        }
        assert_eq!(damping_for(1.0), 0.0);
    }
}
