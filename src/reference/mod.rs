//! The reference model: an exact event-driven impulse-momentum solver (docs/MODEL.md §1-4), f64,
//! no engine. It is the ground truth every other model is measured against.
//!
//! Between events the frame moves in closed form ([`crate::oscillator`]) and free balls fly in straight
//! lines, so the state at any time is exact up to round-off. Events are
//! - ball-ball contacts, whose times are exact (linear gaps);
//! - contacts between a ball and the frame (a wall, or a ball stuck to it), found by
//!   [`Solver::search_frame_pair`], which splits time at the sign changes of the frame's
//!   acceleration: on each piece the gap is convex or concave, and the first root is bracketed
//!   by Newton iteration from the safe side, so a graze is never stepped over;
//! - the reversal of the force that holds a stuck group of balls against a wall (release).
//!
//! Impacts follow [`impact_law`]. Persistent contact is a state, not a stream of impacts: when
//! two touching bodies approach slower than `v_stick`, or a ball would bounce off an
//! accelerating wall and return within `t_stick`, the touching run of bodies is merged
//! (perfectly inelastic, momentum kept, the energy lost booked as an impact). A run that reaches
//! a wall moves with the frame (its mass joins the frame's oscillator) until the wall would pull
//! it, and is then released. Chattering, inelastic collapse and resting balls therefore end in
//! a bounded number of events with the energy balance intact.
//!
//! One `impl Solver` split by phase, as rapier splits its physics pipeline: `segment` (the
//! frame's closed-form motion and its sign changes), `geometry` (gaps, tolerances and the
//! contact invariant), `search` (when each pair next touches), `events` (impacts, merges,
//! releases, one instant's resolution), `output` (samples and the finished run); this file
//! holds the solver's state, its limits and the event loop.

mod events;
mod exact;
mod geometry;
mod output;
mod search;
mod segment;

use exact::ExactTally;
use geometry::*;
use output::*;
use search::*;
use segment::*;

use crate::model::{Budget, Checks, Meter, Model, ModelError, OverBudget, RunOptions, Setting, Simulator};
use crate::run::{EnergyAccount, Impact, Record, Recorder, Run};
use crate::scene::{Body, Scene};
pub use crate::impact_law::impact_law;
pub use crate::oscillator::Oscillator;
use crate::oscillator::{gauss_legendre, Harmonic, ROUNDOFF_ULPS};

/// Most events one run may process before it is declared stalled.
pub const MAX_EVENTS: u64 = 20_000_000;
/// Shortest time between two impacts of one pair that are resolved as separate impacts, s.
///
/// The impulse model treats impacts as instantaneous, which holds only while they are further
/// apart than a real contact lasts (tens of microseconds for centimetre steel balls at these
/// speeds). Closer repeats, such as a light elastic ball squeezed between two heavy ones
/// (whose bounce rate grows without bound as the gap closes), are persistent contact: the
/// touching run is merged, with the energy booked as an impact loss.
pub const CONTACT_DURATION: f64 = 1e-6;
/// Most events at one instant: everything at an instant is resolved by one `resolve`, so a
/// second event at the same time already means two judgements disagree.
const MAX_EVENTS_PER_INSTANT: u64 = 1000;
/// Most impacts resolved at one instant before the touching run is merged.
const MAX_IMPULSES_PER_INSTANT: usize = 10_000;
/// Contact tolerance relative to the scene's length scale (to which the round-off of
/// evaluating a gap is added, see [`Solver::frame_gap_tolerance`]).
const LENGTH_TOLERANCE: f64 = 1e-12;
/// Most iterations of one root search (Newton, bisection): bisection halves a bracket to an
/// ulp in at most about 1100 halvings of the whole f64 range, Newton on these smooth gaps in a
/// few dozen; this cap is never reached by a search that converges.
const MAX_ROOT_ITERATIONS: usize = 200;
/// Sign changes of a forced segment kept before those already past are dropped.
const SIGN_CHANGES_KEPT: usize = 1024;
/// A value is round-off (its sign carries no information) when it is below this fraction of
/// the size of the terms it was computed from.
const ROUNDOFF_RELATIVE: f64 = 1e-9;
/// Sticking speed relative to the scene's speed scale.
const STICK_SPEED: f64 = 1e-9;
/// Bounce-return time below which a ball sticks to the frame, relative to the time scale.
const STICK_TIME: f64 = 1e-7;

