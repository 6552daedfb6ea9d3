//! How a command shows that it is working, so that none is silent for more than a few seconds:
//! one run says early what it will cost and shows its progress ([`watched`]); a study shows how
//! many of its runs are done ([`Work`]). On a terminal these are progress bars; off a terminal
//! (a script, a batch job, a log) they are lines on standard error.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

use lpc_damper::model::{cost, Model, ModelError, Progress, RunOptions};
use lpc_damper::run::Run;
use lpc_damper::scene::{human, Scene};

use crate::exit::Result;

/// How long a run goes before its progress bar is shown.
const QUIET_FOR_S: f64 = 1.0;
/// When a study off a terminal first says how far it is, and how often after that.
const FIRST_BEAT: Duration = Duration::from_secs(1);
const HEARTBEAT: Duration = Duration::from_secs(5);

/// Whether standard error is a terminal (progress bars) or not (lines).
fn on_terminal() -> bool {
    std::io::stderr().is_terminal()
}

/// `model` on `scene` under `options` (whose progress is set here), the model's error as it is.
/// A run estimated to take a second or more says so early, with its estimated cost ([`cost`],
/// revised when it moves by more than twofold), and shows a progress bar (on a terminal) once
/// it has run for [`QUIET_FOR_S`].
pub fn watched_model(model: Model, scene: &Scene, options: RunOptions) -> std::result::Result<Run, ModelError> {
    let progress = Progress::default();
    let options = RunOptions { progress: Some(&progress), ..options };
    let unit = model.step_unit();
    let done = AtomicBool::new(false);
    let watch = || {
        let bar = if on_terminal() { ProgressBar::new(1000) } else { ProgressBar::hidden() };
        let shown = std::cell::Cell::new(false);
        let say = |said: cost::Said| {
            // Said on a terminal or in a log: what the whole run will cost.
            let e = said.estimate;
            let line = format!(
                "{model}: `{}` {}: about {} {unit} and {:.1} s of computing in all, at its recent rate (t = {:.3e} of {} s \
                     after {:.2} s and {} {unit}; lately {} {unit} per simulated second, {:.2e} s each; a run's cost can change \
                     tenfold as it goes, so this is revised when it moves twofold; --max-steps and --max-wall-time bound it)",
                scene.name,
                if said.revision { "revised" } else { "is a long run" },
                human(e.steps.round()),
                e.seconds,
                said.t,
                human(scene.horizon),
                said.elapsed_s,
                said.steps,
                human(e.steps_per_simulated_second.round()),
                e.seconds_per_step,
            );
            if bar.is_hidden() || !shown.get() {
                eprintln!("{line}");
            } else {
                bar.println(line);
            }
        };
        let tick = |elapsed_s: f64, t: f64, steps: u64| {
            if elapsed_s < QUIET_FOR_S {
                return;
            }
            if !shown.replace(true) {
                let template = format!("{model} [{{bar:30}}] {{msg}} ({{elapsed}}, about {{eta}} to go)");
                bar.set_style(ProgressStyle::with_template(&template).expect("valid template"));
            }
            bar.set_position((1000.0 * t / scene.horizon).clamp(0.0, 1000.0) as u64);
            bar.set_message(format!("t = {t:.3e} of {:.3e} s, {steps} {unit}", scene.horizon));
        };
        cost::watch(&progress, scene.horizon, &done, say, tick);
        bar.finish_and_clear();
    };
    beside_watcher(&done, watch, || model.simulate(scene, &options))
}

/// Runs `run` beside `watch` (on its own thread, which watches until `done`) and ends the watch
/// when `run` returns or panics: the scope waits for the watcher before a panic goes on, so a
/// watch left running would hang the command.
fn beside_watcher<R>(done: &AtomicBool, watch: impl FnOnce() + Send, run: impl FnOnce() -> R) -> R {
    /// Ends the watch when dropped, as the run ends either way.
    struct RunEnded<'a> {
        done: &'a AtomicBool,
        watcher: std::thread::Thread,
    }
    impl Drop for RunEnded<'_> {
        fn drop(&mut self) {
            self.done.store(true, Ordering::Relaxed);
            self.watcher.unpark();
        }
    }
    std::thread::scope(|s| {
        let watcher = s.spawn(watch);
        let _ended = RunEnded { done, watcher: watcher.thread().clone() };
        run()
    })
}

