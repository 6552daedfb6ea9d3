//! The periodic motion of a one-ball impact damper under a harmonic force, in closed form
//! (Masri & Caughey, J. Appl. Mech. 33, 1966; with a dashpot on the primary, Masri, J. Acoust.
//! Soc. Am. 47, 1970), derived here independently of the crate's oscillator module.
//!
//! The primary `M x'' + c x' + k x = F0 sin(w t)` carries a ball of mass `m` free to travel `d`
//! between its walls (ball centre relative to the frame in `[-d/2, d/2]`). The symmetric motion
//! with two impacts per forcing period has the ball strike the right wall at phase `phi = w tau`
//! and the left wall half a period later, with every state negated: the frame is at `X0` and
//! `-X0`, the frame moves at `v-`/`v+` before/after, the ball at `-u`/`u` (so `u < 0` leaves the
//! right wall). Five conditions fix `(X0, v-, v+, u)` and `phi`:
//!
//! 1. momentum at the impact: `M (v+ - v-) + 2 m u = 0`;
//! 2. restitution: `u - v+ = -e (-u - v-)`;
//! 3. the ball's flight over half a period: `u pi / w = -2 X0 - d`;
//! 4. (two rows) the frame's flight: with `p(t)` the steady response to the force and `Phi`
//!    the free oscillator's transition over `pi / w`,
//!    `Phi [X0 - p; v+ - p'](tau) = -[X0 - p; v- - p'](tau)`, as `p(t + pi/w) = -p(t)`.
//!
//! All five are linear in `(X0, v-, v+, u, sin phi, cos phi)`; the first four give the
//! velocities and `X0` as linear functions of `(sin phi, cos phi)`, the fifth is then
//! `A sin phi + B cos phi = C`: two phases per period (two branches), each checked for
//! admissibility (the ball approaches the wall it strikes and touches no wall in flight).

use std::f64::consts::PI;

/// A one-ball damper under `F0 sin(w t)` (underdamped primary).
#[derive(Debug, Clone, Copy)]
pub struct ImpactDamper {
    /// `M`, kg.
    pub frame_mass: f64,
    /// `k`, N/m.
    pub stiffness: f64,
    /// `c`, N s/m.
    pub damping: f64,
    /// `m`, kg.
    pub ball_mass: f64,
    /// `e`.
    pub restitution: f64,
    /// Free travel of the ball between the walls `d`, m.
    pub travel: f64,
    /// `F0`, N.
    pub force: f64,
    /// Forcing frequency, Hz.
    pub frequency: f64,
}

/// One branch of the periodic motion.
#[derive(Debug, Clone, Copy)]
pub struct Periodic {
    /// Phase `w t mod 2 pi` of the right-wall impact, rad.
    pub phase: f64,
    /// Frame displacement at the right-wall impact, m.
    pub x_impact: f64,
    /// Frame velocity just before / after the right-wall impact, m/s.
    pub frame_before: f64,
    /// Frame velocity just after, m/s.
    pub frame_after: f64,
    /// Ball velocity just after the right-wall impact (negative), m/s.
    pub ball_after: f64,
    /// Relative approach speed at every impact, m/s.
    pub approach_speed: f64,
    /// `max |x(t)|` over the period, m.
    pub amplitude: f64,
    /// The ball approaches the wall it strikes and stays off both walls in flight.
    pub admissible: bool,
    /// Over one forcing period: the work of the force, the loss in the dashpot and the loss in
    /// the two impacts, J.
    pub energy: [f64; 3],
}