/// Impacts a run makes room for at its start (80 bytes each).
const IMPACTS_RESERVED: usize = 256;

/// Events between two looks at the budgets and two reports of progress.
const BUDGET_EVENTS: u64 = 4096;

/// The reference model.
#[derive(Debug, Clone, Copy)]
pub struct Reference;

impl Simulator for Reference {
    fn model(&self) -> Model {
        Model::Reference
    }

    fn supports(&self, _scene: &Scene) -> Result<(), String> {
        Ok(())
    }

    fn simulate(&self, scene: &Scene, options: &RunOptions) -> Result<Run, ModelError> {
        let meter = Meter::new(options, BUDGET_EVENTS);
        let mut solver = Solver::new(scene, options.record);
        let stop = solver.run(&meter)?;
        let (t, events) = (solver.t, solver.events);
        meter.finish(t, events);
        let Some(budget) = stop else {
            let mut run = solver.finish();
            run.wall_time_s = meter.elapsed();
            return Ok(run);
        };
        let cost = format!("{} impacts so far", solver.impacts.len());
        let mut partial = solver.finish_at(t);
        let wall_s = meter.elapsed();
        partial.wall_time_s = wall_s;
        Err(ModelError::OverBudget(Box::new(OverBudget {
            scene: scene.name.clone(),
            model: Model::Reference,
            t,
            horizon: scene.horizon,
            steps: events,
            wall_s,
            budget,
            limit: meter.limit(budget),
            cost,
            partial,
        })))
    }

    fn checks(&self, scene: &Scene, _run: &Run) -> Checks {
        // Exact to round-off: contacts within the contact tolerance (a bound of order 1e-13 to
        // 1e-11 m, docs/MODEL.md §10), far inside a nanometre per millimetre of container.
        let contact = 1e-9 * scene.container.map_or(1e-3, |c| c.length.max(1e-3));
        Checks {
            energy_gain: 1e-9,
            balance: Some(1e-9),
            impact_gain: 1e-9,
            exact_impacts: true,
            momentum: 1e-9,
            wall_overlap: contact,
            ball_overlap: Some(contact),
            stall_by_rate: true,
        }
    }

    fn settings(&self) -> &'static [Setting] {
        &[]
    }

    fn stepping(&self, _scene: &Scene) -> &'static str {
        "event-driven"
    }
}

/// Which wall a stuck ball is held by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Hold {
    Free,
    Left,
    Right,
}

