//! A shear building's floors between impulses in closed form (docs/MODEL.md §16), shared by
//! every model that moves a structure of several storeys.
//!
//! With the floors' displacements `u` relative to the ground, `M u'' + C u' + K u = -M 1 ag(t)`.
//! Written for the state `z = [u; u']` as `z' = A z + b(t)`, the motion over a stretch on which
//! the ground's acceleration is linear, `ag = g0 + g1 s`, is a particular solution that is
//! linear in time plus the free motion `V e^{L s} V^-1 h` of the departure `h` from it, where
//! `A = V L V^-1` is the state matrix's eigen-decomposition (complex modes; classical damping
//! is not needed, so balls held on a floor may change its mass).

use nalgebra::{Complex, DMatrix, DVector};

/// A complex number of `f64`.
pub type C64 = Complex<f64>;

/// Largest residual `|A V - V L| / (|A| |V|)` of an eigen-decomposition that is accepted: a
/// structure whose modes are (nearly) critically damped has no basis of modes to this accuracy.
const DECOMPOSITION_RESIDUAL: f64 = 1e-9;

/// What a piecewise-linear record drives: the ground's acceleration `ag` under every floor
/// (`M u'' + C u' + K u = -M 1 ag`), or a force `f` on one floor (`... = e_j f`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Load {
    /// The ground accelerates.
    Ground,
    /// A force acts on this floor (0 at the bottom).
    Floor(usize),
}

/// How the storeys dissipate.
#[derive(Debug, Clone, PartialEq)]
pub enum StoreyDamping {
    /// `C = a0 M + a1 K` (the bare building's `M`).
    Rayleigh {
        /// `a0`, 1/s.
        mass: f64,
        /// `a1`, s.
        stiffness: f64,
    },
    /// A damping ratio for each undamped mode, lowest first.
    Modal(Vec<f64>),
}

/// A shear building: floor masses, storey stiffnesses (storey `i` between floor `i - 1` and
/// floor `i`, floor 0 the ground) and the damping matrix.
#[derive(Debug, Clone, PartialEq)]
pub struct Building {
    /// Floor masses, bottom to top, kg.
    pub masses: Vec<f64>,
    /// Storey stiffnesses, bottom to top, N/m.
    pub stiffnesses: Vec<f64>,
    /// `C`, N s/m.
    pub damping: DMatrix<f64>,
}

impl Building {
    /// The building of `masses` and `stiffnesses` (of one length, every value positive) damped
    /// as `damping` says.
    pub fn new(masses: Vec<f64>, stiffnesses: Vec<f64>, damping: &StoreyDamping) -> Self {
        let n = masses.len();
        let mut b = Building { masses, stiffnesses, damping: DMatrix::zeros(n, n) };
        let k = b.stiffness();
        b.damping = match damping {
            StoreyDamping::Rayleigh { mass, stiffness } => {
                DMatrix::from_diagonal(&DVector::from_vec(b.masses.clone())) * *mass + k * *stiffness
            }
            StoreyDamping::Modal(ratios) => {
                let (omegas, shapes) = b.undamped_modes();
                let m = DMatrix::from_diagonal(&DVector::from_vec(b.masses.clone()));
                let diag = DVector::from_iterator(n, (0..n).map(|i| 2.0 * ratios.get(i).copied().unwrap_or(0.0) * omegas[i]));
                let mp = &m * &shapes;
                &mp * DMatrix::from_diagonal(&diag) * mp.transpose()
            }
        };
        b
    }

    /// Number of floors.
    pub fn floors(&self) -> usize {
        self.masses.len()
    }

    /// `K`, tridiagonal.
    pub fn stiffness(&self) -> DMatrix<f64> {
        let n = self.floors();
        let k = &self.stiffnesses;
        DMatrix::from_fn(n, n, |i, j| {
            if i == j {
                k[i] + if i + 1 < n { k[i + 1] } else { 0.0 }
            } else if j == i + 1 {
                -k[j]
            } else if i == j + 1 {
                -k[i]
            } else {
                0.0
            }
        })
    }

