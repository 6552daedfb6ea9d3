//! The scene as an ordinary differential equation: the state's layout (frame, balls, and the
//! energy integrals carried with them), the pairs of neighbours that can touch with their Hertz
//! constants, and the derivative with every open contact's force.

use super::contact;
use super::FLOOR_SPEED_FRACTION;
use crate::scene::{Body, Pairs, Scene, Structure};
use nalgebra::DMatrix;

/// One side of a pair.
#[derive(Debug, Clone, Copy)]
pub(super) enum Side {
    /// A ball.
    Ball(usize),
    /// A wall of the frame at this offset from `xs`.
    Wall(f64),
}

/// Two neighbouring bodies that can touch.
#[derive(Debug, Clone, Copy)]
pub(super) struct Pair {
    /// Pair number as the scene counts it ([`Pairs`]).
    pub(super) p: usize,
    pub(super) left: Side,
    pub(super) right: Side,
    /// Hertz stiffness `K`.
    pub(super) k: f64,
    /// Reduced mass, kg.
    pub(super) mass: f64,
    /// Hertz length at the scene's speed scale.
    pub(super) length: f64,
    /// How far apart the bodies of an open contact may come and still be in that contact: the
    /// largest overlap of an impact at the floor speed. Bodies resting against each other
    /// tremble across zero overlap; each tremble is not a new impact.
    pub(super) rest_band: f64,
}

/// The scene as an ODE: state layout, contact geometry, derivative.
pub(super) struct System<'a> {
    pub(super) scene: &'a Scene,
    pub(super) n: usize,
    pub(super) frame_mass: f64,
    pub(super) mass: Vec<f64>,
    pub(super) radius: Vec<f64>,
    pub(super) pairs: Vec<Pair>,
    /// The scene's pairs of neighbours, numbered on its chains.
    pub(super) slots: Pairs,
    /// `c = alpha v0` giving the scene's restitution.
    pub(super) c: f64,
    /// Overlap rates below this set the damping as if they were this (resting contacts).
    pub(super) v_floor: f64,
    /// The scene's speed scale: frame swing, initial ball speeds, forcing.
    pub(super) v_scale: f64,
    /// Position error scale when no contact is open: the smallest Hertz length at `v_scale`.
    pub(super) length_scale: f64,
    /// Longest step: a twentieth of the frame's natural period and of the forcing period, so
    /// that the acceleration bound used to predict contacts holds over a step.
    pub(super) h_max: f64,
    /// Shortest step the closing bound may ask for (a tenth of the shortest contact time scale
    /// at `v_scale`): pairs touching at rest would otherwise shrink steps to nothing.
    pub(super) h_floor: f64,
    /// A structure's floors, when the frame is the floor of a building that carries it.
    pub(super) floors: Option<Floors<'a>>,
}

/// A structure of several storeys (or one under a record) as the ODE carries it. The carrying
/// floor is the frame (`XS`, `VS`: absolute, as the balls are); every other floor's
/// displacement and velocity relative to the ground come after the contacts' dissipation
/// integrals in the state.
pub(super) struct Floors<'a> {
    pub(super) structure: &'a Structure,
    /// `K`, N/m.
    pub(super) stiffness: DMatrix<f64>,
    /// Index of the first other floor's displacement in the state.
    base: usize,
    /// The fastest undamped mode's rate, rad/s.
    pub(super) fastest: f64,
    /// Largest `|ag|` of the ground's record, m/s^2.
    peak_ground: f64,
}

impl Floors<'_> {
    /// Number of floors.
    pub(super) fn count(&self) -> usize {
        self.structure.floors()
    }
    /// State index of floor `j`'s displacement (the carrying floor's is `XS`).
    pub(super) fn x(&self, j: usize) -> usize {
        let d = self.structure.floor;
        match j.cmp(&d) {
            std::cmp::Ordering::Equal => XS,
            std::cmp::Ordering::Less => self.base + j,
            std::cmp::Ordering::Greater => self.base + j - 1,
        }
    }
    /// State index of floor `j`'s velocity (the carrying floor's is `VS`).
    pub(super) fn v(&self, j: usize) -> usize {
        if j == self.structure.floor {
            VS
        } else {
            self.x(j) + self.count() - 1
        }
    }
    /// The floors' displacements and velocities relative to the ground, read through `get`,
    /// the ground at `(xg, vg)`.
    pub(super) fn relative(&self, get: impl Fn(usize) -> f64, (xg, vg): (f64, f64)) -> (Vec<f64>, Vec<f64>) {
        let d = self.structure.floor;
        let n = self.count();
        let u = (0..n).map(|j| get(self.x(j)) - if j == d { xg } else { 0.0 }).collect();
        let v = (0..n).map(|j| get(self.v(j)) - if j == d { vg } else { 0.0 }).collect();
        (u, v)
    }
}

