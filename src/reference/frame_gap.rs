//! A ball flying on a line along the frame's motion against a wall of the frame: its gap
//! `s (x_ball - xs) + k` as a function of time, the contact tolerance of that gap, and the sound
//! root isolation that finds its first contact (docs/MODEL.md §10). Both the one-line event loop
//! and the spatial one ask it, each for its own balls.

use super::frame::FrameMotion;
use super::geometry::Limits;
use super::search::{Candidate, NO_EVENT};
use super::MAX_ROOT_ITERATIONS;
use crate::oscillator::Oscillator;

/// The gap between a ball moving at constant velocity along x and a wall of the frame.
pub(super) struct FrameGap<'a> {
    pub(super) frame: &'a FrameMotion,
    /// The floor whose walls these are (the frame's on a frame).
    pub(super) floor: usize,
    pub(super) limits: &'a Limits,
    pub(super) horizon: f64,
    /// The instant at which the ball is at `x`, s.
    pub(super) now: f64,
    /// The ball's centre along the motion at `now`, m.
    pub(super) x: f64,
    /// The ball's velocity along the motion, m/s.
    pub(super) v: f64,
    /// A bound on the rounding gathered in `x`, m.
    pub(super) drift: f64,
    /// `+1` for a wall left of the ball, `-1` for one right of it.
    pub(super) s: f64,
    /// The gap's offset (radii and the wall's place on the frame), m.
    pub(super) k: f64,
}

/// Where and how fast a frame can be from some instant to the horizon: no farther from 0 than
/// `reach`, no faster than `speed`, its evaluated position off by no more than `roundoff`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct FrameReach {
    /// m.
    pub(super) reach: f64,
    /// m/s.
    pub(super) speed: f64,
    /// m.
    pub(super) roundoff: f64,
}

impl FrameReach {
    /// The bound of an unforced frame of oscillator `osc` whose every segment until `horizon`
    /// stays within `reach` ([`Oscillator::envelope`](crate::oscillator::Oscillator::envelope)):
    /// its speed then stays within `w0 reach`, and a segment starting within both rounds off
    /// its position by no more than one starting at both at once, evaluated at the horizon.
    pub(super) fn new(osc: &Oscillator, reach: f64, horizon: f64) -> FrameReach {
        let speed = osc.w0() * reach;
        FrameReach { reach, speed, roundoff: osc.roundoff(reach, speed, horizon) }
    }
}

