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

use std::cell::{Cell, RefCell};
use std::ops::Deref;
use std::sync::Arc;

use super::segment::illinois;
use crate::floor_motion::{FloorMotion, Piece};
use crate::oscillator::ROUNDOFF_ULPS;
use crate::scene::{Forcing, Structure};
use crate::storeys::C64;

use super::ROUNDOFF_RELATIVE;

/// The carrying floor's acceleration at one time, with its jerk.
#[derive(Debug, Clone, Copy)]
struct Probe {
    t: f64,
    a: f64,
    jerk: f64,
}

/// The sign changes found so far in the current segment, and how far the scan has gone.
#[derive(Debug, Default)]
struct SignScan {
    scanned_to: f64,
    roots: Vec<f64>,
}

/// The floors' closed-form motion since the last impulse on the carrying floor, with the
/// sign changes of the carrying floor's acceleration found so far.
pub(super) struct StoreyMotion {
    motion: FloorMotion,
    /// Each floor's scan (only the watched floors' are used).
    scans: RefCell<Vec<SignScan>>,
    /// Longest scan step of the sign-change search: a sixteenth of the shortest period.
    pub(super) scan_step: f64,
    /// The longest period, or the horizon when no mode oscillates.
    pub(super) span: f64,
    /// Why the motion cannot go on (a decomposition that failed), once it cannot.
    pub(super) failure: Option<String>,
    /// Evaluations of the carrying floor's acceleration so far: what the scan costs.
    probes: Cell<u64>,
}

/// The reference reads the floors' closed form as its own state.
impl Deref for StoreyMotion {
    type Target = FloorMotion;
    fn deref(&self) -> &FloorMotion {
        &self.motion
    }
}

impl StoreyMotion {
    /// The floors of `structure` under `forcing`, with the motion of each of `floors` (those
    /// that carry dampers) read as the carrying floor's is.
    pub(super) fn new(structure: Arc<Structure>, forcing: Option<Forcing>, horizon: f64, floors: &[usize]) -> Result<Self, String> {
        let motion = FloorMotion::new(structure, forcing)?.watching(floors);
        let scans = RefCell::new((0..motion.n()).map(|_| SignScan { scanned_to: motion.t0, roots: Vec::new() }).collect());
        let mut m = StoreyMotion { motion, scans, scan_step: 0.0, span: 0.0, failure: None, probes: Cell::new(0) };
        m.set_scales(horizon);
        Ok(m)
    }

    fn set_scales(&mut self, horizon: f64) {
        let forcing_period = self.sine.as_ref().map_or(f64::INFINITY, |s| 2.0 * std::f64::consts::PI / s.omega);
        let shortest = self.modes.shortest_period.min(forcing_period);
        self.scan_step = if shortest.is_finite() { shortest / 16.0 } else { horizon.min(1.0 / self.modes.rate.max(1e-300)) };
        self.span = if self.modes.longest_period.is_finite() { self.modes.longest_period } else { horizon };
    }

    /// Floor `floor`'s absolute acceleration, jerk and snap at `t`, with the size of the
    /// terms of each.
    fn derivatives(&self, p: &Piece, floor: usize, t: f64) -> [(f64, f64); 3] {
        let s = t - p.start;
        let mut d = [0.0; 3];
        let terms = p.terms(floor);
        for (w, l) in terms.w.iter().zip(&self.modes.lambda) {
            let mut e = w * (l * s).exp() * l * l;
            for x in &mut d {
                *x += e.re;
                e *= l;
            }
        }
        if let Some(sine) = &self.sine {
            let i_w = C64::new(0.0, sine.omega);
            let mut e = sine.h[floor] * C64::new(0.0, sine.omega * t).exp();
            for x in &mut d {
                *x += e.re;
                e *= i_w;
            }
        }
        let bounds = &terms.bounds;
        [(d[0] + p.a0 + p.a1 * s, bounds[2] + (p.a0 + p.a1 * s).abs()), (d[1] + p.a1, bounds[3] + p.a1.abs()), (d[2], bounds[4])]
    }

