//! What a run will cost, judged from the run itself while it goes: the steps (or events) still
//! to take at the rate of its recent steps per simulated second, and the seconds at its
//! measured cost per step. Every model reports where it stands through [`super::Progress`].
//!
//! Why measured, not predicted from the scene alone: a model's cost is set by what its contacts
//! do, which only it resolves. A pack of balls pressed together trembles at its Hertz
//! frequencies in the compliant model and rattles through thousands of contacts where the
//! reference counts one merge (docs/BENCHMARKS.md, "Compliant model on packs and resting
//! contacts"), and a run's first milliseconds (the first impacts, a pack settling) often cost
//! more per simulated second than the rest. So the estimate reads the *recent* half of the
//! run's computing time, which has left the start behind, and is revised as the run goes
//! ([`CostWatch::revised`]).

/// An estimate of a whole run's cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CostEstimate {
    /// Steps (accepted and rejected) the whole run will take.
    pub steps: f64,
    /// Seconds of computing the whole run will take.
    pub seconds: f64,
    /// The recent rate: steps per simulated second.
    pub steps_per_simulated_second: f64,
    /// The recent cost of one step, s.
    pub seconds_per_step: f64,
}

/// The progress of one run as read at times of its computing: `(computing s, simulated s,
/// steps)`, in order.
#[derive(Debug, Clone, Default)]
pub struct CostWatch {
    history: Vec<(f64, f64, u64)>,
    /// The estimate last said, if any.
    said: Option<CostEstimate>,
    /// The estimate at the previous call of [`CostWatch::revised`].
    previous: Option<CostEstimate>,
}

/// A said estimate is revised when a new one differs from it by more than this factor; an
/// estimate is steady when it agrees within it with the one before.
pub const REVISION_FACTOR: f64 = 2.0;

impl CostWatch {
    /// Notes where the run stands after `wall_s` seconds of computing.
    pub fn record(&mut self, wall_s: f64, t: f64, steps: u64) {
        self.history.push((wall_s, t, steps));
    }

    /// The whole run's cost at the rate of the recent half of its computing time (from the
    /// last reading taken at or before half the time computed so far, to the newest), for a
    /// run of horizon `horizon`; `None` before the run has moved over two readings.
    pub fn estimate(&self, horizon: f64) -> Option<CostEstimate> {
        let &(w1, t1, s1) = self.history.last()?;
        let k = self.history.partition_point(|&(w, _, _)| w <= 0.5 * w1).saturating_sub(1);
        let (w0, t0, s0) = self.history[k];
        if !(t1 > t0 && s1 > s0 && w1 > w0) {
            return None;
        }
        let steps_per_simulated_second = (s1 - s0) as f64 / (t1 - t0);
        let seconds_per_step = (w1 - w0) / (s1 - s0) as f64;
        let remaining = steps_per_simulated_second * (horizon - t1).max(0.0);
        Some(CostEstimate {
            steps: s1 as f64 + remaining,
            seconds: w1 + remaining * seconds_per_step,
            steps_per_simulated_second,
            seconds_per_step,
        })
    }

    /// The estimate to say now, if steady (within [`REVISION_FACTOR`] of the one at the
    /// previous call, so that a start still in its costly first impacts is not said): the
    /// first one, or one that differs from the last one said by more than the factor in steps
    /// or seconds (which it then becomes).
    pub fn revised(&mut self, horizon: f64) -> Option<CostEstimate> {
        let now = self.estimate(horizon);
        let previous = std::mem::replace(&mut self.previous, now);
        let now = now?;
        let off = |a: &CostEstimate, b: &CostEstimate| {
            let apart = |x: f64, y: f64| x > REVISION_FACTOR * y || y > REVISION_FACTOR * x;
            apart(a.steps, b.steps) || apart(a.seconds, b.seconds)
        };
        let steady = previous.is_some_and(|p| !off(&now, &p));
        let say = steady && self.said.is_none_or(|s| off(&now, &s));
        if say {
            self.said = Some(now);
        }
        say.then_some(now)
    }
}

/// How long a run goes before its cost is estimated (its first readings).
pub const ESTIMATE_AFTER_S: f64 = 0.25;
/// A run estimated to take at least this many seconds of computing is a long run: its
/// estimate is said.
pub const LONG_RUN_S: f64 = 1.0;
/// How often [`watch`] reads a run's progress.
pub const READ_EVERY: std::time::Duration = std::time::Duration::from_millis(50);

/// An estimate to say, with where the run stood when it was made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Said {
    /// The estimate.
    pub estimate: CostEstimate,
    /// Whether an estimate was said before (this one revises it).
    pub revision: bool,
    /// Computing time so far, s.
    pub elapsed_s: f64,
    /// Simulated time reached, s.
    pub t: f64,
    /// Steps taken so far.
    pub steps: u64,
}

