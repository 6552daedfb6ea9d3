//! A structure's floors since the last change of the carrying floor's velocity or mass (docs/
//! MODEL.md §16-17): the closed form of [`crate::storeys`] stretch by stretch of the ground
//! record, and what the reference asks of the carrying floor (its absolute motion, where its
//! acceleration changes sign, the round-off of both), found with bounds that carry round-off as
//! the one-storey frame's are.
//!
//! On a stretch the carrying floor's absolute acceleration is `a(s) = Re sum_k w_k L_k^2
//! e^{L_k s} + a0 + a1 s` (the ground's line; zero under a force record), plus `Re H e^{i w t}`
//! under a sine: with damping `>= 0` every
//! `|e^{L_k s}| <= 1`, so its `n`-th derivative is bounded by `B_n = sum_k |w_k| |L_k|^n` (the
//! ground's line adds to the first only, a sine `|H| w^n` to each), and the scan that clears an
//! interval of sign changes uses those bounds.

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::Arc;

use super::segment::illinois;
use crate::oscillator::{gauss_legendre, ROUNDOFF_ULPS};
use crate::scene::record::Stretch;
use crate::scene::{Forcing, ForcingKind, Structure};
use crate::storeys::{Modes, C64};
use nalgebra::DMatrix;

use super::ROUNDOFF_RELATIVE;

/// One stretch of the segment: on `[start, end)` the record's load (the ground's acceleration
/// or a floor's force) is `g0 + g1 (t - start)`.
#[derive(Debug, Clone)]
struct Piece {
    start: f64,
    end: f64,
    /// The ground's stretch (a still one under a force record).
    ground: Stretch,
    g0: f64,
    g1: f64,
    /// The ground's acceleration `a0 + a1 (t - start)`: the load's line when it is the ground's,
    /// zero under a force record.
    a0: f64,
    a1: f64,
    /// Modal coefficients at `start`.
    c: Vec<C64>,
    /// The carrying floor's displacement as `Re sum w_k e^{L_k s}` (plus the particular part).
    w: Vec<C64>,
    /// `B_n = sum |w_k| |L_k|^n`, `n = 0..=5`.
    bounds: [f64; 6],
}

/// The carrying floor's acceleration at one time, with its jerk.
#[derive(Debug, Clone, Copy)]
struct Probe {
    t: f64,
    a: f64,
    jerk: f64,
}

/// The stretch of no load and a still ground.
const STILL: Stretch = Stretch { index: 0, start: 0.0, end: f64::INFINITY, g0: 0.0, g1: 0.0, x0: 0.0, v0: 0.0 };

/// A sum with Neumaier's compensation of the rounding of each addition.
#[derive(Debug, Default, Clone, Copy)]
struct Compensated {
    sum: f64,
    lost: f64,
}

impl Compensated {
    fn add(&mut self, x: f64) {
        let t = self.sum + x;
        self.lost += if self.sum.abs() >= x.abs() { (self.sum - t) + x } else { (x - t) + self.sum };
        self.sum = t;
    }
    fn value(&self) -> f64 {
        self.sum + self.lost
    }
}

/// A sine load on the structure (a force on the carrying floor, or the ground moving as
/// `Y sin w t`) and the floors' steady response to it, for the current modes.
#[derive(Debug, Clone)]
struct Sine {
    omega: f64,
    /// The ground's amplitude `Y` (base motion), m.
    ground: f64,
    /// The force's amplitude on the carrying floor, N.
    force: f64,
    /// The floors' steady response, `u = Re U e^{i w t}`.
    u: Vec<C64>,
    /// The carrying floor's absolute acceleration in it, `Re H e^{i w t}`.
    h: C64,
}

/// The sign changes found so far in the current segment, and how far the scan has gone.
#[derive(Debug, Default)]
struct SignScan {
    scanned_to: f64,
    roots: Vec<f64>,
}

