//! The frame's motion between impulses, shared by every model: `M x'' + c x' + k x = 0` in closed form, for every damping regime
//! (under-, critically and over-damped, `k = 0`, `c = 0`) through one formula,
//!
//! `x(t) = x0 E(t) + (v0 + sigma x0) F(t)`, `v(t) = v0 E(t) - (w0^2 x0 + sigma v0) F(t)`,
//!
//! where `E = e^{-sigma t} C(t)`, `F = e^{-sigma t} S(t)` and `(C, S)` is `(cos wt, sin(wt)/w)`,
//! `(1, t)` or `(cosh bt, sinh(bt)/b)`. `S` is written so that it stays accurate as `w` or `b`
//! tends to zero, so near-critical damping loses no precision. The same basis gives the
//! acceleration (itself a solution of the ODE), its sign changes, and the energy dissipated.
//!
//! Under harmonic forcing `P sin(wt) + Q cos(wt)` the motion is that closed form applied to the
//! departure from the steady response [`Harmonic`] (the particular solution), plus it.

use std::f64::consts::PI;

/// Ulps of round-off that one evaluation of a closed form may accumulate, with a factor of two
/// to spare (see [`Oscillator::roundoff`]).
pub const ROUNDOFF_ULPS: f64 = 16.0;

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
    /// [`Oscillator::w0`], [`Oscillator::rate`] and [`Oscillator::f_cap`], which every
    /// round-off bound asks for.
    w0: f64,
    rate: f64,
    f_cap: f64,
}

