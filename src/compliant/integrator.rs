//! The Dormand-Prince 5(4) embedded Runge-Kutta pair with its continuous extension of order 4
//! (Hairer, Norsett & Wanner, *Solving ODEs I*, routine DOPRI5): the one integrator of the
//! compliant model, also used to tabulate the dimensionless Hunt-Crossley contact.
//!
//! The driver, not this module, chooses steps: a step is attempted, its error estimate judged
//! against the caller's scales, and the dense output then serves event location (contact onset
//! and end) and sampling, so no step has to land on an event or a sample time.

/// `c_i` of the tableau.
const C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];
/// Rows of `a_ij`.
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
];
/// Fifth-order minus fourth-order weights: the local error estimate is `h sum E_i k_i`.
const E: [f64; 7] = [71.0 / 57600.0, 0.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0];
/// Weights of the fourth-order continuous extension.
const D: [f64; 7] = [
    -12715105075.0 / 11282082432.0,
    0.0,
    87487479700.0 / 32700410799.0,
    -10690763975.0 / 1880347072.0,
    701980252875.0 / 199316789632.0,
    -1453857185.0 / 822651844.0,
    69997945.0 / 29380423.0,
];

/// Workspace and result of the last attempted step.
#[derive(Debug, Clone)]
pub struct Dopri5 {
    n: usize,
    k: [Vec<f64>; 7],
    stage: Vec<f64>,
    /// Start of the last step.
    pub t: f64,
    /// Its length.
    pub h: f64,
    /// The state at `t + h` (fifth order).
    pub y1: Vec<f64>,
    /// The local error estimate per component.
    pub err: Vec<f64>,
    /// Coefficients of the dense output.
    rcont: [Vec<f64>; 5],
}

impl Dopri5 {
    /// A workspace for states of `n` components.
    pub fn new(n: usize) -> Self {
        Dopri5 {
            n,
            k: std::array::from_fn(|_| vec![0.0; n]),
            stage: vec![0.0; n],
            t: 0.0,
            h: 0.0,
            y1: vec![0.0; n],
            err: vec![0.0; n],
            rcont: std::array::from_fn(|_| vec![0.0; n]),
        }
    }

    /// The derivative at the end of the last step (first-same-as-last: the next step's first stage).
    pub fn last_derivative(&self) -> &[f64] {
        &self.k[6]
    }

    /// Attempts a step of length `h` from `(t, y)` whose derivative there is `dy`; `f(t, y, dy)`
    /// writes the derivative. The result stays in [`Dopri5::y1`] and [`Dopri5::err`], and the
    /// dense output is ready.
    pub fn step(&mut self, f: &mut impl FnMut(f64, &[f64], &mut [f64]), t: f64, y: &[f64], dy: &[f64], h: f64) {
        let n = self.n;
        self.t = t;
        self.h = h;
        self.k[0].copy_from_slice(dy);
        for s in 1..7 {
            for i in 0..n {
                let mut acc = 0.0;
                for (j, a) in A[s][..s].iter().enumerate() {
                    acc += a * self.k[j][i];
                }
                self.stage[i] = y[i] + h * acc;
            }
            f(t + C[s] * h, &self.stage, &mut self.k[s]);
        }
        // Stage 7 was evaluated at the fifth-order solution itself.
        self.y1.copy_from_slice(&self.stage);
        for i in 0..n {
            let mut e = 0.0;
            let mut d = 0.0;
            for s in 0..7 {
                e += E[s] * self.k[s][i];
                d += D[s] * self.k[s][i];
            }
            self.err[i] = h * e;
            let dy0 = self.y1[i] - y[i];
            let bspl = h * self.k[0][i] - dy0;
            self.rcont[0][i] = y[i];
            self.rcont[1][i] = dy0;
            self.rcont[2][i] = bspl;
            self.rcont[3][i] = dy0 - h * self.k[6][i] - bspl;
            self.rcont[4][i] = h * d;
        }
    }