/// The floors' closed-form motion since the last impulse on the carrying floor.
pub(super) struct StoreyMotion {
    structure: Arc<Structure>,
    modes: Rc<Modes>,
    /// Modes already decomposed, by the mass the carrying floor holds.
    cache: Vec<(f64, Rc<Modes>)>,
    t0: f64,
    z0: Vec<f64>,
    pieces: RefCell<Vec<Piece>>,
    scan: RefCell<SignScan>,
    /// Longest scan step of the sign-change search: a sixteenth of the shortest period.
    pub(super) scan_step: f64,
    /// The longest period, or the horizon when no mode oscillates.
    pub(super) span: f64,
    /// Why the motion cannot go on (a decomposition that failed), once it cannot.
    pub(super) failure: Option<String>,
    /// The sine load and the response to it, when the scene has one.
    sine: Option<Sine>,
    /// The sine load as the scene gives it.
    forcing: Option<Forcing>,
    /// `K`.
    stiffness: DMatrix<f64>,
}

impl StoreyMotion {
    pub(super) fn new(structure: Arc<Structure>, forcing: Option<Forcing>, horizon: f64) -> Result<Self, String> {
        let modes = Rc::new(structure.building.modes(structure.floor, 0.0, structure.load())?);
        let structure_stiffness = structure.building.stiffness();
        let z0 = structure.initial_displacements.iter().chain(&structure.initial_velocities).copied().collect();
        let mut m = StoreyMotion {
            structure,
            modes: modes.clone(),
            cache: vec![(0.0, modes)],
            t0: 0.0,
            z0,
            pieces: RefCell::new(Vec::new()),
            scan: RefCell::default(),
            scan_step: 0.0,
            span: 0.0,
            failure: None,
            sine: None,
            forcing,
            stiffness: structure_stiffness,
        };
        m.sine = m.steady_response()?;
        m.set_scales(horizon);
        m.reset();
        Ok(m)
    }

    /// The steady response to the sine load with the current modes' masses, if any.
    fn steady_response(&self) -> Result<Option<Sine>, String> {
        let Some(g) = self.forcing else { return Ok(None) };
        let (n, d, omega) = (self.n(), self.structure.floor, g.omega());
        let (ground, force) = match g.kind {
            ForcingKind::Base => (g.amplitude, 0.0),
            ForcingKind::Force => (0.0, g.amplitude),
        };
        // sin w t = Re(-i e^{i w t}): the ground's acceleration -Y w^2 sin w t is Re(i Y w^2 e^{i w t}).
        let ag = C64::new(0.0, ground * omega * omega);
        let loads: Vec<C64> =
            (0..n).map(|i| -ag * self.modes.masses[i] + if i == d { C64::new(0.0, -force) } else { C64::new(0.0, 0.0) }).collect();
        let u = self
            .structure
            .building
            .harmonic_response(&self.modes.masses, omega, &loads)
            .ok_or_else(|| format!("the structure has no steady response at {} Hz (undamped, at a natural frequency)", g.frequency))?;
        let h = -u[d] * omega * omega + ag;
        Ok(Some(Sine { omega, ground, force, u, h }))
    }

    /// The sine's part of the floors' state `[u; u']` at `t` (zero without one).
    fn sine_state(&self, t: f64) -> Vec<f64> {
        let n = self.n();
        match &self.sine {
            None => vec![0.0; 2 * n],
            Some(s) => {
                let e = C64::new(0.0, s.omega * t).exp();
                let i_w = C64::new(0.0, s.omega);
                (0..2 * n).map(|k| if k < n { (s.u[k] * e).re } else { (s.u[k - n] * e * i_w).re }).collect()
            }
        }
    }

    fn set_scales(&mut self, horizon: f64) {
        let forcing_period = self.sine.as_ref().map_or(f64::INFINITY, |s| 2.0 * std::f64::consts::PI / s.omega);
        let shortest = self.modes.shortest_period.min(forcing_period);
        self.scan_step = if shortest.is_finite() { shortest / 16.0 } else { horizon.min(1.0 / self.modes.rate.max(1e-300)) };
        self.span = if self.modes.longest_period.is_finite() { self.modes.longest_period } else { horizon };
    }