    fn probe(&self, p: &Piece, floor: usize, t: f64) -> Probe {
        self.probes.set(self.probes.get() + 1);
        let [(a, _), (jerk, _), _] = self.derivatives(p, floor, t);
        Probe { t, a, jerk }
    }

    /// The carrying floor's absolute acceleration just after `t`: its value, with the sign of
    /// the first derivative that is not round-off when the acceleration itself is. The value
    /// and the jerk come from the floors' state, as the force of the storeys (and of a sine)
    /// over the floor's mass: at a segment's start that state is exactly the one it was made
    /// from, so the sign is the same whatever mass the floor holds, and holding and releasing
    /// a ball agree at the instant they happen.
    pub(super) fn accel_ahead(&self, d: usize, t: f64) -> f64 {
        let n = self.n();
        let carrying = self.structure.floor;
        let b = &self.structure.building;
        let m = &self.modes.masses;
        let (z, _) = self.floors(t);
        let (u, v) = z.split_at(n);
        // The external force on floor `d` and its rate, and the ground's acceleration; forces
        // on other floors move `d` through them.
        let mut elsewhere = [None, None];
        let (force, force_rate, ag) = {
            let stretch = self.stretch(t);
            let s = t - stretch.start;
            let line = (stretch.g0 + stretch.g1 * s, stretch.g1);
            let (mut f, mut fr, mut g) = match self.structure.force.as_ref().map(|f| f.floor) {
                None => (0.0, 0.0, line.0),
                Some(j) if j == d => (line.0, line.1, 0.0),
                Some(j) => {
                    elsewhere[0] = Some((j, line.0));
                    (0.0, 0.0, 0.0)
                }
            };
            if let Some(sine) = &self.sine {
                let (sin, cos) = (sine.omega * t).sin_cos();
                let w = sine.omega;
                // The sine's force acts on the carrying floor.
                if carrying == d {
                    f += sine.force * sin;
                    fr += sine.force * w * cos;
                } else {
                    elsewhere[1] = Some((carrying, sine.force * sin));
                }
                g -= sine.ground * w * w * sin;
            }
            (f, fr, g)
        };
        let mut forces = b.restoring_forces(u, v);
        forces[d] += force;
        for (j, f) in elsewhere.into_iter().flatten() {
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
            let snap = self.with_piece(t, |p| self.derivatives(p, d, t)[2].0);
            if snap == 0.0 {
                return 0.0;
            }
            snap.signum()
        };
        sign * a.abs().max(f64::MIN_POSITIVE)
    }

    /// A bound on the round-off of floor `d`'s absolute position at `t`.
    pub(super) fn position_roundoff(&self, d: usize, t: f64) -> f64 {
        self.with_piece(t, |p| {
            let s = (t - p.start).max(0.0);
            let (up, _) = self.modes.particular(d, p.g0, p.g1, s);
            let sg = t - p.ground.start;
            let g = &p.ground;
            let ground = g.x0.abs() + sg * (g.v0.abs() + sg * (0.5 * g.g0.abs() + sg * g.g1.abs() / 6.0));
            let phase = self.sine.as_ref().map_or(0.0, |sine| sine.omega * t.abs());
            let free = (2.0 + self.modes.rate * s + phase) * p.terms(d).bounds[0];
            ROUNDOFF_ULPS * f64::EPSILON * (free + up.abs() + self.modes.influence[d].abs() * p.g0.abs() + ground)
        })
    }

