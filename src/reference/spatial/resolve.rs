//! Resolving an event: an impact by Eq. 9-10 along the normal under the collapse rule, a ball
//! coming to rest on a wall or leaving it, a cell crossing, and the searches of the frame's walls
//! that end.

use super::*;
use crate::model::ModelError;
use crate::scene::Body;

/// The collapse rule's separation speed for a contact closing at `approach` (negative when
/// it opens) under the acceleration `pressing` (positive when it closes it), with
/// restitution `e`: `e approach`, but never less than the speed that keeps a pressed contact
/// open for the contact duration `t_c`. `None` when the contact opens fast enough by itself.
fn separation(approach: f64, pressing: f64, e: f64, t_c: f64) -> Option<f64> {
    let keep_open = if pressing > 0.0 { 0.5 * pressing * t_c } else { 0.0 };
    if approach > 0.0 {
        Some((e * approach).max(keep_open))
    } else if -approach < keep_open {
        Some(keep_open)
    } else {
        None
    }
}

impl Solver<'_> {
    /// The elastic rule of the TC model: `e`, or 1 within the contact duration of either
    /// ball's previous impact.
    pub(super) fn restitution(&self, i: usize, j: Option<usize>) -> f64 {
        let recent = |k: usize| self.t - self.balls[k].last_impact < self.t_c;
        if recent(i) || j.is_some_and(recent) {
            1.0
        } else {
            self.e
        }
    }

    pub(super) fn record(&mut self, a: Body, b: Body, approach: f64, lost: f64) {
        self.impact_loss += lost;
        let impact =
            Impact { t: self.t, a, b, approach_speed: approach, energy_lost: lost, impulses: 1, peak_force: None, contact_duration: None };
        self.impacts.push(impact);
    }

    /// A ball resting on a wall keeps none of its velocity into it (the wall takes it, a
    /// plastic contact) and leaves it when it moves away.
    pub(super) fn settle_rest(&mut self, i: usize) -> f64 {
        let b = &mut self.balls[i];
        let Some((axis, side)) = b.rest else { return 0.0 };
        let into = side * b.v[axis];
        if into > 0.0 {
            b.v[axis] = 0.0;
            0.5 * b.mass * into * into
        } else {
            if into < 0.0 {
                b.rest = None;
            }
            0.0
        }
    }

    pub(super) fn resolve(&mut self, entry: Entry) -> Result<(), ModelError> {
        let i = entry.ball as usize;
        match entry.kind {
            Kind::Cell(axis, dir) => {
                self.bring(i);
                let b = &mut self.balls[i];
                let old = b.cell;
                b.cell[axis as usize] += dir as i64;
                let new = b.cell;
                let cells = &mut self.cells[b.damper as usize];
                cells.remove(old, i as u32);
                cells.insert(new, i as u32);
                self.predict_slab(i, axis as usize, dir as i64);
            }
            Kind::Pair(j) => {
                let j = j as usize;
                self.bring(i);
                self.bring(j);
                let (bi, bj) = (self.balls[i], self.balls[j]);
                let d: [f64; 3] = std::array::from_fn(|k| bj.p[k] - bi.p[k]);
                let dist = dot(d, d).sqrt();
                let gap = dist - bi.radius - bj.radius;
                let n = d.map(|c| c / dist);
                let (ui, uj) = (dot(bi.v, n), dot(bj.v, n));
                let pressing = dot(bi.acceleration(self.gravity), n) - dot(bj.acceleration(self.gravity), n);
                // The impulse pushes `j` along `n` and `i` against it. A ball it pushes into the
                // wall it rests on has the wall's reaction at once: it moves only along the
                // wall, so along `n` it weighs `m / (1 - n_w^2)` (docs/MODEL.md §14).
                let (along_i, mi) = bi.pushed(n.map(|c| -c));
                let (along_j, mj) = bj.pushed(n);
                // An approach the velocities cannot resolve is none (the pair moves on touching).
                let approach = if ui - uj > still(bi.v, bj.v) { ui - uj } else { (ui - uj).min(0.0) };
                let touching = gap <= self.pair_tolerance(i, j, ui - uj);
                // Two balls each pushed square into its wall cannot move along `n`.
                let movable = mi.is_finite() || mj.is_finite();
                let mut struck = false;
                if let Some(after) = separation(approach, pressing, self.restitution(i, Some(j)), self.t_c).filter(|_| touching && movable)
                {
                    let (wi, wj) = separate(mi, ui, mj, uj, after);
                    let impulse = if mj.is_finite() { mj * (wj - uj) } else { mi * (ui - wi) };
                    for k in 0..3 {
                        self.balls[i].v[k] += impulse / bi.mass * along_i[k];
                        self.balls[j].v[k] += impulse / bj.mass * along_j[k];
                    }
                    let lost = 0.5 * reduced_mass(mi, mj) * ((ui - uj) * (ui - uj) - after * after);
                    let rest_loss = self.settle_rest(i) + self.settle_rest(j);
                    self.record(Body::Ball(i), Body::Ball(j), (ui - uj).max(0.0), lost + rest_loss);
                    self.balls[i].last_impact = self.t;
                    self.balls[j].last_impact = self.t;
                    struck = true;
                }
                self.predict(i, struck)?;
                self.predict(j, struck)?;
            }
            Kind::Across(axis, side) => {
                self.bring(i);
                let (axis, side) = (axis as usize, side as f64);
                let b = self.balls[i];
                let approach = side * b.v[axis];
                let pressed = side * self.gravity[axis];
                let mut struck = false;
                if approach > 0.0 || (approach == 0.0 && pressed > 0.0) {
                    let e = self.restitution(i, None);
                    let after = e * approach;
                    let half = self.cells[self.balls[i].damper as usize].half[axis - 1];
                    let ball = &mut self.balls[i];
                    let rests = pressed > 0.0 && 2.0 * after < pressed * self.t_c;
                    let lost = if rests {
                        // Its next bounce would come back within a contact duration: it rests,
                        // its centre on the wall's contact plane.
                        ball.v[axis] = 0.0;
                        ball.p[axis] = side * (half - ball.radius);
                        ball.rest = Some((axis, side));
                        0.5 * ball.mass * approach * approach
                    } else {
                        ball.v[axis] = -side * after;
                        0.5 * ball.mass * (approach * approach - after * after)
                    };
                    // A ball that only touches the wall (placed on the floor, or come to it at
                    // rest) settles on it without an impact.
                    if approach > 0.0 {
                        self.record(Body::Ball(i), Body::across(axis, side > 0.0), approach, lost);
                        self.balls[i].last_impact = self.t;
                    }
                    struck = true;
                }
                self.predict(i, struck)?;
            }
            Kind::Wait(side) => {
                self.bring(i);
                self.search_frame_wall(i, side as f64);
            }
            Kind::Frame(side, exact) => {
                let side = side as f64;
                if !exact {
                    // No contact before now: the search goes on from here.
                    self.bring(i);
                    self.search_frame_wall(i, side);
                    return Ok(());
                }
                self.bring(i);
                let b = self.balls[i];
                let walls = self.walls[b.damper as usize];
                let (xs, vs, accel) = self.frame.now_of(walls.floor, self.t);
                let approach = side * (vs - b.v[0]);
                if let Some(after) = separation(approach, side * accel, self.restitution(i, None), self.t_c) {
                    // The wall on the left (`side > 0`) leaves the ball behind it, the right one ahead.
                    let (vb, vf) = separate(b.mass, b.v[0], walls.mass, vs, -side * after);
                    let lost = 0.5 * reduced_mass(b.mass, walls.mass) * (approach * approach - after * after);
                    let (damping, work) = self.frame.segment_energy(self.t, self.scene);
                    self.damping_loss += damping;
                    self.forcing_work += work;
                    let mut searched_before = Vec::new();
                    if self.frame.exists() {
                        self.frame.restart_of(walls.floor, self.t, xs, vf);
                        // Every entry against the frame's walls belongs to the motion just ended.
                        self.frame_calendar.clear();
                        searched_before = self.searches_ended(lost);
                    }
                    self.balls[i].v[0] = vb;
                    self.balls[i].last_impact = self.t;
                    let (a, bb) = if side > 0.0 { (Body::LeftWall, Body::Ball(i)) } else { (Body::Ball(i), Body::RightWall) };
                    self.record(a, bb, approach.max(0.0), lost);
                    self.limits.fastest = self.limits.fastest.max(approach);
                    self.predict(i, true)?;
                    // The walls move otherwise from now: the searches against them start again
                    // (from each ball's flight as it stands, so no ball is moved).
                    for (k, w) in searched_before {
                        if k != i {
                            self.predict_frame_wall(k, if w == 0 { 1.0 } else { -1.0 });
                        }
                    }
                } else {
                    self.predict(i, false)?;
                }
            }
        }
        Ok(())
    }

    /// After the frame's segment changed at an impact that lost `lost`: the walls whose searches
    /// it ended, each once. The waits hold while the frame keeps within the bound they were taken
    /// with, so only the searches end; a segment beyond the bound widens it, and a bound that the
    /// energy lost since it was taken halves tightens it, each ending every wait and search.
    pub(super) fn searches_ended(&mut self, lost: f64) -> Vec<(usize, usize)> {
        let within = match (&self.frame_reach, self.frame.reach()) {
            (Some(bound), Some(reach)) => reach <= bound.reach,
            _ => false,
        };
        let left = self.start_energy - self.impact_loss - lost - self.damping_loss;
        let tighter = match (&self.frame_reach, energy_reach(&self.frame, left)) {
            (Some(bound), Some(reach)) if within && reach < 0.5 * bound.reach => Some(reach),
            _ => None,
        };
        if !within || tighter.is_some() {
            if self.frame_reach.is_some() {
                let reach = tighter.or_else(|| self.frame.reach().map(|r| r * (1.0 + 1e-6)));
                self.frame_reach = reach.map(|r| FrameReach::new(&self.frame.seg.osc, r, self.horizon));
                self.reach_version += 1;
            }
            self.searching.clear();
            self.searched.iter_mut().for_each(|s| *s = [false; 2]);
            return (0..self.balls.len()).flat_map(|k| [(k, 0), (k, 1)]).collect();
        }
        let mut ended = Vec::new();
        for (k, w) in std::mem::take(&mut self.searching) {
            let (k, w) = (k as usize, w as usize);
            if std::mem::replace(&mut self.searched[k][w], false) {
                ended.push((k, w));
            }
        }
        ended
    }
}
