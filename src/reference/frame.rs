//! The frame's motion since its last change of velocity or mass (a [`Segment`]), with what the
//! searches and checks ask of it again and again kept: its state at the last instant asked for,
//! its state and acceleration ahead now, and the sign changes of a forced segment's
//! acceleration, found once and shared by every search over the segment.

use std::cell::{Cell, RefCell};

use super::segment::{Segment, SignChanges};
use super::storeys::StoreyMotion;
use super::{ROUNDOFF_RELATIVE, SIGN_CHANGES_KEPT};
use crate::oscillator::{gauss_legendre, Oscillator};
use crate::scene::Scene;

/// The frame at one instant (see [`FrameMotion::now`]).
#[derive(Debug, Clone, Copy)]
struct FrameNow {
    segment: u64,
    floor: usize,
    t: f64,
    xs: f64,
    vs: f64,
    accel_ahead: f64,
}

/// The frame's closed-form motion and the balls it carries.
pub(super) struct FrameMotion {
    /// The bare frame's mass, or infinity without a frame (free balls).
    pub(super) mass: f64,
    damping: f64,
    stiffness: f64,
    /// The harmonic load `(P, Q, w)` on the frame, when forced.
    load: Option<(f64, f64, f64)>,
    /// The motion since its last change.
    pub(super) seg: Segment,
    /// Serial number of `seg` (segments can start at the same instant).
    pub(super) segment: u64,
    /// Mass of the balls the frame holds.
    pub(super) held_mass: f64,
    /// One damped period of the frame with what it carries, or the horizon.
    pub(super) span: f64,
    horizon: f64,
    sign_changes: RefCell<SignChanges>,
    /// The frame's state and acceleration ahead at `t` under segment `segment`, kept while
    /// neither changes (a cascade of impulses at one instant asks for them every pass).
    now: Cell<Option<FrameNow>>,
    /// The last frame state evaluated, `(segment, floor, t, xs, vs)`: the searches of both
    /// walls and the checks ask for the same instant in turn, and each evaluation costs an
    /// `exp` and a `sin_cos` ([`FrameMotion::state`]).
    last_state: Cell<(u64, usize, f64, f64, f64)>,
    /// The floor that carries the damper (0 on a frame): the one the queries without a floor
    /// are about.
    pub(super) carrying: usize,
    /// A structure of several storeys or a moving ground: the carrying floor's motion comes
    /// from it, and `seg` is unused.
    storeys: Option<Box<StoreyMotion>>,
}

impl FrameMotion {
    /// The frame of `scene`, or why its structure has no closed form.
    pub(super) fn new(scene: &Scene) -> Result<Self, String> {
        let (mass, damping, stiffness) = scene.frame.map_or((f64::INFINITY, 0.0, 0.0), |f| (f.mass, f.damping, f.stiffness));
        let osc = Oscillator::new(if mass.is_finite() { mass } else { 1.0 }, damping, stiffness);
        let load = scene.harmonic_load();
        let seg = Segment::new(0.0, scene.initial_displacement, 0.0, osc, load);
        let floors: Vec<usize> = scene.damper_list().iter().map(|d| d.floor).collect();
        let storeys = match &scene.structure {
            Some(s) => Some(Box::new(StoreyMotion::new(s.clone(), scene.forcing, scene.horizon, &floors)?)),
            None => None,
        };
        let span = storeys.as_ref().map_or_else(|| span(&seg, scene.horizon), |s| s.span);
        Ok(FrameMotion {
            mass,
            damping,
            stiffness,
            load,
            seg,
            segment: 1,
            held_mass: 0.0,
            span,
            horizon: scene.horizon,
            sign_changes: Default::default(),
            now: Default::default(),
            last_state: Cell::new((0, 0, f64::NAN, 0.0, 0.0)),
            carrying: scene.structure.as_ref().map_or(0, |s| s.floor),
            storeys,
        })
    }

    /// The structure's motion, when the frame is a floor of one.
    pub(super) fn storeys(&self) -> Option<&StoreyMotion> {
        self.storeys.as_deref()
    }

    /// The scan step of a motion whose acceleration's sign changes are scanned (forced, or a
    /// structure's), `None` when they come in closed form.
    pub(super) fn scan_step(&self) -> Option<f64> {
        match &self.storeys {
            Some(s) => Some(s.scan_step),
            None => self.seg.forced.map(|f| f.scan),
        }
    }

    /// Whether an excitation does work on the frame.
    pub(super) fn is_driven(&self) -> bool {
        match &self.storeys {
            Some(s) => s.is_driven(),
            None => self.seg.forced.is_some(),
        }
    }

