//! The reference model: the exact event-driven impulse-momentum solver of docs/MODEL.md §1-4,
//! f64 and no engine, the ground truth every other model is measured against. Between events
//! the frame moves in closed form and free balls fly straight, so the state at any time is a
//! formula; events are contacts (ball-frame contacts found by the sound root isolation of
//! docs/MODEL.md §10), releases of held balls and the horizon; persistent contact is a state
//! (§4), so chattering and inelastic collapse end in a bounded number of events.
//!
//! The solver is composed of parts that own their state: `balls`, `frame` (the current segment
//! of closed-form motion, whose mathematics is `segment`), `search` (each pair's next event),
//! `geometry` (gaps, tolerances, the postcondition), `events` (impacts, merges, releases and
//! the ledger) and `output` (samples, the exact metrics of `exact`, the finished run). This
//! file holds the limits and the event loop that composes them.

mod balls;
mod events;
mod exact;
mod frame;
mod frame_gap;
mod geometry;
mod output;
mod search;
mod segment;
mod spatial;
mod storeys;

use balls::{Balls, Gap, Hold};
use events::Ledger;
use exact::ExactTally;
use frame::FrameMotion;
use frame_gap::FrameGap;
use geometry::{Contact, Limits, PairNow, Scratch};
use output::Sampler;
use search::Search;
use segment::{Segment, Zeros};

pub use crate::impact_law::impact_law;
use crate::model::{Budget, Checks, Meter, Model, ModelError, OverBudget, RunOptions, Setting, Simulator, STALL_EVENTS_PER_SIM_S};
pub use crate::oscillator::Oscillator;
use crate::oscillator::{gauss_legendre, Harmonic, ROUNDOFF_ULPS};
use crate::run::{BallPath, EnergyAccount, Impact, Record, Recorder, Run};
use crate::scene::{Body, Scene};

/// Most events one run may process: each may be an impact, which the run keeps for its
/// outputs (96 bytes, 1.9 GB at the bound). On one line, where the resting state keeps a
/// run's events few, a run past it is declared stalled. Beyond one line, where the collapse
/// rule makes a pile's events at a steady rate, a run that keeps its impacts stops there with
/// the run so far (or as stalled, if it made them faster than the rule makes a pile's), and
/// one that counts them goes on.
pub const MAX_EVENTS: u64 = crate::run::MAX_KEPT_IMPACTS as u64;
/// Most events at one instant: everything at an instant is resolved by one `resolve`, so a
/// second event at the same time already means two judgements disagree.
const MAX_EVENTS_PER_INSTANT: u64 = 1000;
/// Most impacts resolved at one instant before the touching run is merged.
const MAX_IMPULSES_PER_INSTANT: usize = 10_000;
/// Contact tolerance relative to the scene's length scale (to which the round-off of
/// evaluating a gap is added, see [`FrameGap::with_tolerance`]).
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

/// Impacts a run makes room for at its start (96 bytes each).
const IMPACTS_RESERVED: usize = 256;

/// Events between two looks at the budgets and two reports of progress.
const BUDGET_EVENTS: u64 = 4096;

/// The reference model.
#[derive(Debug, Clone, Copy)]
pub struct Reference;

/// Whether the reference runs `scene` beyond one line (docs/MODEL.md §14) rather than on its
/// lines.
fn runs_in_space(scene: &Scene) -> bool {
    scene.space.beyond_lines(&scene.initial_positions).is_some()
}

/// Why the reference on lines, which holds one container, cannot run `scene`, when it has
/// several dampers.
fn one_damper_on_lines(scene: &Scene) -> Result<(), String> {
    if !scene.has_several_dampers() {
        return Ok(());
    }
    Err(format!(
        "the scene has {} dampers whose balls stay on their lines; the reference carries several dampers only when their balls leave their lines (on lines it holds one container): run the contact or compliant model, or give one [[damper]]",
        scene.dampers.len()
    ))
}

impl Simulator for Reference {
    fn model(&self) -> Model {
        Model::Reference
    }

    fn supports(&self, scene: &Scene) -> Result<(), String> {
        if runs_in_space(scene) {
            spatial::refusal(scene).map_or(Ok(()), Err)
        } else {
            one_damper_on_lines(scene)
        }
    }