/// Watches a run through its [`super::Progress`] until `done` (the run's thread sets it and
/// unparks this one, which then returns at once): reads it every [`READ_EVERY`],
/// passes each reading to `tick(elapsed_s, t, steps)`, and from [`ESTIMATE_AFTER_S`] on passes
/// to `say` the estimates of a long run to say ([`CostWatch::revised`]; once a run has been
/// said to be long, its revisions whatever their size). Run on its own thread beside the run.
pub fn watch(
    progress: &super::Progress,
    horizon: f64,
    done: &std::sync::atomic::AtomicBool,
    mut say: impl FnMut(Said),
    mut tick: impl FnMut(f64, f64, u64),
) {
    let start = std::time::Instant::now();
    let mut watch = CostWatch::default();
    let mut long = false;
    while !done.load(std::sync::atomic::Ordering::Relaxed) {
        std::thread::park_timeout(READ_EVERY);
        if done.load(std::sync::atomic::Ordering::Relaxed) {
            break;
        }
        let (elapsed_s, t, steps) = (start.elapsed().as_secs_f64(), progress.time(), progress.steps());
        watch.record(elapsed_s, t, steps);
        if elapsed_s >= ESTIMATE_AFTER_S {
            if let Some(estimate) = watch.revised(horizon) {
                if long || estimate.seconds >= LONG_RUN_S {
                    say(Said { estimate, revision: long, elapsed_s, t, steps });
                    long = true;
                }
            }
        }
        tick(elapsed_s, t, steps);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run at a steady rate is estimated exactly, from any reading on.
    #[test]
    fn a_steady_run_is_estimated_exactly() {
        let mut w = CostWatch::default();
        // 1000 steps per simulated second, 1 ms of computing per step, horizon 2 s.
        for k in 1..=10u64 {
            let steps = 100 * k;
            w.record(steps as f64 * 1e-3, steps as f64 / 1000.0, steps);
            let Some(e) = w.estimate(2.0) else {
                assert_eq!(k, 1, "an estimate from the second reading on");
                continue;
            };
            approx::assert_relative_eq!(e.steps, 2000.0, max_relative = 1e-12);
            approx::assert_relative_eq!(e.seconds, 2.0, max_relative = 1e-12);
        }
    }

    /// A costly start (a pack settling) is left behind: the estimate follows the recent rate,
    /// where the rate of the whole run so far would be off by the start's share.
    #[test]
    fn a_costly_start_is_left_behind() {
        let mut w = CostWatch::default();
        // The first 0.2 s of computing (200 steps) cover 1 ms; then 100 steps per 10 ms.
        let mut history = vec![(0.1, 0.0005, 100u64), (0.2, 0.001, 200)];
        for k in 1..=4u64 {
            history.push((0.2 + 0.1 * k as f64, 0.001 + 0.01 * k as f64, 200 + 100 * k));
        }
        for (wall, t, steps) in history {
            w.record(wall, t, steps);
        }
        let e = w.estimate(1.0).unwrap();
        // From the reading at 0.3 s on: 10 000 steps per simulated second, 1 ms per step.
        approx::assert_relative_eq!(e.steps_per_simulated_second, 10_000.0, max_relative = 1e-9);
        approx::assert_relative_eq!(e.steps, 600.0 + 10_000.0 * (1.0 - 0.041), max_relative = 1e-9);
        // The whole run's average rate would have said 14 600 steps.
        let average = 600.0 / 0.041;
        assert!(average > 1.4 * e.steps_per_simulated_second);
    }

    /// Said once, then again only when off by more than the revision factor.
    #[test]
    fn revisions_are_said_when_the_estimate_moves() {
        let mut w = CostWatch::default();
        assert!(w.revised(1.0).is_none(), "nothing to say before two readings");
        // A costly start: 1000 steps in the first millisecond.
        w.record(0.1, 0.0005, 500);
        w.record(0.2, 0.001, 1000);
        assert!(w.revised(1.0).is_none(), "the first estimate is not steady yet");
        // Then 100 steps per 10 ms.
        w.record(0.3, 0.011, 1100);
        w.record(0.4, 0.021, 1200);
        assert!(w.revised(1.0).is_none(), "not steady: the previous estimate still held the start");
        w.record(0.5, 0.031, 1300);
        w.record(0.6, 0.041, 1400);
        let first = w.revised(1.0).expect("a steady estimate is said");
        approx::assert_relative_eq!(first.steps, 1400.0 + 10_000.0 * (1.0 - 0.041), max_relative = 1e-9);
        w.record(0.7, 0.051, 1500);
        assert!(w.revised(1.0).is_none(), "unchanged");
        // The run slows down twentyfold, for long enough to be steady.
        for k in 1..=12u64 {
            w.record(0.7 + 0.1 * k as f64, 0.051 + 0.0005 * k as f64, 1500 + 100 * k);
            if let Some(again) = w.revised(1.0) {
                assert!(again.steps > REVISION_FACTOR * first.steps, "{again:?}");
                return;
            }
        }
        panic!("a twentyfold slower run was never said");
    }

    /// No estimate from a run that has not moved (no simulated time or no steps between the
    /// readings), rather than an infinite or NaN one.
    #[test]
    fn a_run_that_has_not_moved_has_no_estimate() {
        let mut w = CostWatch::default();
        w.record(0.1, 0.0, 0);
        w.record(0.2, 0.0, 0);
        assert!(w.estimate(1.0).is_none());
        let mut w = CostWatch::default();
        w.record(0.1, 0.01, 10);
        assert!(w.estimate(1.0).is_none(), "one reading");
    }
}
