//! The frame's motion between impulses, shared by every model: `M x'' + c x' + k x = 0` in closed form, for every damping regime
//! (under-, critically and over-damped, `k = 0`, `c = 0`) through one formula,
//!
//! `x(t) = x0 E(t) + (v0 + sigma x0) F(t)`, `v(t) = v0 E(t) - (w0^2 x0 + sigma v0) F(t)`,
//!
//! where `E = e^{-sigma t} C(t)`, `F = e^{-sigma t} S(t)` and `(C, S)` is `(cos wt, sin(wt)/w)`,
//! `(1, t)` or `(cosh bt, sinh(bt)/b)`. `S` is written so that it stays accurate as `w` or `b`
//! tends to zero, so near-critical damping loses no precision. The same basis gives the
//! acceleration (itself a solution of the ODE), its sign changes, and the energy dissipated.

use std::f64::consts::PI;

/// Damping regime, with the constants its basis needs.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Regime {
    /// `sigma^2 < w0^2`: `w = sqrt(w0^2 - sigma^2)`.
    Under { w: f64 },
    /// `sigma^2 = w0^2`.
    Critical,
    /// `sigma^2 > w0^2`: `b = sqrt(sigma^2 - w0^2)`, roots `r1 = -sigma + b` (computed without
    /// cancellation), `r2 = -sigma - b`.
    Over { b: f64, r1: f64, r2: f64 },
}

/// A damped oscillator `M x'' + c x' + k x = 0` (mass `M` may include balls stuck to the frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Oscillator {
    /// `M`.
    pub mass: f64,
    /// `c`.
    pub damping: f64,
    /// `k`.
    pub stiffness: f64,
    /// `c / 2M`.
    pub sigma: f64,
    /// `k / M`.
    pub w0sq: f64,
    regime: Regime,
}

impl Oscillator {
    /// The oscillator of mass `mass`, damping `damping` and stiffness `stiffness`.
    pub fn new(mass: f64, damping: f64, stiffness: f64) -> Self {
        let sigma = damping / (2.0 * mass);
        let w0sq = stiffness / mass;
        let lambda = sigma * sigma - w0sq;
        let regime = if lambda < 0.0 {
            Regime::Under { w: (-lambda).sqrt() }
        } else if lambda == 0.0 {
            Regime::Critical
        } else {
            let b = lambda.sqrt();
            // r1 r2 = w0^2, so r1 = -w0^2 / (sigma + b) avoids the cancellation in -sigma + b.
            let r1 = if sigma + b > 0.0 { -w0sq / (sigma + b) } else { 0.0 };
            Regime::Over { b, r1, r2: -sigma - b }
        };
        Oscillator { mass, damping, stiffness, sigma, w0sq, regime }
    }

    /// The damped angular frequency, when the oscillator oscillates.
    pub fn damped_omega(&self) -> Option<f64> {
        match self.regime {
            Regime::Under { w } => Some(w),
            _ => None,
        }
    }

    /// `(E(t), F(t))`.
    #[inline]
    pub fn basis(&self, t: f64) -> (f64, f64) {
        match self.regime {
            Regime::Under { w } => {
                let decay = (-self.sigma * t).exp();
                let (s, c) = (w * t).sin_cos();
                (decay * c, decay * s / w)
            }
            Regime::Critical => {
                let decay = (-self.sigma * t).exp();
                (decay, decay * t)
            }
            Regime::Over { b, r1, r2 } => {
                let e1 = (r1 * t).exp();
                let e2 = (r2 * t).exp();
                // e^{r1 t} - e^{r2 t} = e^{r2 t} expm1(2 b t): exact as b -> 0.
                (0.5 * (e1 + e2), e2 * (2.0 * b * t).exp_m1() / (2.0 * b))
            }
        }
    }

    /// State `(x, v)` a time `t` after the state `(x0, v0)`.
    #[inline]
    pub fn state(&self, x0: f64, v0: f64, t: f64) -> (f64, f64) {
        let (e, f) = self.basis(t);
        (x0 * e + (v0 + self.sigma * x0) * f, v0 * e - (self.w0sq * x0 + self.sigma * v0) * f)
    }

    /// Acceleration `-(c v + k x)/M` at state `(x, v)`.
    #[inline]
    pub fn accel(&self, x: f64, v: f64) -> f64 {
        -2.0 * self.sigma * v - self.w0sq * x
    }

    /// The state transition over a fixed step `h`: `[x; v](t + h) = P [x; v](t)`.
    pub fn transition(&self, h: f64) -> [[f64; 2]; 2] {
        let (e, f) = self.basis(h);
        [[e + self.sigma * f, f], [-self.w0sq * f, e - self.sigma * f]]
    }

    /// The first time `t > after` at which the solution `y` with `y(0) = y0`, `y'(0) = y1`
    /// changes sign (for the acceleration: where the force on the frame reverses).
    pub fn next_sign_change(&self, y0: f64, y1: f64, after: f64) -> Option<f64> {
        let q = y1 + self.sigma * y0;
        match self.regime {
            Regime::Under { w } => {
                if y0 == 0.0 && q == 0.0 {
                    return None;
                }
                // y ~ cos(w t - phi): zero where w t = phi + pi/2 + k pi.
                let phi = (q / w).atan2(y0);
                let base = phi + 0.5 * PI;
                let mut k = ((w * after - base) / PI).floor();
                let mut t = (base + k * PI) / w;
                while t <= after {
                    k += 1.0;
                    t = (base + k * PI) / w;
                }
                Some(t)
            }
            Regime::Critical => {
                // y ~ y0 + q t.
                let t = -y0 / q;
                (q != 0.0 && t > after).then_some(t)
            }
            Regime::Over { b, .. } => {
                // y ~ y0 cosh(bt) + (q/b) sinh(bt): tanh(bt) = -y0 b / q.
                if q == 0.0 {
                    return None;
                }
                let z = -y0 * b / q;
                if z <= 0.0 || z >= 1.0 {
                    return None;
                }
                let t = z.atanh() / b;
                (t > after).then_some(t)
            }
        }
    }