    fn n(&self) -> usize {
        self.modes.n
    }

    /// The record's stretch that holds `t` (the ground's acceleration or a floor's force), or
    /// one of no load.
    fn stretch(&self, t: f64) -> Stretch {
        match (&self.structure.ground, &self.structure.force) {
            (Some(g), _) => g.stretch(t),
            (None, Some(f)) => f.record.stretch(t),
            (None, None) => STILL,
        }
    }

    /// The ground's stretch that holds `t`: the record's, or one of a still ground.
    fn ground_stretch(&self, t: f64) -> Stretch {
        self.structure.ground.as_ref().map_or(STILL, |g| g.stretch(t))
    }

    /// The piece that starts at `start` from the state `z`.
    fn piece(&self, start: f64, z: &[f64]) -> Piece {
        let load = self.stretch(start);
        let (g0, g1) = (load.g0 + load.g1 * (start - load.start), load.g1);
        let ground = self.ground_stretch(start);
        let (a0, a1) = if self.structure.ground.is_some() { (g0, g1) } else { (0.0, 0.0) };
        let steady = self.sine_state(start);
        let departure: Vec<f64> = z.iter().zip(&steady).map(|(z, s)| z - s).collect();
        let c = self.modes.coefficients(&departure, g0, g1);
        let w = self.modes.floor_terms(&c, self.structure.floor);
        let mut bounds: [f64; 6] =
            std::array::from_fn(|n| w.iter().zip(&self.modes.lambda).map(|(w, l)| w.norm() * l.norm().powi(n as i32)).sum());
        if let Some(s) = &self.sine {
            // The sine's displacement (with the ground's) and its absolute acceleration.
            let shift = s.u[self.structure.floor].norm() + s.ground;
            for (n, b) in bounds.iter_mut().enumerate() {
                *b += if n < 2 { shift * s.omega.powi(n as i32) } else { s.h.norm() * s.omega.powi(n as i32 - 2) };
            }
        }
        Piece { start, end: load.end, ground, g0, g1, a0, a1, c, w, bounds }
    }

    /// Drops the pieces and sign changes of the last segment and starts from `(t0, z0)`.
    fn reset(&mut self) {
        let first = self.piece(self.t0, &self.z0);
        *self.pieces.get_mut() = vec![first];
        *self.scan.get_mut() = SignScan { scanned_to: self.t0, roots: Vec::new() };
    }

    /// The index of the piece that holds `t` (at a boundary, the piece that starts there),
    /// adding pieces as far as `t`.
    fn index(&self, t: f64) -> usize {
        let mut pieces = self.pieces.borrow_mut();
        while pieces.last().is_some_and(|p| p.end <= t) {
            let last = pieces.last().expect("a segment has a piece");
            let z = self.full_state(last, last.end);
            let next = self.piece(last.end, &z);
            pieces.push(next);
        }
        pieces.partition_point(|p| p.start <= t).saturating_sub(1)
    }

    fn with_piece<R>(&self, t: f64, f: impl FnOnce(&Piece) -> R) -> R {
        let k = self.index(t);
        f(&self.pieces.borrow()[k])
    }

    /// The floors' state `[u; u']` at `t` on piece `p`: its free and linear parts and the sine's.
    fn full_state(&self, p: &Piece, t: f64) -> Vec<f64> {
        let mut z = self.modes.state(&p.c, p.g0, p.g1, t - p.start);
        if self.sine.is_some() {
            for (z, s) in z.iter_mut().zip(self.sine_state(t)) {
                *z += s;
            }
        }
        z
    }

    /// The sine ground's displacement and velocity at `t` (zero without one).
    fn sine_ground(&self, t: f64) -> (f64, f64) {
        match &self.sine {
            Some(s) if s.ground != 0.0 => {
                let (sin, cos) = (s.omega * t).sin_cos();
                (s.ground * sin, s.ground * s.omega * cos)
            }
            _ => (0.0, 0.0),
        }
    }