pub(super) const XS: usize = 0;
pub(super) const VS: usize = 1;

impl<'a> System<'a> {
    pub(super) fn new(scene: &'a Scene) -> Self {
        let n = scene.balls.len();
        let mass: Vec<f64> = scene.balls.iter().map(|b| b.mass).collect();
        let radius: Vec<f64> = scene.balls.iter().map(|b| b.radius).collect();
        let frame_mass = scene.frame.map_or(f64::INFINITY, |f| f.mass);
        let e_star = contact::effective_modulus(&scene.compliant);
        let w0 = scene.frame.map_or(0.0, |f| (f.stiffness / f.mass).sqrt());
        let v_scale = scene.speed_scale();
        let mut pairs = Vec::new();
        let walls = scene.container.map(|c| c.length);
        let slots = Pairs::new(n, &scene.space.chain_starts, walls.is_some());
        for p in slots.range() {
            let (left, right) = slots.balls(p);
            let left = left.map_or(Side::Wall(0.0), Side::Ball);
            let right = right.map_or(Side::Wall(walls.unwrap_or(0.0)), Side::Ball);
            let (r_star, m_star) = match (left, right) {
                (Side::Ball(i), Side::Ball(j)) => {
                    (contact::effective_radius(radius[i], Some(radius[j])), mass[i] * mass[j] / (mass[i] + mass[j]))
                }
                (Side::Ball(i), Side::Wall(_)) | (Side::Wall(_), Side::Ball(i)) => (
                    contact::effective_radius(radius[i], None),
                    if frame_mass.is_finite() { mass[i] * frame_mass / (mass[i] + frame_mass) } else { mass[i] },
                ),
                (Side::Wall(_), Side::Wall(_)) => continue,
            };
            let k = contact::stiffness(e_star, r_star);
            pairs.push(Pair {
                p,
                left,
                right,
                k,
                mass: m_star,
                length: contact::length_scale(m_star, v_scale, k),
                rest_band: contact::max_overlap(m_star, FLOOR_SPEED_FRACTION * v_scale, k),
            });
        }
        let length_scale = pairs.iter().map(|p| p.length).reduce(f64::min).unwrap_or_else(|| scene.length_scale() * 1e-3);
        let h_floor = pairs.iter().map(|p| 0.1 * p.length / v_scale).reduce(f64::min).unwrap_or(scene.horizon);
        let mut h_max = scene.horizon;
        if w0 > 0.0 {
            h_max = h_max.min(2.0 * std::f64::consts::PI / w0 / 20.0);
        }
        if let Some(g) = scene.forcing {
            h_max = h_max.min(1.0 / (20.0 * g.frequency));
        }
        let floors = scene.structure.as_deref().map(|structure| {
            let (omegas, _) = structure.building.undamped_modes();
            let fastest = omegas.iter().fold(0.0, |m: f64, w| m.max(*w));
            Floors {
                structure,
                stiffness: structure.building.stiffness(),
                base: 4 + 2 * n + slots.count(),
                fastest,
                peak_ground: structure.ground.as_ref().map_or(0.0, |g| g.peak()),
            }
        });
        if let Some(f) = &floors {
            h_max = h_max.min(2.0 * std::f64::consts::PI / f.fastest / 20.0);
        }
        System {
            scene,
            n,
            frame_mass,
            mass,
            radius,
            pairs,
            slots,
            c: contact::damping_for(scene.restitution),
            v_floor: FLOOR_SPEED_FRACTION * v_scale,
            v_scale,
            length_scale,
            h_max,
            h_floor,
            floors,
        }
    }