struct Solver<'a> {
    scene: &'a Scene,
    n: usize,
    walls: bool,
    mass: Vec<f64>,
    radius: Vec<f64>,
    e: f64,
    frame_mass: f64,
    damping: f64,
    stiffness: f64,
    length: f64,
    seg: Segment,
    /// Serial number of `seg` (segments can start at the same instant).
    segment: u64,
    sign_changes: std::cell::RefCell<SignChanges>,
    /// The frame's state and acceleration ahead at `t` under segment `segment`, kept while
    /// neither changes (a cascade of impulses at one instant asks for them every pass).
    now: std::cell::Cell<Option<FrameNow>>,
    /// The last frame state evaluated, `(segment, t, xs, vs)`: the searches of both walls and
    /// the checks ask for the same instant in turn, and each evaluation costs an `exp` and a
    /// `sin_cos` ([`Solver::frame_state`]).
    last_state: std::cell::Cell<(u64, f64, f64, f64)>,
    /// Scratch of `resolve`: each pair's contact now.
    contacts: Vec<Contact>,
    /// Each pair as [`Solver::check_contacts`] last read it (for `resolve`'s first pass).
    pairs_now: Vec<Option<PairNow>>,
    t: f64,
    x: Vec<f64>,
    v: Vec<f64>,
    /// A bound on the rounding that advancing has added to each ball's position `x` so far.
    drift: Vec<f64>,
    hold: Vec<Hold>,
    offset: Vec<f64>,
    held_mass: f64,
    packed: bool,
    cand: Vec<Candidate>,
    dirty: Vec<bool>,
    frame_dirty: bool,
    release_at: f64,
    tol: f64,
    v_stick: f64,
    /// The scene's speed scale (the frame's initial or forced speed, or a length per
    /// horizon), raised to the fastest approach of any impact so far: the speed at which
    /// contacts can be placed no closer than two ulps of time (see
    /// [`Solver::frame_gap_tolerance`]). It never falls, so bodies that met fast and move on
    /// together keep a tolerance their meeting needed.
    fastest: f64,
    /// The largest contact tolerance a touching pair has had so far (see
    /// [`Solver::check_contacts`]).
    accepted_overlap: f64,
    t_stick: f64,
    span: f64,
    horizon: f64,
    damping_loss: f64,
    forcing_work: f64,
    /// The harmonic load `(P, Q, w)` on the frame, when forced.
    load: Option<(f64, f64, f64)>,
    impact_loss: f64,
    impacts: Vec<Impact>,
    last_impact: Vec<Option<usize>>,
    events: u64,
    recorder: Recorder,
    /// Exact metrics of a free run (`None` when forced or frameless: read at the samples).
    exact: Option<ExactTally>,
    next_sample: usize,
    sample_count: usize,
    cursor: SampleCursor,
}

impl<'a> Solver<'a> {
    fn new(scene: &'a Scene, record: Record) -> Self {
        let n = scene.balls.len();
        let (frame_mass, damping, stiffness) =
            scene.frame.map_or((f64::INFINITY, 0.0, 0.0), |f| (f.mass, f.damping, f.stiffness));
        let walls = scene.container.is_some();
        let length = scene.container.map_or(0.0, |c| c.length);
        let osc = Oscillator::new(if frame_mass.is_finite() { frame_mass } else { 1.0 }, damping, stiffness);
        let xs0 = scene.initial_displacement;
        let length_scale = scene.length_scale();
        let time_scale = scene.frame.map_or(scene.horizon, |f| {
            let p = f.damped_period();
            if p > 0.0 {
                p
            } else {
                scene.horizon
            }
        });
        let load = scene.harmonic_load();
        let speed_scale = scene.speed_scale();
        let samples = scene.sample_count();
        // Where its metrics are exact the reference tallies no samples, and takes none unless
        // the series is kept.
        let exact = ExactTally::new(scene);
        let recorder = Recorder::new(scene, record);
        let mut s = Solver {
            scene,
            n,
            walls,
            mass: scene.balls.iter().map(|b| b.mass).collect(),
            radius: scene.balls.iter().map(|b| b.radius).collect(),
            e: scene.restitution,
            frame_mass,
            damping,
            stiffness,
            length,
            seg: Segment::new(0.0, xs0, 0.0, osc, load),
            segment: 1,
            sign_changes: Default::default(),
            now: Default::default(),
            last_state: std::cell::Cell::new((0, f64::NAN, 0.0, 0.0)),
            contacts: Vec::new(),
            pairs_now: Vec::new(),
            t: 0.0,
            x: scene.initial_positions.clone(),
            v: scene.initial_velocities.clone(),
            drift: vec![0.0; n],
            hold: vec![Hold::Free; n],
            offset: vec![0.0; n],
            held_mass: 0.0,
            packed: false,
            cand: vec![NO_EVENT; n + 1],
            dirty: vec![true; n + 1],
            frame_dirty: true,
            release_at: f64::INFINITY,
            tol: LENGTH_TOLERANCE * length_scale,
            v_stick: STICK_SPEED * speed_scale,
            fastest: speed_scale,
            accepted_overlap: 0.0,
            t_stick: STICK_TIME * time_scale,
            span: f64::INFINITY,
            horizon: scene.horizon,
            damping_loss: 0.0,
            forcing_work: 0.0,
            load,
            impact_loss: 0.0,
            // Room for a paper scene's impacts: growing a vector of them copies it each time.
            impacts: Vec::with_capacity(IMPACTS_RESERVED),
            last_impact: vec![None; n + 1],
            events: 0,
            recorder: if exact.is_some() { recorder.untallied() } else { recorder },
            exact,
            next_sample: 0,
            sample_count: samples,
            cursor: SampleCursor { seg_t0: f64::NAN, k: 0, x: 0.0, v: 0.0, steps: 0, mass: f64::NAN, transition: [[0.0; 2]; 2] },
        };
        s.span = s.group_span();
        s
    }