    /// The ground's displacement and velocity at `t`.
    pub(super) fn ground(&self, t: f64) -> (f64, f64) {
        let g = self.ground_stretch(t);
        let (x, v, _) = g.at(t - g.start);
        let (xs, vs) = self.sine_ground(t);
        (x + xs, v + vs)
    }

    /// The floors' state `[u; u']` relative to the ground at `t`, and the ground's displacement
    /// and velocity.
    pub(super) fn floors(&self, t: f64) -> (Vec<f64>, (f64, f64)) {
        if t == self.t0 {
            return (self.z0.clone(), self.ground(t));
        }
        self.with_piece(t, |p| {
            let (x, v, _) = p.ground.at(t - p.ground.start);
            let (xs, vs) = self.sine_ground(t);
            (self.full_state(p, t), (x + xs, v + vs))
        })
    }

    /// The carrying floor's absolute displacement and velocity at `t`.
    pub(super) fn state(&self, t: f64) -> (f64, f64) {
        let d = self.structure.floor;
        if t == self.t0 {
            // At its start the segment is exactly the state it was made from.
            let (xg, vg) = self.ground(t);
            return (xg + self.z0[d], vg + self.z0[self.n() + d]);
        }
        self.with_piece(t, |p| {
            let s = t - p.start;
            let (mut u, mut v) = self.modes.particular(d, p.g0, p.g1, s);
            for (w, l) in p.w.iter().zip(&self.modes.lambda) {
                let e = w * (l * s).exp();
                u += e.re;
                v += (e * l).re;
            }
            let (xg, vg, _) = p.ground.at(t - p.ground.start);
            if let Some(sine) = &self.sine {
                let e = sine.u[d] * C64::new(0.0, sine.omega * t).exp();
                let (xs, vs) = self.sine_ground(t);
                u += e.re + xs;
                v += (e * C64::new(0.0, sine.omega)).re + vs;
            }
            (xg + u, vg + v)
        })
    }

    /// The carrying floor's absolute acceleration, jerk and snap at `t`, with the size of the
    /// terms of each.
    fn derivatives(&self, p: &Piece, t: f64) -> [(f64, f64); 3] {
        let s = t - p.start;
        let mut d = [0.0; 3];
        for (w, l) in p.w.iter().zip(&self.modes.lambda) {
            let mut e = w * (l * s).exp() * l * l;
            for x in &mut d {
                *x += e.re;
                e *= l;
            }
        }
        if let Some(sine) = &self.sine {
            let i_w = C64::new(0.0, sine.omega);
            let mut e = sine.h * C64::new(0.0, sine.omega * t).exp();
            for x in &mut d {
                *x += e.re;
                e *= i_w;
            }
        }
        [(d[0] + p.a0 + p.a1 * s, p.bounds[2] + (p.a0 + p.a1 * s).abs()), (d[1] + p.a1, p.bounds[3] + p.a1.abs()), (d[2], p.bounds[4])]
    }

    fn probe(&self, p: &Piece, t: f64) -> Probe {
        let [(a, _), (jerk, _), _] = self.derivatives(p, t);
        Probe { t, a, jerk }
    }