    pub(super) fn len(&self) -> usize {
        4 + 2 * self.n + self.slots.count() + self.floors.as_ref().map_or(0, |f| 2 * (f.count() - 1))
    }
    pub(super) fn x(&self, i: usize) -> usize {
        2 + i
    }
    pub(super) fn v(&self, i: usize) -> usize {
        2 + self.n + i
    }
    pub(super) fn damping_work(&self) -> usize {
        2 + 2 * self.n
    }
    pub(super) fn forcing_work(&self) -> usize {
        3 + 2 * self.n
    }
    pub(super) fn dissipation(&self, p: usize) -> usize {
        4 + 2 * self.n + p
    }
    pub(super) fn has_frame(&self) -> bool {
        self.frame_mass.is_finite()
    }

    /// Overlap and overlap rate of `pair`, reading component `i` through `get(i)`.
    #[inline]
    pub(super) fn overlap(&self, pair: &Pair, get: impl Fn(usize) -> f64) -> (f64, f64) {
        let edge = |s: Side, sign: f64| -> (f64, f64) {
            match s {
                Side::Ball(i) => (get(self.x(i)) + sign * self.radius[i], get(self.v(i))),
                Side::Wall(off) => (get(XS) + off, get(VS)),
            }
        };
        let (xl, vl) = edge(pair.left, 1.0);
        let (xr, vr) = edge(pair.right, -1.0);
        (xl - xr, vl - vr)
    }

    /// The damping of a pair at overlap rate `rate`, the contact's largest rate so far being `v_max`.
    #[inline]
    pub(super) fn alpha(&self, v_max: f64, rate: f64) -> f64 {
        self.c / v_max.max(rate).max(self.v_floor)
    }