    /// The farthest the frame goes from 0 in this segment, when known (an unforced frame).
    pub(super) fn reach(&self) -> Option<f64> {
        if self.storeys.is_some() {
            return None;
        }
        self.seg.reach
    }

    /// A bound on the round-off of the position of floor `floor` (the frame's on a frame)
    /// at `t`.
    pub(super) fn position_roundoff_of(&self, floor: usize, t: f64) -> f64 {
        match &self.storeys {
            Some(s) => s.position_roundoff(floor, t),
            None => self.seg.position_roundoff(t),
        }
    }

    /// Why the frame's motion cannot go on, once it cannot.
    pub(super) fn failure(&self) -> Option<&str> {
        self.storeys.as_ref().and_then(|s| s.failure.as_deref())
    }

    /// The mechanical energy of the frame (and the floors of its structure) at `t`, without
    /// the balls it holds.
    pub(super) fn energy(&self, t: f64, scene: &Scene) -> f64 {
        match &self.storeys {
            Some(s) => s.energy(t),
            None => {
                let (xs, vs) = self.seg.state(t);
                scene.frame_energy(t, xs, vs)
            }
        }
    }

    /// Whether there is a frame (a chain of free balls has none).
    pub(super) fn exists(&self) -> bool {
        self.mass.is_finite()
    }

    /// Starts a new segment at `t` from displacement `xs` with velocity `v`, the frame carrying
    /// `held_mass` of balls.
    pub(super) fn restart(&mut self, t: f64, xs: f64, v: f64) {
        self.restart_of(self.carrying, t, xs, v);
    }

    /// [`FrameMotion::restart`] from an impulse on floor `floor` (the frame's on a frame),
    /// which holds no balls unless it is the carrying floor.
    pub(super) fn restart_of(&mut self, floor: usize, t: f64, xs: f64, v: f64) {
        if let Some(s) = &mut self.storeys {
            if floor == self.carrying {
                s.restart(t, v, self.held_mass);
            } else {
                s.restart_floor(t, floor, v);
            }
            self.segment += 1;
            self.span = s.span;
            return;
        }
        let osc = if self.seg.osc.mass == self.mass + self.held_mass {
            self.seg.osc
        } else {
            Oscillator::new(self.mass + self.held_mass, self.damping, self.stiffness)
        };
        self.seg = Segment::new(t, xs, v, osc, self.load);
        self.segment += 1;
        self.span = span(&self.seg, self.horizon);
    }

    /// What the frame's damper dissipated, and the excitation put in, over the current segment
    /// up to `t`: closed form when free; when forced, Gauss-Legendre on pieces of a sixteenth of
    /// the shorter period (exact to round-off, see [`gauss_legendre`]).
    pub(super) fn segment_energy(&self, t: f64, scene: &Scene) -> (f64, f64) {
        if let Some(s) = &self.storeys {
            return s.segment_energy(t);
        }
        let seg = self.seg;
        let Some(f) = seg.forced else {
            return (seg.osc.dissipated(seg.x0, seg.v0, t - seg.t0), 0.0);
        };
        let [damping, work] = gauss_legendre(seg.t0, t, f.scan, |t| {
            let (xs, vs) = seg.state(t);
            [scene.damping_power(t, vs), scene.forcing_power(t, xs, vs)]
        });
        (damping, work)
    }

    /// The frame's state at `t` in the current segment (the last one asked for is kept).
    #[inline(always)]
    pub(super) fn state(&self, t: f64) -> (f64, f64) {
        self.state_of(self.carrying, t)
    }

    /// [`FrameMotion::state`] of floor `floor` (the frame's on a frame).
    #[inline(always)]
    pub(super) fn state_of(&self, floor: usize, t: f64) -> (f64, f64) {
        let (segment, last_floor, last, xs, vs) = self.last_state.get();
        if segment == self.segment && last_floor == floor && last == t {
            return (xs, vs);
        }
        let (xs, vs) = match &self.storeys {
            Some(s) => s.floor_state(floor, t),
            None => self.seg.state(t),
        };
        self.last_state.set((self.segment, floor, t, xs, vs));
        (xs, vs)
    }

    /// The frame's position, velocity and acceleration ahead ([`FrameMotion::accel_ahead`]) at
    /// `t`, the current instant (kept until it or the segment changes).
    #[inline(always)]
    pub(super) fn now(&self, t: f64) -> (f64, f64, f64) {
        self.now_of(self.carrying, t)
    }