    fn simulate(&self, scene: &Scene, options: &RunOptions) -> Result<Run, ModelError> {
        if runs_in_space(scene) {
            return spatial::simulate(scene, options);
        }
        // Every event reads every pair: with many balls the meter looks more often, so that a
        // long run reports about once per a few hundred thousand pair readings.
        let every = (BUDGET_EVENTS * 16 / (scene.balls.len() as u64 + 1)).clamp(1, BUDGET_EVENTS);
        let meter = Meter::new(options, every);
        let mut solver = Solver::new(scene, options.record)?;
        let stop = solver.run(&meter)?;
        let (t, events) = (solver.t, solver.events);
        meter.finish(t, events);
        let Some(budget) = stop else {
            let mut run = solver.finish();
            run.wall_time_s = meter.elapsed();
            return Ok(run);
        };
        let cost = format!("{} impacts so far", solver.ledger.impacts.len());
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
            stall_rate: Some(if runs_in_space(scene) { spatial::stall_rate(scene) } else { STALL_EVENTS_PER_SIM_S }),
        }
    }

    fn settings(&self) -> &'static [Setting] {
        &[]
    }

    fn stepping(&self, _scene: &Scene) -> &'static str {
        "event-driven"
    }
}

/// The solver of one run: the parts that own its state, composed by the event loop
/// ([`Solver::run`]). Each part's own file says what it holds; the methods that need several
/// parts (a gap needs the balls and the frame) are the solver's, in the file of their phase.
struct Solver<'a> {
    scene: &'a Scene,
    /// The balls: where they are, how they move, which the frame holds.
    balls: Balls,
    /// The frame's closed-form motion since its last change.
    frame: FrameMotion,
    /// Each pair's next event and the release of held balls.
    search: Search,
    /// The contact and sticking tolerances, and what the run has needed of them so far.
    limits: Limits,
    /// Impacts and the energy account.
    ledger: Ledger,
    /// The samples and the metrics.
    sampler: Sampler,
    /// Scratch of one instant: each pair as the postcondition read it, and its contact.
    scratch: Scratch,
    /// `e`.
    e: f64,
    t: f64,
    horizon: f64,
    events: u64,
}

impl<'a> Solver<'a> {
    fn new(scene: &'a Scene, record: Record) -> Result<Self, ModelError> {
        let balls = Balls::new(scene);
        let pairs = balls.pairs.count();
        Ok(Solver {
            scene,
            balls,
            frame: FrameMotion::new(scene).map_err(ModelError::Refused)?,
            search: Search::new(pairs),
            limits: Limits::new(scene),
            ledger: Ledger::new(pairs),
            sampler: Sampler::new(scene, record),
            scratch: Scratch::default(),
            e: scene.restitution,
            t: 0.0,
            horizon: scene.horizon,
            events: 0,
        })
    }

    fn has_frame(&self) -> bool {
        self.frame.exists()
    }

    /// Pairs that can touch (see [`crate::scene::Pairs`]).
    fn pair_range(&self) -> std::ops::Range<usize> {
        self.balls.pair_range()
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
                let c = self.search.cand[p];
                if c.t < next.0 || (c.t == next.0 && c.exact && !next_exact && next.1.is_some()) {
                    next = (c.t, Some(p));
                    next_exact = c.exact;
                }
            }
            // The release is an exact event too: it goes before a search stopped at its time.
            let release = self.search.release_at < next.0 || (self.search.release_at == next.0 && !next_exact);
            if release {
                next = (self.search.release_at, None);
            }
            let (t, pair) = next;
            if !release && pair.is_none() {
                break;
            }
            if let Some(p) = pair {
                if !self.search.cand[p].exact {
                    self.search.cand[p] = self.candidate(p, t, self.exact_event_bound(Some(p)));
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
            if let Some(why) = self.frame.failure() {
                return Err(ModelError::Unstable { scene: self.scene.name.clone(), model: Model::Reference, t, reason: why.to_string() });
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
                self.search.release_at = f64::INFINITY;
                self.search.frame_dirty = true;
            }
            if let Some(p) = pair {
                // Searched again from now even if resolving changes nothing (a contact that
                // turns out not to be one), or its cached time would fire forever.
                self.search.dirty[p] = true;
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
