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

/// Each pair's next event, whether it must be searched again, and when the frame releases the
/// balls it holds.
pub(super) struct Search {
    /// Pair `p`'s next event.
    pub(super) cand: Vec<Candidate>,
    /// Pair `p` changed since its candidate was found.
    pub(super) dirty: Vec<bool>,
    /// The frame's motion changed: every ball-frame pair and the release are searched again.
    pub(super) frame_dirty: bool,
    /// When the frame's force next turns away from the balls it holds.
    pub(super) release_at: f64,
}

impl Search {
    pub(super) fn new(pairs: usize) -> Self {
        Search { cand: vec![NO_EVENT; pairs], dirty: vec![true; pairs], frame_dirty: true, release_at: f64::INFINITY }
    }

    /// The ball whose left pair is `p` changed: both its pairs are searched again.
    pub(super) fn touch_pairs_from(&mut self, p: usize) {
        self.dirty[p] = true;
        self.dirty[p + 1] = true;
    }
}

impl Solver<'_> {
    /// Pair `p`'s next contact after `from`, searched no further than `bound` (a later contact
    /// is reported as "none before `bound`").
    pub(super) fn candidate(&self, p: usize, from: f64, bound: f64) -> Candidate {
        match self.balls.gap(p) {
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
        let bound = if self.frame.seg.forced.is_some() { bound } else { self.horizon };
        let limit = (from + self.frame.span).min(self.horizon).min(bound);
        if !self.frame_may_reach(ball, s, k, from, limit) {
            // What the search below would conclude, without evaluating the frame's motion.
            return if limit >= self.horizon { NO_EVENT } else { Candidate { t: limit, exact: false } };
        }
        let mut a = from;
        loop {
            let b = self.frame.next_sign_change(a, limit, self.t).min(limit);
            // The sign just after `a` holds over the whole piece; judged as `resolve` judges it,
            // so that the two agree even where the acceleration is round-off (a frame at rest).
            let curvature = -s * self.frame.accel_ahead(a);
            let root = if curvature >= 0.0 { self.convex_root(ball, s, k, a, b) } else { self.concave_root(ball, s, k, a, b) };
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
    /// [`Solver::search_frame_pair`] would find no root there (the same answer, without the
    /// closed form's `exp` and `sin_cos` at every piece and iterate).
    ///
    /// An unforced frame with a spring and damping `>= 0` never leaves `|xs| <= R =
    /// sqrt(x0^2 + v0^2 / w0^2)` ([`Segment::reach`]) nor `|vs| <= w0 R` (its `v^2 + w0^2 x^2`
    /// never grows), so the gap is at least `s x_ball + k - R`, a line in time whose least value
    /// lies at an end. That bound must clear the tolerance by what the evaluated gap can err by
    /// (as [`Solver::frame_tolerance`] counts it, at the window's far end and with the frame at
    /// its extremes, twice over), which also keeps every Newton step of the search longer than
    /// an ulp of time.
    pub(super) fn frame_may_reach(&self, ball: usize, s: f64, k: f64, from: f64, limit: f64) -> bool {
        let seg = &self.frame.seg;
        let Some(reach) = seg.reach else { return true };
        let speed = seg.osc.w0() * reach;
        let (x, v) = (self.balls.x[ball], self.balls.v[ball]);
        let line = |t: f64| s * (x + v * (t - self.t)) + k;
        let nearest = line(from).min(line(limit));
        let eps = f64::EPSILON;
        let farthest = x.abs() + v.abs() * (limit - self.t).abs();
        let err = 2.0
            * (self.balls.drift[ball]
                + seg.position_roundoff(limit)
                + 4.0 * eps * (farthest + reach + k.abs())
                + 2.0 * eps * limit.abs() * (v.abs() + speed).max(self.limits.fastest))
            + 4.0 * eps * reach;
        // Written so that a NaN anywhere answers "may reach" (the search then decides).
        !(nearest - reach - err > self.limits.tol)
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
            if gp >= 0.0 || (t == a && g <= self.limits.tol && self.reopens(gp, -s * self.frame.accel_ahead(a))) {
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

    /// Whether a touching pair whose gap changes at `rate` with curvature `curvature` (the
    /// wall accelerating away from the ball when positive) separates by itself: it approaches
    /// slower than `v_stick` (round-off: a forced frame's velocity re-evaluated after a
    /// release can differ from the ball's by an ulp) and turns within `t_stick`, sinking less
    /// than `v_stick t_stick / 2`, far below the contact tolerance. `resolve` and the contact
    /// search judge it alike, so they never disagree about a contact now.
    pub(super) fn reopens(&self, rate: f64, curvature: f64) -> bool {
        rate < 0.0 && -rate < self.limits.v_stick && curvature > 0.0 && -rate < curvature * self.limits.t_stick
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

    pub(super) fn concave_root(&self, ball: usize, s: f64, k: f64, a: f64, b: f64) -> Option<f64> {
        let (ga, gpa) = self.frame_gap_at(ball, s, k, a);
        if ga <= self.limits.tol && gpa <= 0.0 {
            // Touching and not separating: a contact now if the wall presses, judged exactly as
            // `resolve` judges it (a piece can be an ulp long at a sign change, and its
            // midpoint then disagrees); otherwise the ball is about to leave the wall.
            return (-s * self.frame.accel_ahead(a) < 0.0).then_some(a);
        }
        let (gb, _) = self.frame_gap_at(ball, s, k, b);
        if gb > self.limits.tol {
            return None; // a concave function's minimum lies at an end of the piece
        }
        let mut lo = a;
        if ga <= self.limits.tol {
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
            if self.frame_gap_at(ball, s, k, lo).0 <= self.limits.tol {
                return Some(lo);
            }
        }
        // g decreases on [lo, b] from above tol to at most tol: one root; Newton from the right.
        let (mut l, mut h) = (lo, b);
        let mut t = b;
        for _ in 0..MAX_ROOT_ITERATIONS {
            let (g, gp) = self.frame_gap_at(ball, s, k, t);
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

    pub(super) fn refresh_candidates(&mut self) {
        if self.search.frame_dirty && self.has_frame() {
            for p in self.pair_range() {
                if self.balls.is_frame_pair(p) {
                    self.search.dirty[p] = true;
                }
            }
            self.search.release_at = if self.frame.held_mass > 0.0 && !self.balls.packed {
                // Forced: at most one span ahead; if nothing changed sign by then, `release`
                // finds nothing to let go and the search goes on from there.
                self.frame.next_sign_change(self.t, (self.t + self.frame.span).min(self.horizon), self.t)
            } else {
                f64::INFINITY
            };
        }
        self.search.frame_dirty = false;
        // A pair's search need not look past the earliest exact event already known (the
        // frame pairs' searches are the costly ones): exact ball-ball times first, then the
        // frame pairs, each bounded by everything found so far.
        let mut bound = self.exact_event_bound(None);
        let mut frame = std::mem::take(&mut self.scratch.frame_pairs);
        frame.clear();
        for p in self.pair_range() {
            if !self.search.dirty[p] {
                continue;
            }
            if self.balls.is_frame_pair(p) {
                // At most two per chain: the free balls next to the walls (or to balls the
                // frame holds).
                frame.push(p);
            } else {
                self.search.cand[p] = self.candidate(p, self.t, bound);
                self.search.dirty[p] = false;
                if self.search.cand[p].exact {
                    bound = bound.min(self.search.cand[p].t);
                }
            }
        }
        debug_assert!(frame.len() <= 2 * self.balls.chains.len().max(1), "more than two ball-frame pairs per chain");
        match self.frame.seg.forced {
            // Both frame pairs searched side by side over windows that double from a scan
            // step: the far wall's search then stops where the near wall's contact is. As
            // unforced, no search looks more than a span ahead; one that finds nothing by then
            // goes on when its time comes.
            Some(f) => {
                let (mut reached, mut window) = (self.t, f.scan);
                let mut bound = bound.min(self.t + self.frame.span);
                loop {
                    let until = (reached + window).min(bound);
                    for &p in &frame {
                        if let Gap::Frame { ball, s, k } = self.balls.gap(p) {
                            self.search.cand[p] = self.search_frame_pair(ball, s, k, reached, until);
                            if self.search.cand[p].exact {
                                bound = bound.min(self.search.cand[p].t);
                            }
                        }
                    }
                    if until >= bound || frame.is_empty() {
                        break;
                    }
                    reached = until;
                    window = (2.0 * window).min(self.frame.span);
                }
            }
            None => {
                for &p in &frame {
                    self.search.cand[p] = self.candidate(p, self.t, bound);
                }
            }
        }
        for &p in &frame {
            self.search.dirty[p] = false;
        }
        self.scratch.frame_pairs = frame;
    }

    /// The earliest exact event among the clean pairs but `except`, the release and the horizon.
    pub(super) fn exact_event_bound(&self, except: Option<usize>) -> f64 {
        let mut bound = self.search.release_at.min(self.horizon);
        for p in self.pair_range() {
            if Some(p) != except && !self.search.dirty[p] && self.search.cand[p].exact {
                bound = bound.min(self.search.cand[p].t);
            }
        }
        bound
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// [`Solver::frame_may_reach`] answers "cannot" only where the evaluated gap stays above
    /// the tolerance over the whole window (read on a fine grid and at the window's ends), and
    /// the test draws cases of both answers, so it can fail either way.
    #[test]
    fn a_frame_pair_ruled_out_never_touches_in_its_window() {
        let scene = crate::scene::load(crate::scene::scenes_dir().join("lpc-lsl.toml")).unwrap().scene.unwrap();
        let mut rng = rand_pcg::Pcg64::seed_from_u64(13);
        let (mut ruled_out, mut kept) = (0, 0);
        for _ in 0..2000 {
            let mut s = Solver::new(&scene, Record::MetricsOnly);
            let (x0, v0) = (rng.random_range(-0.02..0.02), rng.random_range(-1.0..1.0));
            let t0 = rng.random_range(0.0..2.0);
            s.frame.seg = Segment::new(t0, x0, v0, s.frame.seg.osc, None);
            s.frame.segment += 1;
            s.t = t0;
            let ball = if rng.random_bool(0.5) { 0 } else { s.balls.n - 1 };
            s.balls.v[ball] = rng.random_range(-0.5..0.5);
            s.balls.x[ball] += rng.random_range(-0.01..0.01);
            let p = if ball == 0 { 0 } else { s.balls.n };
            let Gap::Frame { ball, s: side, k } = s.balls.gap(p) else { panic!("pair {p} is not a ball-frame pair") };
            let limit = t0 + rng.random_range(0.0..0.3);
            if s.frame_may_reach(ball, side, k, t0, limit) {
                kept += 1;
                continue;
            }
            ruled_out += 1;
            for i in 0..=2000 {
                let t = t0 + (limit - t0) * i as f64 / 2000.0;
                let (g, _) = s.frame_gap_at(ball, side, k, t);
                assert!(g > s.limits.tol, "ruled out, but the gap is {g:e} m at t = {t} (window {t0}..{limit})");
            }
        }
        assert!(ruled_out > 100 && kept > 100, "{ruled_out} ruled out, {kept} kept");
    }
}