    fn has_frame(&self) -> bool {
        self.frame_mass.is_finite()
    }

    /// One damped period of the frame with what it carries, or the horizon.
    fn group_span(&self) -> f64 {
        self.seg.osc.damped_omega().map_or(self.horizon, |w| 2.0 * std::f64::consts::PI / w)
    }

    /// Pairs that can touch: `p` lies between body `p - 1` and body `p` (body `-1` is the left
    /// wall, body `n` the right wall).
    fn pair_range(&self) -> std::ops::Range<usize> {
        if self.walls {
            0..self.n + 1
        } else {
            1..self.n.max(1)
        }
    }

    /// Runs the events to the horizon: `Some(budget)` when a budget stopped it first.
    fn run(&mut self, meter: &Meter) -> Result<Option<Budget>, ModelError> {
        let mut same_instant = 0u64;
        self.resolve(false)?;
        loop {
            self.refresh_candidates();
            // The earliest candidate; at a tie an exact one, so that a search stopped at that
            // time is resumed only after it.
            let mut next = (self.horizon, None);
            let mut next_exact = true;
            for p in self.pair_range() {
                let c = self.cand[p];
                if c.t < next.0 || (c.t == next.0 && c.exact && !next_exact && next.1.is_some()) {
                    next = (c.t, Some(p));
                    next_exact = c.exact;
                }
            }
            // The release is an exact event too: it goes before a search stopped at its time.
            let release = self.release_at < next.0 || (self.release_at == next.0 && !next_exact);
            if release {
                next = (self.release_at, None);
            }
            let (t, pair) = next;
            if !release && pair.is_none() {
                break;
            }
            if let Some(p) = pair {
                if !self.cand[p].exact {
                    self.cand[p] = self.candidate(p, t, self.exact_event_bound(Some(p)));
                    continue;
                }
            }
            self.tally_until(t);
            self.sample_until(t, false);
            same_instant = if t == self.t { same_instant + 1 } else { 0 };
            self.advance(t);
            self.check_contacts(pair)?;
            self.events += 1;
            if let Some(budget) = meter.look(t, self.events) {
                return Ok(Some(budget));
            }
            if self.events > MAX_EVENTS || same_instant > MAX_EVENTS_PER_INSTANT {
                let why = if same_instant > MAX_EVENTS_PER_INSTANT {
                    format!("more than {MAX_EVENTS_PER_INSTANT} events at one instant")
                } else {
                    format!("more than {MAX_EVENTS} events")
                };
                return Err(self.stalled(why));
            }
            if release {
                self.release_at = f64::INFINITY;
                self.frame_dirty = true;
            }
            if let Some(p) = pair {
                // Searched again from now even if resolving changes nothing (a contact that
                // turns out not to be one), or its cached time would fire forever.
                self.dirty[p] = true;
            }
            self.resolve(true)?;
        }
        self.tally_until(self.horizon);
        self.sample_until(self.horizon, true);
        self.advance(self.horizon);
        self.check_contacts(None)?;
        Ok(None)
    }

    /// The stall of this run at the current time, for `why`.
    fn stalled(&self, why: String) -> ModelError {
        ModelError::Stalled { scene: self.scene.name.clone(), model: Model::Reference, t: self.t, steps: self.events, why }
    }
}
