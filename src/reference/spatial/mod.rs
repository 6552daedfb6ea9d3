//! The reference beyond one line (docs/MODEL.md §14): smooth balls flying in closed form in the
//! plane or in space under gravity inside the container the frame (or a structure's floor)
//! carries, their impacts by
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
mod checks;
mod flight;
mod predict;
mod resolve;

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::frame::FrameMotion;
use super::frame_gap::{FrameGap, FrameReach};
use super::geometry::Limits;
use super::MAX_EVENTS;
use crate::impact_law::{reduced_mass, separate};
use crate::model::{Budget, Meter, Model, ModelError, OverBudget, RunOptions, STALL_EVENTS_PER_SIM_S};
use crate::run::{EnergyAccount, Impact, ImpactRecord, Impacts, Recorder, Run};
use crate::scene::Scene;
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
    let dampers = scene.damper_list();
    if scene.container.is_none() || dampers.iter().any(|d| d.section[0] <= 0.0 || d.section[1] <= 0.0) {
        return Some("the scene's balls leave their lines but it gives the container no cross-section (width and height)".into());
    }
    // Each damper's balls start a chain of their own; more than one in a damper are divided.
    let chains_in = |d: &crate::scene::Damper| space.chain_starts.iter().filter(|s| d.balls.contains(s)).count();
    if dampers.iter().any(|d| chains_in(d) > 1 || d.channel > 0.0) {
        return Some("the reference beyond one line has one chamber: it has no dividers between chains".into());
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
    /// The damper it is in.
    damper: u32,
}

/// What a damper's end walls are: how far apart, and the floor (or frame) that moves them.
#[derive(Debug, Clone, Copy)]
struct EndWalls {
    /// The container's inner length, m.
    length: f64,
    /// The floor that carries it (0 on a frame).
    floor: usize,
    /// That floor's mass (the frame's on a frame), kg: what the balls' impulses on the walls
    /// move.
    mass: f64,
}

/// The spatial reference's run of one scene.
struct Solver<'a> {
    scene: &'a Scene,
    balls: Vec<Ball>,
    frame: FrameMotion,
    limits: Limits,
    /// Each damper's cells: balls of two dampers never meet.
    cells: Vec<Cells>,
    /// Each damper's end walls.
    walls: Vec<EndWalls>,
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
    t: f64,
    horizon: f64,
    events: u64,
    /// The impacts, every one kept or only counted ([`ImpactRecord`]).
    impacts: Impacts,
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
    let given: f64 = balls
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let section = scene.section_of(i);
            let half = [0.5 * section[0], 0.5 * section[1]];
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
            let mut cost = format!("{} impacts so far; {} balls", s.impacts.len(), s.balls.len());
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
        let dampers = scene.damper_list();
        let frame = FrameMotion::new(scene).map_err(ModelError::Refused)?;
        let mut cells: Vec<Cells> = dampers
            .iter()
            .map(|d| {
                let largest = scene.balls[d.balls.clone()].iter().map(|b| b.radius).fold(0.0, f64::max);
                Cells::new(largest, d.container.length, d.section, scene.balls.len())
            })
            .collect();
        let walls = dampers
            .iter()
            .map(|d| {
                // A floor's own mass; the carrying floor's is the frame's.
                let mass = scene.structure.as_ref().map_or(frame.mass, |s| s.building.masses[d.floor]);
                EndWalls { length: d.container.length, floor: d.floor, mass }
            })
            .collect();
        let balls: Vec<Ball> = scene
            .balls
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let [y, z] = scene.space.lateral_of(i);
                let [vy, vz] = scene.space.lateral_velocity_of(i);
                let p = [scene.initial_positions[i], y, z];
                let damper = scene.damper_of(i);
                let cell = cells[damper].cell_of(p);
                cells[damper].insert(cell, i as u32);
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
                    damper: damper as u32,
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
            walls,
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
            t: 0.0,
            horizon: scene.horizon,
            events: 0,
            impacts: Impacts::new(impacts),
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

    /// Ball `i` (at the current time) against its damper's end wall on side `side`.
    fn frame_gap(&self, i: usize, side: f64) -> FrameGap<'_> {
        let b = &self.balls[i];
        let walls = &self.walls[b.damper as usize];
        let k = if side > 0.0 { -b.radius } else { walls.length - b.radius };
        FrameGap {
            frame: &self.frame,
            floor: walls.floor,
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
            if let Some(why) = self.frame.failure() {
                return Err(ModelError::Unstable {
                    scene: self.scene.name.clone(),
                    model: Model::Reference,
                    t: self.t,
                    reason: why.to_string(),
                });
            }
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
        let g = self.gravity;
        let ball = |i: usize| self.balls[i].at(ts, g);
        match self.frame.storeys() {
            // A structure's floors relative to the ground, and the ground, from their closed form.
            Some(storeys) => {
                let (z, ground) = storeys.floors(ts);
                recorder.sample_floors_in_space(self.scene, ts, z.split_at(z.len() / 2), ground, ball);
            }
            None => {
                let (xs, vs) = self.frame.state(ts);
                recorder.sample_in_space(self.scene, ts, xs, vs, ball);
            }
        }
    }

    fn stalled(&self, why: String) -> ModelError {
        ModelError::Stalled { scene: self.scene.name.clone(), model: Model::Reference, t: self.t, steps: self.events, why }
    }

    fn broken(&self, what: String) -> ModelError {
        ModelError::Broken { scene: self.scene.name.clone(), model: Model::Reference, t: self.t, what }
    }

    fn finish(self, recorder: Recorder, t: f64) -> Run {
        let scene = self.scene;
        let (damping, work) = self.frame.segment_energy(t, scene);
        let mut final_ = self.frame.energy(t, scene) + scene.height_energy_at_start();
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
            impacts: self.impacts.kept,
            counted_impacts: self.impacts.counted,
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
mod tests;
