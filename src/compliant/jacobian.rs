//! The compliant system's Jacobian and the linear solve of a Rosenbrock stage,
//! `(I / (h gamma) - J) u = r`, in O(n).
//!
//! Contacts couple neighbours only: ball `i` with ball `i + 1` of its chain, and each chain's
//! end balls with the frame through the walls (between chains the coupling is zero, so the
//! tridiagonal part is block tridiagonal, one block per chain). Eliminating the position increments (`u_x = h gamma (r_x + u_v)`)
//! leaves one equation per body for the velocity increments, whose matrix, each row times its
//! body's mass, is `m / (h gamma) + sum over the body's contacts of w` on the diagonal and `-w`
//! between the two bodies of a contact, with `w = h gamma dF/dd + dF/dd'` (never negative: a
//! pulling force is cut to zero, and with it its derivatives). It is symmetric and strictly
//! diagonally dominant, so Gaussian elimination without pivoting is stable: a tridiagonal
//! matrix over the balls bordered by the frame's row and column, solved by the Thomas algorithm
//! and one Schur complement. The integrals (damper and forcing work, contact dissipation)
//! depend on the bodies but nothing depends on them: their increments follow explicitly.

use super::system::{Floors, Pair, Side, System, VS, XS};

/// One contact's partial derivatives at the start of a step.
#[derive(Debug, Clone, Copy, Default)]
struct Partials {
    /// `dF/dd`, N/m.
    kd: f64,
    /// `dF/dd'`, N s/m.
    kr: f64,
    /// Derivatives of the dissipation rate `(F - K d^(3/2)) d'` by `d` and by `d'`.
    gd: f64,
    gr: f64,
}

/// The factored stage matrix of one step.
#[derive(Debug, Clone, Default)]
pub(super) struct Stage {
    /// `h gamma`.
    hg: f64,
    partials: Vec<Partials>,
    /// Thomas factors over the balls: the modified superdiagonal and the pivots' inverses.
    upper: Vec<f64>,
    inverse_pivot: Vec<f64>,
    /// Off-diagonal between ball `i` and `i + 1` (`-w`).
    off: Vec<f64>,
    /// The frame's column over the balls, and `T^-1` of it.
    border: Vec<f64>,
    border_solved: Vec<f64>,
    /// The frame's diagonal less the border's Schur term.
    schur: f64,
    /// `d(frame force)/d xs` and `/d vs` (spring and damper), N/m and N s/m.
    frame_kx: f64,
    frame_kv: f64,
    /// Derivatives of the damper power and the forcing power by `xs` and `vs`.
    damping_dv: f64,
    forcing_dx: f64,
    forcing_dv: f64,
    /// Scratch: the right-hand side over the balls, and the balls' diagonal.
    rhs: Vec<f64>,
    diag: Vec<f64>,
    /// A structure's floors: their matrix less the border's Schur term on the carrying floor,
    /// factored, and the derivatives of the damper and forcing powers by each floor's
    /// displacement and velocity.
    floors: Option<FloorStage>,
}

/// The floors' part of a factored stage.
#[derive(Debug, Clone)]
struct FloorStage {
    lu: nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>,
    damping_dv: Vec<f64>,
    forcing_dx: Vec<f64>,
    forcing_dv: Vec<f64>,
}