/// A bound on `|F(t)|` for every `t >= 0` (`F <= t` always; this caps it): `1/w` oscillating,
/// `1/(2b)` overdamped, `1/(e sigma)` critical, infinite without damping or spring.
fn f_cap(regime: Regime, sigma: f64) -> f64 {
    match regime {
        Regime::Under { w } => 1.0 / w,
        Regime::Over { b, .. } => 1.0 / (2.0 * b),
        Regime::Critical if sigma > 0.0 => 1.0 / (std::f64::consts::E * sigma),
        Regime::Critical => f64::INFINITY,
    }
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
        let w0 = w0sq.sqrt();
        Oscillator { mass, damping, stiffness, sigma, w0sq, regime, w0, rate: 2.0 * (sigma + w0), f_cap: f_cap(regime, sigma) }
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

    /// The fastest rate (1/s) at which the basis turns or decays, `2 (sigma + w0)`: the
    /// round-off of evaluating it at `t` grows as `1 + rate t` (the rounding of the arguments
    /// of `exp`, `sin` and `cos`), see [`Oscillator::roundoff`].
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// The undamped angular frequency `w0 = sqrt(k / M)`, rad/s.
    pub fn w0(&self) -> f64 {
        self.w0
    }

    /// A bound on `|F(t)|` for every `t >= 0` ([`f_cap`]).
    fn f_cap(&self) -> f64 {
        self.f_cap
    }

    /// A bound on `|y(t)|` for all `t >= 0` of the solution with `y(0) = y0`, `y'(0) = y1`,
    /// `sqrt(y0^2 + y1^2 / w0^2)`: with damping `>= 0` its `y'^2 + w0^2 y^2` never grows (its
    /// derivative is `-4 sigma y'^2`). `None` without a spring or with negative damping. The
    /// frame's position, velocity and acceleration are such solutions.
    pub fn envelope(&self, y0: f64, y1: f64) -> Option<f64> {
        (self.w0sq > 0.0 && self.sigma >= 0.0).then(|| (y0 * y0 + y1 * y1 / self.w0sq).sqrt())
    }

    /// A bound on the round-off of evaluating `y(t) = y0 E(t) + (y1 + sigma y0) F(t)` (the
    /// first component of [`Oscillator::state`]) in floating point, for any `t >= 0`.
    ///
    /// `|E| <= 1` and `|F| <= min(t, f_cap)` for `sigma >= 0`; `E` and `F` are computed with
    /// a relative error of a few ulps plus the rounding of their arguments, `eps rate t`; the
    /// products and the sum add a few ulps more. [`ROUNDOFF_ULPS`] covers all of it with a
    /// factor of two to spare. It is the margin that the reference's root isolation adds to
    /// every bound it clears an interval with (docs/MODEL.md, "Finding contacts in floating
    /// point").
    pub fn roundoff(&self, y0: f64, y1: f64, t: f64) -> f64 {
        let t = t.max(0.0);
        ROUNDOFF_ULPS * f64::EPSILON * (2.0 + self.rate() * t) * (y0.abs() + (y1 + self.sigma * y0).abs() * t.min(self.f_cap()))
    }

    /// For an oscillating solution `y` with `y(0) = y0`, `y'(0) = y1` (`y ~ cos(w t - phi)`),
    /// the phase `phi + pi / 2` at which its zeros fall, `w t = phi + pi/2 + k pi`: one `atan2`
    /// per solution, which [`Oscillator::next_sign_change`] would otherwise repeat per call.
    pub fn zero_phase(&self, y0: f64, y1: f64) -> Option<f64> {
        match self.regime {
            Regime::Under { w } if y0 != 0.0 || y1 + self.sigma * y0 != 0.0 => Some(((y1 + self.sigma * y0) / w).atan2(y0) + 0.5 * PI),
            _ => None,
        }
    }

    /// The first zero after `after` of an oscillating solution whose zeros have phase `base`
    /// ([`Oscillator::zero_phase`]), angular frequency `w`.
    #[inline]
    pub fn next_zero(w: f64, base: f64, after: f64) -> f64 {
        let mut k = ((w * after - base) / PI).floor();
        let mut t = (base + k * PI) / w;
        while t <= after {
            k += 1.0;
            t = (base + k * PI) / w;
        }
        t
    }

    /// The first time `t > after` at which the solution `y` with `y(0) = y0`, `y'(0) = y1`
    /// changes sign (for the acceleration: where the force on the frame reverses).
    pub fn next_sign_change(&self, y0: f64, y1: f64, after: f64) -> Option<f64> {
        let q = y1 + self.sigma * y0;
        match self.regime {
            // `zero_phase` is `None` for the solution that is identically zero.
            Regime::Under { w } => Some(Self::next_zero(w, self.zero_phase(y0, y1)?, after)),
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

/// The steady response `xp(t) = X sin(w t) + Z cos(w t)` of an oscillator to the load
/// `P sin(w t) + Q cos(w t)`: the particular solution added to the closed form under forcing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Harmonic {
    /// `X`, m.
    pub sin: f64,
    /// `Z`, m.
    pub cos: f64,
    /// `w`, rad/s.
    pub omega: f64,
}

impl Harmonic {
    /// The `n`-th time derivative of `xp` at `t`.
    #[inline]
    pub fn derivative(&self, t: f64, n: u32) -> f64 {
        let (s, c) = (self.omega * t).sin_cos();
        let scale = self.omega.powi(n as i32);
        // Each derivative turns (sin, cos) a quarter turn: d/dt (X s + Z c) = w (X c - Z s).
        scale
            * match n % 4 {
                0 => self.sin * s + self.cos * c,
                1 => self.sin * c - self.cos * s,
                2 => -(self.sin * s + self.cos * c),
                _ => -(self.sin * c - self.cos * s),
            }
    }
    /// `xp` and its first four derivatives at `t` (one `sin_cos` for all).
    #[inline]
    pub fn derivatives(&self, t: f64) -> [f64; 5] {
        let (s, c) = (self.omega * t).sin_cos();
        let (p, q) = (self.sin * s + self.cos * c, self.sin * c - self.cos * s);
        let w = self.omega;
        [p, w * q, -w * w * p, -w * w * w * q, w * w * w * w * p]
    }
    /// `(xp, xp')` at `t`.
    #[inline]
    pub fn state(&self, t: f64) -> (f64, f64) {
        let (s, c) = (self.omega * t).sin_cos();
        (self.sin * s + self.cos * c, self.omega * (self.sin * c - self.cos * s))
    }
    /// A bound on the round-off of [`Harmonic::derivative`] `n` at `t`: a few ulps of
    /// `w^n (|X| + |Z|)`, plus the rounding of the phase `w t` (see [`Oscillator::roundoff`]).
    pub fn roundoff(&self, t: f64, n: u32) -> f64 {
        ROUNDOFF_ULPS * f64::EPSILON * self.omega.powi(n as i32) * (self.sin.abs() + self.cos.abs()) * (2.0 + (self.omega * t).abs())
    }
    /// Amplitude `sqrt(X^2 + Z^2)`, m.
    pub fn amplitude(&self) -> f64 {
        self.sin.hypot(self.cos)
    }
}

impl Oscillator {
    /// The steady response to `p sin(omega t) + q cos(omega t)`. An undamped oscillator driven
    /// exactly at resonance has none (scene validation refuses that case); the result is then
    /// infinite.
    pub fn harmonic_response(&self, p: f64, q: f64, omega: f64) -> Harmonic {
        let d = self.stiffness - self.mass * omega * omega;
        let cw = self.damping * omega;
        let det = d * d + cw * cw;
        Harmonic { sin: (d * p + cw * q) / det, cos: (d * q - cw * p) / det, omega }
    }
}

/// An oscillator with its optional harmonic load: the exact motion between any two times.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Driven {
    /// The free oscillator.
    pub osc: Oscillator,
    /// Its steady response to the load, when loaded.
    pub xp: Option<Harmonic>,
}

impl Driven {
    /// `osc` under the load `p sin(w t) + q cos(w t)` given as `(p, q, w)`, or free.
    pub fn new(osc: Oscillator, load: Option<(f64, f64, f64)>) -> Self {
        Driven { osc, xp: load.map(|(p, q, w)| osc.harmonic_response(p, q, w)) }
    }
    /// State at `t1` of the motion that has state `(x0, v0)` at `t0`.
    #[inline]
    pub fn state(&self, x0: f64, v0: f64, t0: f64, t1: f64) -> (f64, f64) {
        match &self.xp {
            None => self.osc.state(x0, v0, t1 - t0),
            Some(xp) => {
                let (p0, q0) = xp.state(t0);
                let (xh, vh) = self.osc.state(x0 - p0, v0 - q0, t1 - t0);
                let (p1, q1) = xp.state(t1);
                (xh + p1, vh + q1)
            }
        }
    }
}

/// Two integrals over `[a, b]` at once by 8-point Gauss-Legendre on pieces no longer than
/// `piece`: exact to round-off for integrands built from sines and decaying exponentials of
/// rate `w` when `w piece <= pi / 4` (error about `(w piece)^16 / 16!`).
pub fn gauss_legendre(a: f64, b: f64, piece: f64, mut f: impl FnMut(f64) -> [f64; 2]) -> [f64; 2] {
    const NODES: [f64; 4] = [0.183_434_642_495_649_8, 0.525_532_409_916_329, 0.796_666_477_413_626_7, 0.960_289_856_497_536_3];
    const WEIGHTS: [f64; 4] = [0.362_683_783_378_362, 0.313_706_645_877_887_3, 0.222_381_034_453_374_5, 0.101_228_536_290_376_3];
    if b <= a {
        return [0.0, 0.0];
    }
    let pieces = ((b - a) / piece).ceil().max(1.0);
    let h = (b - a) / pieces;
    let mut sum = [0.0, 0.0];
    for k in 0..pieces as usize {
        let mid = a + (k as f64 + 0.5) * h;
        for (node, weight) in NODES.iter().zip(WEIGHTS) {
            for t in [mid - 0.5 * h * node, mid + 0.5 * h * node] {
                let [y0, y1] = f(t);
                sum[0] += weight * y0;
                sum[1] += weight * y1;
            }
        }
    }
    [0.5 * h * sum[0], 0.5 * h * sum[1]]
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

    #[test]
    fn harmonic_response_solves_the_forced_equation() {
        for (m, c, k, w) in [(1.35, 1.092, 865.0, 20.0), (2.0, 0.0, 50.0, 3.0), (1.0, 40.0, 100.0, 0.5), (1.0, 0.3, 0.0, 7.0)] {
            let o = Oscillator::new(m, c, k);
            let (p, q) = (3.0, -1.5);
            let h = o.harmonic_response(p, q, w);
            for t in [0.0, 0.1, 0.77, 3.0] {
                let lhs = m * h.derivative(t, 2) + c * h.derivative(t, 1) + k * h.derivative(t, 0);
                let rhs = p * (w * t).sin() + q * (w * t).cos();
                assert!((lhs - rhs).abs() <= 1e-12 * (p.abs() + q.abs()), "{lhs} vs {rhs}");
                let (x, v) = h.state(t);
                assert_eq!((x, v), (h.derivative(t, 0), h.derivative(t, 1)));
            }
        }
    }

    #[test]
    fn gauss_legendre_is_exact_for_smooth_periodic_integrands() {
        let w = 7.0;
        let piece = std::f64::consts::PI / (4.0 * w);
        let [a, b] = gauss_legendre(0.3, 2.9, piece, |t| [(w * t).sin().powi(2), (-0.5 * t).exp() * (w * t).cos()]);
        let exact_a = 0.5 * (2.9 - 0.3) - ((2.0 * w * 2.9).sin() - (2.0 * w * 0.3).sin()) / (4.0 * w);
        // ∫ e^{-t/2} cos(wt) = e^{-t/2} (w sin wt - cos(wt)/2) / (w^2 + 1/4).
        let prim = |t: f64| (-0.5 * t).exp() * (w * (w * t).sin() - 0.5 * (w * t).cos()) / (w * w + 0.25);
        assert!((a - exact_a).abs() < 1e-14, "{a} vs {exact_a}");
        assert!((b - (prim(2.9) - prim(0.3))).abs() < 1e-14);
    }

    #[test]
    fn driven_motion_is_the_forced_solution() {
        let osc = Oscillator::new(1.35, 1.092, 865.0);
        let d = Driven::new(osc, Some((2.0, 0.5, 30.0)));
        // Against RK4 on the forced equation with a fine step.
        let (mut x, mut v, t0) = (0.01, -0.2, 0.4);
        let (xe, ve) = d.state(x, v, t0, t0 + 0.5);
        let f = |t: f64, x: f64, v: f64| (2.0 * (30.0 * t).sin() + 0.5 * (30.0 * t).cos() - 1.092 * v - 865.0 * x) / 1.35;
        let n = 50_000;
        let h = 0.5 / n as f64;
        for k in 0..n {
            let t = t0 + k as f64 * h;
            let (k1x, k1v) = (v, f(t, x, v));
            let (k2x, k2v) = (v + 0.5 * h * k1v, f(t + 0.5 * h, x + 0.5 * h * k1x, v + 0.5 * h * k1v));
            let (k3x, k3v) = (v + 0.5 * h * k2v, f(t + 0.5 * h, x + 0.5 * h * k2x, v + 0.5 * h * k2v));
            let (k4x, k4v) = (v + h * k3v, f(t + h, x + h * k3x, v + h * k3v));
            x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        }
        assert!((x - xe).abs() < 1e-12 && (v - ve).abs() < 1e-10, "{x} {xe} {v} {ve}");
    }
}
