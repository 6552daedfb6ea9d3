//! Where the bodies are relative to each other now: gaps, their rates and tolerances, and the
//! contact invariant checked after every event.

use super::*;

/// A pair's gap now (see [`Solver::pair_now`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct PairNow {
    pub(super) g: f64,
    pub(super) rate: f64,
    pub(super) tol: f64,
    pub(super) curvature: Option<f64>,
}

/// A pair at the current instant, as `resolve` judges it (see [`Solver::contact_now`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct Contact {
    pub(super) approach: Option<f64>,
    pub(super) pressed: bool,
    pub(super) frame: bool,
}

/// The frame at the current instant (see [`Solver::frame_now`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct FrameNow {
    pub(super) segment: u64,
    pub(super) t: f64,
    pub(super) xs: f64,
    pub(super) vs: f64,
    pub(super) accel_ahead: f64,
}

/// The gap of a pair as a function of time.
#[derive(Debug, Clone, Copy)]
pub(super) enum Gap {
    /// Both sides move with the frame: the gap never changes.
    Fixed,
    /// Two free balls: `g(t) = g + rate (t - t_now)`.
    Linear { g: f64, rate: f64 },
    /// A free ball `ball` against the frame: `g(t) = s (x_ball(t) - xs(t)) + k`.
    Frame { ball: usize, s: f64, k: f64 },
}