    /// [`FrameMotion::now`] of floor `floor` (the frame's on a frame).
    #[inline(always)]
    pub(super) fn now_of(&self, floor: usize, t: f64) -> (f64, f64, f64) {
        if let Some(n) = self.now.get() {
            if n.segment == self.segment && n.floor == floor && n.t == t {
                return (n.xs, n.vs, n.accel_ahead);
            }
        }
        let (xs, vs) = self.state_of(floor, t);
        let accel_ahead = self.accel_ahead_of(floor, t);
        self.now.set(Some(FrameNow { segment: self.segment, floor, t, xs, vs, accel_ahead }));
        (xs, vs, accel_ahead)
    }

    /// The acceleration of floor `floor` (the frame's on a frame) just after `t`: its value, with
    /// the sign of the first derivative that is not round-off when the acceleration itself is (at
    /// a sign change). Every sign involved is that of `-(c v + k x)` and its derivatives, whatever
    /// the mass the frame carries, so holding and releasing a ball always agree.
    pub(super) fn accel_ahead_of(&self, floor: usize, t: f64) -> f64 {
        if let Some(s) = &self.storeys {
            return s.accel_ahead(floor, t);
        }
        if let Some(f) = &self.seg.forced {
            return ahead(self.seg.forced_derivatives(f, t));
        }
        let (x, v) = self.state(t);
        let o = &self.seg.osc;
        let a = o.accel(x, v);
        // Scales of a and its derivative over the motion (w0 |v| matters where x passes 0).
        let rate = 2.0 * o.sigma + o.w0();
        if a.abs() > ROUNDOFF_RELATIVE * (o.w0sq * x.abs() + rate * v.abs()) {
            return a;
        }
        let jerk = -2.0 * o.sigma * a - o.w0sq * v;
        let sign = if jerk.abs() > ROUNDOFF_RELATIVE * (rate * a.abs() + o.w0sq * v.abs()) {
            jerk.signum()
        } else {
            let snap = -2.0 * o.sigma * jerk - o.w0sq * a;
            if snap == 0.0 {
                return 0.0;
            }
            snap.signum()
        };
        sign * a.abs().max(f64::MIN_POSITIVE)
    }

    /// Next time after `t` at which the frame's acceleration changes sign, or `limit` if none
    /// comes first (unforced segments ignore `limit`: their sign changes are closed form).
    /// A forced segment's sign changes are scanned once and kept ([`SignChanges`]); no search
    /// starts before `now`, so older ones are dropped.
    pub(super) fn next_sign_change(&self, t: f64, limit: f64, now: f64) -> f64 {
        self.next_sign_change_of(self.carrying, t, limit, now)
    }

    /// [`FrameMotion::next_sign_change`] of floor `floor` (the frame's on a frame).
    pub(super) fn next_sign_change_of(&self, floor: usize, t: f64, limit: f64, now: f64) -> f64 {
        if let Some(s) = &self.storeys {
            return s.next_sign_change(floor, t, limit);
        }
        let Some(f) = &self.seg.forced else {
            return self.seg.free_sign_change(t);
        };
        if !(limit > t) {
            return limit;
        }
        let mut c = self.sign_changes.borrow_mut();
        if c.segment != self.segment {
            *c = SignChanges { segment: self.segment, pieces: 0, roots: Vec::new() };
        }
        if c.roots.len() > SIGN_CHANGES_KEPT {
            c.roots.retain(|&r| r >= now);
        }
        loop {
            let k = c.roots.partition_point(|&r| r <= t);
            if let Some(&root) = c.roots.get(k) {
                return root.min(limit);
            }
            let scanned = self.seg.t0 + c.pieces as f64 * f.scan;
            if scanned >= limit {
                return limit;
            }
            let end = self.seg.t0 + (c.pieces + 1) as f64 * f.scan;
            self.seg.forced_sign_changes(f, scanned, end, &mut c.roots);
            c.pieces += 1;
        }
    }
}

/// The acceleration just after an instant, from its value, jerk and snap there with the size
/// of the terms of each: the value, with the sign of the first derivative that is not
/// round-off when the value itself is.
pub(super) fn ahead([(a, sa), (jerk, sj), (snap, _)]: [(f64, f64); 3]) -> f64 {
    if a.abs() > ROUNDOFF_RELATIVE * sa {
        return a;
    }
    let sign = if jerk.abs() > ROUNDOFF_RELATIVE * sj {
        jerk.signum()
    } else if snap == 0.0 {
        return 0.0;
    } else {
        snap.signum()
    };
    sign * a.abs().max(f64::MIN_POSITIVE)
}

/// One damped period of the frame in segment `seg`, or the horizon.
fn span(seg: &Segment, horizon: f64) -> f64 {
    seg.osc.damped_omega().map_or(horizon, |w| 2.0 * std::f64::consts::PI / w)
}