    /// The undamped natural angular frequencies (rad/s, lowest first) and mode shapes
    /// normalised to the mass matrix (`phi^T M phi = I`, one column per mode).
    pub fn undamped_modes(&self) -> (Vec<f64>, DMatrix<f64>) {
        let n = self.floors();
        let root: Vec<f64> = self.masses.iter().map(|m| 1.0 / m.sqrt()).collect();
        let k = self.stiffness();
        let s = DMatrix::from_fn(n, n, |i, j| root[i] * k[(i, j)] * root[j]);
        let eig = s.symmetric_eigen();
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let omegas = order.iter().map(|&c| eig.eigenvalues[c].max(0.0).sqrt()).collect();
        let shapes = DMatrix::from_fn(n, n, |i, j| root[i] * eig.eigenvectors[(i, order[j])]);
        (omegas, shapes)
    }

    /// The forces of the storeys' springs and dampers on each floor, `-(C v + K u)`, N.
    pub fn restoring_forces(&self, u: &[f64], v: &[f64]) -> Vec<f64> {
        let n = self.floors();
        let k = &self.stiffnesses;
        (0..n)
            .map(|i| {
                let below = k[i] * (u[i] - if i > 0 { u[i - 1] } else { 0.0 });
                let above = if i + 1 < n { k[i + 1] * (u[i + 1] - u[i]) } else { 0.0 };
                let damping: f64 = (0..n).map(|j| self.damping[(i, j)] * v[j]).sum();
                above - below - damping
            })
            .collect()
    }

    /// The energy in the storeys' springs, `u^T K u / 2`, J.
    pub fn spring_energy(&self, u: &[f64]) -> f64 {
        (0..self.floors()).map(|i| 0.5 * self.stiffnesses[i] * (u[i] - if i > 0 { u[i - 1] } else { 0.0 }).powi(2)).sum()
    }

    /// The power the dampers dissipate, `v^T C v`, W (`v` relative to the ground).
    pub fn damping_power(&self, v: &[f64]) -> f64 {
        let n = self.floors();
        (0..n).map(|i| v[i] * (0..n).map(|j| self.damping[(i, j)] * v[j]).sum::<f64>()).sum()
    }

    /// The force the structure exerts on the ground through its lowest storey and its
    /// dampers, `1^T (C v + K u)`, N: the ground's power is minus this times its velocity.
    pub fn base_shear(&self, u: &[f64], v: &[f64]) -> f64 {
        -self.restoring_forces(u, v).iter().sum::<f64>()
    }

    /// The steady response `U` (complex amplitudes per floor, `u = Re U e^{i w t}`) to the
    /// loads `Re F e^{i w t}` on the floors of masses `masses`: `(K - w^2 M + i w C) U = F`.
    /// `None` when the structure has no steady state at `w` (undamped, at a natural frequency).
    pub fn harmonic_response(&self, masses: &[f64], omega: f64, loads: &[C64]) -> Option<Vec<C64>> {
        let n = self.floors();
        let k = self.stiffness();
        let d = DMatrix::<C64>::from_fn(n, n, |i, j| {
            let mass = if i == j { masses[i] } else { 0.0 };
            C64::new(k[(i, j)] - omega * omega * mass, omega * self.damping[(i, j)])
        });
        let u = d.lu().solve(&DVector::from_column_slice(loads))?;
        u.iter().all(|x| x.re.is_finite() && x.im.is_finite()).then(|| u.iter().copied().collect())
    }

    /// The state matrix's modes with `added` kg on floor `floor` (balls the floor carries), and
    /// the static responses to `load`.
    pub fn modes(&self, floor: usize, added: f64, load: Load) -> Result<Modes, String> {
        let mut each = vec![0.0; self.floors()];
        each[floor] = added;
        Modes::new(self, &each, load)
    }

    /// [`Building::modes`] with `added[j]` kg on each floor `j`.
    pub fn modes_holding(&self, added: &[f64], load: Load) -> Result<Modes, String> {
        Modes::new(self, added, load)
    }
}

