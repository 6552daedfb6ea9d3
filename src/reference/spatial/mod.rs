//! The reference beyond one line (docs/MODEL.md §14): smooth balls flying in closed form in the
//! plane or in space under gravity inside the container the frame carries, their impacts by
//! Eq. 9-10 along the contact normal, found by an event calendar (a list per ball under a
//! tournament tree, and a heap for the frame's walls; stale entries are dropped when they
//! surface) over cells as wide as a ball. Ball-ball and
//! ball-floor times are roots of quadratics; a ball against the walls that move with the frame
//! is found by the one-line reference's sound root isolation ([`FrameGap`]).
//!
//! Inelastic collapse is kept from stalling by a stated rule: an impact within the contact
//! duration of a ball's previous one is elastic (the TC model), and a ball whose bounce off a
//! wall that gravity presses it against would return within the contact duration rests on it.

mod calendar;
mod cells;
mod flight;

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::frame::FrameMotion;
use super::frame_gap::{FrameGap, FrameReach};
use super::geometry::Limits;
use super::MAX_EVENTS;
use crate::impact_law::{reduced_mass, separate};
use crate::model::{Budget, Meter, Model, ModelError, OverBudget, RunOptions, STALL_EVENTS_PER_SIM_S};
use crate::run::{CountedImpacts, EnergyAccount, Impact, ImpactRecord, Recorder, Run};
use crate::scene::{Body, Scene};
use calendar::Calendar;
use cells::Cells;
use flight::{pair_time, plane_time, still};

/// Most events at one instant before the run is declared stalled.
const MAX_EVENTS_PER_INSTANT: u64 = 10_000;
/// Events between two looks at the budgets.
const BUDGET_EVENTS: u64 = 4096;

/// Most events per simulated second a run of `scene` makes before it counts as stalled: the
/// one-line reference's rate, and for each ball its at most six contacts with other balls and
/// three with walls, each struck at most once a contact duration while it is pressed (the
/// collapse rule, docs/MODEL.md §14).
pub(super) fn stall_rate(scene: &Scene) -> f64 {
    STALL_EVENTS_PER_SIM_S + 9.0 * scene.balls.len() as f64 / scene.reference.contact_duration
}

/// Why the spatial reference cannot run `scene`, or `None` when it can.
pub(super) fn refusal(scene: &Scene) -> Option<String> {
    let space = &scene.space;
    if space.friction != 0.0 {
        return Some(format!(
            "the scene has friction {}; the reference's impacts are frictionless (Eq. 9-10 along the normal): run it with the rapier model, or set `world.friction = 0`",
            space.friction
        ));
    }
    if space.gravity[0] != 0.0 {
        return Some(format!(
            "the scene has gravity {} m/s^2 along the frame's motion; the reference finds the walls on the frame for balls flying straight along it",
            space.gravity[0]
        ));
    }
    if scene.container.is_none() || space.section[0] <= 0.0 || space.section[1] <= 0.0 {
        return Some("the scene's balls leave their lines but it gives the container no cross-section (width and height)".into());
    }
    if space.chains() > 1 {
        return Some("the reference beyond one line has one chamber: it has no dividers between chains".into());
    }
    if scene.structure.is_some() {
        return Some(
            "the reference runs structures of several storeys and ground-motion records with balls on lines, not yet with beds".into(),
        );
    }
    None
}

/// What an entry of the calendar is about.
#[derive(Debug, Clone, Copy)]
enum Kind {
    /// Balls `i` and `j` touch.
    Pair(u32),
    /// Ball `i` meets the wall across the motion on `axis` (1 for y, 2 for z), on side `side`.
    Across(u8, i8),
    /// Ball `i` meets the frame's wall on side `side` (`+1` the left wall); at `t` when
    /// `exact`, else "not before `t`".
    Frame(i8, bool),
    /// Ball `i` leaves its cell across `axis` on side `dir`.
    Cell(u8, i8),
    /// Ball `i` may come near the frame's wall on side `side`: its search starts then.
    Wait(i8),
}

/// An entry of the calendar, valid while its balls' stamps (and for a wall of the frame, the
/// frame's segment; for a wait, the bound's version) are those it was predicted with.
#[derive(Debug, Clone, Copy)]
struct Entry {
    t: f64,
    ball: u32,
    kind: Kind,
    stamps: (u32, u32),
    version: u64,
}

impl calendar::Timed for Entry {
    /// The time's bits, which order as the times do: no entry is before the start.
    fn key(&self) -> u64 {
        debug_assert!(self.t >= 0.0);
        (self.t + 0.0).to_bits()
    }
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    /// Earliest first (reversed for the max-heap); at a tie the lower ball, so the order never
    /// depends on the heap's history.
    fn cmp(&self, other: &Self) -> Ordering {
        other.t.total_cmp(&self.t).then(other.ball.cmp(&self.ball))
    }
}

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