impl System<'_> {
    /// The body a side of a pair moves with: a ball's index, or `n` for the frame (`None`
    /// for a fixed wall).
    fn body(&self, side: Side) -> Option<usize> {
        match side {
            Side::Ball(i) => Some(i),
            Side::Wall(_) => self.has_frame().then_some(self.n),
        }
    }

    /// The largest rate at which an open contact's damping acts on its bodies,
    /// `(dF/dd') (1/m1 + 1/m2)`, 1/s: an explicit step much longer than its inverse is unstable.
    pub(super) fn damping_rate(&self, y: &[f64], dy: &[f64], v_max: &[f64]) -> f64 {
        let mut rate_max = 0.0f64;
        for (q, pair) in self.pairs.iter().enumerate() {
            let p = self.partials(pair, y, dy, v_max[q]);
            if p.kr > 0.0 {
                rate_max = rate_max.max(p.kr * self.inverse_mass(pair));
            }
        }
        rate_max
    }

    fn inverse_mass(&self, pair: &Pair) -> f64 {
        let inv = |s: Side| match s {
            Side::Ball(i) => 1.0 / self.mass[i],
            Side::Wall(_) => 1.0 / self.frame_mass,
        };
        inv(pair.left) + inv(pair.right)
    }

    /// The partials at `y`, where the derivative is `dy`.
    fn partials(&self, pair: &Pair, y: &[f64], dy: &[f64], v_max: f64) -> Partials {
        let (d, rate) = self.overlap(pair, |i| y[i]);
        if d <= 0.0 {
            return Partials::default();
        }
        let alpha = self.alpha(v_max, rate);
        let elastic = pair.k * d * d.sqrt();
        let f = elastic * (1.0 + alpha * rate);
        if f <= 0.0 {
            return Partials::default();
        }
        let kd = 1.5 * pair.k * d.sqrt() * (1.0 + alpha * rate);
        // When the rate itself sets the damping (alpha = c / rate), the damping force is
        // c K d^(3/2), independent of the rate. A rate at its largest so far (as it is after
        // every step of a contact being squeezed harder) takes the side it is heading to: the
        // Jacobian must be that of the step ahead, or the method loses its order.
        let top = v_max.max(self.v_floor);
        let rising = self.overlap(pair, |i| dy[i]).1 > 0.0;
        let kr = if rate > top || (rate == top && rising) { 0.0 } else { elastic * alpha };
        Partials { kd, kr, gd: (kd - 1.5 * pair.k * d.sqrt()) * rate, gr: f - elastic + kr * rate }
    }

    /// Factors `I / hg - J` at `(t, y)` into `stage`.
    pub(super) fn factor(&self, t: f64, y: &[f64], dy: &[f64], v_max: &[f64], hg: f64, stage: &mut Stage) {
        let n = self.n;
        stage.hg = hg;
        stage.partials.clear();
        stage.partials.extend(self.pairs.iter().enumerate().map(|(q, p)| self.partials(p, y, dy, v_max[q])));
        let mut diag = std::mem::take(&mut stage.diag);
        diag.clear();
        diag.extend(self.mass.iter().map(|m| m / hg));
        stage.off.clear();
        stage.off.resize(n.saturating_sub(1), 0.0);
        stage.border.clear();
        stage.border.resize(n, 0.0);
        let mut frame_diag = 0.0;
        (stage.frame_kx, stage.frame_kv, stage.damping_dv, stage.forcing_dx, stage.forcing_dv) = (0.0, 0.0, 0.0, 0.0, 0.0);
        if self.floors.is_some() {
            // The floors' own terms are added by `factor_floors`.
        } else if let Some(f) = self.scene.frame {
            let (yd, force) = match self.scene.forcing {
                Some(g) => (g.ground(t).1, g.force(t)),
                None => (0.0, 0.0),
            };
            stage.frame_kx = -f.stiffness;
            stage.frame_kv = -f.damping;
            stage.damping_dv = 2.0 * f.damping * (y[VS] - yd);
            (stage.forcing_dx, stage.forcing_dv) = match self.scene.forcing.map(|g| g.kind) {
                Some(crate::scene::ForcingKind::Force) => (0.0, force),
                Some(crate::scene::ForcingKind::Base) => (-yd * f.stiffness, -yd * f.damping),
                None => (0.0, 0.0),
            };
            frame_diag = f.mass / hg + hg * f.stiffness + f.damping;
        }
        for (pair, p) in self.pairs.iter().zip(&stage.partials) {
            let w = hg * p.kd + p.kr;
            if w == 0.0 {
                continue;
            }
            let (a, b) = (self.body(pair.left), self.body(pair.right));
            for body in [a, b].into_iter().flatten() {
                if body == n {
                    frame_diag += w;
                } else {
                    diag[body] += w;
                }
            }
            match (a, b) {
                (Some(i), Some(j)) if i < n && j < n => stage.off[i.min(j)] -= w,
                (Some(i), Some(j)) => stage.border[if i == n { j } else { i }] -= w,
                _ => {}
            }
        }
        // Thomas factorisation of the balls' tridiagonal part.
        stage.upper.clear();
        stage.inverse_pivot.clear();
        for i in 0..n {
            let pivot = diag[i] - if i > 0 { stage.off[i - 1] * stage.upper[i - 1] } else { 0.0 };
            stage.inverse_pivot.push(1.0 / pivot);
            stage.upper.push(if i + 1 < n { stage.off[i] / pivot } else { 0.0 });
        }
        stage.border_solved.clone_from(&stage.border);
        Self::thomas(stage, true);
        let coupling: f64 = stage.border.iter().zip(&stage.border_solved).map(|(c, w)| c * w).sum();
        stage.schur = frame_diag - coupling;
        stage.floors = self.floors.as_ref().map(|floors| self.factor_floors(floors, t, y, hg, frame_diag - coupling));
        stage.rhs.resize(n, 0.0);
        stage.diag = diag;
    }

    /// The floors' stage matrix `M / hg + hg K + C`, with `contacts` (the balls' contact terms
    /// less their Schur complement) added on the carrying floor, factored; and the partials of
    /// the storeys' dissipation `v^T C v` and of the excitation's power
    /// `vg sum(-(K u + C v)) + F vs + f (v_j + vg)` (a recorded force `f` on floor `j`).
    fn factor_floors(&self, floors: &Floors, t: f64, y: &[f64], hg: f64, contacts: f64) -> FloorStage {
        let structure = floors.structure;
        let b = &structure.building;
        let (d, n) = (structure.floor, floors.count());
        let mut matrix = &floors.stiffness * hg + &b.damping;
        for j in 0..n {
            matrix[(j, j)] += b.masses[j] / hg;
        }
        matrix[(d, d)] += contacts;
        let (xg, vg, _) = self.scene.ground_motion(t);
        let (_, v) = floors.relative(|i| y[i], (xg, vg));
        let damping_dv = (0..n).map(|k| 2.0 * (0..n).map(|j| b.damping[(k, j)] * v[j]).sum::<f64>()).collect();
        let forcing_dx = (0..n).map(|k| -vg * floors.stiffness.column(k).sum()).collect();
        let force = self.scene.forcing.map_or(0.0, |g| g.force(t));
        let recorded = structure.force.as_ref().map_or((n, 0.0), |f| (f.floor, structure.recorded_force(t)));
        let forcing_dv = (0..n)
            .map(|k| -vg * b.damping.column(k).sum() + if k == d { force } else { 0.0 } + if k == recorded.0 { recorded.1 } else { 0.0 })
            .collect();
        FloorStage { lu: matrix.lu(), damping_dv, forcing_dx, forcing_dv }
    }

    /// Solves the balls' tridiagonal system in place, on `border_solved` or on `rhs`.
    fn thomas(stage: &mut Stage, border: bool) {
        let n = stage.inverse_pivot.len();
        let x = if border { &mut stage.border_solved } else { &mut stage.rhs };
        for i in 0..n {
            let prev = if i > 0 { stage.off[i - 1] * x[i - 1] } else { 0.0 };
            x[i] = (x[i] - prev) * stage.inverse_pivot[i];
        }
        for i in (0..n.saturating_sub(1)).rev() {
            x[i] -= stage.upper[i] * x[i + 1];
        }
    }

    /// Overwrites `r` with `(I / hg - J)^-1 r` for the matrix factored in `stage`.
    pub(super) fn solve(&self, stage: &mut Stage, r: &mut [f64]) {
        let (n, hg) = (self.n, stage.hg);
        // Velocity equations times each body's mass: m r_v + hg (m A_x r_x).
        for i in 0..n {
            stage.rhs[i] = self.mass[i] * r[self.v(i)];
        }
        let mut frame_rhs = 0.0;
        if self.floors.is_some() {
            // The carrying floor's own terms come with the other floors'.
        } else if self.has_frame() {
            frame_rhs = self.frame_mass * r[VS] + hg * stage.frame_kx * r[XS];
        }
        let position = |side: Side, r: &[f64]| match side {
            Side::Ball(i) => r[self.x(i)],
            Side::Wall(_) => r[XS],
        };
        for (pair, p) in self.pairs.iter().zip(&stage.partials) {
            if p.kd == 0.0 {
                continue;
            }
            let df = hg * p.kd * (position(pair.left, r) - position(pair.right, r));
            for (side, sign) in [(pair.left, -1.0), (pair.right, 1.0)] {
                match self.body(side) {
                    Some(b) if b == n => frame_rhs += sign * df,
                    Some(b) => stage.rhs[b] += sign * df,
                    None => {}
                }
            }
        }
        // Balls, then the frame by its Schur complement, then the balls' correction.
        Self::thomas(stage, false);
        if let (Some(floors), Some(fs)) = (&self.floors, stage.floors.take()) {
            self.solve_floors(floors, &fs, stage, r, frame_rhs);
            stage.floors = Some(fs);
            return;
        }
        let frame_u = if self.has_frame() {
            let u = (frame_rhs - stage.border.iter().zip(&stage.rhs).map(|(c, z)| c * z).sum::<f64>()) / stage.schur;
            for (z, w) in stage.rhs.iter_mut().zip(&stage.border_solved) {
                *z -= w * u;
            }
            u
        } else {
            0.0
        };
        for i in 0..n {
            r[self.v(i)] = stage.rhs[i];
            r[self.x(i)] = hg * (r[self.x(i)] + stage.rhs[i]);
        }
        if self.has_frame() {
            r[VS] = frame_u;
            r[XS] = hg * (r[XS] + frame_u);
        } else {
            r[VS] *= hg;
            r[XS] *= hg;
        }
        self.solve_integrals(stage, r);
        let (dw, fw) = (self.damping_work(), self.forcing_work());
        r[dw] = hg * (r[dw] + stage.damping_dv * r[VS]);
        r[fw] = hg * (r[fw] + stage.forcing_dx * r[XS] + stage.forcing_dv * r[VS]);
    }

    /// [`System::solve`] for the floors of a structure, once the balls' system is solved on
    /// `stage.rhs`: the floors' velocity increments from their factored matrix, with
    /// `contact_rhs` (the contacts' terms) on the carrying floor, then the balls' correction.
    fn solve_floors(&self, floors: &Floors, fs: &FloorStage, stage: &mut Stage, r: &mut [f64], contact_rhs: f64) {
        let (n, hg) = (self.n, stage.hg);
        let structure = floors.structure;
        let b = &structure.building;
        let (d, count) = (structure.floor, floors.count());
        // Velocity equations times each floor's mass: m r_v - hg (K r_x).
        let mut rhs = nalgebra::DVector::from_iterator(
            count,
            (0..count).map(|j| {
                let spring: f64 = (0..count).map(|k| floors.stiffness[(j, k)] * r[floors.x(k)]).sum();
                b.masses[j] * r[floors.v(j)] - hg * spring
            }),
        );
        rhs[d] += contact_rhs - stage.border.iter().zip(&stage.rhs).map(|(c, z)| c * z).sum::<f64>();
        let w = fs.lu.solve(&rhs).unwrap_or_else(|| nalgebra::DVector::from_element(count, f64::NAN));
        for (z, c) in stage.rhs.iter_mut().zip(&stage.border_solved) {
            *z -= c * w[d];
        }
        for i in 0..n {
            r[self.v(i)] = stage.rhs[i];
            r[self.x(i)] = hg * (r[self.x(i)] + stage.rhs[i]);
        }
        for j in 0..count {
            r[floors.v(j)] = w[j];
            r[floors.x(j)] = hg * (r[floors.x(j)] + w[j]);
        }
        self.solve_integrals(stage, r);
        let (dw, fw) = (self.damping_work(), self.forcing_work());
        let (mut damping, mut forcing) = (0.0, 0.0);
        for j in 0..count {
            let (x, v) = (r[floors.x(j)], r[floors.v(j)]);
            damping += fs.damping_dv[j] * v;
            forcing += fs.forcing_dx[j] * x + fs.forcing_dv[j] * v;
        }
        r[dw] = hg * (r[dw] + damping);
        r[fw] = hg * (r[fw] + forcing);
    }

    /// The contacts' dissipation integrals of [`System::solve`]: `u_q = hg (r_q + J_q u)`, `J_q`
    /// acting on the bodies' increments just found.
    fn solve_integrals(&self, stage: &Stage, r: &mut [f64]) {
        let hg = stage.hg;
        let edge = |side: Side, r: &[f64]| match side {
            Side::Ball(i) => (r[self.x(i)], r[self.v(i)]),
            Side::Wall(_) => (r[XS], r[VS]),
        };
        for p in 0..self.slots.count() {
            r[self.dissipation(p)] *= hg;
        }
        for (pair, p) in self.pairs.iter().zip(&stage.partials) {
            if p.gd != 0.0 || p.gr != 0.0 {
                let ((xl, vl), (xr, vr)) = (edge(pair.left, r), edge(pair.right, r));
                r[self.dissipation(pair.p)] += hg * (p.gd * (xl - xr) + p.gr * (vl - vr));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::system::{System, VS, XS};
    use super::Stage;
    use crate::scene::{load_scene, scenes_dir, Scene};

    /// The analytic Jacobian and the bordered tridiagonal solve against central differences
    /// of the derivative: every pair pressed (both walls too), a base-excited frame, so every
    /// row and column of the system is exercised. `solve(u / hg - J_fd u)` must give `u` back
    /// to the differences' accuracy (their truncation `(delta / d)^2 / 24` and round-off
    /// `ulp(x) / delta` are both about 1e-8 here).
    #[test]
    fn solve_inverts_the_stage_matrix_of_finite_differences() {
        check_stage(load_scene(scenes_dir().join("forced-lsl.toml")).unwrap());
    }

    /// The same for the floors of a building shaken by a record, the damper on its top floor:
    /// the floors' block, its coupling to the balls through the walls, and the storeys'
    /// dissipation and the ground's work.
    #[test]
    fn solve_inverts_the_stage_matrix_of_a_building() {
        check_stage(load_scene(scenes_dir().join("mdof-3storey-record.toml")).unwrap());
    }

    fn check_stage(mut scene: Scene) {
        let diameters: f64 = scene.balls.iter().map(|b| 2.0 * b.radius).sum();
        let mut container = scene.container.unwrap();
        // Shorter than the balls by 80 um: the walls and the balls all press each other.
        container.length = diameters - 8e-5;
        scene.container = Some(container);
        let sys = System::new(&scene);
        let n = sys.n;
        let mut y = vec![0.0; sys.len()];
        y[XS] = 1e-3;
        y[VS] = -0.2;
        let mut x = y[XS] - 2e-5;
        for i in 0..n {
            x += scene.balls[i].radius;
            y[sys.x(i)] = x;
            y[sys.v(i)] = 0.1 * (i as f64 - 1.0);
            x += scene.balls[i].radius - 2e-5;
        }
        let mut floor_positions = Vec::new();
        if let Some(floors) = &sys.floors {
            for j in (0..floors.count()).filter(|&j| j != floors.structure.floor) {
                y[floors.x(j)] = 1e-3 * (0.5 + j as f64);
                y[floors.v(j)] = 0.03 * (1.0 - j as f64);
                floor_positions.push(floors.x(j));
            }
        }
        for pair in &sys.pairs {
            assert!(sys.overlap(pair, |i| y[i]).0 > 0.0, "pair {} does not press", pair.p);
        }
        let v_max = vec![10.0 * sys.v_scale; sys.pairs.len()];
        let t = 0.3;
        let mut dy = vec![0.0; y.len()];
        sys.rhs(t, &y, &mut dy, &v_max);
        let hg = 2e-6;
        let mut stage = Stage::default();
        sys.factor(t, &y, &dy, &v_max, hg, &mut stage);
        // A direction with every component moving, the integrals' too, positions by about `hg`
        // times velocities as in a step (so that neither half of the matrix swamps the other).
        let integral = |k: usize| (sys.damping_work()..sys.dissipation(sys.slots.count())).contains(&k);
        let position = |k: usize| k == XS || (2..2 + n).contains(&k) || floor_positions.contains(&k);
        let u: Vec<f64> = (0..y.len())
            .map(|k| match k {
                k if integral(k) => 0.5,
                k if position(k) => hg * 1e-6 * (1.0 + 0.37 * k as f64).sin(),
                k => 1e-6 * (1.0 + 0.37 * k as f64).sin(),
            })
            .collect();
        let mut ju = vec![0.0; y.len()];
        let (mut ahead, mut behind) = (vec![0.0; y.len()], vec![0.0; y.len()]);
        for k in 0..y.len() {
            let delta = if integral(k) {
                1.0
            } else if position(k) {
                1e-9
            } else {
                1e-7
            };
            let mut yp = y.clone();
            yp[k] += delta;
            sys.rhs(t, &yp, &mut ahead, &v_max);
            yp[k] -= 2.0 * delta;
            sys.rhs(t, &yp, &mut behind, &v_max);
            for (j, out) in ju.iter_mut().enumerate() {
                *out += (ahead[j] - behind[j]) / (2.0 * delta) * u[k];
            }
        }
        let mut r: Vec<f64> = u.iter().zip(&ju).map(|(u, ju)| u / hg - ju).collect();
        sys.solve(&mut stage, &mut r);
        let scale = u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for k in 0..y.len() {
            let of = if integral(k) {
                scale
            } else if position(k) {
                hg * 1e-6
            } else {
                1e-6
            };
            assert!((r[k] - u[k]).abs() <= 1e-6 * of, "component {k}: {} vs {}", r[k], u[k]);
        }
    }
}
