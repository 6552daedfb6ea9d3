//! A structure's floors since the last impulse on the carrying floor (docs/MODEL.md §16-17),
//! in closed form: the modes of [`crate::storeys::Building::modes`] stretch by stretch of the
//! record, a sine load's steady response on top, and the energy the storeys dissipate and the
//! excitation puts in. Every model that feeds impulses to a structure moves its floors with
//! this.

use std::cell::RefCell;
use std::sync::Arc;

use crate::oscillator::gauss_legendre;
use crate::scene::record::Stretch;
use crate::scene::{Forcing, ForcingKind, Structure};
use crate::storeys::{Modes, C64};
use nalgebra::DMatrix;

/// One stretch of the segment: on `[start, end)` the record's load (the ground's acceleration
/// or a floor's force) is `g0 + g1 (t - start)`.
#[derive(Debug, Clone)]
pub(crate) struct Piece {
    pub(crate) start: f64,
    pub(crate) end: f64,
    /// The ground's stretch (a still one under a force record).
    pub(crate) ground: Stretch,
    pub(crate) g0: f64,
    pub(crate) g1: f64,
    /// The ground's acceleration `a0 + a1 (t - start)`: the load's line when it is the ground's,
    /// zero under a force record.
    pub(crate) a0: f64,
    pub(crate) a1: f64,
    /// Modal coefficients at `start`.
    pub(crate) c: Vec<C64>,
    /// The watched floors' terms ([`FloorMotion::watching`]), the carrying floor's first.
    pub(crate) floors: Vec<FloorTerms>,
}

/// One floor's displacement on a piece as `Re sum w_k e^{L_k s}` (plus the particular part),
/// with the bounds of its derivatives.
#[derive(Debug, Clone)]
pub(crate) struct FloorTerms {
    pub(crate) floor: usize,
    pub(crate) w: Vec<C64>,
    /// `|w_k|`.
    pub(crate) norms: Vec<f64>,
    /// `B_n = sum |w_k| |L_k|^n`, `n = 0..=5`, with the sine's share.
    pub(crate) bounds: [f64; 6],
}

impl Piece {
    /// The terms of `floor`, one of the floors watched when the piece was made.
    pub(crate) fn terms(&self, floor: usize) -> &FloorTerms {
        self.floors.iter().find(|f| f.floor == floor).expect("only a watched floor's terms are asked for")
    }
}

/// The stretch of no load and a still ground.
pub(crate) const STILL: Stretch = Stretch { index: 0, start: 0.0, end: f64::INFINITY, g0: 0.0, g1: 0.0, x0: 0.0, v0: 0.0 };

/// A sum with Neumaier's compensation of the rounding of each addition.
#[derive(Debug, Default, Clone, Copy)]
pub(crate) struct Compensated {
    sum: f64,
    lost: f64,
}

impl Compensated {
    pub(crate) fn add(&mut self, x: f64) {
        let t = self.sum + x;
        self.lost += if self.sum.abs() >= x.abs() { (self.sum - t) + x } else { (x - t) + self.sum };
        self.sum = t;
    }
    pub(crate) fn value(&self) -> f64 {
        self.sum + self.lost
    }
}

/// A sine load on the structure (a force on the carrying floor, or the ground moving as
/// `Y sin w t`) and the floors' steady response to it, for the current modes.
#[derive(Debug, Clone)]
pub(crate) struct Sine {
    pub(crate) omega: f64,
    /// The ground's amplitude `Y` (base motion), m.
    pub(crate) ground: f64,
    /// The force's amplitude on the carrying floor, N.
    pub(crate) force: f64,
    /// The floors' steady response, `u = Re U e^{i w t}`.
    pub(crate) u: Vec<C64>,
    /// Each floor's absolute acceleration in it, `Re H_j e^{i w t}`.
    pub(crate) h: Vec<C64>,
}

/// The floors' closed-form motion since the last impulse on the carrying floor: a segment
/// that starts at `t0` from the floors' state `z0` and runs piece by piece of the record.
#[derive(Debug)]
pub struct FloorMotion {
    pub(crate) structure: Arc<Structure>,
    pub(crate) modes: Arc<Modes>,
    /// Modes already decomposed, by the mass each floor holds, with the sine's steady response
    /// for them: the bare floors' first, then at most [`MODES_KEPT`] others, the oldest dropped
    /// first.
    cache: Vec<(Vec<f64>, Arc<Modes>, Option<Sine>)>,
    pub(crate) t0: f64,
    pub(crate) z0: Vec<f64>,
    pub(crate) pieces: RefCell<Vec<Piece>>,
    /// The sine load and the response to it, when the scene has one.
    pub(crate) sine: Option<Sine>,
    /// The sine load as the scene gives it.
    forcing: Option<Forcing>,
    /// `K`.
    pub(crate) stiffness: DMatrix<f64>,
    /// The floors whose terms each piece carries, the carrying floor first.
    watched: Vec<usize>,
    /// The mass of balls each floor holds in this segment, kg.
    held: Vec<f64>,
}