    /// The carrying floor's absolute acceleration just after `t`: its value, with the sign of
    /// the first derivative that is not round-off when the acceleration itself is. The value
    /// and the jerk come from the floors' state, as the force of the storeys (and of a sine)
    /// over the floor's mass: at a segment's start that state is exactly the one it was made
    /// from, so the sign is the same whatever mass the floor holds, and holding and releasing
    /// a ball agree at the instant they happen.
    pub(super) fn accel_ahead(&self, t: f64) -> f64 {
        let n = self.n();
        let d = self.structure.floor;
        let b = &self.structure.building;
        let m = &self.modes.masses;
        let (z, _) = self.floors(t);
        let (u, v) = z.split_at(n);
        // The external force on the carrying floor and its rate, and the ground's acceleration.
        let mut elsewhere = None;
        let (force, force_rate, ag) = {
            let stretch = self.stretch(t);
            let s = t - stretch.start;
            let line = (stretch.g0 + stretch.g1 * s, stretch.g1);
            let (mut f, mut fr, mut g) = match self.structure.force.as_ref().map(|f| f.floor) {
                None => (0.0, 0.0, line.0),
                Some(j) if j == d => (line.0, line.1, 0.0),
                Some(j) => {
                    // A force on another floor moves the carrying floor through that floor.
                    elsewhere = Some((j, line.0));
                    (0.0, 0.0, 0.0)
                }
            };
            if let Some(sine) = &self.sine {
                let (sin, cos) = (sine.omega * t).sin_cos();
                let w = sine.omega;
                f += sine.force * sin;
                fr += sine.force * w * cos;
                g -= sine.ground * w * w * sin;
            }
            (f, fr, g)
        };
        let mut forces = b.restoring_forces(u, v);
        forces[d] += force;
        if let Some((j, f)) = elsewhere {
            forces[j] += f;
        }
        let row = |j: usize| (self.stiffness[(d, j)], b.damping[(d, j)]);
        let size: f64 = (0..n).map(|j| row(j).0.abs() * u[j].abs() + row(j).1.abs() * v[j].abs()).sum::<f64>() + force.abs();
        let a = forces[d] / m[d];
        if a.abs() > ROUNDOFF_RELATIVE * size / m[d] {
            return a;
        }
        // The storeys' force changes as `-(C u'' + K u')`, with `u''` each floor's force over
        // its mass less the ground's acceleration.
        let relative: Vec<f64> = (0..n).map(|j| forces[j] / m[j] - ag).collect();
        let mut jerk = force_rate;
        let mut jerk_size = force_rate.abs();
        for j in 0..n {
            let (k, c) = row(j);
            jerk -= c * relative[j] + k * v[j];
            jerk_size += (c * relative[j]).abs() + (k * v[j]).abs();
        }
        let sign = if jerk.abs() > ROUNDOFF_RELATIVE * jerk_size {
            jerk.signum()
        } else {
            let snap = self.with_piece(t, |p| self.derivatives(p, t)[2].0);
            if snap == 0.0 {
                return 0.0;
            }
            snap.signum()
        };
        sign * a.abs().max(f64::MIN_POSITIVE)
    }

    /// A bound on the round-off of the carrying floor's absolute position at `t`.
    pub(super) fn position_roundoff(&self, t: f64) -> f64 {
        self.with_piece(t, |p| {
            let s = (t - p.start).max(0.0);
            let d = self.structure.floor;
            let (up, _) = self.modes.particular(d, p.g0, p.g1, s);
            let sg = t - p.ground.start;
            let g = &p.ground;
            let ground = g.x0.abs() + sg * (g.v0.abs() + sg * (0.5 * g.g0.abs() + sg * g.g1.abs() / 6.0));
            let phase = self.sine.as_ref().map_or(0.0, |sine| sine.omega * t.abs());
            let free = (2.0 + self.modes.rate * s + phase) * p.bounds[0];
            ROUNDOFF_ULPS * f64::EPSILON * (free + up.abs() + self.modes.influence[d].abs() * p.g0.abs() + ground)
        })
    }

    /// The next time after `t` at which the carrying floor's acceleration changes sign or the
    /// ground's acceleration changes its line (a piece ends), or `limit` if none comes first.
    pub(super) fn next_sign_change(&self, t: f64, limit: f64) -> f64 {
        if !(limit > t) {
            return limit;
        }
        let boundary = self.with_piece(t, |p| p.end);
        let limit = limit.min(boundary);
        loop {
            {
                let scan = self.scan.borrow();
                let k = scan.roots.partition_point(|&r| r <= t);
                if let Some(&root) = scan.roots.get(k) {
                    return root.min(limit);
                }
                if scan.scanned_to >= limit {
                    return limit;
                }
            }
            let from = self.scan.borrow().scanned_to;
            let k = self.index(from);
            let pieces = self.pieces.borrow();
            let p = &pieces[k];
            // Chunks anchored at the piece's start, so that every search finds the same roots.
            let steps = ((from - p.start) / self.scan_step).floor() + 1.0;
            let mut end = (p.start + steps * self.scan_step).min(p.end);
            if !(end > from) {
                end = (from + self.scan_step).min(p.end);
            }
            let mut found = Vec::new();
            if end > from {
                let mut left = self.probe(p, from);
                let right = self.probe(p, end);
                while let Some(root) = self.first_sign_change(p, &left, &right) {
                    found.push(root);
                    if root >= right.t {
                        break;
                    }
                    left = self.probe(p, root);
                }
            }
            drop(pieces);
            let mut scan = self.scan.borrow_mut();
            scan.roots.extend(found);
            scan.scanned_to = end;
        }
    }

