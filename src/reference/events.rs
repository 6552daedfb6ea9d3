//! State changes at an event: advancing to it, impacts, merges of touching runs, releases, and
//! the resolution of every contact of one instant.

use super::*;

/// The run's impacts, in time order, and its energy account so far.
pub(super) struct Ledger {
    pub(super) impacts: Vec<Impact>,
    /// Index in `impacts` of each pair's latest impact.
    pub(super) last_impact: Vec<Option<usize>>,
    /// Lost in impacts, J.
    pub(super) impact_loss: f64,
    /// Dissipated by the frame's damper, J.
    pub(super) damping_loss: f64,
    /// Put in by the excitation, J.
    pub(super) forcing_work: f64,
}

impl Ledger {
    pub(super) fn new(pairs: usize) -> Self {
        Ledger {
            // Room for a paper scene's impacts: growing a vector of them copies it each time.
            impacts: Vec::with_capacity(IMPACTS_RESERVED),
            last_impact: vec![None; pairs],
            impact_loss: 0.0,
            damping_loss: 0.0,
            forcing_work: 0.0,
        }
    }
}

impl Solver<'_> {
    /// Moves time on to `t`: the free balls fly there.
    pub(super) fn advance(&mut self, t: f64) {
        self.balls.advance(t - self.t);
        self.t = t;
    }

    /// Starts a new frame segment at the current time with velocity `v` and the current load,
    /// booking what the frame's damper dissipated and the excitation put in over the last one.
    pub(super) fn set_frame(&mut self, v: f64) {
        self.book_segment_energy();
        let (xs, _, _) = self.frame.now(self.t);
        self.frame.restart(self.t, xs, v);
        self.search.frame_dirty = true;
    }

    /// Books the energy the frame's damper and excitation exchanged over the current segment
    /// up to now ([`FrameMotion::segment_energy`]).
    pub(super) fn book_segment_energy(&mut self) {
        let (damping, work) = self.frame.segment_energy(self.t, self.scene);
        self.ledger.damping_loss += damping;
        if self.frame.is_driven() {
            self.ledger.forcing_work += work;
        }
    }

    pub(super) fn touch_ball(&mut self, i: usize) {
        self.search.touch_pairs_from(self.balls.pairs.left_of(i));
    }

    pub(super) fn record(&mut self, p: usize, approach_speed: f64, energy_lost: f64, impulses: u32) {
        let (a, b) = self.pair_bodies(p);
        self.limits.fastest = self.limits.fastest.max(approach_speed);
        self.ledger.impact_loss += energy_lost;
        // Sequential impulses across one pair at one instant are one impact of that pair.
        if let Some(k) = self.ledger.last_impact[p] {
            let last = &mut self.ledger.impacts[k];
            if last.t == self.t {
                last.energy_lost += energy_lost;
                last.impulses += impulses;
                return;
            }
        }
        self.ledger.last_impact[p] = Some(self.ledger.impacts.len());
        self.ledger.impacts.push(Impact {
            t: self.t,
            a,
            b,
            approach_speed,
            energy_lost,
            impulses,
            peak_force: None,
            contact_duration: None,
        });
    }

    /// An impact with restitution `e` across pair `p`.
    pub(super) fn collide(&mut self, p: usize, approach_speed: f64) {
        match self.balls.gap(p) {
            Gap::Fixed => {}
            Gap::Linear { .. } => {
                let (Some(i), Some(j)) = self.balls.pairs.balls(p) else { unreachable!("a linear gap is between two balls") };
                let (vi, vj, lost) = impact_law(self.balls.mass[i], self.balls.v[i], self.balls.mass[j], self.balls.v[j], self.e);
                self.balls.v[i] = vi;
                self.balls.v[j] = vj;
                self.touch_ball(i);
                self.touch_ball(j);
                self.record(p, approach_speed, lost, 1);
            }
            Gap::Frame { ball, .. } => {
                let (_, vs, _) = self.frame.now(self.t);
                let group = self.frame.mass + self.frame.held_mass;
                let (vb, vf, lost) = impact_law(self.balls.mass[ball], self.balls.v[ball], group, vs, self.e);
                self.balls.v[ball] = vb;
                self.touch_ball(ball);
                self.set_frame(vf);
                self.record(p, approach_speed, lost, 1);
            }
        }
    }

    /// Is pair `p` touching and slow enough (relative speed below `v_stick`) to move as one?
    pub(super) fn stuck_pair(&self, p: usize) -> bool {
        self.pair_now(p).is_some_and(|q| q.g <= q.tol && q.rate.abs() < self.limits.v_stick)
    }

    /// Perfectly inelastic merge of the run of touching slow bodies around pair `p`; a run that
    /// reaches the frame is held by it.
    pub(super) fn merge_run(&mut self, p: usize, approach_speed: f64) {
        let range = self.pair_range();
        let (mut lo, mut hi) = (p, p);
        // Extend across pairs of free balls only: the frame's group is one body already.
        while lo > range.start && self.balls.left_free_ball(lo).is_some() && self.stuck_pair(lo - 1) {
            lo -= 1;
        }
        while hi + 1 < range.end && self.balls.right_free_ball(hi).is_some() && self.stuck_pair(hi + 1) {
            hi += 1;
        }
        // The run holds the bodies either side of pairs lo ..= hi, a wall or a held ball at
        // either end being the frame.
        let reaches_left = self.balls.left_free_ball(lo).is_none();
        let reaches_right = self.balls.right_free_ball(hi).is_none();
        let with_frame = self.has_frame() && self.balls.walls && (reaches_left || reaches_right);
        let balls: Vec<usize> =
            self.balls.left_free_ball(lo).into_iter().chain((lo..=hi).filter_map(|q| self.balls.right_free_ball(q))).collect();
        let (_, vs, _) = self.frame.now(self.t);
        let group = self.frame.mass + self.frame.held_mass;
        let (mut pm, mut m) = (0.0, 0.0);
        for &i in &balls {
            pm += self.balls.mass[i] * self.balls.v[i];
            m += self.balls.mass[i];
        }
        if with_frame {
            pm += group * vs;
            m += group;
        }
        let vc = pm / m;
        let mut lost = 0.0;
        for &i in &balls {
            lost += 0.5 * self.balls.mass[i] * (self.balls.v[i] - vc).powi(2);
            self.balls.v[i] = vc;
            self.touch_ball(i);
        }
        if with_frame {
            lost += 0.5 * group * (vs - vc).powi(2);
            let (xs, _, _) = self.frame.now(self.t);
            let side = if reaches_left { Hold::Left } else { Hold::Right };
            for &i in &balls {
                self.balls.hold[i] = side;
                self.balls.offset[i] = self.balls.x[i] - xs;
                self.frame.held_mass += self.balls.mass[i];
            }
            if reaches_left && reaches_right {
                // The chain is packed wall to wall: all its balls move with the frame for good.
                let first = balls.first().copied();
                let chain = self.balls.chains.iter().find(|c| first.is_some_and(|i| c.contains(&i))).cloned().unwrap_or_default();
                for i in chain {
                    self.balls.hold[i] = Hold::Packed;
                }
            }
            self.balls.packed = !self.balls.hold.iter().any(|h| matches!(h, Hold::Left | Hold::Right));
            self.set_frame(vc);
        }
        self.record(p, approach_speed, lost, balls.len() as u32 + with_frame as u32);
    }

    /// Releases the held runs whose wall would now pull on them.
    pub(super) fn release(&mut self) -> bool {
        if self.frame.held_mass == 0.0 || self.balls.packed {
            return false;
        }
        let (xs, vs, a) = self.frame.now(self.t);
        let mut released = false;
        for i in 0..self.balls.n {
            let pulled = match self.balls.hold[i] {
                Hold::Left => a < 0.0,
                Hold::Right => a > 0.0,
                Hold::Free | Hold::Packed => false,
            };
            if pulled {
                self.balls.hold[i] = Hold::Free;
                self.balls.x[i] = xs + self.balls.offset[i];
                self.balls.drift[i] += f64::EPSILON * self.balls.x[i].abs();
                self.balls.v[i] = vs;
                self.frame.held_mass -= self.balls.mass[i];
                self.touch_ball(i);
                released = true;
            }
        }
        if released {
            if self.balls.hold.iter().all(|h| *h == Hold::Free) {
                self.frame.held_mass = 0.0; // no round-off residue
            }
            self.balls.packed = !self.balls.hold.iter().any(|h| matches!(h, Hold::Left | Hold::Right));
            self.set_frame(vs);
        }
        released
    }

    /// What `resolve` needs of pair `p` now: the speed at which it approaches when it touches
    /// (`None` when it does not touch, does not approach, or drifts off a wall that
    /// accelerates away, see [`Limits::reopens`]), and whether the frame presses it together.
    #[inline(always)]
    pub(super) fn contact_now(&self, p: usize) -> Contact {
        self.contact_of(self.pair_now(p))
    }

    /// [`Solver::contact_now`] of a pair read already.
    #[inline(always)]
    pub(super) fn contact_of(&self, pair: Option<PairNow>) -> Contact {
        let Some(PairNow { g, rate, tol, curvature }) = pair else {
            return Contact { approach: None, pressed: false, frame: false };
        };
        let frame = curvature.is_some();
        if g > tol {
            return Contact { approach: None, pressed: false, frame };
        }
        let drifting_off = curvature.is_some_and(|c| self.limits.reopens(rate, c));
        Contact {
            approach: (rate < 0.0 && !drifting_off).then_some(-rate),
            pressed: curvature.is_some_and(|c| c < 0.0) && rate < self.limits.v_stick,
            frame,
        }
    }

    /// Resolves everything that happens at the current instant: impacts of touching
    /// approaching pairs (fastest first), merges of slow ones, holds and releases.
    ///
    /// A cascade at one instant can take thousands of impulses (a light ball between heavy
    /// ones), so each pass re-reads only the pairs its last impulse changed: the pair's
    /// neighbours, and every ball-frame pair when the frame's velocity changed. With `checked`
    /// the first pass takes the pairs [`Solver::check_contacts`] has just read at this state.
    pub(super) fn resolve(&mut self, checked: bool) -> Result<(), ModelError> {
        let range = self.pair_range();
        let mut contacts = std::mem::take(&mut self.scratch.contacts);
        contacts.clear();
        contacts.resize(self.balls.pairs.count(), Contact { approach: None, pressed: false, frame: false });
        let mut impulses = 0usize;
        // Pairs to re-read: all, or the neighbours of `changed` (and the frame's pairs).
        let mut all = true;
        let mut first = checked;
        let mut changed = (0usize, false);
        // Each pass changes the state (an impulse, a merge or a release); more passes than the
        // impulse cap allows plus a few per body means two judgements disagree and would
        // cycle: a stall to report, not a hang.
        let most_passes = MAX_IMPULSES_PER_INSTANT + 8 * (self.balls.n + 1);
        for _ in 0..most_passes {
            if first {
                for p in range.clone() {
                    contacts[p] = self.contact_of(self.scratch.pairs_now[p]);
                }
                first = false;
            } else if all {
                for p in range.clone() {
                    contacts[p] = self.contact_now(p);
                }
            } else {
                let (p, frame) = changed;
                for q in p.saturating_sub(1)..=p + 1 {
                    if range.contains(&q) {
                        contacts[q] = self.contact_now(q);
                    }
                }
                if frame {
                    for q in range.clone() {
                        if contacts[q].frame {
                            contacts[q] = self.contact_now(q);
                        }
                    }
                }
            }
            let mut fastest: Option<(usize, f64)> = None;
            let mut pressed: Option<usize> = None;
            for p in range.clone() {
                let c = contacts[p];
                if let Some(u) = c.approach {
                    if fastest.is_none_or(|(_, v)| u > v) {
                        fastest = Some((p, u));
                    }
                }
                if c.pressed && pressed.is_none() {
                    pressed = Some(p);
                }
            }
            all = true;
            if let Some((p, u)) = fastest {
                let bounce_returns_fast = match self.balls.gap(p) {
                    Gap::Frame { s, .. } => {
                        let a = -s * self.frame.now(self.t).2;
                        a < 0.0 && 2.0 * self.e * u / -a < self.limits.t_stick
                    }
                    _ => false,
                };
                // With e = 0 a touching approaching run ends as one body: merge it at once
                // instead of converging to that through a geometric series of impulses.
                // A pair striking again within a contact duration is in persistent contact.
                let repeats_within_contact = self.ledger.last_impact[p].is_some_and(|k| {
                    self.ledger.impacts[k].t < self.t && self.t - self.ledger.impacts[k].t < self.scene.reference.contact_duration
                });
                if self.e > 0.0
                    && u >= self.limits.v_stick
                    && !bounce_returns_fast
                    && !repeats_within_contact
                    && impulses < MAX_IMPULSES_PER_INSTANT
                {
                    self.collide(p, u);
                    impulses += 1;
                    (all, changed) = (false, (p, contacts[p].frame));
                } else {
                    self.merge_run(p, u);
                }
                continue;
            }
            if let Some(p) = pressed {
                self.merge_run(p, 0.0);
                continue;
            }
            if !self.release() {
                self.scratch.contacts = contacts;
                return Ok(());
            }
        }
        Err(self.stalled(format!("{most_passes} impacts, merges and releases at one instant did not settle")))
    }
}