/// The eigen-decomposition of a building's state matrix, and the static responses that give the
/// particular solution under a load (a ground acceleration or a floor's force) linear in time.
#[derive(Debug, Clone)]
pub struct Modes {
    /// Floors.
    pub n: usize,
    /// Floor masses with what they carry, kg.
    pub masses: Vec<f64>,
    /// Eigenvalues `L` of the state matrix (`2n`), 1/s.
    pub lambda: Vec<C64>,
    /// `|L|` of each, 1/s.
    pub lambda_norms: Vec<f64>,
    /// Eigenvectors, one column per eigenvalue (`2n x 2n`).
    pub vectors: DMatrix<C64>,
    inverse: DMatrix<C64>,
    /// The static displacement under a unit load is `-r`: `r = K^-1 M 1` for the ground's
    /// acceleration, `r = -K^-1 e_j` for a force on floor `j`.
    pub influence: Vec<f64>,
    /// `K^-1 C r`: the lag of the response to a load that grows linearly.
    pub lag: Vec<f64>,
    /// Largest `|L|`, 1/s.
    pub rate: f64,
    /// Longest period of an oscillating mode, s (infinite when no mode oscillates).
    pub longest_period: f64,
    /// Shortest period of an oscillating mode, s.
    pub shortest_period: f64,
}

impl Modes {
    fn new(b: &Building, added: &[f64], load: Load) -> Result<Modes, String> {
        let n = b.floors();
        let mut masses = b.masses.clone();
        for (m, a) in masses.iter_mut().zip(added) {
            *m += a;
        }
        let k = b.stiffness();
        // The state scaled as `[s u; u']`, with `s` the largest `sqrt(K_ii / m_i)`: its matrix
        // then has the size of the fastest mode's rate rather than of its square, and the
        // eigenvalues (whose real parts set each mode's decay, hence the energy balance) come
        // out with round-off relative to the rates, not to the rates squared.
        let s = (0..n).map(|i| k[(i, i)] / masses[i]).fold(0.0, f64::max).sqrt().max(f64::MIN_POSITIVE);
        let mut a = DMatrix::<f64>::zeros(2 * n, 2 * n);
        for i in 0..n {
            a[(i, n + i)] = s;
            for j in 0..n {
                a[(n + i, j)] = -k[(i, j)] / masses[i] / s;
                a[(n + i, n + j)] = -b.damping[(i, j)] / masses[i];
            }
        }
        let lambda: Vec<C64> = a.complex_eigenvalues().iter().copied().collect();
        let ac = a.map(|x| C64::new(x, 0.0));
        let norm_a = a.iter().map(|x| x.abs()).fold(0.0, f64::max);
        let mut vectors = DMatrix::<C64>::zeros(2 * n, 2 * n);
        for (c, &l) in lambda.iter().enumerate() {
            // Inverse iteration with a shift just off the eigenvalue: a few solves converge to
            // its eigenvector.
            let shift = l + C64::new(1e-10 * norm_a.max(1.0), 1e-10 * norm_a.max(1.0));
            let lu = (&ac - DMatrix::<C64>::identity(2 * n, 2 * n) * shift).lu();
            let mut v = DVector::<C64>::from_fn(2 * n, |i, _| C64::new(1.0 + i as f64 * 0.37, 0.1 * i as f64));
            for _ in 0..4 {
                v = lu.solve(&v).ok_or("the structure's state matrix has no eigenvector there")?;
                let size = v.iter().map(|x| x.norm()).fold(0.0, f64::max);
                v /= C64::new(size, 0.0);
            }
            vectors.set_column(c, &v);
        }
        let residual = (&ac * &vectors - &vectors * DMatrix::from_diagonal(&DVector::from_vec(lambda.clone())))
            .iter()
            .map(|x| x.norm())
            .fold(0.0, f64::max);
        if !(residual <= DECOMPOSITION_RESIDUAL * norm_a.max(f64::MIN_POSITIVE)) {
            return Err("the structure's modes are too close to critical damping to be separated".into());
        }
        let mut inverse = vectors.clone().try_inverse().ok_or("the structure's modes are too close to critical damping to be separated")?;
        // Back to the state `[u; u']`: `V = D^-1 V_s`, `V^-1 = V_s^-1 D` with `D = diag(s, 1)`.
        for i in 0..n {
            vectors.row_mut(i).scale_mut(1.0 / s);
            inverse.column_mut(i).scale_mut(s);
        }
        let kinv = k.clone().try_inverse().ok_or("the structure has a storey without stiffness")?;
        let pattern = match load {
            Load::Ground => DVector::from_vec(masses.clone()),
            Load::Floor(j) => DVector::from_fn(n, |i, _| if i == j { -1.0 } else { 0.0 }),
        };
        let influence: Vec<f64> = (kinv.clone() * pattern).iter().copied().collect();
        let lag: Vec<f64> = (kinv * &b.damping * DVector::from_vec(influence.clone())).iter().copied().collect();
        let lambda_norms: Vec<f64> = lambda.iter().map(|l| l.norm()).collect();
        let rate = lambda_norms.iter().copied().fold(0.0, f64::max);
        let periods = lambda.iter().filter(|l| l.im > 0.0).map(|l| 2.0 * std::f64::consts::PI / l.im);
        let (longest_period, shortest_period) = periods.fold((0.0f64, f64::INFINITY), |(lo, sh), p| (lo.max(p), sh.min(p)));
        Ok(Modes {
            n,
            masses,
            lambda,
            lambda_norms,
            vectors,
            inverse,
            influence,
            lag,
            rate,
            longest_period: if longest_period > 0.0 { longest_period } else { f64::INFINITY },
            shortest_period,
        })
    }

