//! The event search: when each pair next touches (exact for ball-ball pairs, bracketed roots for
//! ball-frame pairs between sign changes of the frame's acceleration), and when held balls are
//! released.

use super::*;

/// A pair's next event: at `t` when `exact`, else "no contact before `t`" (search again from `t`).
#[derive(Debug, Clone, Copy)]
pub(super) struct Candidate {
    pub(super) t: f64,
    pub(super) exact: bool,
}

pub(super) const NO_EVENT: Candidate = Candidate { t: f64::INFINITY, exact: true };

impl Solver<'_> {
    /// Next time after `t` at which the frame's acceleration changes sign, or `limit` if none
    /// comes first (unforced segments ignore `limit`: their sign changes are closed form).
    /// A forced segment's sign changes are scanned once and kept ([`SignChanges`]).
    pub(super) fn next_sign_change(&self, t: f64, limit: f64) -> f64 {
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
        // Searches start at the current time or later: older roots are never asked for again.
        if c.roots.len() > SIGN_CHANGES_KEPT {
            let now = self.t;
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

    /// Pair `p`'s next contact after `from`, searched no further than `bound` (a later contact
    /// is reported as "none before `bound`").
    pub(super) fn candidate(&self, p: usize, from: f64, bound: f64) -> Candidate {
        match self.gap(p) {
            Gap::Fixed => NO_EVENT,
            Gap::Linear { g, rate } => {
                if rate < 0.0 {
                    Candidate { t: self.t + g.max(0.0) / -rate, exact: true }
                } else {
                    NO_EVENT
                }
            }
            Gap::Frame { ball, s, k } => self.search_frame_pair(ball, s, k, from, bound),
        }
    }

    /// First contact of a ball with the frame after `from`, searched over one damped period
    /// at a time. The frame's acceleration keeps its sign between consecutive sign changes, so
    /// there the gap `g` has `g'' = -s a` of one sign: on a convex piece Newton's method from
    /// the left never passes the first root; on a concave piece a root exists only if `g` at
    /// the piece's end is not positive, and Newton from the right converges to it from above.
    pub(super) fn search_frame_pair(&self, ball: usize, s: f64, k: f64, from: f64, bound: f64) -> Candidate {
        // Only a forced segment's search is cut at `bound`: its sign changes are scanned, so
        // looking further costs, where an unforced segment's come in closed form (and cutting
        // its pieces would change the roots' last bits, which chaotic runs amplify).
        let bound = if self.seg.forced.is_some() { bound } else { self.horizon };
        let limit = (from + self.span).min(self.horizon).min(bound);
        let mut a = from;
        loop {
            let b = self.next_sign_change(a, limit).min(limit);
            // The sign just after `a` holds over the whole piece; judged as `resolve` judges it,
            // so that the two agree even where the acceleration is round-off (a frame at rest).
            let curvature = -s * self.accel_ahead(a);
            let root = if curvature >= 0.0 {
                self.convex_root(ball, s, k, a, b)
            } else {
                self.concave_root(ball, s, k, a, b)
            };
            if let Some(t) = root {
                return Candidate { t, exact: true };
            }
            if b >= limit {
                return if limit >= self.horizon { NO_EVENT } else { Candidate { t: limit, exact: false } };
            }
            a = b;
        }
    }

    /// The first root of a gap that is convex on `[a, b]`: Newton from the left, whose
    /// iterates never pass the root in exact arithmetic. Should one land deeper than the
    /// contact tolerance all the same (round-off where the piece is barely convex), the
    /// crossing is bisected back between it and the previous iterate.
    pub(super) fn convex_root(&self, ball: usize, s: f64, k: f64, a: f64, b: f64) -> Option<f64> {
        let mut t = a;
        let mut before = None;
        for _ in 0..MAX_ROOT_ITERATIONS {
            let (g, gp) = self.frame_gap_at(ball, s, k, t);
            if let Some(l) = before {
                if g < -self.frame_gap_tolerance(ball, s, k, t).2 {
                    return Some(self.bisect_crossing(ball, s, k, l, t));
                }
            }
            if gp >= 0.0 || (t == a && g <= self.tol && self.reopens(gp, -s * self.accel_ahead(a))) {
                return None; // convex and not decreasing (or about to): it only rises from here on
            }
            if g <= self.tol {
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

    /// Whether a touching pair whose gap changes at `rate` with curvature `curvature` (the
    /// wall accelerating away from the ball when positive) separates by itself: it approaches
    /// slower than `v_stick` (round-off: a forced frame's velocity re-evaluated after a
    /// release can differ from the ball's by an ulp) and turns within `t_stick`, sinking less
    /// than `v_stick t_stick / 2`, far below the contact tolerance. `resolve` and the contact
    /// search judge it alike, so they never disagree about a contact now.
    pub(super) fn reopens(&self, rate: f64, curvature: f64) -> bool {
        rate < 0.0 && -rate < self.v_stick && curvature > 0.0 && -rate < curvature * self.t_stick
    }

    /// A crossing of the gap between `l` (gap above the tolerance) and `h` (below it): a time
    /// at which the gap is within the tolerance, or `h` once the bracket is an ulp wide.
    pub(super) fn bisect_crossing(&self, ball: usize, s: f64, k: f64, mut l: f64, mut h: f64) -> f64 {
        for _ in 0..MAX_ROOT_ITERATIONS {
            let m = 0.5 * (l + h);
            if m <= l || m >= h {
                break;
            }
            let (g, _) = self.frame_gap_at(ball, s, k, m);
            if g.abs() <= self.tol {
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

    pub(super) fn concave_root(&self, ball: usize, s: f64, k: f64, a: f64, b: f64) -> Option<f64> {
        let (ga, gpa) = self.frame_gap_at(ball, s, k, a);
        if ga <= self.tol && gpa <= 0.0 {
            // Touching and not separating: a contact now if the wall presses, judged exactly as
            // `resolve` judges it (a piece can be an ulp long at a sign change, and its
            // midpoint then disagrees); otherwise the ball is about to leave the wall.
            return (-s * self.accel_ahead(a) < 0.0).then_some(a);
        }
        let (gb, _) = self.frame_gap_at(ball, s, k, b);
        if gb > self.tol {
            return None; // a concave function's minimum lies at an end of the piece
        }
        let mut lo = a;
        if ga <= self.tol {
            // Touching but separating: the return is after the maximum of g (where g' = 0,
            // g' decreasing on a concave piece).
            let (mut l, mut h) = (a, b);
            for _ in 0..MAX_ROOT_ITERATIONS {
                let m = 0.5 * (l + h);
                if m <= l || m >= h {
                    break;
                }
                if self.frame_gap_at(ball, s, k, m).1 > 0.0 {
                    l = m;
                } else {
                    h = m;
                }
            }
            lo = l;
            if self.frame_gap_at(ball, s, k, lo).0 <= self.tol {
                return Some(lo);
            }
        }
        // g decreases on [lo, b] from above tol to at most tol: one root; Newton from the right.
        let (mut l, mut h) = (lo, b);
        let mut t = b;
        for _ in 0..MAX_ROOT_ITERATIONS {
            let (g, gp) = self.frame_gap_at(ball, s, k, t);
            if g >= -self.tol && g <= self.tol {
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

    pub(super) fn refresh_candidates(&mut self) {
        if self.frame_dirty && self.has_frame() {
            for p in self.pair_range() {
                if matches!(self.gap(p), Gap::Frame { .. }) {
                    self.dirty[p] = true;
                }
            }
            self.release_at = if self.held_mass > 0.0 && !self.packed {
                // Forced: at most one span ahead; if nothing changed sign by then, `release`
                // finds nothing to let go and the search goes on from there.
                self.next_sign_change(self.t, (self.t + self.span).min(self.horizon))
            } else {
                f64::INFINITY
            };
        }
        self.frame_dirty = false;
        // A pair's search need not look past the earliest exact event already known (the
        // frame pairs' searches are the costly ones): exact ball-ball times first, then the
        // frame pairs, each bounded by everything found so far.
        let mut bound = self.exact_event_bound(None);
        let mut frame = [usize::MAX; 2];
        let mut frames = 0;
        for p in self.pair_range() {
            if !self.dirty[p] {
                continue;
            }
            if matches!(self.gap(p), Gap::Frame { .. }) {
                // At most two: the free balls next to the walls (or to balls the frame holds).
                frame[frames.min(1)] = p;
                frames += 1;
            } else {
                self.cand[p] = self.candidate(p, self.t, bound);
                self.dirty[p] = false;
                if self.cand[p].exact {
                    bound = bound.min(self.cand[p].t);
                }
            }
        }
        debug_assert!(frames <= 2, "more than two ball-frame pairs");
        let frame = &frame[..frames.min(2)];
        match self.seg.forced {
            // Both frame pairs searched side by side over windows that double from a scan
            // step: the far wall's search then stops where the near wall's contact is. As
            // unforced, no search looks more than a span ahead; one that finds nothing by then
            // goes on when its time comes.
            Some(f) => {
                let (mut reached, mut window) = (self.t, f.scan);
                let mut bound = bound.min(self.t + self.span);
                loop {
                    let until = (reached + window).min(bound);
                    for &p in frame {
                        if let Gap::Frame { ball, s, k } = self.gap(p) {
                            self.cand[p] = self.search_frame_pair(ball, s, k, reached, until);
                            if self.cand[p].exact {
                                bound = bound.min(self.cand[p].t);
                            }
                        }
                    }
                    if until >= bound || frame.is_empty() {
                        break;
                    }
                    reached = until;
                    window = (2.0 * window).min(self.span);
                }
            }
            None => {
                for &p in frame {
                    self.cand[p] = self.candidate(p, self.t, bound);
                }
            }
        }
        for &p in frame {
            self.dirty[p] = false;
        }
    }

    /// The earliest exact event among the clean pairs but `except`, the release and the horizon.
    pub(super) fn exact_event_bound(&self, except: Option<usize>) -> f64 {
        let mut bound = self.release_at.min(self.horizon);
        for p in self.pair_range() {
            if Some(p) != except && !self.dirty[p] && self.cand[p].exact {
                bound = bound.min(self.cand[p].t);
            }
        }
        bound
    }
}