impl ImpactDamper {
    fn omega(&self) -> f64 {
        2.0 * PI * self.frequency
    }
    /// Steady response `p(t) = a sin(w t) + b cos(w t)` of the bare primary.
    fn steady(&self) -> (f64, f64) {
        let (m, c, k, w) = (self.frame_mass, self.damping, self.stiffness, self.omega());
        let det = (k - m * w * w).powi(2) + (c * w).powi(2);
        (self.force * (k - m * w * w) / det, -self.force * c * w / det)
    }
    /// The free primary's state a time `h` after `(x0, v0)`: `e^{-s h}` times a rotation.
    fn free(&self, x0: f64, v0: f64, h: f64) -> (f64, f64) {
        let s = self.damping / (2.0 * self.frame_mass);
        let w0sq = self.stiffness / self.frame_mass;
        let wd = (w0sq - s * s).sqrt();
        let (sn, cs) = (wd * h).sin_cos();
        let d = (-s * h).exp();
        let x = d * (x0 * cs + (v0 + s * x0) * sn / wd);
        let v = d * (v0 * cs - (w0sq * x0 + s * v0) * sn / wd);
        (x, v)
    }
    /// Frame motion from the right-wall impact at `t0` (state `x0`, `v0` just after).
    fn frame_at(&self, t0: f64, x0: f64, v0: f64, t: f64) -> (f64, f64) {
        let (a, b) = self.steady();
        let w = self.omega();
        let p = |t: f64| (a * (w * t).sin() + b * (w * t).cos(), w * (a * (w * t).cos() - b * (w * t).sin()));
        let (p0, q0) = p(t0);
        let (xh, vh) = self.free(x0 - p0, v0 - q0, t - t0);
        let (p1, q1) = p(t);
        (xh + p1, vh + q1)
    }

    /// Both branches of the periodic motion (none when the force cannot sustain it).
    pub fn solutions(&self) -> Vec<Periodic> {
        let (mm, m, e, d) = (self.frame_mass, self.ball_mass, self.restitution, self.travel);
        let w = self.omega();
        let half = PI / w;
        let (a, b) = self.steady();
        // Transition of the free primary over half a period: columns from unit states.
        let c0 = self.free(1.0, 0.0, half);
        let c1 = self.free(0.0, 1.0, half);
        let phi = [[c0.0, c1.0], [c0.1, c1.1]];
        // p = a s + b c and p' = w (a c - b s) with (s, c) = (sin phi, cos phi).
        let p = [a, b];
        let pd = [-w * b, w * a];
        // Rows over (X0, v-, v+, u) = rhs over (1, s, c).
        let mut rows: Vec<([f64; 4], [f64; 3])> =
            vec![([0.0, -mm, mm, 2.0 * m], [0.0; 3]), ([0.0, -e, -1.0, 1.0 - e], [0.0; 3]), ([2.0, 0.0, 0.0, half], [-d, 0.0, 0.0])];
        for i in 0..2 {
            // phi_i0 (X0 - p) + phi_i1 (v+ - p') + (X0 - p if i = 0 else v- - p') = 0.
            let cp = phi[i][0] + if i == 0 { 1.0 } else { 0.0 };
            let cpd = phi[i][1] + if i == 1 { 1.0 } else { 0.0 };
            let lhs = [cp, if i == 1 { 1.0 } else { 0.0 }, phi[i][1], 0.0];
            rows.push((lhs, [0.0, cp * p[0] + cpd * pd[0], cp * p[1] + cpd * pd[1]]));
        }
        let matrix: [[f64; 4]; 4] = [rows[0].0, rows[1].0, rows[2].0, rows[3].0];
        let k: Vec<[f64; 4]> = (0..3).map(|j| solve4(matrix, [rows[0].1[j], rows[1].1[j], rows[2].1[j], rows[3].1[j]])).collect();
        let (lhs, rhs) = rows[4];
        let dot = |z: [f64; 4]| (0..4).map(|i| lhs[i] * z[i]).sum::<f64>();
        // A s + B c = C.
        let (aa, bb, cc) = (dot(k[1]) - rhs[1], dot(k[2]) - rhs[2], rhs[0] - dot(k[0]));
        let r = aa.hypot(bb);
        if cc.abs() > r {
            return vec![];
        }
        let psi = bb.atan2(aa);
        let base = (cc / r).asin();
        [base - psi, PI - base - psi]
            .into_iter()
            .map(|angle| {
                let (s, c) = angle.sin_cos();
                let z: Vec<f64> = (0..4).map(|i| k[0][i] + k[1][i] * s + k[2][i] * c).collect();
                let (x0, vm, vp, u) = (z[0], z[1], z[2], z[3]);
                let phase = angle.rem_euclid(2.0 * PI);
                self.branch(phase, x0, vm, vp, u)
            })
            .collect()
    }