    /// The particular solution `(u, u')` of floor `i` a time `s` into a stretch with load
    /// `g0 + g1 s`: `u = -r (g0 + g1 s) + K^-1 C r g1`, `u' = -r g1`.
    #[inline]
    pub fn particular(&self, i: usize, g0: f64, g1: f64, s: f64) -> (f64, f64) {
        (-self.influence[i] * (g0 + g1 * s) + self.lag[i] * g1, -self.influence[i] * g1)
    }

    /// The modal coefficients `V^-1 h` of the state `z` (`[u; u']`) less the particular
    /// solution at the start of a stretch with load `g0 + g1 s`.
    pub fn coefficients(&self, z: &[f64], g0: f64, g1: f64) -> Vec<C64> {
        let n = self.n;
        let h = DVector::<C64>::from_fn(2 * n, |i, _| {
            let (u, v) = self.particular(i % n, g0, g1, 0.0);
            C64::new(z[i] - if i < n { u } else { v }, 0.0)
        });
        // One step of iterative refinement: the closed form then starts from `z` to the
        // round-off of one evaluation, whatever the conditioning of `V`.
        let c = &self.inverse * &h;
        let residual = DVector::<C64>::from_fn(2 * n, |i, _| {
            C64::new(h[i].re - (0..2 * n).map(|k| (self.vectors[(i, k)] * c[k]).re).sum::<f64>(), 0.0)
        });
        (c + &self.inverse * residual).iter().copied().collect()
    }

    /// The state `[u; u']` a time `s` into the stretch whose coefficients are `c`.
    pub fn state(&self, c: &[C64], g0: f64, g1: f64, s: f64) -> Vec<f64> {
        let n = self.n;
        let growth: Vec<C64> = self.lambda.iter().zip(c).map(|(l, c)| c * (l * s).exp()).collect();
        (0..2 * n)
            .map(|i| {
                let free: f64 = (0..2 * n).map(|k| (self.vectors[(i, k)] * growth[k]).re).sum();
                let (u, v) = self.particular(i % n, g0, g1, s);
                free + if i < n { u } else { v }
            })
            .collect()
    }