impl Solver<'_> {
    /// Whether pair `p` is a free ball against the frame (a wall, or a ball the frame holds):
    /// [`Solver::gap`]'s kind without its arithmetic.
    #[inline]
    pub(super) fn is_frame_pair(&self, p: usize) -> bool {
        let left_frame = p == 0 || self.hold[p - 1] != Hold::Free;
        let right_frame = p == self.n || self.hold[p] != Hold::Free;
        left_frame != right_frame
    }

    #[inline(always)]
    pub(super) fn gap(&self, p: usize) -> Gap {
        // The left body's right edge and the right body's left edge: a free ball's, or the
        // frame's (a wall, or a ball the frame holds, at an offset from `xs`).
        let left_free = p >= 1 && self.hold[p - 1] == Hold::Free;
        let right_free = p < self.n && self.hold[p] == Hold::Free;
        match (left_free, right_free) {
            (true, true) => {
                let (i, j) = (p - 1, p);
                Gap::Linear { g: (self.x[j] - self.radius[j]) - (self.x[i] + self.radius[i]), rate: self.v[j] - self.v[i] }
            }
            (false, true) => {
                let c = if p == 0 { 0.0 } else { self.offset[p - 1] + self.radius[p - 1] };
                Gap::Frame { ball: p, s: 1.0, k: -self.radius[p] - c }
            }
            (true, false) => {
                let c = if p == self.n { self.length } else { self.offset[p] - self.radius[p] };
                Gap::Frame { ball: p - 1, s: -1.0, k: c - self.radius[p - 1] }
            }
            (false, false) => Gap::Fixed,
        }
    }

    /// The frame's state at `t` in the current segment (the last one asked for is kept).
    #[inline(always)]
    pub(super) fn frame_state(&self, t: f64) -> (f64, f64) {
        let (segment, last, xs, vs) = self.last_state.get();
        if segment == self.segment && last == t {
            return (xs, vs);
        }
        let (xs, vs) = self.seg.state(t);
        self.last_state.set((self.segment, t, xs, vs));
        (xs, vs)
    }

    /// Gap and its rate for a ball-frame pair at time `t` (the ball flies from `self.t`).
    #[inline(always)]
    pub(super) fn frame_gap_at(&self, ball: usize, s: f64, k: f64, t: f64) -> (f64, f64) {
        let (xs, vs) = self.frame_state(t);
        let xb = self.x[ball] + self.v[ball] * (t - self.t);
        (s * (xb - xs) + k, s * (self.v[ball] - vs))
    }

    /// A ball-frame pair's gap, its rate and its contact tolerance at `t`: the length
    /// tolerance plus what the gap's value can err by (the rounding accumulated in the ball's
    /// position, the round-off of the frame's closed form and of the gap's sum, and two ulps
    /// of time at the gap's rate or the fastest speed of the run so far, whichever is faster: a
    /// contact taken at that speed is placed no closer, and bodies that then move together
    /// keep that overlap). The reference
    /// takes no contact below minus this, and its postcondition checks it (docs/MODEL.md).
    pub(super) fn frame_gap_tolerance(&self, ball: usize, s: f64, k: f64, t: f64) -> (f64, f64, f64) {
        let (xs, vs) = self.frame_state(t);
        let xb = self.x[ball] + self.v[ball] * (t - self.t);
        let rate = s * (self.v[ball] - vs);
        (s * (xb - xs) + k, rate, self.frame_tolerance(ball, t, xb, xs, k, rate))
    }

    /// The contact tolerance of a ball-frame gap `s (xb - xs) + k` of rate `rate` at `t` (see
    /// [`Solver::frame_gap_tolerance`]).
    #[inline(always)]
    pub(super) fn frame_tolerance(&self, ball: usize, t: f64, xb: f64, xs: f64, k: f64, rate: f64) -> f64 {
        let eps = f64::EPSILON;
        self.tol
            + self.drift[ball]
            + self.seg.position_roundoff(t)
            + 4.0 * eps * (xb.abs() + xs.abs() + k.abs())
            + 2.0 * eps * t.abs() * rate.abs().max(self.fastest)
    }

    /// The contact tolerance of ball-ball pair `p` of rate `rate` now (see
    /// [`Solver::frame_gap_tolerance`]).
    #[inline(always)]
    pub(super) fn ball_gap_tolerance(&self, p: usize, rate: f64) -> f64 {
        let (i, j) = (p - 1, p);
        let eps = f64::EPSILON;
        self.tol
            + self.drift[i]
            + self.drift[j]
            + 4.0 * eps * (self.x[i].abs() + self.x[j].abs() + self.radius[i] + self.radius[j])
            + 2.0 * eps * self.t.abs() * rate.abs().max(self.fastest)
    }

    /// Pair `p` now: its gap, the gap's rate, its contact tolerance and, for a ball-frame
    /// pair, the gap's curvature (positive when the wall accelerates away from the ball);
    /// `None` for a pair that moves as one body.
    ///
    /// Forced inline, as the gap and tolerance helpers it calls: every event reads every pair
    /// (the postcondition, `resolve`), and as calls returning through memory these cost more
    /// than their arithmetic (docs/BENCHMARKS.md, "Ensembles").
    #[inline(always)]
    pub(super) fn pair_now(&self, p: usize) -> Option<PairNow> {
        match self.gap(p) {
            Gap::Fixed => None,
            Gap::Linear { g, rate } => Some(PairNow { g, rate, tol: self.ball_gap_tolerance(p, rate), curvature: None }),
            Gap::Frame { ball, s, k } => {
                let (xs, vs, a) = self.frame_now();
                let xb = self.x[ball];
                let rate = s * (self.v[ball] - vs);
                let tol = self.frame_tolerance(ball, self.t, xb, xs, k, rate);
                Some(PairNow { g: s * (xb - xs) + k, rate, tol, curvature: Some(-s * a) })
            }
        }
    }

    /// The postcondition of every event (docs/MODEL.md §10): the pair whose contact triggered
    /// it touches, and no pair overlaps, within the contact tolerance. An overlap accepted at a
    /// contact moves on with bodies that move together (held, merged, released), under a
    /// tolerance that may then be smaller (a held ball's gap carries the frame's round-off, a
    /// free pair's does not), so no pair may overlap by more than the largest tolerance a
    /// touching pair has had so far. A violation means a contact was missed or mistimed: an
    /// error naming the scene, the time and the pair, never a silent wrong run.
    ///
    /// Each pair read is kept in `self.pairs_now`: `resolve`, which comes next at the same
    /// instant and state, judges the contacts from them instead of reading every pair again.
    pub(super) fn check_contacts(&mut self, trigger: Option<usize>) -> Result<(), ModelError> {
        let mut pairs_now = std::mem::take(&mut self.pairs_now);
        pairs_now.clear();
        pairs_now.resize(self.n + 1, None);
        for p in self.pair_range() {
            pairs_now[p] = self.pair_now(p);
            let Some(PairNow { g, tol, .. }) = pairs_now[p] else { continue };
            if g.abs() <= tol {
                self.accepted_overlap = self.accepted_overlap.max(tol);
            }
            let apart = trigger == Some(p) && g > tol;
            let allowed = tol.max(self.accepted_overlap);
            if g < -allowed || apart {
                let (a, b) = self.pair_bodies(p);
                let what = format!(
                    "its contact invariant at t = {} s: {} / {} {} by {:.3e} m (tolerance {:.3e} m)",
                    crate::scene::human(self.t),
                    a.name(),
                    b.name(),
                    if apart { "are apart at their contact" } else { "overlap" },
                    g.abs(),
                    if apart { tol } else { allowed },
                );
                return Err(ModelError::Broken { scene: self.scene.name.clone(), model: Model::Reference, t: self.t, what });
            }
        }
        self.pairs_now = pairs_now;
        Ok(())
    }

    /// The bodies either side of pair `p`.
    pub(super) fn pair_bodies(&self, p: usize) -> (Body, Body) {
        crate::scene::pair_bodies(p, self.n)
    }

    /// The frame's position, velocity and acceleration ahead ([`Solver::accel_ahead`]) now.
    #[inline(always)]
    pub(super) fn frame_now(&self) -> (f64, f64, f64) {
        if let Some(n) = self.now.get() {
            if n.segment == self.segment && n.t == self.t {
                return (n.xs, n.vs, n.accel_ahead);
            }
        }
        let (xs, vs) = self.frame_state(self.t);
        let accel_ahead = self.accel_ahead(self.t);
        self.now.set(Some(FrameNow { segment: self.segment, t: self.t, xs, vs, accel_ahead }));
        (xs, vs, accel_ahead)
    }

    /// The frame's acceleration just after `t`: its value, with the sign of the first
    /// derivative that is not round-off when the acceleration itself is (at a sign change).
    /// Every sign involved is that of `-(c v + k x)` and its derivatives, whatever the mass
    /// the frame carries, so holding and releasing a ball always agree.
    pub(super) fn accel_ahead(&self, t: f64) -> f64 {
        if let Some(f) = &self.seg.forced {
            let [(a, sa), (jerk, sj), (snap, _)] = self.seg.forced_derivatives(f, t);
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
            return sign * a.abs().max(f64::MIN_POSITIVE);
        }
        let (x, v) = self.frame_state(t);
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
}