/// One ball between its events.
#[derive(Debug, Clone, Copy)]
struct Ball {
    /// Centre at `since` (x in the world, y and z in the container), m.
    p: [f64; 3],
    /// Velocity at `since`, m/s.
    v: [f64; 3],
    since: f64,
    mass: f64,
    radius: f64,
    /// The wall across the motion it rests on (`(axis, side)`), if any.
    rest: Option<(usize, f64)>,
    /// Time of its last impact, s.
    last_impact: f64,
    /// Changes at every event of the ball: entries with an older stamp are stale.
    stamp: u32,
    cell: [i64; 3],
    /// A bound on the rounding gathered in `p[0]`, m.
    drift: f64,
}

/// The spatial reference's run of one scene.
struct Solver<'a> {
    scene: &'a Scene,
    balls: Vec<Ball>,
    frame: FrameMotion,
    limits: Limits,
    cells: Cells,
    /// Every entry but the balls' contacts with the frame's walls, each owned by its `ball`.
    calendar: Calendar<Entry>,
    /// The balls' contacts with the frame's walls, apart: each impact on those walls changes
    /// the frame's motion, invalidates them all and predicts them all anew, so this calendar is
    /// emptied then rather than left to carry a stale entry per ball.
    frame_calendar: BinaryHeap<Entry>,
    /// Where the frame can be from now to the horizon, for the balls' waits before their
    /// searches against its walls; `None` when unknown (a forced frame, or one without a
    /// spring), and then every ball searches.
    frame_reach: Option<FrameReach>,
    /// The most energy the frame could have at the start ([`reach_energy`]): less the impacts'
    /// and the damping's losses, the most it can have now.
    start_energy: f64,
    /// Changes when `frame_reach` does: the waits taken with an older bound are stale.
    reach_version: u64,
    /// Whether each ball's contact with the frame's wall on each side (left, right) is being
    /// searched, rather than waited for: what an impact on those walls must search again.
    searched: Vec<[bool; 2]>,
    /// The walls that balls started searching since the last impact on the frame's walls
    /// (some have stopped since), so that the impact looks at these and not at every ball.
    searching: Vec<(u32, u8)>,
    gravity: [f64; 3],
    e: f64,
    /// The collapse rule's contact duration, s.
    t_c: f64,
    length: f64,
    t: f64,
    horizon: f64,
    events: u64,
    /// Whether the run keeps every impact ([`ImpactRecord::Every`]) or counts them.
    keeps_impacts: bool,
    impacts: Vec<Impact>,
    counted_impacts: CountedImpacts,
    impact_loss: f64,
    damping_loss: f64,
    forcing_work: f64,
    start: Vec<[f64; 3]>,
}

/// The index of the frame's wall on side `side` (`+1` the left wall) in a ball's flags.
fn wall_index(side: f64) -> usize {
    usize::from(side < 0.0)
}

/// The most energy the frame of `scene` can ever have (docs/MODEL.md §14), for an unforced
/// frame with a spring and damping `>= 0`: its energy `M v^2 / 2 + K x^2 / 2` can grow only by
/// what the balls give it, at most their kinetic energy and the height gravity can still take
/// them down. What the impacts and the damping take from then on comes off it.
fn reach_energy(scene: &Scene, frame: &FrameMotion, balls: &[Ball]) -> f64 {
    let g = scene.space.gravity;
    let half = [0.5 * scene.space.section[0], 0.5 * scene.space.section[1]];
    let given: f64 = balls
        .iter()
        .map(|b| {
            let lowest: f64 = (1..3).map(|k| g[k].abs() * (half[k - 1] - b.radius).max(0.0)).sum();
            b.mass * (0.5 * dot(b.v, b.v) + (lowest - dot(g, b.p)).max(0.0))
        })
        .sum();
    frame.energy(0.0, scene) + given
}

/// How far a frame with `energy` at most goes, `sqrt(2 E / K)` with a millionth to spare for
/// round-off, and never less than its present segment's reach; `None` when unknown (a forced
/// frame, or one without a spring). A segment beyond it (the collapse rule's energy) widens it
/// then (see [`Solver::searches_ended`]).
fn energy_reach(frame: &FrameMotion, energy: f64) -> Option<f64> {
    if !frame.exists() {
        return None;
    }
    let reach = frame.reach()?;
    let bound = frame.seg.osc.envelope(0.0, (2.0 * energy.max(0.0) * (1.0 + 1e-6) / frame.mass).sqrt())?;
    Some(bound.max(reach * (1.0 + 1e-6)))
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Ball {
    fn acceleration(&self, g: [f64; 3]) -> [f64; 3] {
        // Written component by component rather than by storing into the wall's axis: the
        // store, read back as a vector, stalled every prediction.
        match self.rest {
            Some((axis, _)) => std::array::from_fn(|k| if k == axis { 0.0 } else { g[k] }),
            None => g,
        }
    }

    /// How the ball takes an impulse along `n`: the direction its velocity changes in (`n`, less
    /// its component into the wall the ball rests on when `n` pushes it into that wall) and its
    /// mass along `n`, `m / (1 - n_w^2)` in that case (the wall's reaction), else `m`.
    fn pushed(&self, n: [f64; 3]) -> ([f64; 3], f64) {
        match self.rest {
            Some((axis, side)) if side * n[axis] > 0.0 => {
                let mut along = n;
                along[axis] = 0.0;
                let share = 1.0 - n[axis] * n[axis];
                (along, if share > 0.0 { self.mass / share } else { f64::INFINITY })
            }
            _ => (n, self.mass),
        }
    }

    /// Centre and velocity at `t`.
    fn at(&self, t: f64, g: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        let (p, v, _) = self.motion(t, g);
        (p, v)
    }

    /// Position, velocity and acceleration at `t`.
    fn motion(&self, t: f64, g: [f64; 3]) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let a = self.acceleration(g);
        let dt = t - self.since;
        (std::array::from_fn(|k| self.p[k] + self.v[k] * dt + 0.5 * a[k] * dt * dt), std::array::from_fn(|k| self.v[k] + a[k] * dt), a)
    }
}

