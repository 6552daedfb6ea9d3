//! Predicting the next events of a ball: its impacts with the frame's walls (sound root
//! isolation on the walls' closed-form motion), with the walls across the motion and the cells'
//! faces, and with its neighbours, entered in the calendar.

use super::*;
use crate::model::ModelError;

impl Solver<'_> {
    /// Enters an event at `t` in the calendar, unless it comes after the horizon.
    pub(super) fn push(&mut self, t: f64, ball: usize, kind: Kind, other: Option<usize>) {
        if t <= self.horizon {
            let stamps = (self.balls[ball].stamp, other.map_or(0, |j| self.balls[j].stamp));
            let version = if matches!(kind, Kind::Wait(_)) { self.reach_version } else { self.frame.segment };
            let entry = Entry { t, ball: ball as u32, kind, stamps, version };
            if matches!(kind, Kind::Frame(..)) {
                self.frame_calendar.push(entry);
            } else {
                self.calendar.push(ball, entry);
            }
        }
    }

    /// The earliest entry of the two calendars (at a tie, the other entries' first).
    pub(super) fn next_entry(&mut self) -> Option<Entry> {
        match (self.calendar.peek(), self.frame_calendar.peek()) {
            (Some(a), Some(f)) if f > a => self.frame_calendar.pop(),
            (Some(_), _) => self.calendar.pop(),
            (None, _) => self.frame_calendar.pop(),
        }
    }

    /// Ball `i`'s next contact with the frame's wall on side `side`: searched from now when
    /// the ball may be near that wall, else a wait until it may be (most balls are far from
    /// the walls, and most of those meet another body first).
    pub(super) fn predict_frame_wall(&mut self, i: usize, side: f64) {
        let wait = match &self.frame_reach {
            // The frame's state now is kept by `FrameMotion::state`: one evaluation serves
            // both walls and every ball predicted at this instant.
            Some(bound) => self.frame_gap(i, side).earliest_reach(self.t, self.frame.state(self.t).0, bound),
            None => Some(self.t),
        };
        match wait {
            Some(t) if t <= self.t => self.search_frame_wall(i, side),
            Some(t) => {
                self.searched[i][wall_index(side)] = false;
                self.push(t, i, Kind::Wait(side as i8), None);
            }
            None => self.searched[i][wall_index(side)] = false,
        }
    }

    /// Ball `i`'s next contact with the frame's wall on side `side`, searched from now.
    pub(super) fn search_frame_wall(&mut self, i: usize, side: f64) {
        let w = wall_index(side);
        if !self.searched[i][w] {
            self.searched[i][w] = true;
            self.searching.push((i as u32, w as u8));
            if self.searching.len() > 4 * self.balls.len() + 64 {
                // Rebuilt from the flags, so that the list never outgrows them.
                self.searching = (0..self.balls.len() as u32)
                    .flat_map(|k| [(k, 0u8), (k, 1)])
                    .filter(|&(k, w)| self.searched[k as usize][w as usize])
                    .collect();
            }
        }
        // On a forced frame or a structure the walls' motion changes at every end-wall impact
        // of any ball, and where a bed presses its walls those come a contact duration apart: a
        // search is cut at a scan step of the walls' motion, where it goes on unless the
        // motion has changed.
        let bound = match self.frame.scan_step() {
            Some(step) => self.t + step,
            None => self.horizon,
        };
        let c = self.frame_gap(i, side).search(self.t, bound);
        if c.t.is_finite() {
            self.push(c.t, i, Kind::Frame(side as i8, c.exact), None);
        }
    }

    /// Everything ball `i` (brought to now) meets next: walls, its cell's faces, the balls of
    /// the cells around it. With `check`, after an impact of the ball, first the postcondition:
    /// it overlaps no wall and none of those balls (the cells are read once for both).
    pub(super) fn predict(&mut self, i: usize, check: bool) -> Result<(), ModelError> {
        if check {
            self.check_walls(i)?;
        }
        self.balls[i].stamp = self.balls[i].stamp.wrapping_add(1);
        // Every entry the ball owns is stale from here on. Its place in the calendar's tree is
        // found once, when all its new entries are in.
        self.calendar.hold(i);
        self.calendar.clear(i);
        let b = self.balls[i];
        let t = self.t;
        // Ball `i`'s motion now, evaluated once for its walls, its cell and all its neighbours.
        let motion = b.motion(t, self.gravity);
        let a = motion.2;
        for axis in 1..3 {
            let half = self.cells[b.damper as usize].half[axis - 1];
            for side in [1.0, -1.0] {
                if b.rest == Some((axis, side)) {
                    continue;
                }
                let g0 = half - side * b.p[axis] - b.radius;
                if let Some(dt) = plane_time(g0, side, b.v[axis], a[axis]) {
                    self.push(t + dt, i, Kind::Across(axis as u8, side as i8), None);
                }
            }
        }
        for side in [1.0, -1.0] {
            self.predict_frame_wall(i, side);
        }
        self.predict_crossing(i, a);
        let predicted = self.predict_pairs(i, motion, self.cells[b.damper as usize].heads(Cells::around_block(b.cell)), check);
        self.calendar.release();
        predicted
    }

    /// Ball `i` (brought to now) has crossed into its cell along `axis` on side `dir`: its
    /// flight goes on, so its entries stand; it meets in addition the balls of the slab of
    /// nine cells it neighbours now and did not before, and it crosses again.
    pub(super) fn predict_slab(&mut self, i: usize, axis: usize, dir: i64) {
        let b = self.balls[i];
        let motion = b.motion(self.t, self.gravity);
        self.calendar.hold(i);
        self.predict_crossing(i, motion.2);
        let cells = &self.cells[b.damper as usize];
        if let Some(slab) = cells.slab_block(b.cell, axis, dir) {
            let heads = cells.heads(slab);
            self.predict_pairs(i, motion, heads, false).expect("a prediction without a check cannot fail");
        }
        self.calendar.release();
    }

    /// When ball `i` (brought to now), accelerated by `a`, next leaves its cell.
    pub(super) fn predict_crossing(&mut self, i: usize, a: [f64; 3]) {
        let b = self.balls[i];
        let cells = &self.cells[b.damper as usize];
        // The earliest crossing, at a tie the first axis's; never when the time is infinite.
        let mut crossing: (f64, usize, i64) = (f64::INFINITY, 0, 1);
        for axis in 0..3 {
            let lower = cells.face(b.cell, axis);
            let v = b.v[axis];
            if a[axis] == 0.0 {
                // Without acceleration along the axis, only the face ahead is crossed, at the
                // gap over the speed (`plane_time`'s root to the bit), chosen without a branch
                // on the velocity's sign, which is as good as random.
                let ahead = v > 0.0;
                let dir = if ahead { 1 } else { -1 };
                let g0 = std::hint::select_unpredictable(ahead, lower + cells.size - b.p[axis], b.p[axis] - lower);
                let dt = g0.max(0.0) / v.abs();
                let earlier = (v != 0.0) & cells.has_neighbour(b.cell, axis, dir) & (dt < crossing.0);
                crossing = std::hint::select_unpredictable(earlier, (dt, axis, dir), crossing);
                continue;
            }
            for dir in [1i64, -1] {
                if !cells.has_neighbour(b.cell, axis, dir) {
                    continue;
                }
                let (g0, side) = if dir > 0 { (lower + cells.size - b.p[axis], 1.0) } else { (b.p[axis] - lower, -1.0) };
                if let Some(dt) = plane_time(g0.max(0.0), side, v, a[axis]) {
                    if dt < crossing.0 {
                        crossing = (dt, axis, dir);
                    }
                }
            }
        }
        let (dt, axis, dir) = crossing;
        self.push(self.t + dt, i, Kind::Cell(axis as u8, dir as i8), None);
    }

    /// When ball `i`, in `motion` (position, velocity, acceleration) now, and each other ball
    /// of the cells whose first balls are `heads` ([`Cells::heads`]) touch. With `check`, first
    /// the postcondition for each pair (from the same positions): they overlap by no more than
    /// the contact tolerance.
    pub(super) fn predict_pairs(
        &mut self,
        i: usize,
        motion: ([f64; 3], [f64; 3], [f64; 3]),
        heads: ([u32; 27], usize),
        check: bool,
    ) -> Result<(), ModelError> {
        let (pi, vi, ai) = motion;
        let from = self.t;
        // The cells' lists are walked here rather than gathered into a list first: a ball's
        // pairs are most of what an event costs.
        let (heads, count) = heads;
        let damper = self.balls[i].damper as usize;
        for &head in &heads[..count] {
            let mut next = Some(head);
            while let Some(j) = next {
                next = self.cells[damper].next(j);
                let j = j as usize;
                if j == i {
                    continue;
                }
                let (pj, vj, aj) = self.balls[j].motion(from, self.gravity);
                let dr = std::array::from_fn(|k| pj[k] - pi[k]);
                if check {
                    self.check_pair(i, j, dr)?;
                }
                let dv = std::array::from_fn(|k| vj[k] - vi[k]);
                let da = std::array::from_fn(|k| aj[k] - ai[k]);
                let reach = self.balls[i].radius + self.balls[j].radius;
                let (lo, hi) = (i.min(j), i.max(j));
                if let Some(dt) = pair_time(dr, dv, da, reach, still(vi, vj), self.horizon - from) {
                    self.push(from + dt, lo, Kind::Pair(hi as u32), Some(hi));
                }
            }
        }
        Ok(())
    }

    pub(super) fn valid(&self, e: &Entry) -> bool {
        let i = e.ball as usize;
        if self.balls[i].stamp != e.stamps.0 {
            return false;
        }
        match e.kind {
            Kind::Pair(j) => self.balls[j as usize].stamp == e.stamps.1,
            Kind::Frame(..) => self.frame.segment == e.version,
            Kind::Wait(_) => self.reach_version == e.version,
            _ => true,
        }
    }
}