    /// The next time after `t` at which floor `floor`'s acceleration changes sign or the
    /// ground's acceleration changes its line (a piece ends), or `limit` if none comes first.
    pub(super) fn next_sign_change(&self, floor: usize, t: f64, limit: f64) -> f64 {
        if !(limit > t) {
            return limit;
        }
        let boundary = self.with_piece(t, |p| p.end);
        let limit = limit.min(boundary);
        loop {
            {
                let scans = self.scans.borrow();
                let scan = &scans[floor];
                let k = scan.roots.partition_point(|&r| r <= t);
                if let Some(&root) = scan.roots.get(k) {
                    return root.min(limit);
                }
                if scan.scanned_to >= limit {
                    return limit;
                }
            }
            let from = self.scans.borrow()[floor].scanned_to;
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
                let mut left = self.probe(p, floor, from);
                let right = self.probe(p, floor, end);
                while let Some(root) = self.first_sign_change(p, floor, &left, &right) {
                    found.push(root);
                    if root >= right.t {
                        break;
                    }
                    left = self.probe(p, floor, root);
                }
            }
            drop(pieces);
            let mut scans = self.scans.borrow_mut();
            let scan = &mut scans[floor];
            scan.roots.extend(found);
            scan.scanned_to = end;
        }
    }

    /// Whether `a` keeps its sign (`order` 0), or its jerk keeps its sign so that `a` is
    /// monotone (`order` 1), over `[l.t, r.t]`, with every round-off margin: a function `y`
    /// with `|y''| <= M` is at least `min(|y(l)|, |y(r)|) - M h^2 / 8` in magnitude between
    /// ends of one sign.
    fn holds(&self, p: &Piece, floor: usize, l: &Probe, r: &Probe, order: usize) -> bool {
        let (yl, yr) = if order == 0 { (l.a, r.a) } else { (l.jerk, r.jerk) };
        if !((yl > 0.0 && yr > 0.0) || (yl < 0.0 && yr < 0.0)) {
            return false;
        }
        let h = r.t - l.t;
        let curvature = self.bound(p, floor, l.t, order + 4);
        yl.abs().min(yr.abs()) - self.roundoff(p, floor, l.t, r.t, order) > curvature * (1.0 + ROUNDOFF_ULPS * f64::EPSILON) * h * h / 8.0
    }

    /// `B_n` from `from` on: the bound on the `n`-th derivative of floor `floor`'s
    /// position over the rest of piece `p`, each mode's term decayed to `from` (`|e^{L s}|`
    /// only falls where damping is `>= 0`). A run whose motion dies away keeps bounds of the
    /// motion's own size, so that the scan's steps do not shrink as it decays.
    fn bound(&self, p: &Piece, floor: usize, from: f64, n: usize) -> f64 {
        let s = (from - p.start).max(0.0);
        let modal: f64 = p
            .terms(floor)
            .norms
            .iter()
            .zip(self.modes.lambda.iter().zip(&self.modes.lambda_norms))
            .map(|(w, (l, norm))| w * norm.powi(n as i32) * (l.re * s).exp().min(1.0))
            .sum();
        let sine = self.sine.as_ref().map_or(0.0, |sine| {
            let shift = sine.u[floor].norm() + sine.ground;
            if n < 2 {
                shift * sine.omega.powi(n as i32)
            } else {
                sine.h[floor].norm() * sine.omega.powi(n as i32 - 2)
            }
        });
        modal + sine
    }

    /// A bound on the round-off of the acceleration (`order` 0) or the jerk (`order` 1) of the
    /// carrying floor evaluated anywhere in `[from, t]` on piece `p`: each term rounds relative
    /// to its own size, at most its size at `from`.
    fn roundoff(&self, p: &Piece, floor: usize, from: f64, t: f64, order: usize) -> f64 {
        let s = t - p.start;
        let line = if order == 0 { p.a0.abs() + p.a1.abs() * s } else { p.a1.abs() };
        let phase = self.sine.as_ref().map_or(0.0, |sine| sine.omega * t.abs());
        ROUNDOFF_ULPS * f64::EPSILON * ((2.0 + self.modes.rate * s + phase) * self.bound(p, floor, from, order + 2) + line)
    }

    /// Whether the acceleration is round-off over all of `[l.t, r.t]`, so that its sign there
    /// says nothing: both ends within their round-off `err`, and its curvature bound keeping it
    /// within `2 err` in between (a floor starting from rest, whose acceleration grows as the
    /// square of time). No sign change is taken there.
    fn is_roundoff(&self, p: &Piece, floor: usize, l: &Probe, r: &Probe) -> bool {
        let err = self.roundoff(p, floor, l.t, r.t, 0);
        let h = r.t - l.t;
        l.a.abs() <= err && r.a.abs() <= err && self.bound(p, floor, l.t, 4) * h * h / 8.0 <= err
    }

    /// The first sign change of the acceleration in `(l.t, r.t]`: depth-first over halves.
    fn first_sign_change(&self, p: &Piece, floor: usize, l: &Probe, r: &Probe) -> Option<f64> {
        let same_sign = (l.a > 0.0 && r.a > 0.0) || (l.a < 0.0 && r.a < 0.0);
        if (same_sign && self.holds(p, floor, l, r, 0)) || self.is_roundoff(p, floor, l, r) {
            return None;
        }
        if !same_sign && l.a != 0.0 && r.a != 0.0 && self.holds(p, floor, l, r, 1) {
            return Some(self.illinois(p, floor, l, r));
        }
        if r.t - l.t <= self.time_resolution(r.t) {
            return (!same_sign).then_some(r.t);
        }
        let m = self.probe(p, floor, 0.5 * (l.t + r.t));
        self.first_sign_change(p, floor, l, &m).or_else(|| self.first_sign_change(p, floor, &m, r))
    }

    /// The one root of a monotone acceleration between `l` and `r` (of opposite signs).
    fn illinois(&self, p: &Piece, floor: usize, l: &Probe, r: &Probe) -> f64 {
        illinois((l.t, l.a), (r.t, r.a), |b| self.time_resolution(b), |m| self.probe(p, floor, m).a)
    }

    fn time_resolution(&self, t: f64) -> f64 {
        8.0 * f64::EPSILON * t.abs().max(self.scan_step)
    }

    /// Starts a new segment at `t`, the carrying floor moving at `v` (absolute) and holding
    /// `held` kg of balls.
    pub(super) fn restart(&mut self, t: f64, v: f64, held: f64) {
        if let Err(why) = self.motion.restart(t, v, held) {
            self.failure = Some(why);
        }
        self.clear_scans(t);
    }

    /// Starts a new segment at `t`, floor `floor` moving at `v` (absolute), no balls held.
    pub(super) fn restart_floor(&mut self, t: f64, floor: usize, v: f64) {
        self.motion.restart_floors(t, &[(floor, v)]);
        self.clear_scans(t);
    }

    fn clear_scans(&mut self, t: f64) {
        for scan in self.scans.get_mut() {
            *scan = SignScan { scanned_to: t, roots: Vec::new() };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storeys::{Building, StoreyDamping};

    /// A stiff building whose motion dies away within its run (periods of 2 to 6 ms, Rayleigh
    /// damping `a0 = 105/s`: the motion falls by `e^-52` a second), released from its top floor.
    fn dying_building() -> StoreyMotion {
        let building = Building::new(
            vec![2.2390371377866, 0.9431587145120875, 0.8047614900951305],
            vec![2360784.973313983, 3337886.1395310615, 7528324.220022116],
            &StoreyDamping::Rayleigh { mass: 105.15650480532963, stiffness: 0.000043857512602898 },
        );
        let structure = Structure {
            building,
            floor: 2,
            initial_displacements: vec![0.0, 0.0, 0.006329741487089392],
            initial_velocities: vec![0.0; 3],
            ground: None,
            force: None,
        };
        StoreyMotion::new(Arc::new(structure), None, 1.35, &[2]).unwrap()
    }

    /// The scan's cost does not grow as the motion dies away: finding every sign change of
    /// the acceleration over 1.35 s (most of it after the motion has fallen by 1e-20) takes a
    /// few dozen evaluations per scan step, as while the motion is strong. With bounds kept at
    /// the segment's start instead, the scan halved every interval down to round-off of time
    /// once the motion had decayed far enough, and the search took minutes.
    #[test]
    fn the_scan_keeps_its_cost_as_the_motion_dies_away() {
        let motion = dying_building();
        let (mut t, end) = (0.0, 1.35);
        let mut changes = 0;
        while t < end {
            t = motion.next_sign_change(2, t, end);
            changes += 1;
        }
        let steps = end / motion.scan_step;
        let probes = motion.probes.get() as f64;
        assert!(changes > 100, "{changes} sign changes");
        assert!(probes <= 64.0 * (steps + changes as f64), "{probes} evaluations over {steps} scan steps and {changes} sign changes");
    }
}