/// Runs the spatial reference on `scene` (which [`refusal`] accepts).
pub(super) fn simulate(scene: &Scene, options: &RunOptions) -> Result<Run, ModelError> {
    simulate_with(scene, options, true, MAX_EVENTS)
}

/// [`simulate`], with the balls waiting before their searches against the frame's walls where
/// the frame's motion is bounded (`waits`), or always searching, and stopping past
/// `max_events` events when it keeps every impact.
fn simulate_with(scene: &Scene, options: &RunOptions, waits: bool, max_events: u64) -> Result<Run, ModelError> {
    // Only a run that keeps every impact is bounded by memory; one that counts them only by its
    // budgets (and stops as stalled if its events pile up at one instant).
    let meter = Meter::new(options, BUDGET_EVENTS);
    let meter = if options.impacts == ImpactRecord::Every { meter.keeping(max_events) } else { meter };
    let mut s = Solver::new(scene, options.impacts)?;
    if !waits {
        s.frame_reach = None;
    }
    let mut recorder = Recorder::new(scene, options.record);
    let outcome = s.run(&meter, &mut recorder);
    let t = s.t;
    meter.finish(t, s.events);
    match outcome? {
        None => {
            let mut run = s.finish(recorder, scene.horizon);
            run.wall_time_s = meter.elapsed();
            Ok(run)
        }
        Some(budget) => {
            let wall_s = meter.elapsed();
            let steps = s.events;
            let rate = steps as f64 / t;
            let mut cost = format!("{} impacts so far; {} balls", s.impacts.len() + s.counted_impacts.count, s.balls.len());
            if budget == Budget::Memory {
                // Past the rate the collapse rule makes on a pile, the events are a flood that
                // no part of it resolves; below it, a pile's steady price.
                if rate > stall_rate(scene) {
                    return Err(s.stalled(format!(
                        "more than {max_events} events, {rate:.3e} per simulated second, more than the collapse rule makes (docs/MODEL.md §14)"
                    )));
                }
                cost = format!(
                    "{cost}; {rate:.3e} events per simulated second: a pile or a bed pressed against a wall has each pressed contact struck about once a contact duration (docs/MODEL.md §14, here {} s); a run that counts its impacts instead of keeping them (`--impacts count`) is not bounded by memory, and a longer `[reference] contact_duration` makes it cheaper but departs further from the ideal model where the pile is dense (docs/MODEL.md §14, choosing t_c)",
                    crate::scene::human(s.t_c)
                );
            }
            let mut partial = s.finish(recorder, t);
            partial.wall_time_s = wall_s;
            Err(ModelError::OverBudget(Box::new(OverBudget {
                scene: scene.name.clone(),
                model: Model::Reference,
                t,
                horizon: scene.horizon,
                steps,
                wall_s,
                budget,
                limit: meter.limit(budget),
                cost,
                partial,
            })))
        }
    }
}

