//! RODAS4 (Hairer & Wanner, *Solving ODEs II*, §VI.4 and their routine RODAS): a six-stage,
//! L-stable, stiffly accurate Rosenbrock method of order 4 with an embedded estimate of order 3
//! and a continuous extension of order 3. The compliant model steps with it while an open
//! contact is stiff for the explicit pair (a heavily damped contact pressed at a small speed
//! damps faster than any step the explicit method can take), so that steps follow the motion
//! instead of the contact's stability limit.
//!
//! Each stage solves `(I / (h gamma) - J) u_i = f(t + c_i h, y + sum a_ij u_j) + sum C_ij u_j / h
//! + h d_i f_t` with the Jacobian `J` and time derivative `f_t` of the start of the step: the
//! caller factors the matrix once per step and hands its solver in. Linear invariants of the
//! system (momentum, when `J` keeps them) are kept to round-off.

/// `gamma`, the diagonal of the method.
pub const GAMMA: f64 = 0.25;
/// Stage abscissae `c_i`.
const C: [f64; 6] = [0.0, 0.386, 0.21, 0.63, 1.0, 1.0];
/// Time-derivative weights `d_i` (`gamma_i` of the non-autonomous form).
const D: [f64; 6] = [0.25, -0.1043, 0.1035, -0.0362, 0.0, 0.0];
/// Rows of `a_ij`: where stage `i` evaluates `f`. Row 6 plus `u_6` is the solution.
const A: [[f64; 5]; 6] = [
    [0.0; 5],
    [1.544, 0.0, 0.0, 0.0, 0.0],
    [0.9466785280815826, 0.2557011698983284, 0.0, 0.0, 0.0],
    [3.314825187068521, 2.896124015972201, 0.9986419139977817, 0.0, 0.0],
    [1.221224509226641, 6.019134481288629, 12.53708332932087, -0.687_886_036_105_895, 0.0],
    [1.221224509226641, 6.019134481288629, 12.53708332932087, -0.687_886_036_105_895, 1.0],
];
/// Rows of `C_ij`.
const CC: [[f64; 5]; 6] = [
    [0.0; 5],
    [-5.6688, 0.0, 0.0, 0.0, 0.0],
    [-2.430093356833875, -0.2063599157091915, 0.0, 0.0, 0.0],
    [-0.1073529058151375, -9.594562251023355, -20.47028614809616, 0.0, 0.0],
    [7.496443313967647, -10.24680431464352, -33.99990352819905, 11.708_908_932_061_6, 0.0],
    [8.083246795921522, -7.981132988064893, -31.52159432874371, 16.31930543123136, -6.058818238834054],
];
/// Weights of the two correction terms of the dense output.
const H: [[f64; 5]; 2] = [
    [10.12623508344586, -7.487995877610167, -34.80091861555747, -7.992771707568823, 1.025137723295662],
    [-0.6762803392801253, 6.087714651680015, 16.43084320892478, 24.76722511418386, -6.594389125716872],
];

/// Workspace and result of the last attempted step.
#[derive(Debug, Clone)]
pub struct Rodas4 {
    u: [Vec<f64>; 6],
    arg: Vec<f64>,
    fi: Vec<f64>,
    /// The state at the start of the last step.
    y0: Vec<f64>,
    /// The state at its end.
    pub y1: Vec<f64>,
    /// The local error estimate per component (`u_6`).
    pub err: Vec<f64>,
    /// The derivative at the end of the step.
    dy1: Vec<f64>,
    /// Correction terms of the dense output.
    dense1: Vec<f64>,
    dense2: Vec<f64>,
}

impl Rodas4 {
    /// A workspace for states of `n` components.
    pub fn new(n: usize) -> Self {
        Rodas4 {
            u: std::array::from_fn(|_| vec![0.0; n]),
            arg: vec![0.0; n],
            fi: vec![0.0; n],
            y0: vec![0.0; n],
            y1: vec![0.0; n],
            err: vec![0.0; n],
            dy1: vec![0.0; n],
            dense1: vec![0.0; n],
            dense2: vec![0.0; n],
        }
    }