    /// The derivative of the state; `v_max[q]` is the largest overlap rate of pair `q`'s open
    /// contact (0 when none is open).
    pub(super) fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64], v_max: &[f64]) {
        dy.fill(0.0);
        for i in 0..self.n {
            dy[self.x(i)] = y[self.v(i)];
        }
        let mut frame_contact = 0.0;
        for (q, pair) in self.pairs.iter().enumerate() {
            let (d, rate) = self.overlap(pair, |i| y[i]);
            if d <= 0.0 {
                continue;
            }
            let f = contact::force(pair.k, self.alpha(v_max[q], rate), d, rate);
            // Power leaving the bodies minus the rate of elastic storage: what the damping takes.
            dy[self.dissipation(pair.p)] = (f - pair.k * d * d.sqrt()) * rate;
            match pair.left {
                Side::Ball(i) => dy[self.v(i)] -= f,
                Side::Wall(_) => frame_contact -= f,
            }
            match pair.right {
                Side::Ball(j) => dy[self.v(j)] += f,
                Side::Wall(_) => frame_contact += f,
            }
        }
        for i in 0..self.n {
            dy[self.v(i)] /= self.mass[i];
        }
        if let Some(floors) = &self.floors {
            self.floors_rhs(floors, t, y, dy, frame_contact);
        } else if self.has_frame() {
            let (xs, vs) = (y[XS], y[VS]);
            dy[XS] = vs;
            dy[VS] = (self.scene.frame_force(t, xs, vs) + frame_contact) / self.frame_mass;
            dy[self.damping_work()] = self.scene.damping_power(t, vs);
            dy[self.forcing_work()] = self.scene.forcing_power(t, xs, vs);
        }
    }

    /// The floors' part of the derivative: the carrying floor's absolute acceleration with the
    /// balls' contact force `contact` on it, the other floors' relative ones, the storeys'
    /// dissipation and the excitation's power (docs/MODEL.md §16).
    fn floors_rhs(&self, floors: &Floors, t: f64, y: &[f64], dy: &mut [f64], contact: f64) {
        let structure = floors.structure;
        let (d, n) = (structure.floor, floors.count());
        let (xg, vg, ag) = self.scene.ground_motion(t);
        let (u, v) = floors.relative(|i| y[i], (xg, vg));
        let restoring = structure.building.restoring_forces(&u, &v);
        let force = self.scene.forcing.map_or(0.0, |g| g.force(t));
        let recorded = structure.force.as_ref().map(|f| (f.floor, structure.recorded_force(t)));
        for j in 0..n {
            dy[floors.x(j)] = y[floors.v(j)];
            let m = structure.building.masses[j];
            let external = recorded.filter(|r| r.0 == j).map_or(0.0, |r| r.1);
            dy[floors.v(j)] = if j == d { (restoring[j] + contact + force + external) / m } else { (restoring[j] + external) / m - ag };
        }
        dy[self.damping_work()] = structure.building.damping_power(&v);
        let recorded_power = recorded.map_or(0.0, |(j, f)| f * (v[j] + vg));
        dy[self.forcing_work()] = vg * restoring.iter().sum::<f64>() + force * y[VS] + recorded_power;
    }

    /// A bound on the frame's smooth acceleration over the next while: now, plus what the
    /// spring and damper can give at the frame's amplitude, plus the largest excitation.
    pub(super) fn frame_accel_bound(&self, t: f64, y: &[f64]) -> f64 {
        if let Some(floors) = &self.floors {
            return self.floor_accel_bound(floors, t, y);
        }
        let (xs, vs) = (y[XS], y[VS]);
        let Some(f) = self.scene.frame else { return 0.0 };
        let w0sq = f.stiffness / f.mass;
        let amp = if w0sq > 0.0 { (xs * xs + vs * vs / w0sq).sqrt() } else { xs.abs() };
        let forcing = self.scene.forcing.map_or(0.0, |g| {
            let (p, q) = g.harmonic_load(f.damping, f.stiffness);
            p.hypot(q)
        });
        self.scene.frame_acceleration(t, xs, vs).abs() + w0sq * amp + (f.damping * vs.abs() + forcing) / f.mass
    }

    /// [`System::frame_accel_bound`] on a structure: the carrying floor's acceleration now, plus
    /// what its storeys can give with the floors anywhere their relative energy `E` lets them
    /// be (each storey's drift at most `sqrt(2 E / k_min)`, so `|u_j| <= n` times that, and
    /// `|v_j| <= sqrt(2 E / m_j)`),
    /// plus the ground's and the sine's largest.
    fn floor_accel_bound(&self, floors: &Floors, t: f64, y: &[f64]) -> f64 {
        let structure = floors.structure;
        let b = &structure.building;
        let (d, n) = (structure.floor, floors.count());
        let (xg, vg, ag) = self.scene.ground_motion(t);
        let (u, v) = floors.relative(|i| y[i], (xg, vg));
        let m = b.masses[d];
        let energy = structure.energy(&u, &v, 0.0);
        let k_min = b.stiffnesses.iter().fold(f64::INFINITY, |a, k| a.min(*k));
        let u_max = (n as f64) * (2.0 * energy / k_min).sqrt();
        let spring = (0..n).map(|j| floors.stiffness[(d, j)].abs()).sum::<f64>() * u_max;
        let damper: f64 = (0..n).map(|j| b.damping[(d, j)].abs() * (2.0 * energy / b.masses[j]).sqrt()).sum();
        let sine = self.scene.forcing.map_or(0.0, |g| if g.kind == crate::scene::ForcingKind::Force { g.amplitude } else { 0.0 });
        // A recorded force reaches the carrying floor at most whole.
        let force = sine + structure.force.as_ref().map_or(0.0, |f| f.record.peak());
        let base = self.scene.forcing.map_or(0.0, |g| {
            if g.kind == crate::scene::ForcingKind::Base {
                g.amplitude * g.omega() * g.omega()
            } else {
                0.0
            }
        });
        let now = self.scene.floor_accelerations(t, &u, &v)[d];
        now.abs() + (spring + damper + force) / m + ag.abs().max(floors.peak_ground) + base
    }

    /// Mechanical energy: frame, balls, and elastic energy in open contacts.
    pub(super) fn energy(&self, t: f64, y: &[f64]) -> f64 {
        let frame = match &self.floors {
            Some(floors) => {
                let (xg, vg, _) = self.scene.ground_motion(t);
                let (u, v) = floors.relative(|i| y[i], (xg, vg));
                floors.structure.energy(&u, &v, vg)
            }
            None if self.has_frame() => self.scene.frame_energy(t, y[XS], y[VS]),
            None => 0.0,
        };
        let balls: f64 = (0..self.n).map(|i| 0.5 * self.mass[i] * y[self.v(i)] * y[self.v(i)]).sum();
        let elastic: f64 = self.pairs.iter().map(|p| contact::elastic_energy(p.k, self.overlap(p, |i| y[i]).0)).sum();
        frame + balls + elastic
    }

    pub(super) fn bodies(&self, pair: &Pair) -> (Body, Body) {
        self.slots.bodies(pair.p)
    }
}