    /// Energy dissipated by the damper, `c * integral_0^t v^2`, starting from `(x0, v0)`.
    ///
    /// For an oscillating frame this is the closed-form integral, independent of the motion
    /// formula, so the energy balance checks one against the other. Near-critical and
    /// non-oscillating frames use the energy identity (the integral's closed form cancels
    /// catastrophically there); the balance then checks the impacts alone.
    pub fn dissipated(&self, x0: f64, v0: f64, t: f64) -> f64 {
        if self.damping == 0.0 || t <= 0.0 {
            return 0.0;
        }
        match self.regime {
            Regime::Under { w } if w * w >= 0.01 * self.w0sq => {
                // v = e^{-sigma t} (v0 cos wt + (wc / w) sin wt), wc = -(w0^2 x0 + sigma v0).
                let p = v0;
                let q = -(self.w0sq * x0 + self.sigma * v0) / w;
                let a = 2.0 * self.sigma;
                let bb = 2.0 * w;
                let decay = (-a * t).exp();
                let i0 = if a == 0.0 { t } else { -(-a * t).exp_m1() / a };
                let (s2, c2) = (bb * t).sin_cos();
                let den = a * a + bb * bb;
                let ic = (a - decay * (a * c2 - bb * s2)) / den;
                let is = (bb - decay * (a * s2 + bb * c2)) / den;
                // (p cos + q sin)^2 = (p^2+q^2)/2 + (p^2-q^2)/2 cos 2wt + p q sin 2wt.
                self.damping * (0.5 * (p * p + q * q) * i0 + 0.5 * (p * p - q * q) * ic + p * q * is)
            }
            _ => {
                let (x, v) = self.state(x0, v0, t);
                let energy = |x: f64, v: f64| 0.5 * self.mass * v * v + 0.5 * self.stiffness * x * x;
                energy(x0, v0) - energy(x, v)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RK4 with a tiny step as an independent check of every regime.
    fn rk4(o: &Oscillator, x0: f64, v0: f64, t: f64) -> (f64, f64, f64) {
        let n = 200_000;
        let h = t / n as f64;
        let (mut x, mut v, mut diss) = (x0, v0, 0.0);
        let f = |x: f64, v: f64| (v, o.accel(x, v), o.damping * v * v);
        for _ in 0..n {
            let k1 = f(x, v);
            let k2 = f(x + 0.5 * h * k1.0, v + 0.5 * h * k1.1);
            let k3 = f(x + 0.5 * h * k2.0, v + 0.5 * h * k2.1);
            let k4 = f(x + h * k3.0, v + h * k3.1);
            x += h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
            v += h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
            diss += h / 6.0 * (k1.2 + 2.0 * k2.2 + 2.0 * k3.2 + k4.2);
        }
        (x, v, diss)
    }

    #[test]
    fn every_regime_matches_rk4() {
        // (M, c, k): paper frame, critical, over, near-critical both sides, k = 0, free.
        let cases = [
            (1.35, 1.092, 865.0),
            (1.0, 2.0, 1.0),
            (1.0, 10.0, 4.0),
            (1.0, 2.0 * (1.0f64 - 1e-9).sqrt(), 1.0),
            (1.0, 2.0 * (1.0f64 + 1e-9).sqrt(), 1.0),
            (2.0, 3.0, 0.0),
            (1.0, 0.0, 0.0),
            (1.0, 0.0, 50.0),
        ];
        for (m, c, k) in cases {
            let o = Oscillator::new(m, c, k);
            let (x, v) = o.state(0.02, -0.3, 0.7);
            let (xr, vr, dr) = rk4(&o, 0.02, -0.3, 0.7);
            // RK4 at h = 3.5e-6 is accurate to ~1e-13 of these magnitudes.
            assert!((x - xr).abs() < 1e-11, "x {m} {c} {k}: {x} vs {xr}");
            assert!((v - vr).abs() < 1e-10, "v {m} {c} {k}: {v} vs {vr}");
            let d = o.dissipated(0.02, -0.3, 0.7);
            assert!((d - dr).abs() < 1e-11, "dissipation {m} {c} {k}: {d} vs {dr}");
        }
    }

    #[test]
    fn sign_changes_are_roots_of_the_acceleration() {
        for (m, c, k) in [(1.35, 1.092, 865.0), (1.0, 2.0, 1.0), (1.0, 10.0, 4.0)] {
            let o = Oscillator::new(m, c, k);
            let (x0, v0) = (0.01, 2.0);
            let a0 = o.accel(x0, v0);
            let j0 = -2.0 * o.sigma * a0 - o.w0sq * v0;
            if let Some(t) = o.next_sign_change(a0, j0, 0.0) {
                let (x, v) = o.state(x0, v0, t);
                let scale = o.w0sq * x0.abs() + 2.0 * o.sigma * v0.abs();
                assert!(o.accel(x, v).abs() < 1e-12 * scale, "{m} {c} {k}");
                let (xa, va) = o.state(x0, v0, 0.99 * t);
                let (xb, vb) = o.state(x0, v0, 1.01 * t);
                assert!(o.accel(xa, va) * o.accel(xb, vb) < 0.0);
            }
        }
    }
}
