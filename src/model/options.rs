//! What a caller asks of one run besides the scene: what to keep, how much it may cost, and
//! where to report its progress. Every model takes the same options.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use crate::run::{ImpactRecord, Record};

/// How one run is to be made.
#[derive(Debug, Clone, Copy, Default)]
pub struct RunOptions<'a> {
    /// What the run keeps besides its metrics.
    pub record: Record,
    /// What the run keeps of its impacts.
    pub impacts: ImpactRecord,
    /// What the run may cost before it stops with the run so far.
    pub limits: Limits,
    /// Where the run reports the simulated time reached and the steps taken as it goes.
    pub progress: Option<&'a Progress>,
}

impl RunOptions<'_> {
    /// A run that keeps only its metrics and counts its impacts (an ensemble member's).
    pub fn metrics_only() -> Self {
        RunOptions { record: Record::MetricsOnly, impacts: ImpactRecord::Count, ..RunOptions::default() }
    }
    /// A run that keeps its series, within `limits`.
    pub fn limited(limits: Limits) -> Self {
        RunOptions { limits, ..RunOptions::default() }
    }
}

/// What one run may cost: past either budget it stops with the run so far
/// ([`super::ModelError::OverBudget`]). A study gives each of its runs the same limits.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Limits {
    /// Most steps (the reference: events).
    pub max_steps: Option<u64>,
    /// Most seconds of computing.
    pub max_wall_s: Option<f64>,
}

impl Limits {
    /// No budget: the run goes to its horizon (or to a model's own limit).
    pub const NONE: Limits = Limits { max_steps: None, max_wall_s: None };

    /// The rules the budgets keep (`--max-steps`, `--max-wall-time` and their Python keywords):
    /// at least one step, a positive and finite number of seconds. The rule broken, for the
    /// caller to name its field (a budget the user sets, so one with a flag and a keyword).
    pub fn check(&self) -> Result<(), (Budget, String)> {
        if self.max_steps == Some(0) {
            return Err((Budget::Steps, "must be at least 1".into()));
        }
        match self.max_wall_s {
            Some(w) if !(w > 0.0 && w.is_finite()) => Err((Budget::WallTime, format!("must be a positive number of seconds (got {w})"))),
            _ => Ok(()),
        }
    }
}

/// A run's budget: steps (events, for the reference) or seconds of computing, which the user
/// sets, or the events a run may keep, which no one sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Budget {
    /// Steps or events.
    Steps,
    /// Seconds of computing.
    WallTime,
    /// The events whose impacts a run keeps in memory for its outputs: a fixed bound, so that
    /// a run's answer never depends on the machine.
    Memory,
}

impl Budget {
    /// The command-line flag that sets it, `None` for the fixed bound.
    pub fn flag(self) -> Option<&'static str> {
        match self {
            Budget::Steps => Some("--max-steps"),
            Budget::WallTime => Some("--max-wall-time"),
            Budget::Memory => None,
        }
    }
    /// The Python keyword that sets it, `None` for the fixed bound.
    pub fn keyword(self) -> Option<&'static str> {
        match self {
            Budget::Steps => Some("max_steps"),
            Budget::WallTime => Some("max_wall_time"),
            Budget::Memory => None,
        }
    }
}

/// Where a run stands, for a progress bar or a cost estimate on another thread: the simulated
/// time reached and the steps (or events) taken, updated as the run goes ([`Meter`]).
#[derive(Debug, Default)]
pub struct Progress {
    t: AtomicU64,
    steps: AtomicU64,
}

impl Progress {
    /// Simulated time reached, s.
    pub fn time(&self) -> f64 {
        f64::from_bits(self.t.load(Ordering::Relaxed))
    }
    /// Steps (or events) taken.
    pub fn steps(&self) -> u64 {
        self.steps.load(Ordering::Relaxed)
    }
    /// Records where the run stands.
    pub fn set(&self, t: f64, steps: u64) {
        self.t.store(t.to_bits(), Ordering::Relaxed);
        self.steps.store(steps, Ordering::Relaxed);
    }
}

/// A run's budgets and progress as its model looks at them: every `every` steps it reports
/// where it stands and says which budget, if any, has run out. Every model keeps one, so the
/// budgets mean the same in all of them.
#[derive(Debug, Clone, Copy)]
pub struct Meter<'a> {
    start: Instant,
    every: u64,
    max_steps: Option<u64>,
    max_wall_s: Option<f64>,
    max_kept: Option<u64>,
    progress: Option<&'a Progress>,
}

impl<'a> Meter<'a> {
    /// A meter started now for a run under `options`, looking every `every` steps.
    pub fn new(options: &RunOptions<'a>, every: u64) -> Self {
        Meter {
            start: Instant::now(),
            every: every.max(1),
            max_steps: options.limits.max_steps,
            max_wall_s: options.limits.max_wall_s,
            max_kept: None,
            progress: options.progress,
        }
    }
    /// The meter, stopping the run past `events` steps whose impacts it keeps in memory
    /// ([`Budget::Memory`]).
    pub fn keeping(self, events: u64) -> Self {
        Meter { max_kept: Some(events), ..self }
    }
    /// Seconds of computing since the run started.
    pub fn elapsed(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
    /// The run has taken `steps` steps and reached `t`: on every `every`-th step, on the
    /// steps 1, 2, 4, ... before it, and past the step budgets, reports it and returns the
    /// budget that has run out, if any. The early looks bound a run of slow steps: it overruns
    /// its wall-time budget by at most the time it had taken when it last looked.
    #[inline]
    pub fn look(&self, t: f64, steps: u64) -> Option<Budget> {
        let over_steps = self.max_steps.is_some_and(|m| steps > m);
        let over_kept = self.max_kept.is_some_and(|m| steps > m);
        let due = steps.is_multiple_of(self.every) || (steps < self.every && steps.is_power_of_two());
        if !(over_steps | over_kept | due) {
            return None;
        }
        if let Some(p) = self.progress {
            p.set(t, steps);
        }
        if over_steps {
            return Some(Budget::Steps);
        }
        if over_kept {
            return Some(Budget::Memory);
        }
        self.max_wall_s.filter(|&w| self.elapsed() > w).map(|_| Budget::WallTime)
    }
    /// Reports the end of the run.
    pub fn finish(&self, t: f64, steps: u64) {
        if let Some(p) = self.progress {
            p.set(t, steps);
        }
    }
    /// The limit of `budget`, in its unit (steps, or seconds).
    pub fn limit(&self, budget: Budget) -> f64 {
        match budget {
            Budget::Steps => self.max_steps.unwrap_or(u64::MAX) as f64,
            Budget::WallTime => self.max_wall_s.unwrap_or(f64::INFINITY),
            Budget::Memory => self.max_kept.unwrap_or(u64::MAX) as f64,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Past both, the user's step budget is the one named; past the bound on the events kept
    /// alone, that bound, at its own limit.
    #[test]
    fn the_users_step_budget_comes_before_the_bound_on_events_kept() {
        let options = RunOptions::limited(Limits { max_steps: Some(10), ..Limits::NONE });
        let meter = Meter::new(&options, 1000).keeping(10);
        assert_eq!(meter.look(0.0, 10), None);
        assert_eq!(meter.look(0.0, 11), Some(Budget::Steps));
        let meter = Meter::new(&options, 1000).keeping(5);
        assert_eq!(meter.look(0.0, 5), None);
        assert_eq!(meter.look(0.0, 6), Some(Budget::Memory));
        assert_eq!(meter.limit(Budget::Memory), 5.0);
    }
}