    /// Whether `a` keeps its sign (`order` 0), or its jerk keeps its sign so that `a` is
    /// monotone (`order` 1), over `[l.t, r.t]`, with every round-off margin: a function `y`
    /// with `|y''| <= M` is at least `min(|y(l)|, |y(r)|) - M h^2 / 8` in magnitude between
    /// ends of one sign.
    fn holds(&self, p: &Piece, l: &Probe, r: &Probe, order: usize) -> bool {
        let (yl, yr) = if order == 0 { (l.a, r.a) } else { (l.jerk, r.jerk) };
        if !((yl > 0.0 && yr > 0.0) || (yl < 0.0 && yr < 0.0)) {
            return false;
        }
        let h = r.t - l.t;
        let curvature = p.bounds[order + 4];
        yl.abs().min(yr.abs()) - self.roundoff(p, r.t, order) > curvature * (1.0 + ROUNDOFF_ULPS * f64::EPSILON) * h * h / 8.0
    }

    /// A bound on the round-off of the acceleration (`order` 0) or the jerk (`order` 1) of the
    /// carrying floor evaluated at `t` on piece `p` (at most `t` into it).
    fn roundoff(&self, p: &Piece, t: f64, order: usize) -> f64 {
        let s = t - p.start;
        let line = if order == 0 { p.a0.abs() + p.a1.abs() * s } else { p.a1.abs() };
        let phase = self.sine.as_ref().map_or(0.0, |sine| sine.omega * t.abs());
        ROUNDOFF_ULPS * f64::EPSILON * ((2.0 + self.modes.rate * s + phase) * p.bounds[order + 2] + line)
    }

    /// Whether the acceleration is round-off over all of `[l.t, r.t]`, so that its sign there
    /// says nothing: both ends within their round-off `err`, and its curvature bound keeping it
    /// within `2 err` in between (a floor starting from rest, whose acceleration grows as the
    /// square of time). No sign change is taken there.
    fn is_roundoff(&self, p: &Piece, l: &Probe, r: &Probe) -> bool {
        let err = self.roundoff(p, r.t, 0);
        let h = r.t - l.t;
        l.a.abs() <= err && r.a.abs() <= err && p.bounds[4] * h * h / 8.0 <= err
    }

    /// The first sign change of the acceleration in `(l.t, r.t]`: depth-first over halves.
    fn first_sign_change(&self, p: &Piece, l: &Probe, r: &Probe) -> Option<f64> {
        let same_sign = (l.a > 0.0 && r.a > 0.0) || (l.a < 0.0 && r.a < 0.0);
        if (same_sign && self.holds(p, l, r, 0)) || self.is_roundoff(p, l, r) {
            return None;
        }
        if !same_sign && l.a != 0.0 && r.a != 0.0 && self.holds(p, l, r, 1) {
            return Some(self.illinois(p, l, r));
        }
        if r.t - l.t <= self.time_resolution(r.t) {
            return (!same_sign).then_some(r.t);
        }
        let m = self.probe(p, 0.5 * (l.t + r.t));
        self.first_sign_change(p, l, &m).or_else(|| self.first_sign_change(p, &m, r))
    }

    /// The one root of a monotone acceleration between `l` and `r` (of opposite signs).
    fn illinois(&self, p: &Piece, l: &Probe, r: &Probe) -> f64 {
        illinois((l.t, l.a), (r.t, r.a), |b| self.time_resolution(b), |m| self.probe(p, m).a)
    }

