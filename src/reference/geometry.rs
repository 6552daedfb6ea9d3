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

/// The contact and sticking tolerances of a run (docs/MODEL.md §4, §10).
pub(super) struct Limits {
    /// The length tolerance: `1e-12` of the scene's length scale, m.
    pub(super) tol: f64,
    /// Touching bodies approaching slower than this stick, m/s.
    pub(super) v_stick: f64,
    /// The scene's speed scale, raised to the fastest approach of any impact so far: the
    /// speed at which contacts can be placed no closer than two ulps of time (see
    /// [`FrameGap::with_tolerance`]). It never falls, so bodies that met fast and move on
    /// together keep a tolerance their meeting needed.
    pub(super) fastest: f64,
    /// The largest contact tolerance a touching pair has had so far (see
    /// [`Solver::check_contacts`]).
    pub(super) accepted_overlap: f64,
    /// A ball whose bounce off an accelerating wall returns sooner sticks, s.
    pub(super) t_stick: f64,
}

impl Limits {
    /// The limits a run of `scene` starts with: the length tolerance at [`LENGTH_TOLERANCE`] of
    /// its length scale, sticking at [`STICK_SPEED`] of its speed scale and [`STICK_TIME`] of
    /// its time scale (the frame's damped period, else the horizon).
    pub(super) fn new(scene: &Scene) -> Limits {
        let time_scale = scene.frame.map_or(scene.horizon, |f| {
            let p = f.damped_period();
            if p > 0.0 {
                p
            } else {
                scene.horizon
            }
        });
        let speed_scale = scene.speed_scale();
        Limits {
            tol: LENGTH_TOLERANCE * scene.length_scale(),
            v_stick: STICK_SPEED * speed_scale,
            fastest: speed_scale,
            accepted_overlap: 0.0,
            t_stick: STICK_TIME * time_scale,
        }
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
}

/// What one instant's postcondition read of each pair, for `resolve` to judge the contacts by,
/// and `resolve`'s own scratch.
#[derive(Default)]
pub(super) struct Scratch {
    /// Each pair as [`Solver::check_contacts`] last read it.
    pub(super) pairs_now: Vec<Option<PairNow>>,
    /// Each pair's contact now.
    pub(super) contacts: Vec<Contact>,
    /// The ball-frame pairs `refresh_candidates` searches.
    pub(super) frame_pairs: Vec<usize>,
}

impl Solver<'_> {
    /// Ball `ball` against the frame, the gap `s (x_ball - xs) + k`, from now.
    #[inline(always)]
    pub(super) fn frame_gap(&self, ball: usize, s: f64, k: f64) -> FrameGap<'_> {
        FrameGap {
            frame: &self.frame,
            floor: self.frame.carrying,
            limits: &self.limits,
            horizon: self.horizon,
            now: self.t,
            x: self.balls.x[ball],
            v: self.balls.v[ball],
            drift: self.balls.drift[ball],
            s,
            k,
        }
    }

    /// The contact tolerance of ball-ball pair `p` of rate `rate` now (see
    /// [`FrameGap::with_tolerance`]).
    #[inline(always)]
    pub(super) fn ball_gap_tolerance(&self, p: usize, rate: f64) -> f64 {
        let (Some(i), Some(j)) = self.balls.pairs.balls(p) else { unreachable!("a ball-ball pair") };
        let eps = f64::EPSILON;
        self.limits.tol
            + self.balls.drift[i]
            + self.balls.drift[j]
            + 4.0 * eps * (self.balls.x[i].abs() + self.balls.x[j].abs() + self.balls.radius[i] + self.balls.radius[j])
            + 2.0 * eps * self.t.abs() * rate.abs().max(self.limits.fastest)
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
        match self.balls.gap(p) {
            Gap::Fixed => None,
            Gap::Linear { g, rate } => Some(PairNow { g, rate, tol: self.ball_gap_tolerance(p, rate), curvature: None }),
            Gap::Frame { ball, s, k } => {
                let (xs, vs, a) = self.frame.now(self.t);
                let xb = self.balls.x[ball];
                let rate = s * (self.balls.v[ball] - vs);
                let tol = self.frame_gap(ball, s, k).tolerance(self.t, xb, xs, rate);
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
    /// Each pair read is kept in `self.scratch.pairs_now`: `resolve`, which comes next at the same
    /// instant and state, judges the contacts from them instead of reading every pair again.
    pub(super) fn check_contacts(&mut self, trigger: Option<usize>) -> Result<(), ModelError> {
        let mut pairs_now = std::mem::take(&mut self.scratch.pairs_now);
        pairs_now.clear();
        pairs_now.resize(self.balls.pairs.count(), None);
        for p in self.pair_range() {
            pairs_now[p] = self.pair_now(p);
            let Some(PairNow { g, tol, .. }) = pairs_now[p] else { continue };
            if g.abs() <= tol {
                self.limits.accepted_overlap = self.limits.accepted_overlap.max(tol);
            }
            let apart = trigger == Some(p) && g > tol;
            let allowed = tol.max(self.limits.accepted_overlap);
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
        self.scratch.pairs_now = pairs_now;
        Ok(())
    }

    /// The bodies either side of pair `p`.
    pub(super) fn pair_bodies(&self, p: usize) -> (Body, Body) {
        self.balls.pairs.bodies(p)
    }
}