/// [`watched_model`], its error as the command's.
pub fn watched(model: Model, scene: &Scene, options: RunOptions) -> Result<Run> {
    Ok(watched_model(model, scene, options)?)
}

/// What the heartbeat of a study shares with it.
struct Shared {
    label: String,
    total: Option<u64>,
    start: Instant,
    done: AtomicU64,
    finished: Mutex<bool>,
    wake: Condvar,
}

impl Shared {
    /// `sweep: 12 of 40 done after 31 s; about 72 s to go`.
    fn line(&self) -> String {
        let done = self.done.load(Ordering::Relaxed);
        let elapsed = self.start.elapsed().as_secs_f64();
        let mut line = match self.total {
            Some(total) => format!("{}: {done} of {total} done after {elapsed:.0} s", self.label),
            None => format!("{}: {done} done after {elapsed:.0} s", self.label),
        };
        if let (Some(total), true) = (self.total, done > 0) {
            let left = elapsed / done as f64 * total.saturating_sub(done) as f64;
            line += &format!("; about {left:.0} s to go at that rate");
        }
        line
    }
}

/// The progress of a study's runs: a bar on a terminal; off one, a line after [`FIRST_BEAT`]
/// and every [`HEARTBEAT`] after that.
pub struct Work {
    bar: ProgressBar,
    shared: Arc<Shared>,
    heartbeat: Option<std::thread::JoinHandle<()>>,
}

impl Work {
    /// Work of `total` runs (`None`: not known in advance), called `label`.
    pub fn new(total: Option<usize>, label: &str) -> Self {
        let shared = Arc::new(Shared {
            label: label.to_string(),
            total: total.map(|t| t as u64),
            start: Instant::now(),
            done: AtomicU64::new(0),
            finished: Mutex::new(false),
            wake: Condvar::new(),
        });
        if on_terminal() {
            let bar = match total {
                Some(t) => {
                    let bar = ProgressBar::new(t as u64);
                    bar.set_style(
                        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} ({elapsed}, about {eta} to go)")
                            .expect("valid template"),
                    );
                    bar
                }
                None => {
                    let bar = ProgressBar::no_length();
                    bar.set_style(ProgressStyle::with_template("{msg} {pos} ({elapsed})").expect("valid template"));
                    bar
                }
            };
            bar.set_message(label.to_string());
            // The elapsed time moves even while a long run keeps the count still.
            bar.enable_steady_tick(Duration::from_secs(1));
            return Work { bar, shared, heartbeat: None };
        }
        let beat = Arc::clone(&shared);
        let heartbeat = std::thread::spawn(move || {
            let mut finished = beat.finished.lock().expect("not poisoned");
            let mut next = FIRST_BEAT;
            loop {
                let (guard, wait) = beat.wake.wait_timeout(finished, next).expect("not poisoned");
                next = HEARTBEAT;
                finished = guard;
                if *finished {
                    return;
                }
                if wait.timed_out() {
                    eprintln!("{}", beat.line());
                }
            }
        });
        Work { bar: ProgressBar::hidden(), shared, heartbeat: Some(heartbeat) }
    }

    /// One more run done.
    pub fn inc(&self) {
        self.shared.done.fetch_add(1, Ordering::Relaxed);
        self.bar.inc(1);
    }

    /// The work is over: the bar is cleared, the heartbeat stops.
    pub fn finish(mut self) {
        self.stop();
    }

    fn stop(&mut self) {
        self.bar.finish_and_clear();
        *self.shared.finished.lock().expect("not poisoned") = true;
        self.shared.wake.notify_all();
        if let Some(h) = self.heartbeat.take() {
            let _ = h.join();
        }
    }
}

impl Drop for Work {
    fn drop(&mut self) {
        self.stop();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run that panics ends its watch, and the panic goes on instead of the command hanging.
    #[test]
    fn a_run_that_panics_ends_its_watch() {
        let (sender, receiver) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let done = AtomicBool::new(false);
            let watch = || {
                while !done.load(Ordering::Relaxed) {
                    std::thread::park_timeout(Duration::from_millis(10));
                }
            };
            let run = || -> () { panic!("a model's bug") };
            let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| beside_watcher(&done, watch, run)));
            sender.send(outcome.is_err()).ok();
        });
        // A watch left running never lets the scope end: no answer comes at all.
        assert_eq!(receiver.recv_timeout(Duration::from_secs(60)), Ok(true));
    }
}