impl<'a> Solver<'a> {
    fn new(scene: &'a Scene, impacts: ImpactRecord) -> Result<Self, ModelError> {
        let container = scene.container.expect("refusal checks the container");
        let largest = scene.balls.iter().map(|b| b.radius).fold(0.0, f64::max);
        let mut cells = Cells::new(largest, container.length, scene.space.section, scene.balls.len());
        let frame = FrameMotion::new(scene).map_err(ModelError::Refused)?;
        let balls: Vec<Ball> = scene
            .balls
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let [y, z] = scene.space.lateral_of(i);
                let [vy, vz] = scene.space.lateral_velocity_of(i);
                let p = [scene.initial_positions[i], y, z];
                let cell = cells.cell_of(p);
                cells.insert(cell, i as u32);
                Ball {
                    p,
                    v: [scene.initial_velocities[i], vy, vz],
                    since: 0.0,
                    mass: b.mass,
                    radius: b.radius,
                    rest: None,
                    last_impact: f64::NEG_INFINITY,
                    stamp: 0,
                    cell,
                    drift: 0.0,
                }
            })
            .collect();
        let start = balls.iter().map(|b| b.p).collect();
        let start_energy = reach_energy(scene, &frame, &balls);
        let frame_reach = energy_reach(&frame, start_energy).map(|r| FrameReach::new(&frame.seg.osc, r, scene.horizon));
        Ok(Solver {
            scene,
            balls,
            frame,
            limits: Limits::new(scene),
            cells,
            calendar: Calendar::new(scene.balls.len()),
            frame_calendar: BinaryHeap::new(),
            frame_reach,
            start_energy,
            reach_version: 0,
            searched: vec![[false; 2]; scene.balls.len()],
            searching: Vec::new(),
            gravity: scene.space.gravity,
            e: scene.restitution,
            t_c: scene.reference.contact_duration,
            length: container.length,
            t: 0.0,
            horizon: scene.horizon,
            events: 0,
            keeps_impacts: impacts == ImpactRecord::Every,
            impacts: Vec::new(),
            counted_impacts: CountedImpacts::default(),
            impact_loss: 0.0,
            damping_loss: 0.0,
            forcing_work: 0.0,
            start,
        })
    }

    /// Moves ball `i` to the current time.
    fn bring(&mut self, i: usize) {
        let (p, v) = self.balls[i].at(self.t, self.gravity);
        let b = &mut self.balls[i];
        b.drift += f64::EPSILON * (p[0].abs() + (p[0] - b.p[0]).abs());
        b.p = p;
        b.v = v;
        b.since = self.t;
    }

    /// Ball `i` (at the current time) against the frame's wall on side `side`.
    fn frame_gap(&self, i: usize, side: f64) -> FrameGap<'_> {
        let b = &self.balls[i];
        let k = if side > 0.0 { -b.radius } else { self.length - b.radius };
        FrameGap {
            frame: &self.frame,
            limits: &self.limits,
            horizon: self.horizon,
            now: b.since,
            x: b.p[0],
            v: b.v[0],
            drift: b.drift,
            s: side,
            k,
        }
    }

    /// Enters an event at `t` in the calendar, unless it comes after the horizon.
    fn push(&mut self, t: f64, ball: usize, kind: Kind, other: Option<usize>) {
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
    fn next_entry(&mut self) -> Option<Entry> {
        match (self.calendar.peek(), self.frame_calendar.peek()) {
            (Some(a), Some(f)) if f > a => self.frame_calendar.pop(),
            (Some(_), _) => self.calendar.pop(),
            (None, _) => self.frame_calendar.pop(),
        }
    }

    /// Ball `i`'s next contact with the frame's wall on side `side`: searched from now when
    /// the ball may be near that wall, else a wait until it may be (most balls are far from
    /// the walls, and most of those meet another body first).
    fn predict_frame_wall(&mut self, i: usize, side: f64) {
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
    fn search_frame_wall(&mut self, i: usize, side: f64) {
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
        let c = self.frame_gap(i, side).search(self.t, self.horizon);
        if c.t.is_finite() {
            self.push(c.t, i, Kind::Frame(side as i8, c.exact), None);
        }
    }

    /// Everything ball `i` (brought to now) meets next: walls, its cell's faces, the balls of
    /// the cells around it. With `check`, after an impact of the ball, first the postcondition:
    /// it overlaps no wall and none of those balls (the cells are read once for both).
    fn predict(&mut self, i: usize, check: bool) -> Result<(), ModelError> {
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
            let half = self.cells.half[axis - 1];
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
        let predicted = self.predict_pairs(i, motion, self.cells.heads(Cells::around_block(b.cell)), check);
        self.calendar.release();
        predicted
    }

    /// Ball `i` (brought to now) has crossed into its cell along `axis` on side `dir`: its
    /// flight goes on, so its entries stand; it meets in addition the balls of the slab of
    /// nine cells it neighbours now and did not before, and it crosses again.
    fn predict_slab(&mut self, i: usize, axis: usize, dir: i64) {
        let b = self.balls[i];
        let motion = b.motion(self.t, self.gravity);
        self.calendar.hold(i);
        self.predict_crossing(i, motion.2);
        if let Some(slab) = self.cells.slab_block(b.cell, axis, dir) {
            self.predict_pairs(i, motion, self.cells.heads(slab), false).expect("a prediction without a check cannot fail");
        }
        self.calendar.release();
    }

    /// When ball `i` (brought to now), accelerated by `a`, next leaves its cell.
    fn predict_crossing(&mut self, i: usize, a: [f64; 3]) {
        let b = self.balls[i];
        // The earliest crossing, at a tie the first axis's; never when the time is infinite.
        let mut crossing: (f64, usize, i64) = (f64::INFINITY, 0, 1);
        for axis in 0..3 {
            let lower = self.cells.face(b.cell, axis);
            let v = b.v[axis];
            if a[axis] == 0.0 {
                // Without acceleration along the axis, only the face ahead is crossed, at the
                // gap over the speed (`plane_time`'s root to the bit), chosen without a branch
                // on the velocity's sign, which is as good as random.
                let ahead = v > 0.0;
                let dir = if ahead { 1 } else { -1 };
                let g0 = std::hint::select_unpredictable(ahead, lower + self.cells.size - b.p[axis], b.p[axis] - lower);
                let dt = g0.max(0.0) / v.abs();
                let earlier = (v != 0.0) & self.cells.has_neighbour(b.cell, axis, dir) & (dt < crossing.0);
                crossing = std::hint::select_unpredictable(earlier, (dt, axis, dir), crossing);
                continue;
            }
            for dir in [1i64, -1] {
                if !self.cells.has_neighbour(b.cell, axis, dir) {
                    continue;
                }
                let (g0, side) = if dir > 0 { (lower + self.cells.size - b.p[axis], 1.0) } else { (b.p[axis] - lower, -1.0) };
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
    fn predict_pairs(
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
        for &head in &heads[..count] {
            let mut next = Some(head);
            while let Some(j) = next {
                next = self.cells.next(j);
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

    fn valid(&self, e: &Entry) -> bool {
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

    fn run(&mut self, meter: &Meter, recorder: &mut Recorder) -> Result<Option<crate::model::Budget>, ModelError> {
        for i in 0..self.balls.len() {
            self.predict(i, false)?;
        }
        let sample_count = self.scene.sample_count();
        let mut next_sample = 0;
        let mut same_instant = 0u64;
        while let Some(entry) = self.next_entry() {
            if !self.valid(&entry) {
                continue;
            }
            while next_sample < sample_count && (next_sample as f64) * self.scene.sample_dt <= entry.t {
                self.sample(recorder, next_sample as f64 * self.scene.sample_dt);
                next_sample += 1;
            }
            same_instant = if entry.t == self.t { same_instant + 1 } else { 0 };
            if same_instant > MAX_EVENTS_PER_INSTANT {
                let what = match entry.kind {
                    Kind::Pair(j) => format!(
                        "ball{} and ball{} stay in contact (a cluster, or a ball resting on others under gravity)",
                        entry.ball + 1,
                        j + 1
                    ),
                    Kind::Frame(side, _) => format!(
                        "ball{} is pressed against the {} wall by the frame's acceleration",
                        entry.ball + 1,
                        if side > 0 { "left" } else { "right" }
                    ),
                    _ => format!("ball{} stays in contact with a wall", entry.ball + 1),
                };
                return Err(self.stalled(format!(
                    "more than {MAX_EVENTS_PER_INSTANT} events at one instant: {what}; no part of the collapse rule (docs/MODEL.md §14) resolves it"
                )));
            }
            self.t = entry.t;
            self.events += 1;
            if let Some(budget) = meter.look(self.t, self.events) {
                return Ok(Some(budget));
            }
            self.resolve(entry)?;
            if self.calendar.len() + self.frame_calendar.len() > 64 * self.balls.len() + 4096 {
                let mut calendar = std::mem::replace(&mut self.calendar, Calendar::new(0));
                calendar.retain(|e| self.valid(e));
                self.calendar = calendar;
                let kept: Vec<Entry> = std::mem::take(&mut self.frame_calendar).into_iter().filter(|e| self.valid(e)).collect();
                self.frame_calendar = kept.into();
            }
        }
        self.t = self.horizon;
        while next_sample < sample_count {
            self.sample(recorder, (next_sample as f64 * self.scene.sample_dt).min(self.horizon));
            next_sample += 1;
        }
        for i in 0..self.balls.len() {
            self.bring(i);
            self.check_walls(i)?;
            self.check_neighbours(i)?;
        }
        Ok(None)
    }

    fn sample(&self, recorder: &mut Recorder, ts: f64) {
        let (xs, vs) = self.frame.state(ts);
        let g = self.gravity;
        recorder.sample(self.scene, ts, xs, vs, |i| {
            let (p, v) = self.balls[i].at(ts, g);
            (p[0], v[0])
        });
        recorder.sample_across(|i| {
            let (p, _) = self.balls[i].at(ts, g);
            [p[1], p[2]]
        });
    }

    fn stalled(&self, why: String) -> ModelError {
        ModelError::Stalled { scene: self.scene.name.clone(), model: Model::Reference, t: self.t, steps: self.events, why }
    }

    fn broken(&self, what: String) -> ModelError {
        ModelError::Broken { scene: self.scene.name.clone(), model: Model::Reference, t: self.t, what }
    }

    /// The elastic rule of the TC model: `e`, or 1 within the contact duration of either
    /// ball's previous impact.
    fn restitution(&self, i: usize, j: Option<usize>) -> f64 {
        let recent = |k: usize| self.t - self.balls[k].last_impact < self.t_c;
        if recent(i) || j.is_some_and(recent) {
            1.0
        } else {
            self.e
        }
    }

    fn record(&mut self, a: Body, b: Body, approach: f64, lost: f64) {
        self.impact_loss += lost;
        let impact =
            Impact { t: self.t, a, b, approach_speed: approach, energy_lost: lost, impulses: 1, peak_force: None, contact_duration: None };
        if self.keeps_impacts {
            self.impacts.push(impact);
        } else {
            self.counted_impacts.add(&impact);
        }
    }

    /// A ball resting on a wall keeps none of its velocity into it (the wall takes it, a
    /// plastic contact) and leaves it when it moves away.
    fn settle_rest(&mut self, i: usize) -> f64 {
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

    fn resolve(&mut self, entry: Entry) -> Result<(), ModelError> {
        let i = entry.ball as usize;
        match entry.kind {
            Kind::Cell(axis, dir) => {
                self.bring(i);
                let b = &mut self.balls[i];
                let old = b.cell;
                b.cell[axis as usize] += dir as i64;
                let new = b.cell;
                self.cells.remove(old, i as u32);
                self.cells.insert(new, i as u32);
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
                    let half = self.cells.half[axis - 1];
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
                    self.record(Body::Ball(i), Body::SideWall, approach, lost);
                    self.balls[i].last_impact = self.t;
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
                let (xs, vs, accel) = self.frame.now(self.t);
                let b = self.balls[i];
                let approach = side * (vs - b.v[0]);
                if let Some(after) = separation(approach, side * accel, self.restitution(i, None), self.t_c) {
                    // The wall on the left (`side > 0`) leaves the ball behind it, the right one ahead.
                    let (vb, vf) = separate(b.mass, b.v[0], self.frame.mass, vs, -side * after);
                    let lost = 0.5 * reduced_mass(b.mass, self.frame.mass) * (approach * approach - after * after);
                    let (damping, work) = self.frame.segment_energy(self.t, self.scene);
                    self.damping_loss += damping;
                    self.forcing_work += work;
                    let mut searched_before = Vec::new();
                    if self.frame.exists() {
                        self.frame.restart(self.t, xs, vf);
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
    fn searches_ended(&mut self, lost: f64) -> Vec<(usize, usize)> {
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

    /// The contact tolerance of balls `i` and `j` approaching at `rate`: the length tolerance,
    /// the rounding in their positions and two ulps of time at the faster of `rate` and the
    /// run's fastest speed.
    fn pair_tolerance(&self, i: usize, j: usize, rate: f64) -> f64 {
        let (a, b) = (&self.balls[i], &self.balls[j]);
        let eps = f64::EPSILON;
        let size = a.p.iter().chain(&b.p).fold(0.0, |m: f64, c| m.max(c.abs())) + a.radius + b.radius;
        self.limits.tol + a.drift + b.drift + 8.0 * eps * size + 2.0 * eps * self.t.abs() * rate.abs().max(self.limits.fastest)
    }

    /// The postcondition for ball `k` (brought to now) against the walls: it overlaps none
    /// beyond the contact tolerance (docs/MODEL.md §14).
    fn check_walls(&self, k: usize) -> Result<(), ModelError> {
        let (xs, _) = self.frame.state(self.t);
        let b = self.balls[k];
        let tol = self.pair_tolerance(k, k, 0.0) + self.frame.position_roundoff(self.t);
        let walls = [
            ("left-wall", b.p[0] - b.radius - xs),
            ("right-wall", xs + self.length - b.p[0] - b.radius),
            ("front wall", b.p[1] + self.cells.half[0] - b.radius),
            ("back wall", self.cells.half[0] - b.p[1] - b.radius),
            ("floor", b.p[2] + self.cells.half[1] - b.radius),
            ("ceiling", self.cells.half[1] - b.p[2] - b.radius),
        ];
        for (name, gap) in walls {
            if gap < -tol {
                return Err(self.broken(format!(
                    "its contact invariant at t = {} s: ball{} overlaps the {name} by {:.3e} m (tolerance {:.3e} m)",
                    crate::scene::human(self.t),
                    k + 1,
                    -gap,
                    tol
                )));
            }
        }
        Ok(())
    }

    /// The postcondition for ball `k` (brought to now) against the balls of the cells around
    /// it; the first violation found.
    fn check_neighbours(&self, k: usize) -> Result<(), ModelError> {
        let p = self.balls[k].p;
        let mut checked = Ok(());
        self.cells.around(self.balls[k].cell, |o| {
            let o = o as usize;
            if checked.is_ok() && o != k {
                let (po, _) = self.balls[o].at(self.t, self.gravity);
                checked = self.check_pair(k, o, std::array::from_fn(|c| po[c] - p[c]));
            }
        });
        checked
    }

    /// The postcondition for balls `k` and `o`, their centres `d` apart now: they overlap by
    /// no more than the contact tolerance (docs/MODEL.md §14).
    #[inline]
    fn check_pair(&self, k: usize, o: usize, d: [f64; 3]) -> Result<(), ModelError> {
        let reach = self.balls[k].radius + self.balls[o].radius;
        if dot(d, d) >= reach * reach {
            // Apart, or touching: no overlap to weigh against the tolerance.
            return Ok(());
        }
        self.check_overlap(k, o, dot(d, d).sqrt() - reach)
    }

    /// [`Solver::check_pair`] for a pair closer than touching, `gap` (negative) apart.
    #[cold]
    fn check_overlap(&self, k: usize, o: usize, gap: f64) -> Result<(), ModelError> {
        let tol = self.pair_tolerance(k, o, 0.0);
        if gap < -tol {
            return Err(self.broken(format!(
                "its contact invariant at t = {} s: ball{} / ball{} overlap by {:.3e} m (tolerance {:.3e} m)",
                crate::scene::human(self.t),
                k + 1,
                o + 1,
                -gap,
                tol
            )));
        }
        Ok(())
    }

    fn finish(self, recorder: Recorder, t: f64) -> Run {
        let scene = self.scene;
        let (xs, vs) = self.frame.state(t);
        let (damping, work) = self.frame.segment_energy(t, scene);
        let mut final_ = scene.frame_energy(t, xs, vs);
        let mut velocities = Vec::with_capacity(self.balls.len());
        for (b, p0) in self.balls.iter().zip(&self.start) {
            let (p, v) = b.at(t, self.gravity);
            final_ += 0.5 * b.mass * dot(v, v) + b.mass * dot(self.gravity, std::array::from_fn(|k| p0[k] - p[k]));
            velocities.push(v[0]);
        }
        let (series, motion) = recorder.finish();
        Run {
            scene: scene.name.clone(),
            model: Model::Reference,
            horizon: t,
            sample_dt: scene.sample_dt,
            initial_displacement: scene.initial_displacement,
            damped_period: scene.frame.map_or(0.0, |f| f.damped_period()),
            series,
            motion,
            impacts: self.impacts,
            counted_impacts: self.counted_impacts,
            energy: EnergyAccount::forced(
                scene.initial_energy(),
                final_,
                self.damping_loss + damping,
                self.impact_loss,
                self.forcing_work + work,
            ),
            events: self.events,
            final_velocities: velocities,
            peak_true_acceleration: None,
            wall_time_s: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Simulator;

    /// Balls on one line with no gravity across it, run in a container with a cross-section,
    /// meet at the one-line reference's impacts to round-off (the ball-ball times are roots of
    /// the same distance, computed in three dimensions).
    #[test]
    fn balls_on_one_line_give_the_one_line_reference() {
        let mut scene = crate::scene::load(crate::scene::scenes_dir().join("lpc-lsl.toml")).unwrap().scene.unwrap();
        scene.horizon = 0.6;
        let line = super::super::Reference.simulate(&scene, &RunOptions::default()).unwrap();
        scene.space.section = [0.05, 0.05];
        assert!(refusal(&scene).is_none());
        let spatial = simulate(&scene, &RunOptions::default()).unwrap();
        assert!(line.impacts.len() > 20, "{} impacts", line.impacts.len());
        assert_eq!(spatial.impacts.len(), line.impacts.len());
        for (a, b) in spatial.impacts.iter().zip(&line.impacts) {
            assert_eq!((a.a, a.b), (b.a, b.b), "at {} s", b.t);
            assert!((a.t - b.t).abs() <= 1e-12, "{} s against {} s", a.t, b.t);
            assert!((a.approach_speed - b.approach_speed).abs() <= 1e-9 * b.approach_speed, "at {} s", b.t);
        }
        let (fa, fb) = (spatial.series.xs(), line.series.xs());
        assert!(fa.iter().zip(fb).all(|(a, b)| (a - b).abs() <= 1e-12), "the frame moves alike");
        assert!(spatial.energy.balance_error.abs() <= 1e-12, "{:?}", spatial.energy);
    }

    /// Balls that wait before searching against the frame's walls, their waits kept across
    /// the frame's segments, meet the walls where balls that search after every event and
    /// every impact on the walls do: `planar-bed`'s first impacts, dozens of them on the end
    /// walls, alike to round-off (the searches start at other instants, so roots differ in
    /// their last bits, which the bed amplifies later).
    #[test]
    fn waiting_balls_meet_the_frames_walls_where_searching_ones_do() {
        let mut scene = crate::scene::load(crate::scene::scenes_dir().join("planar-bed.toml")).unwrap().scene.unwrap();
        scene.horizon = 0.1;
        let waiting = simulate_with(&scene, &RunOptions::default(), true, MAX_EVENTS).unwrap();
        let searching = simulate_with(&scene, &RunOptions::default(), false, MAX_EVENTS).unwrap();
        let walls =
            |impacts: &[Impact]| impacts.iter().filter(|i| matches!((i.a, i.b), (Body::LeftWall, _) | (_, Body::RightWall))).count();
        let alike = waiting
            .impacts
            .iter()
            .zip(&searching.impacts)
            .take_while(|(a, b)| (a.a, a.b) == (b.a, b.b) && (a.t - b.t).abs() <= 1e-12)
            .count();
        let shared = &waiting.impacts[..alike];
        assert!(alike >= 1000 && walls(shared) >= 30, "{alike} impacts alike, {} on the end walls", walls(shared));
    }

    /// Balls that wait before searching against the frame's walls, with a bound on the frame's
    /// reach that tightens twice as a gas of twenty balls with e = 0.5 loses its energy (from
    /// 11.6 mm to 2.5 mm, every wait and search redone each time), meet the frame's walls where
    /// balls that search after every event do: every impact of the first 0.4 s, twenty on the
    /// end walls, alike to round-off.
    #[test]
    fn a_bound_tightened_as_the_balls_lose_energy_keeps_the_walls_impacts() {
        let mut text = String::from(
            "name = \"gas\"\n[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 0.0\ninitial_displacement = 0.0\n\
             [container]\nlength = 0.1\nwidth = 0.06\nheight = 0.1\n[world]\ngravity = [0.0, 0.0, 0.0]\nrestitution = 0.5\n[run]\nhorizon = 0.4\n",
        );
        for i in 0..20 {
            let (x, y, z) = (0.01 + 0.02 * (i % 4) as f64, -0.02 + 0.02 * ((i / 4) % 3) as f64, -0.04 + 0.02 * (i / 12) as f64);
            let v = [(i as f64 * 0.37).sin(), (i as f64 * 0.91).cos(), (i as f64 * 1.73).sin()];
            text +=
                &format!("[[ball]]\nposition = [{x}, {y}, {z}]\nmass = 0.004\nradius = 0.005\nvelocity = [{}, {}, {}]\n", v[0], v[1], v[2]);
        }
        let scene = crate::scene::parse(&text, "gas.toml", "gas").unwrap().scene.unwrap();
        let options = RunOptions::default();
        let mut solver = Solver::new(&scene, ImpactRecord::Every).unwrap();
        let first = solver.frame_reach.as_ref().unwrap().reach;
        solver.run(&Meter::new(&options, BUDGET_EVENTS), &mut Recorder::new(&scene, options.record)).unwrap();
        let last = solver.frame_reach.as_ref().unwrap().reach;
        assert!(solver.reach_version == 2 && last < 0.25 * first, "{} bounds, from {first} m to {last} m", solver.reach_version);
        let waiting = simulate_with(&scene, &options, true, MAX_EVENTS).unwrap();
        let searching = simulate_with(&scene, &options, false, MAX_EVENTS).unwrap();
        assert_eq!(waiting.impacts.len(), searching.impacts.len());
        for (a, b) in waiting.impacts.iter().zip(&searching.impacts) {
            assert!((a.a, a.b) == (b.a, b.b) && (a.t - b.t).abs() <= 1e-12, "{a:?} against {b:?}");
        }
        let walls = waiting.impacts.iter().filter(|i| matches!((i.a, i.b), (Body::LeftWall, _) | (_, Body::RightWall))).count();
        assert!(walls >= 20, "{walls} impacts on the end walls");
    }
    /// A run past the events it may keep stops with the run so far, which is the unbounded
    /// run's up to there, and says what the events cost and how to make them fewer: a bed's
    /// events come at the rate the collapse rule allows, so this is a bound, not a stall.
    #[test]
    fn a_run_past_the_events_it_keeps_stops_with_the_run_so_far() {
        let mut scene = crate::scene::load(crate::scene::scenes_dir().join("planar-bed.toml")).unwrap().scene.unwrap();
        scene.horizon = 0.5;
        let whole = simulate(&scene, &RunOptions::default()).unwrap();
        let bound = whole.events / 2;
        let err = simulate_with(&scene, &RunOptions::default(), true, bound).unwrap_err();
        let message = err.to_string();
        let ModelError::OverBudget(stop) = err else { panic!("{message}") };
        assert_eq!((stop.budget, stop.limit, stop.steps), (Budget::Memory, bound as f64, bound + 1));
        assert!(message.contains("keeps in memory") && message.contains("`[reference] contact_duration`"), "{message}");
        let partial = &stop.partial;
        assert!(stop.t > 0.0 && stop.t < scene.horizon && partial.horizon == stop.t, "stopped at {}", stop.t);
        assert!(!partial.impacts.is_empty() && partial.impacts.len() < whole.impacts.len());
        assert_eq!(partial.impacts[..], whole.impacts[..partial.impacts.len()]);
        assert!(partial.energy.balance_error.abs() <= 1e-12, "{:?}", partial.energy);
        assert!(message.contains("`--impacts count`"), "{message}");
    }

    /// A run that counts its impacts instead of keeping them is not bounded by memory: past
    /// the bound it goes on to the horizon, and it is the run that keeps them, less the list.
    #[test]
    fn a_run_that_counts_its_impacts_goes_past_the_bound_on_events_kept() {
        let mut scene = crate::scene::load(crate::scene::scenes_dir().join("planar-bed.toml")).unwrap().scene.unwrap();
        scene.horizon = 0.5;
        let whole = simulate(&scene, &RunOptions::default()).unwrap();
        let counting = RunOptions { impacts: ImpactRecord::Count, ..RunOptions::default() };
        let counted = simulate_with(&scene, &counting, true, whole.events / 2).unwrap();
        assert!(counted.impacts.is_empty());
        assert_eq!((counted.counted_impacts.count, counted.impact_count()), (whole.impacts.len(), whole.impact_count()));
        assert_eq!((counted.horizon, counted.events, counted.energy), (whole.horizon, whole.events, whole.energy));
        assert_eq!((counted.series.xs(), counted.final_velocities.as_slice()), (whole.series.xs(), whole.final_velocities.as_slice()));
    }
}
