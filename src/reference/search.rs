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

    /// First contact of ball `ball` with the frame, its gap `s (x_ball - xs) + k`, after
    /// `from`, searched no further than `bound` (see [`FrameGap::search`]).
    pub(super) fn search_frame_pair(&self, ball: usize, s: f64, k: f64, from: f64, bound: f64) -> Candidate {
        self.frame_gap(ball, s, k).search(from, bound)
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
        match self.frame.scan_step() {
            // Both frame pairs searched side by side over windows that double from a scan
            // step: the far wall's search then stops where the near wall's contact is. As
            // unforced, no search looks more than a span ahead; one that finds nothing by then
            // goes on when its time comes.
            Some(scan) => {
                let (mut reached, mut window) = (self.t, scan);
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

    /// [`FrameGap::may_reach`] answers "cannot" only where the evaluated gap stays above
    /// the tolerance over the whole window (read on a fine grid and at the window's ends), and
    /// the test draws cases of both answers, so it can fail either way.
    #[test]
    fn a_frame_pair_ruled_out_never_touches_in_its_window() {
        let scene = crate::scene::load(crate::scene::scenes_dir().join("lpc-lsl.toml")).unwrap().scene.unwrap();
        let mut rng = rand_pcg::Pcg64::seed_from_u64(13);
        let (mut ruled_out, mut kept) = (0, 0);
        for _ in 0..2000 {
            let mut s = Solver::new(&scene, Record::MetricsOnly).unwrap();
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
            if s.frame_gap(ball, side, k).may_reach(t0, limit) {
                kept += 1;
                continue;
            }
            ruled_out += 1;
            for i in 0..=2000 {
                let t = t0 + (limit - t0) * i as f64 / 2000.0;
                let (g, _) = s.frame_gap(ball, side, k).at(t);
                assert!(g > s.limits.tol, "ruled out, but the gap is {g:e} m at t = {t} (window {t0}..{limit})");
            }
        }
        assert!(ruled_out > 100 && kept > 100, "{ruled_out} ruled out, {kept} kept");
    }
}