/// How many decompositions of the floors' modes with balls held a motion keeps besides the bare
/// floors': a box of balls the floors carry in part holds many masses in turn.
pub const MODES_KEPT: usize = 128;

impl FloorMotion {
    /// The floors of `structure` from their initial state at `t = 0`, under the scene's sine
    /// load `forcing` (if any) and the structure's record.
    pub fn new(structure: Arc<Structure>, forcing: Option<Forcing>) -> Result<Self, String> {
        let modes = Arc::new(structure.building.modes(structure.floor, 0.0, structure.load())?);
        let structure_stiffness = structure.building.stiffness();
        let z0 = structure.initial_displacements.iter().chain(&structure.initial_velocities).copied().collect();
        let watched = vec![structure.floor];
        let mut m = FloorMotion {
            structure,
            modes: modes.clone(),
            cache: Vec::new(),
            t0: 0.0,
            z0,
            pieces: RefCell::new(Vec::new()),
            sine: None,
            forcing,
            stiffness: structure_stiffness,
            watched,
            held: Vec::new(),
        };
        m.held = vec![0.0; m.n()];
        m.sine = m.steady_response()?;
        m.cache.push((m.held.clone(), modes, m.sine.clone()));
        m.reset();
        Ok(m)
    }

    /// The steady response to the sine load with the current modes' masses, if any.
    pub(crate) fn steady_response(&self) -> Result<Option<Sine>, String> {
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
        let h = u.iter().map(|u| -u * omega * omega + ag).collect();
        Ok(Some(Sine { omega, ground, force, u, h }))
    }