    /// Largest `|err_i| / scale_i` of the last step (a step is acceptable at most 1).
    pub fn error_norm(&self, scale: &[f64]) -> f64 {
        self.err.iter().zip(scale).fold(0.0, |m, (e, s)| m.max((e / s).abs()))
    }

    /// Component `i` of the dense output at `t + theta h`, `0 <= theta <= 1`.
    #[inline]
    pub fn dense_component(&self, i: usize, theta: f64) -> f64 {
        let r = &self.rcont;
        let th1 = 1.0 - theta;
        r[0][i] + theta * (r[1][i] + th1 * (r[2][i] + theta * (r[3][i] + th1 * r[4][i])))
    }
}

/// The next step length after a step of length `h` with error norm `err` (accepted or not):
/// the classical `0.9 err^(-1/5)`, kept within a factor 0.2..5 so one odd estimate cannot
/// derail the sequence.
pub fn next_step(h: f64, err: f64) -> f64 {
    let fac = if err == 0.0 { 5.0 } else { (0.9 * err.powf(-0.2)).clamp(0.2, 5.0) };
    h * fac
}

/// The root of `g` in `[a, b]`, where `g(a)` and `g(b)` have opposite signs (or `g(b) = 0`),
/// by the Illinois variant of regula falsi: returns a point `x` with `g(x)` of `g(b)`'s sign
/// (or zero), at most `tol` right of the root, so an event is never placed before it happens.
pub fn bracketed_root(mut g: impl FnMut(f64) -> f64, mut a: f64, mut b: f64, tol: f64) -> f64 {
    let (mut ga, mut gb) = (g(a), g(b));
    if gb == 0.0 {
        return b;
    }
    let mut side = 0i8;
    for _ in 0..200 {
        if (b - a).abs() <= tol {
            break;
        }
        let mut x = (a * gb - b * ga) / (gb - ga);
        // A secant point on (or outside) the bracket's end makes no progress: halve instead.
        if !(x > a.min(b) && x < a.max(b)) {
            x = 0.5 * (a + b);
        }
        let gx = g(x);
        if gx == 0.0 {
            return x;
        }
        if (gx > 0.0) == (gb > 0.0) {
            b = x;
            gb = gx;
            if side == 1 {
                ga *= 0.5;
            }
            side = 1;
        } else {
            a = x;
            ga = gx;
            if side == -1 {
                gb *= 0.5;
            }
            side = -1;
        }
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Harmonic oscillator over one period with tight tolerance: back to the start.
    #[test]
    fn harmonic_oscillator_one_period() {
        let mut f = |_t: f64, y: &[f64], dy: &mut [f64]| {
            dy[0] = y[1];
            dy[1] = -y[0];
        };
        let mut rk = Dopri5::new(2);
        let mut y = vec![1.0, 0.0];
        let mut dy = vec![0.0, -1.0];
        let (mut t, mut h) = (0.0f64, 1e-3f64);
        let end = 2.0 * std::f64::consts::PI;
        while t < end {
            let hh = h.min(end - t);
            rk.step(&mut f, t, &y, &dy, hh);
            let err = rk.error_norm(&[1e-12, 1e-12]);
            h = next_step(hh, err);
            if err <= 1.0 {
                t += hh;
                y.copy_from_slice(&rk.y1);
                dy.copy_from_slice(rk.last_derivative());
                // The dense output at the middle of the step is the exact solution too.
                let mid = rk.dense_component(0, 0.5);
                assert!((mid - (t - 0.5 * hh).cos()).abs() < 1e-9);
            }
        }
        assert!((y[0] - 1.0).abs() < 1e-10 && y[1].abs() < 1e-10, "{y:?}");
    }

    #[test]
    fn root_is_never_before_the_crossing() {
        let r = bracketed_root(|x| x * x - 2.0, 0.0, 2.0, 1e-14);
        assert!((r - 2f64.sqrt()).abs() < 1e-14 && r * r - 2.0 >= 0.0);
    }
}