    fn time_resolution(&self, t: f64) -> f64 {
        8.0 * f64::EPSILON * t.abs().max(self.scan_step)
    }

    /// Starts a new segment at `t`, the carrying floor moving at `v` (absolute) and holding
    /// `held` kg of balls.
    pub(super) fn restart(&mut self, t: f64, v: f64, held: f64) {
        let (mut z, (_, vg)) = self.floors(t);
        let d = self.structure.floor;
        z[self.n() + d] = v - vg;
        if let Some((_, m)) = self.cache.iter().find(|(mass, _)| *mass == held) {
            self.modes = m.clone();
        } else {
            match self.structure.building.modes(d, held, self.structure.load()) {
                Ok(m) => {
                    let m = Rc::new(m);
                    self.cache.push((held, m.clone()));
                    self.modes = m;
                }
                Err(why) => self.failure = Some(format!("with {held} kg of balls held on floor {}, {why}", d + 1)),
            }
        }
        if self.forcing.is_some() {
            match self.steady_response() {
                Ok(sine) => self.sine = sine,
                Err(why) => self.failure = Some(format!("with {held} kg of balls held on floor {}, {why}", d + 1)),
            }
        }
        self.t0 = t;
        self.z0 = z;
        self.reset();
    }

    /// The floors' mechanical energy at `t`: their kinetic energy in the ground's inertial
    /// frame and the storeys' springs (balls held on the carrying floor not included), J.
    pub(super) fn energy(&self, t: f64) -> f64 {
        let (z, (_, vg)) = self.floors(t);
        let (u, v) = z.split_at(self.n());
        self.structure.energy(u, v, vg)
    }

    /// What the storeys' dampers dissipated, and the ground put in, from the segment's start
    /// to `t`: Gauss-Legendre on each piece, on sub-pieces short enough that it is exact to
    /// round-off (the integrands turn at up to twice the fastest mode's rate).
    pub(super) fn segment_energy(&self, t: f64) -> (f64, f64) {
        if !(t > self.t0) {
            return (0.0, 0.0);
        }
        let fastest = self.modes.rate.max(self.sine.as_ref().map_or(0.0, |s| s.omega));
        let sub = std::f64::consts::PI / (8.0 * fastest.max(1e-300));
        let last = self.index(t);
        let b_ = &self.structure.building;
        let floor = self.structure.floor;
        let recorded = self.structure.force.as_ref().map(|f| f.floor);
        let n = self.n();
        // Each sub-piece's integral is added with Neumaier's compensation, so that the sum of
        // a long segment's thousands of them adds no round-off of its own.
        let mut sums = [Compensated::default(), Compensated::default()];
        let pieces = self.pieces.borrow();
        for p in &pieces[..=last] {
            let (a, b) = (p.start, p.end.min(t));
            let count = ((b - a) / sub).ceil().max(1.0);
            let h = (b - a) / count;
            for j in 0..count as usize {
                let (lo, hi) = (a + j as f64 * h, if j + 1 == count as usize { b } else { a + (j + 1) as f64 * h });
                let [d, w] = gauss_legendre(lo, hi, hi - lo, |s| {
                    let z = self.full_state(p, s);
                    let (u, v) = z.split_at(n);
                    let vg = p.ground.at(s - p.ground.start).1 + self.sine_ground(s).1;
                    let force = self.sine.as_ref().map_or(0.0, |sine| sine.force * (sine.omega * s).sin() * (v[floor] + vg));
                    let recorded = recorded.map_or(0.0, |j| (p.g0 + p.g1 * (s - p.start)) * (v[j] + vg));
                    [b_.damping_power(v), -vg * b_.base_shear(u, v) + force + recorded]
                });
                sums[0].add(d);
                sums[1].add(w);
            }
        }
        let (damping, work) = (sums[0].value(), sums[1].value());
        (damping, work)
    }

    /// Whether the ground moves or a force acts (then they do work).
    pub(super) fn is_driven(&self) -> bool {
        self.structure.is_recorded() || self.sine.is_some()
    }
}
