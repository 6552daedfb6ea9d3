//! The scene as an ordinary differential equation: the state's layout (frame, balls, and the
//! energy integrals carried with them), the pairs of neighbours that can touch with their Hertz
//! constants, and the derivative with every open contact's force.

use super::contact;
use super::FLOOR_SPEED_FRACTION;
use crate::scene::{Body, Pairs, Scene};

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
        }
    }

    pub(super) fn len(&self) -> usize {
        4 + 2 * self.n + self.slots.count()
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
        if self.has_frame() {
            let (xs, vs) = (y[XS], y[VS]);
            dy[XS] = vs;
            dy[VS] = (self.scene.frame_force(t, xs, vs) + frame_contact) / self.frame_mass;
            dy[self.damping_work()] = self.scene.damping_power(t, vs);
            dy[self.forcing_work()] = self.scene.forcing_power(t, xs, vs);
        }
    }

    /// A bound on the frame's smooth acceleration over the next while: now, plus what the
    /// spring and damper can give at the frame's amplitude, plus the largest excitation.
    pub(super) fn frame_accel_bound(&self, t: f64, xs: f64, vs: f64) -> f64 {
        let Some(f) = self.scene.frame else { return 0.0 };
        let w0sq = f.stiffness / f.mass;
        let amp = if w0sq > 0.0 { (xs * xs + vs * vs / w0sq).sqrt() } else { xs.abs() };
        let forcing = self.scene.forcing.map_or(0.0, |g| {
            let (p, q) = g.harmonic_load(f.damping, f.stiffness);
            p.hypot(q)
        });
        self.scene.frame_acceleration(t, xs, vs).abs() + w0sq * amp + (f.damping * vs.abs() + forcing) / f.mass
    }

    /// Mechanical energy: frame, balls, and elastic energy in open contacts.
    pub(super) fn energy(&self, t: f64, y: &[f64]) -> f64 {
        let frame = if self.has_frame() { self.scene.frame_energy(t, y[XS], y[VS]) } else { 0.0 };
        let balls: f64 = (0..self.n).map(|i| 0.5 * self.mass[i] * y[self.v(i)] * y[self.v(i)]).sum();
        let elastic: f64 = self.pairs.iter().map(|p| contact::elastic_energy(p.k, self.overlap(p, |i| y[i]).0)).sum();
        frame + balls + elastic
    }

    pub(super) fn bodies(&self, pair: &Pair) -> (Body, Body) {
        self.slots.bodies(pair.p)
    }
}