    /// The sine's part of the floors' state `[u; u']` at `t` (zero without one).
    pub(crate) fn sine_state(&self, t: f64) -> Vec<f64> {
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

    pub(crate) fn n(&self) -> usize {
        self.modes.n
    }

    /// The record's stretch that holds `t` (the ground's acceleration or a floor's force), or
    /// one of no load.
    pub(crate) fn stretch(&self, t: f64) -> Stretch {
        self.structure.record_stretch(t).unwrap_or(STILL)
    }

    /// The ground's stretch that holds `t`: the record's, or one of a still ground.
    pub(crate) fn ground_stretch(&self, t: f64) -> Stretch {
        self.structure.ground.as_ref().map_or(STILL, |g| g.stretch(t))
    }

    /// The piece that starts at `start` from the state `z`.
    pub(crate) fn piece(&self, start: f64, z: &[f64]) -> Piece {
        let load = self.stretch(start);
        let (g0, g1) = (load.g0 + load.g1 * (start - load.start), load.g1);
        let ground = self.ground_stretch(start);
        let (a0, a1) = if self.structure.ground.is_some() { (g0, g1) } else { (0.0, 0.0) };
        let steady = self.sine_state(start);
        let departure: Vec<f64> = z.iter().zip(&steady).map(|(z, s)| z - s).collect();
        let c = self.modes.coefficients(&departure, g0, g1);
        let floors = self.watched.iter().map(|&floor| self.floor_terms(&c, floor)).collect();
        Piece { start, end: load.end, ground, g0, g1, a0, a1, c, floors }
    }

    /// The terms of `floor`'s displacement for the modal coefficients `c`.
    fn floor_terms(&self, c: &[C64], floor: usize) -> FloorTerms {
        let w = self.modes.floor_terms(c, floor);
        let norms: Vec<f64> = w.iter().map(|w| w.norm()).collect();
        let mut bounds: [f64; 6] =
            std::array::from_fn(|n| norms.iter().zip(&self.modes.lambda_norms).map(|(w, l)| w * l.powi(n as i32)).sum());
        if let Some(s) = &self.sine {
            // The sine's displacement (with the ground's) and its absolute acceleration.
            let shift = s.u[floor].norm() + s.ground;
            for (n, b) in bounds.iter_mut().enumerate() {
                *b += if n < 2 { shift * s.omega.powi(n as i32) } else { s.h[floor].norm() * s.omega.powi(n as i32 - 2) };
            }
        }
        FloorTerms { floor, w, norms, bounds }
    }

    /// The same motion with every piece carrying the terms of `floors` too (the floors that
    /// carry dampers), so that each one's motion is read as the carrying floor's is.
    pub(crate) fn watching(mut self, floors: &[usize]) -> Self {
        for &f in floors {
            if !self.watched.contains(&f) {
                self.watched.push(f);
            }
        }
        self.reset();
        self
    }

    /// Drops the pieces of the last segment and starts from `(t0, z0)`.
    fn reset(&mut self) {
        let first = self.piece(self.t0, &self.z0);
        *self.pieces.get_mut() = vec![first];
    }

    /// The index of the piece that holds `t` (at a boundary, the piece that starts there),
    /// adding pieces as far as `t`.
    pub(crate) fn index(&self, t: f64) -> usize {
        let mut pieces = self.pieces.borrow_mut();
        while pieces.last().is_some_and(|p| p.end <= t) {
            let last = pieces.last().expect("a segment has a piece");
            let z = self.full_state(last, last.end);
            let next = self.piece(last.end, &z);
            pieces.push(next);
        }
        pieces.partition_point(|p| p.start <= t).saturating_sub(1)
    }

    pub(crate) fn with_piece<R>(&self, t: f64, f: impl FnOnce(&Piece) -> R) -> R {
        let k = self.index(t);
        f(&self.pieces.borrow()[k])
    }

    /// The floors' state `[u; u']` at `t` on piece `p`: its free and linear parts and the sine's.
    pub(crate) fn full_state(&self, p: &Piece, t: f64) -> Vec<f64> {
        let mut z = self.modes.state(&p.c, p.g0, p.g1, t - p.start);
        if self.sine.is_some() {
            for (z, s) in z.iter_mut().zip(self.sine_state(t)) {
                *z += s;
            }
        }
        z
    }

    /// The sine ground's displacement and velocity at `t` (zero without one).
    pub(crate) fn sine_ground(&self, t: f64) -> (f64, f64) {
        match &self.sine {
            Some(s) if s.ground != 0.0 => {
                let (sin, cos) = (s.omega * t).sin_cos();
                (s.ground * sin, s.ground * s.omega * cos)
            }
            _ => (0.0, 0.0),
        }
    }

    /// The ground's displacement and velocity at `t`.
    pub fn ground(&self, t: f64) -> (f64, f64) {
        let g = self.ground_stretch(t);
        let (x, v, _) = g.at(t - g.start);
        let (xs, vs) = self.sine_ground(t);
        (x + xs, v + vs)
    }

    /// The floors' state `[u; u']` relative to the ground at `t`, and the ground's displacement
    /// and velocity.
    pub fn floors(&self, t: f64) -> (Vec<f64>, (f64, f64)) {
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
    pub fn state(&self, t: f64) -> (f64, f64) {
        self.floor_state(self.structure.floor, t)
    }

    /// Floor `d`'s absolute displacement and velocity at `t` (a watched floor's from its
    /// terms, another's from the floors' whole state).
    pub fn floor_state(&self, d: usize, t: f64) -> (f64, f64) {
        if !self.watched.contains(&d) {
            let (z, (xg, vg)) = self.floors(t);
            return (xg + z[d], vg + z[self.n() + d]);
        }
        if t == self.t0 {
            // At its start the segment is exactly the state it was made from.
            let (xg, vg) = self.ground(t);
            return (xg + self.z0[d], vg + self.z0[self.n() + d]);
        }
        self.with_piece(t, |p| {
            let s = t - p.start;
            let (mut u, mut v) = self.modes.particular(d, p.g0, p.g1, s);
            for (w, l) in p.terms(d).w.iter().zip(&self.modes.lambda) {
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

    /// Starts a new segment at `t`, the carrying floor moving at `v` (absolute) and holding
    /// `held` kg of balls. When the floors cannot be decomposed with that mass, the segment
    /// still starts (with the modes it had) and the reason is returned.
    pub fn restart(&mut self, t: f64, v: f64, held: f64) -> Result<(), String> {
        let d = self.structure.floor;
        let mut each = vec![0.0; self.n()];
        each[d] = held;
        self.restart_holding(t, &[(d, v)], &each)
    }

    /// Starts a new segment at `t`, each floor `j` of `velocities` moving at its `v` (absolute),
    /// each floor `j` holding `held[j]` kg of balls. When the floors cannot be decomposed with
    /// those masses, the segment still starts (with the modes it had) and the reason is
    /// returned.
    pub fn restart_holding(&mut self, t: f64, velocities: &[(usize, f64)], held: &[f64]) -> Result<(), String> {
        let z = self.state_moving(t, velocities);
        let n = self.n();
        let mut failure = Ok(());
        if let Some((_, m, sine)) = self.cache.iter().find(|(masses, ..)| masses.as_slice() == held) {
            self.modes = m.clone();
            self.sine = sine.clone();
        } else {
            let on = || {
                let floors: Vec<String> =
                    (0..n).filter(|&j| held[j] != 0.0).map(|j| format!("{} kg of balls held on floor {}", held[j], j + 1)).collect();
                floors.join(" and ")
            };
            match self.structure.building.modes_holding(held, self.structure.load()) {
                Ok(m) => {
                    self.modes = Arc::new(m);
                    match self.steady_response() {
                        Ok(sine) => {
                            self.sine = sine;
                            if self.cache.len() > MODES_KEPT {
                                self.cache.remove(1);
                            }
                            self.cache.push((held.to_vec(), self.modes.clone(), self.sine.clone()));
                        }
                        Err(why) => failure = Err(format!("with {}, {why}", on())),
                    }
                }
                Err(why) => failure = Err(format!("with {}, {why}", on())),
            }
        }
        self.t0 = t;
        self.z0 = z;
        self.held = held.to_vec();
        self.reset();
        failure
    }

    /// The floors' state at `t` relative to the ground, with each floor `j` of `velocities`
    /// moving at its `v` (absolute) instead.
    fn state_moving(&self, t: f64, velocities: &[(usize, f64)]) -> Vec<f64> {
        let (mut z, (_, vg)) = self.floors(t);
        let n = self.n();
        for &(j, v) in velocities {
            z[n + j] = v - vg;
        }
        z
    }

    /// Moves each floor `j` of `shifts` by its `dx` at the start of the segment just started
    /// (impulses that landed within the step before it had moved it so far beyond its closed
    /// form).
    pub fn displace(&mut self, shifts: &[(usize, f64)]) {
        for &(j, dx) in shifts {
            self.z0[j] += dx;
        }
        self.reset();
    }

    /// The change of the storeys' spring energy at `t` were each floor `j` of `shifts` moved by
    /// its `dx`, J.
    pub fn displaced_energy(&self, t: f64, shifts: &[(usize, f64)]) -> f64 {
        let (z, _) = self.floors(t);
        let u = &z[..self.n()];
        let mut moved = u.to_vec();
        for &(j, dx) in shifts {
            moved[j] += dx;
        }
        let building = &self.structure.building;
        building.spring_energy(&moved) - building.spring_energy(u)
    }

    /// The mass of balls each floor holds in this segment, kg.
    pub fn held(&self) -> &[f64] {
        &self.held
    }

    /// Starts a new segment at `t`, each floor `j` of `velocities` moving at its `v` (absolute),
    /// no balls held: several floors struck at one instant.
    pub fn restart_floors(&mut self, t: f64, velocities: &[(usize, f64)]) {
        let z = self.state_moving(t, velocities);
        let n = self.n();
        // The bare floors' modes are the first decomposed.
        let (_, m, sine) = &self.cache[0];
        self.modes = m.clone();
        self.sine = sine.clone();
        self.t0 = t;
        self.z0 = z;
        self.held = vec![0.0; n];
        self.reset();
    }

    /// The floors' mechanical energy at `t`: their kinetic energy in the ground's inertial
    /// frame and the storeys' springs (balls held on the carrying floor not included), J.
    pub fn energy(&self, t: f64) -> f64 {
        let (z, (_, vg)) = self.floors(t);
        let (u, v) = z.split_at(self.n());
        self.structure.energy(u, v, vg)
    }

    /// What the storeys' dampers dissipated, and the ground put in, from the segment's start
    /// to `t`: Gauss-Legendre on each piece, on sub-pieces short enough that it is exact to
    /// round-off (the integrands turn at up to twice the fastest mode's rate).
    pub fn segment_energy(&self, t: f64) -> (f64, f64) {
        self.energy_between(self.t0, t)
    }

    /// [`FloorMotion::segment_energy`] from `from` (within the segment) to `t`.
    pub fn energy_between(&self, from: f64, t: f64) -> (f64, f64) {
        if !(t > from && from >= self.t0) {
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
        for p in pieces[..=last].iter().filter(|p| p.end > from) {
            let (a, b) = (p.start.max(from), p.end.min(t));
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
    pub fn is_driven(&self) -> bool {
        self.structure.is_recorded() || self.sine.is_some()
    }
}