impl FrameGap<'_> {
    /// The gap and its rate at `t`.
    #[inline(always)]
    pub(super) fn at(&self, t: f64) -> (f64, f64) {
        let (xs, vs) = self.frame.state_of(self.floor, t);
        let xb = self.x + self.v * (t - self.now);
        (self.s * (xb - xs) + self.k, self.s * (self.v - vs))
    }

    /// The gap, its rate and its contact tolerance at `t`: the length tolerance plus what the
    /// gap's value can err by (the rounding accumulated in the ball's position, the round-off
    /// of the frame's closed form and of the gap's sum, and two ulps of time at the gap's rate
    /// or the fastest speed of the run so far, whichever is faster: a contact taken at that
    /// speed is placed no closer, and bodies that then move together keep that overlap). The
    /// reference takes no contact below minus this, and its postcondition checks it
    /// (docs/MODEL.md).
    pub(super) fn with_tolerance(&self, t: f64) -> (f64, f64, f64) {
        let (xs, vs) = self.frame.state_of(self.floor, t);
        let xb = self.x + self.v * (t - self.now);
        let rate = self.s * (self.v - vs);
        (self.s * (xb - xs) + self.k, rate, self.tolerance(t, xb, xs, rate))
    }

    /// The contact tolerance of the gap at `t`, with the ball at `xb`, the frame at `xs` and
    /// the gap closing at `rate` (see [`FrameGap::with_tolerance`]).
    #[inline(always)]
    pub(super) fn tolerance(&self, t: f64, xb: f64, xs: f64, rate: f64) -> f64 {
        let eps = f64::EPSILON;
        self.limits.tol
            + self.drift
            + self.frame.position_roundoff_of(self.floor, t)
            + 4.0 * eps * (xb.abs() + xs.abs() + self.k.abs())
            + 2.0 * eps * t.abs() * rate.abs().max(self.limits.fastest)
    }

    /// First contact of a ball with the frame after `from`, searched over one damped period
    /// at a time. The frame's acceleration keeps its sign between consecutive sign changes, so
    /// there the gap `g` has `g'' = -s a` of one sign: on a convex piece Newton's method from
    /// the left never passes the first root; on a concave piece a root exists only if `g` at
    /// the piece's end is not positive, and Newton from the right converges to it from above.
    pub(super) fn search(&self, from: f64, bound: f64) -> Candidate {
        // Only a forced segment's search is cut at `bound`: its sign changes are scanned, so
        // looking further costs, where an unforced segment's come in closed form (and cutting
        // its pieces would change the roots' last bits, which chaotic runs amplify).
        let bound = if self.frame.scan_step().is_some() { bound } else { self.horizon };
        let limit = (from + self.frame.span).min(self.horizon).min(bound);
        if !self.may_reach(from, limit) {
            // What the search below would conclude, without evaluating the frame's motion.
            return if limit >= self.horizon { NO_EVENT } else { Candidate { t: limit, exact: false } };
        }
        let mut a = from;
        loop {
            let b = self.frame.next_sign_change_of(self.floor, a, limit, self.now).min(limit);
            // The sign just after `a` holds over the whole piece; judged as `resolve` judges it,
            // so that the two agree even where the acceleration is round-off (a frame at rest).
            let curvature = -self.s * self.frame.accel_ahead_of(self.floor, a);
            let root = if curvature >= 0.0 { self.convex_root(a, b) } else { self.concave_root(a, b) };
            if let Some(t) = root {
                return Candidate { t, exact: true };
            }
            if b >= limit {
                return if limit >= self.horizon { NO_EVENT } else { Candidate { t: limit, exact: false } };
            }
            a = b;
        }
    }

    /// Whether the gap `s (x_ball - xs) + k` can be evaluated at or below the length
    /// tolerance anywhere on `[from, limit]`; `false` only when it provably cannot, so that
    /// [`FrameGap::search`] would find no root there (the same answer, without the
    /// closed form's `exp` and `sin_cos` at every piece and iterate).
    ///
    /// An unforced frame with a spring and damping `>= 0` never leaves `|xs| <= R =
    /// sqrt(x0^2 + v0^2 / w0^2)` ([`Segment::reach`](super::segment::Segment::reach)) nor `|vs| <= w0 R` (its `v^2 + w0^2 x^2`
    /// never grows), so the gap is at least `s x_ball + k - R`, a line in time whose least value
    /// lies at an end. That bound must clear the tolerance by what the evaluated gap can err by
    /// (as [`FrameGap::tolerance`] counts it, at the window's far end and with the frame at
    /// its extremes, twice over), which also keeps every Newton step of the search longer than
    /// an ulp of time.
    pub(super) fn may_reach(&self, from: f64, limit: f64) -> bool {
        let Some(reach) = self.frame.reach() else { return true };
        let nearest = self.line(from).min(self.line(limit));
        let err = self.bound_error(limit, reach, self.frame.seg.osc.w0() * reach, self.frame.seg.position_roundoff(limit));
        // Written so that a NaN anywhere answers "may reach" (the search then decides).
        !(nearest - reach - err > self.limits.tol)
    }

    /// The gap with the frame at 0 at `t`: a line in time, since the ball flies straight.
    #[inline(always)]
    fn line(&self, t: f64) -> f64 {
        self.s * (self.x + self.v * (t - self.now)) + self.k
    }

    /// What a bound on the gap must clear the tolerance by on a window that ends at `limit`,
    /// for a frame that goes no farther than `reach` nor faster than `speed` and whose
    /// position rounds off by at most `roundoff` there: twice what the evaluated gap can err
    /// by (as [`FrameGap::tolerance`] counts it, at the window's far end and with the frame at
    /// its extremes).
    #[inline(always)]
    fn bound_error(&self, limit: f64, reach: f64, speed: f64, roundoff: f64) -> f64 {
        let eps = f64::EPSILON;
        let farthest = self.x.abs() + self.v.abs() * (limit - self.now).abs();
        2.0 * (self.drift
            + roundoff
            + 4.0 * eps * (farthest + reach + self.k.abs())
            + 2.0 * eps * limit.abs() * (self.v.abs() + speed).max(self.limits.fastest))
            + 4.0 * eps * reach
    }

    /// The earliest time from `from` on at which the gap may come within the length
    /// tolerance, with the frame at `xs` at `from` and within `bound` from then to the
    /// horizon: `from` when it may now, `None` when it cannot before the horizon. The later of
    /// two bounds: the frame goes no farther than the bound's reach (the gap is at least the
    /// ball's line less it), nor faster than its speed (the gap closes no faster than the
    /// ball's speed towards the wall plus that). Both clear the tolerance by the bound's error
    /// at the horizon, its largest, which also counts the two ulps of time at the gap's speed
    /// that rounding the time can cost: the time is never late, and a search need not start
    /// before it.
    pub(super) fn earliest_reach(&self, from: f64, xs: f64, bound: &FrameReach) -> Option<f64> {
        let margin = self.bound_error(self.horizon, bound.reach, bound.speed, bound.roundoff) + self.limits.tol;
        let line = self.line(from);
        let room = line - self.s * xs - margin;
        // Written so that a NaN answers "from now" (the search then decides).
        if !(room > 0.0) {
            return Some(from);
        }
        let closing = -self.s * self.v;
        let mut t = if closing + bound.speed > 0.0 { from + room / (closing + bound.speed) } else { f64::INFINITY };
        let above = line - bound.reach - margin;
        if above > 0.0 {
            t = t.max(if closing > 0.0 { from + above / closing } else { f64::INFINITY });
        }
        (t <= self.horizon).then_some(t)
    }

    /// The first root of a gap that is convex on `[a, b]`: Newton from the left, whose
    /// iterates never pass the root in exact arithmetic. Should one land deeper than the
    /// contact tolerance all the same (round-off where the piece is barely convex), the
    /// crossing is bisected back between it and the previous iterate.
    fn convex_root(&self, a: f64, b: f64) -> Option<f64> {
        let mut t = a;
        let mut before = None;
        for _ in 0..MAX_ROOT_ITERATIONS {
            let (g, gp) = self.at(t);
            if let Some(l) = before {
                if g < -self.with_tolerance(t).2 {
                    return Some(self.bisect_crossing(l, t));
                }
            }
            if gp >= 0.0 || (t == a && g <= self.limits.tol && self.limits.reopens(gp, -self.s * self.frame.accel_ahead_of(self.floor, a)))
            {
                return None; // convex and not decreasing (or about to): it only rises from here on
            }
            if g <= self.limits.tol {
                return Some(t);
            }
            let next = t - g / gp;
            if next > b {
                return None;
            }
            if next <= t {
                return Some(t);
            }
            before = Some(t);
            t = next;
        }
        Some(t)
    }

    /// A crossing of the gap between `l` (gap above the tolerance) and `h` (below it): a time
    /// at which the gap is within the tolerance, or `h` once the bracket is an ulp wide.
    fn bisect_crossing(&self, mut l: f64, mut h: f64) -> f64 {
        for _ in 0..MAX_ROOT_ITERATIONS {
            let m = 0.5 * (l + h);
            if m <= l || m >= h {
                break;
            }
            let (g, _) = self.at(m);
            if g.abs() <= self.limits.tol {
                return m;
            }
            if g > 0.0 {
                l = m;
            } else {
                h = m;
            }
        }
        h
    }

    fn concave_root(&self, a: f64, b: f64) -> Option<f64> {
        let (ga, gpa) = self.at(a);
        if ga <= self.limits.tol && gpa <= 0.0 {
            // Touching and not separating: a contact now if the wall presses, judged exactly as
            // `resolve` judges it (a piece can be an ulp long at a sign change, and its
            // midpoint then disagrees); otherwise the ball is about to leave the wall.
            return (-self.s * self.frame.accel_ahead_of(self.floor, a) < 0.0).then_some(a);
        }
        let (gb, gpb) = self.at(b);
        if gb > self.limits.tol {
            return None; // a concave function's minimum lies at an end of the piece
        }
        let mut lo = a;
        if ga <= self.limits.tol {
            // Touching but separating: the return is after the maximum of g (where g' = 0,
            // g' decreasing on a concave piece), so none on this piece while g still rises at
            // its end (a window that ends within a pressed contact's hop, at the horizon).
            if gpb > 0.0 {
                return None;
            }
            let (mut l, mut h) = (a, b);
            for _ in 0..MAX_ROOT_ITERATIONS {
                let m = 0.5 * (l + h);
                if m <= l || m >= h {
                    break;
                }
                if self.at(m).1 > 0.0 {
                    l = m;
                } else {
                    h = m;
                }
            }
            lo = l;
            if self.at(lo).0 <= self.limits.tol {
                return Some(lo);
            }
        }
        // g decreases on [lo, b] from above tol to at most tol: one root; Newton from the right.
        let (mut l, mut h) = (lo, b);
        let mut t = b;
        for _ in 0..MAX_ROOT_ITERATIONS {
            let (g, gp) = self.at(t);
            if g >= -self.limits.tol && g <= self.limits.tol {
                return Some(t);
            }
            if g > 0.0 {
                l = t;
            } else {
                h = t;
            }
            let newton = t - g / gp;
            t = if gp < 0.0 && newton > l && newton < h { newton } else { 0.5 * (l + h) };
            if h - l <= 4.0 * f64::EPSILON * h.abs() {
                return Some(h);
            }
        }
        Some(h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first contact the search finds from `from`, following its "not before" answers.
    fn first_contact(gap: &FrameGap, mut from: f64) -> f64 {
        loop {
            let c = gap.search(from, gap.horizon);
            if c.exact {
                return c.t;
            }
            from = c.t;
        }
    }

    /// A search that starts where `earliest_reach` says finds the contact a search from now
    /// finds (the wait is never late), for balls at every distance from both walls of a
    /// swinging frame, flying towards them, away or at rest, and from any instant.
    #[test]
    fn a_wait_never_passes_a_contact() {
        let mut scene = crate::scene::load(crate::scene::scenes_dir().join("lpc-lsl.toml")).unwrap().scene.unwrap();
        scene.horizon = 2.0;
        let frame = FrameMotion::new(&scene).unwrap();
        let limits = Limits::new(&scene);
        let bound = FrameReach::new(&frame.seg.osc, frame.reach().unwrap(), scene.horizon);
        let length = 0.1;
        let (mut waited, mut met) = (0, 0);
        for from in [0.0, 0.013, 0.37] {
            let (xs, _) = frame.state(from);
            for step in 0..40 {
                let x = xs - 0.02 + 0.14 * step as f64 / 39.0;
                for v in [-3.0, -0.4, -0.01, 0.0, 0.02, 0.5, 2.5] {
                    for side in [1.0, -1.0] {
                        let k = if side > 0.0 { -0.005 } else { length - 0.005 };
                        let gap = FrameGap {
                            frame: &frame,
                            floor: frame.carrying,
                            limits: &limits,
                            horizon: scene.horizon,
                            now: from,
                            x,
                            v,
                            drift: 0.0,
                            s: side,
                            k,
                        };
                        if gap.at(from).0 <= limits.tol {
                            continue; // in the wall already: not a ball the solver would hold
                        }
                        let contact = first_contact(&gap, from);
                        match gap.earliest_reach(from, xs, &bound) {
                            None => assert!(contact.is_infinite(), "x {x}, v {v}, side {side}: a contact at {contact} s"),
                            Some(t) => {
                                assert!(t <= contact, "x {x}, v {v}, side {side}: waits until {t} s, contact at {contact} s");
                                waited += usize::from(t > from);
                                met += usize::from(contact.is_finite() && t > from);
                            }
                        }
                    }
                }
            }
        }
        assert!(waited > 500 && met > 100, "{waited} waits, {met} of them before a contact");
    }
}