    /// Amplitude, admissibility and energy of the branch with these impact values.
    fn branch(&self, phase: f64, x0: f64, vm: f64, vp: f64, u: f64) -> Periodic {
        let w = self.omega();
        let t0 = phase / w;
        let half = PI / w;
        let d = self.travel;
        // Dense scan of the half period, then the extremum refined by golden section.
        let n = 4000;
        let abs_x = |t: f64| self.frame_at(t0, x0, vp, t).0.abs();
        let mut best = (x0.abs(), t0);
        let mut admissible = -u - vm > 0.0 && u < 0.0;
        for j in 1..n {
            let t = t0 + half * j as f64 / n as f64;
            let (x, _) = self.frame_at(t0, x0, vp, t);
            if x.abs() > best.0 {
                best = (x.abs(), t);
            }
            let y = x0 + 0.5 * d + u * (t - t0) - x;
            if y.abs() >= 0.5 * d {
                admissible = false;
            }
        }
        let h = half / n as f64;
        let (mut lo, mut hi) = ((best.1 - h).max(t0), (best.1 + h).min(t0 + half));
        let g = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..200 {
            let (m1, m2) = (hi - g * (hi - lo), lo + g * (hi - lo));
            if abs_x(m1) > abs_x(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        let amplitude = best.0.max(abs_x(0.5 * (lo + hi)));
        // Energy over a whole period = twice over the half period after the right-wall impact.
        let steps = 20_000;
        let mut work = 0.0;
        let mut damping = 0.0;
        for j in 0..steps {
            // Composite Simpson: the velocity is smooth between the impacts at the ends, so the
            // error is about (w h)^4 / 180 ~ 1e-17 of the integrals.
            for (weight, frac) in [(1.0 / 6.0, 0.0), (4.0 / 6.0, 0.5), (1.0 / 6.0, 1.0)] {
                let t = t0 + half * (j as f64 + frac) / steps as f64;
                let (_, v) = self.frame_at(t0, x0, vp, t);
                work += weight * self.force * (w * t).sin() * v;
                damping += weight * self.damping * v * v;
            }
        }
        let dt = half / steps as f64;
        let mu = self.frame_mass * self.ball_mass / (self.frame_mass + self.ball_mass);
        let impact = (1.0 - self.restitution.powi(2)) * mu * (-u - vm).powi(2);
        Periodic {
            phase,
            x_impact: x0,
            frame_before: vm,
            frame_after: vp,
            ball_after: u,
            approach_speed: -u - vm,
            amplitude,
            admissible,
            energy: [2.0 * work * dt, 2.0 * damping * dt, impact],
        }
    }
}

/// Solves a 4x4 system by Gaussian elimination with partial pivoting.
fn solve4(mut a: [[f64; 4]; 4], mut b: [f64; 4]) -> [f64; 4] {
    for col in 0..4 {
        let pivot = (col..4).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs())).unwrap();
        a.swap(col, pivot);
        b.swap(col, pivot);
        for row in 0..4 {
            if row != col {
                let f = a[row][col] / a[col][col];
                for k in col..4 {
                    a[row][k] -= f * a[col][k];
                }
                b[row] -= f * b[col];
            }
        }
    }
    [b[0] / a[0][0], b[1] / a[1][1], b[2] / a[2][2], b[3] / a[3][3]]
}