    /// Attempts a step of length `h` from `(t, y)` whose derivative there is `dy` and time
    /// derivative `ft` (`None`: autonomous). `f(t, y, dy)` writes the derivative; `solve(r)`
    /// overwrites `r` with `(I / (h GAMMA) - J)^-1 r` for this `h`. The result stays in
    /// [`Rodas4::y1`] and [`Rodas4::err`], with the derivative at the end and the dense output.
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &mut self,
        f: &mut impl FnMut(f64, &[f64], &mut [f64]),
        solve: &mut impl FnMut(&mut [f64]),
        t: f64,
        y: &[f64],
        dy: &[f64],
        ft: Option<&[f64]>,
        h: f64,
    ) {
        self.y0.copy_from_slice(y);
        for s in 0..6 {
            if s == 0 {
                self.fi.copy_from_slice(dy);
            } else {
                for i in 0..y.len() {
                    let mut acc = y[i];
                    for (j, a) in A[s][..s].iter().enumerate() {
                        acc += a * self.u[j][i];
                    }
                    self.arg[i] = acc;
                }
                f(t + C[s] * h, &self.arg, &mut self.fi);
            }
            let (done, rest) = self.u.split_at_mut(s);
            let us = &mut rest[0];
            for i in 0..y.len() {
                let mut r = self.fi[i];
                for (j, c) in CC[s][..s].iter().enumerate() {
                    r += c / h * done[j][i];
                }
                if let Some(ft) = ft {
                    r += h * D[s] * ft[i];
                }
                us[i] = r;
            }
            solve(us);
        }
        // Stiffly accurate: the solution is the last stage's argument plus its increment.
        for i in 0..y.len() {
            self.y1[i] = self.arg[i] + self.u[5][i];
            self.err[i] = self.u[5][i];
            let (mut h1, mut h2) = (0.0, 0.0);
            for j in 0..5 {
                h1 += H[0][j] * self.u[j][i];
                h2 += H[1][j] * self.u[j][i];
            }
            self.dense1[i] = h1;
            self.dense2[i] = h2;
        }
        f(t + h, &self.y1, &mut self.dy1);
    }

    /// The derivative at the end of the last step.
    pub fn last_derivative(&self) -> &[f64] {
        &self.dy1
    }

    /// Largest `|err_i| / scale_i` of the last step (a step is acceptable at most 1).
    pub fn error_norm(&self, scale: &[f64]) -> f64 {
        self.err.iter().zip(scale).fold(0.0, |m, (e, s)| m.max((e / s).abs()))
    }

    /// Component `i` of the dense output at `t + theta h`, `0 <= theta <= 1`.
    #[inline]
    pub fn dense_component(&self, i: usize, theta: f64) -> f64 {
        let th1 = 1.0 - theta;
        th1 * self.y0[i] + theta * (self.y1[i] + th1 * (self.dense1[i] + theta * self.dense2[i]))
    }
}

/// The next step length after a RODAS4 step of length `h` with error norm `err`: as
/// [`super::integrator::next_step`] with the exponent of an order-3 estimate.
pub fn next_step(h: f64, err: f64) -> f64 {
    let fac = if err == 0.0 { 5.0 } else { (0.9 * err.powf(-0.25)).clamp(0.2, 5.0) };
    h * fac
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `y' = J y` with a constant 2x2 `J`: the solver inverts `I / (h gamma) - J` exactly.
    fn linear_run(j: [[f64; 2]; 2], y0: [f64; 2], h: f64, steps: usize) -> (Vec<f64>, Rodas4) {
        let mut f = |_t: f64, y: &[f64], dy: &mut [f64]| {
            dy[0] = j[0][0] * y[0] + j[0][1] * y[1];
            dy[1] = j[1][0] * y[0] + j[1][1] * y[1];
        };
        let g = 1.0 / (h * GAMMA);
        let m = [[g - j[0][0], -j[0][1]], [-j[1][0], g - j[1][1]]];
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        let mut solve = |r: &mut [f64]| {
            let (a, b) = (r[0], r[1]);
            r[0] = (m[1][1] * a - m[0][1] * b) / det;
            r[1] = (m[0][0] * b - m[1][0] * a) / det;
        };
        let mut rk = Rodas4::new(2);
        let mut y = y0.to_vec();
        let mut dy = vec![0.0; 2];
        for k in 0..steps {
            f(0.0, &y, &mut dy);
            rk.step(&mut f, &mut solve, k as f64 * h, &y.clone(), &dy, None, h);
            y.copy_from_slice(&rk.y1);
        }
        (y, rk)
    }

    /// Fourth order: halving the step over one period of an oscillator divides the error by 16.
    #[test]
    fn harmonic_oscillator_converges_at_fourth_order() {
        let period = 2.0 * std::f64::consts::PI;
        let err = |steps: usize| {
            let (y, _) = linear_run([[0.0, 1.0], [-1.0, 0.0]], [1.0, 0.0], period / steps as f64, steps);
            (y[0] - 1.0).hypot(y[1])
        };
        let (e1, e2) = (err(40), err(80));
        let order = (e1 / e2).log2();
        assert!((3.7..4.4).contains(&order), "errors {e1:e} {e2:e}: order {order}");
    }

    /// The dense output is third order inside a step, and meets both ends.
    #[test]
    fn dense_output_is_third_order() {
        let err = |h: f64| {
            let (_, rk) = linear_run([[0.0, 1.0], [-1.0, 0.0]], [1.0, 0.0], h, 1);
            assert!((rk.dense_component(0, 0.0) - 1.0).abs() < 1e-15);
            assert_eq!(rk.dense_component(0, 1.0), rk.y1[0]);
            (0..=10).map(|k| k as f64 / 10.0).map(|th| (rk.dense_component(0, th) - (th * h).cos()).abs()).fold(0.0, f64::max)
        };
        let (e1, e2) = (err(0.2), err(0.1));
        let order = (e1 / e2).log2();
        assert!(order > 3.5, "dense errors {e1:e} {e2:e}: local order {order}");
    }

    /// L-stable: a mode far faster than the step is damped out in one step, not kept or flipped.
    #[test]
    fn stiff_mode_vanishes_in_one_step() {
        let (y, _) = linear_run([[-1e12, 0.0], [0.0, -1.0]], [1.0, 1.0], 0.01, 1);
        assert!(y[0].abs() < 1e-9, "{y:?}");
        assert!((y[1] - (-0.01f64).exp()).abs() < 1e-10, "{y:?}");
    }
}