    /// The free motion of floor `i`'s displacement as terms `w_k e^{L_k s}`: `w_k = V_ik c_k`.
    pub fn floor_terms(&self, c: &[C64], i: usize) -> Vec<C64> {
        (0..2 * self.n).map(|k| self.vectors[(i, k)] * c[k]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn three_storeys(damping: StoreyDamping) -> Building {
        Building::new(vec![2.0, 1.6, 1.35], vec![3000.0, 2400.0, 865.0], &damping)
    }

    /// The augmented state `[z; 1; s]` obeys a constant linear system, so its matrix
    /// exponential (computed by nalgebra's Pade approximant, independent of the modes) is the
    /// motion under a linear ground acceleration.
    fn by_matrix_exponential(b: &Building, z0: &[f64], g0: f64, g1: f64, s: f64) -> Vec<f64> {
        let n = b.floors();
        let k = b.stiffness();
        let dim = 2 * n + 2;
        let mut a = DMatrix::<f64>::zeros(dim, dim);
        for i in 0..n {
            a[(i, n + i)] = 1.0;
            for j in 0..n {
                a[(n + i, j)] = -k[(i, j)] / b.masses[i];
                a[(n + i, n + j)] = -b.damping[(i, j)] / b.masses[i];
            }
            a[(n + i, 2 * n)] = -g0;
            a[(n + i, 2 * n + 1)] = -g1;
        }
        a[(2 * n + 1, 2 * n)] = 1.0;
        let mut x = DVector::<f64>::zeros(dim);
        x.rows_mut(0, 2 * n).copy_from_slice(z0);
        x[2 * n] = 1.0;
        let e = (a * s).exp() * x;
        e.rows(0, 2 * n).iter().copied().collect()
    }

    #[test]
    fn the_modal_motion_is_the_matrix_exponential() {
        for damping in [StoreyDamping::Rayleigh { mass: 0.4, stiffness: 0.002 }, StoreyDamping::Modal(vec![0.02, 0.05, 0.1])] {
            let b = three_storeys(damping);
            let modes = b.modes(2, 0.0, Load::Ground).unwrap();
            let z0 = [0.01, -0.02, 0.03, 0.1, 0.0, -0.3];
            let (g0, g1) = (1.5, -4.0);
            let c = modes.coefficients(&z0, g0, g1);
            for s in [0.0, 0.013, 0.2, 0.71] {
                let z = modes.state(&c, g0, g1, s);
                let e = by_matrix_exponential(&b, &z0, g0, g1, s);
                for i in 0..6 {
                    let scale = if i < 3 { 0.05 } else { 2.0 };
                    assert!((z[i] - e[i]).abs() <= 1e-12 * scale, "{s} {i}: {} vs {}", z[i], e[i]);
                }
            }
        }
    }

    #[test]
    fn modal_damping_gives_each_mode_its_ratio() {
        let b = three_storeys(StoreyDamping::Modal(vec![0.02, 0.05, 0.1]));
        let (omegas, _) = b.undamped_modes();
        let modes = b.modes(0, 0.0, Load::Ground).unwrap();
        let mut ratios: Vec<(f64, f64)> = modes.lambda.iter().filter(|l| l.im > 0.0).map(|l| (l.norm(), -l.re / l.norm())).collect();
        ratios.sort_by(|a, b| a.0.total_cmp(&b.0));
        for ((w, zeta), (w0, z0)) in ratios.iter().zip(omegas.iter().zip([0.02, 0.05, 0.1])) {
            assert!((w - w0).abs() <= 1e-12 * w0 && (zeta - z0).abs() <= 1e-12, "{w} {zeta} vs {w0} {z0}");
        }
    }

    #[test]
    fn a_mass_on_a_floor_changes_the_modes_but_not_the_static_balance() {
        let b = three_storeys(StoreyDamping::Rayleigh { mass: 0.4, stiffness: 0.0 });
        let bare = b.modes(2, 0.0, Load::Ground).unwrap();
        let loaded = b.modes(2, 0.5, Load::Ground).unwrap();
        assert!(loaded.longest_period > bare.longest_period);
        // The static response to a steady ground acceleration is -r ag, and K r = M 1.
        let k = b.stiffness();
        for i in 0..3 {
            let kr: f64 = (0..3).map(|j| k[(i, j)] * loaded.influence[j]).sum();
            assert!((kr - loaded.masses[i]).abs() <= 1e-12 * loaded.masses[i]);
        }
    }
}
