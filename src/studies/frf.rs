//! Frequency response (`lpc frf`): the steady-state amplitude of `xs` against the forcing
//! frequency, with and without the damper, every frequency run in parallel.
//!
//! Steady state is detected from the runs themselves: the peaks of `|xs|` in consecutive
//! forcing periods are grouped in blocks of [`BLOCK_PERIODS`]; the response is steady when the
//! last two blocks' mean peaks agree within [`STEADY_TOLERANCE`] and the last block's peaks
//! spread by no more than twice that. Until then the horizon doubles (up to
//! [`MAX_DOUBLINGS`] times). A response that never settles (impact dampers can respond
//! chaotically near resonance) is reported with `steady = false`; its amplitude is then the
//! largest peak of the last block, the worst case an engineer sizes for. Each frequency also
//! reports how many impacts per forcing period it saw in that last block (two per period is
//! the classic symmetric motion of a one-ball damper).
//!
//! A run that fails (a model stops with its reason, or the reference's postcondition finds a
//! contact it missed) is never read as steady: its frequency carries the error and no
//! amplitude, and the others are still reported.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::model::{Limits, Model, ModelError, RunOptions};
use crate::run::Run;
use crate::scene::Scene;
use crate::studies::ensemble::{Member, Stats};

/// Forcing periods per block of peaks.
pub const BLOCK_PERIODS: usize = 10;
/// Relative agreement of the last two blocks' mean peaks that counts as steady.
pub const STEADY_TOLERANCE: f64 = 0.01;
/// Times the horizon may double while the response is still transient.
pub const MAX_DOUBLINGS: u32 = 3;
/// Samples per forcing period (the peak of a sine sampled so is within 5e-4 of the true one).
pub const SAMPLES_PER_PERIOD: f64 = 100.0;

/// One frequency of the response (the JSON contract of `lpc frf`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrfPoint {
    /// Forcing frequency, Hz.
    pub frequency: f64,
    /// Steady amplitude of `xs` with the damper, m (`None` when its run failed).
    pub amplitude: Option<f64>,
    /// Steady amplitude of `xs` of the bare frame, m (`None` when its run failed).
    pub amplitude_no_damper: Option<f64>,
    /// Whether the response with the damper reached a steady state.
    pub steady: bool,
    /// Whether the bare frame's did.
    pub steady_no_damper: bool,
    /// Simulated time used with the damper, s.
    pub horizon: f64,
    /// Impacts per forcing period with the damper over the measuring window (the last block
    /// of periods).
    pub impacts_per_period: Option<f64>,
    /// Why a run at this frequency failed, when one did.
    pub error: Option<String>,
    /// A structure's every floor's steady amplitude relative to the ground with the damper,
    /// bottom to top, m, read over the window the carrying floor's is (absent for a frame).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floors: Option<Vec<f64>>,
    /// The same without the damper.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floors_no_damper: Option<Vec<f64>>,
}

/// One floor at one frequency of a structure's response (a row of `lpc frf`'s `frf-floors.csv`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FloorAmplitude {
    /// Forcing frequency, Hz.
    pub frequency: f64,
    /// Floor, 1 at the bottom.
    pub floor: usize,
    /// Steady amplitude relative to the ground with the damper, m.
    pub amplitude: Option<f64>,
    /// Without the damper, m.
    pub amplitude_no_damper: Option<f64>,
}

/// The floors of `points`, a row per frequency and floor (empty for a frame).
pub fn floor_rows(points: &[FrfPoint]) -> Vec<FloorAmplitude> {
    let mut rows = Vec::new();
    for p in points {
        let count = p.floors.as_ref().or(p.floors_no_damper.as_ref()).map_or(0, |f| f.len());
        for i in 0..count {
            let at = |f: &Option<Vec<f64>>| f.as_ref().and_then(|f| f.get(i).copied());
            rows.push(FloorAmplitude {
                frequency: p.frequency,
                floor: i + 1,
                amplitude: at(&p.floors),
                amplitude_no_damper: at(&p.floors_no_damper),
            });
        }
    }
    rows
}

/// The steady-state reading of one run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteadyState {
    /// Amplitude, m: the mean peak of the last block when steady, its largest peak otherwise.
    pub amplitude: f64,
    /// Whether the criterion holds.
    pub steady: bool,
    /// Impacts per forcing period over the measuring window.
    pub impacts_per_period: f64,
}

/// Reads the steady amplitude of `run`, forced with period `period`.
pub fn steady_state(run: &Run, period: f64) -> SteadyState {
    steady_reading(run, &period_peaks(run, period), period)
}

/// [`steady_state`] from the run's per-period peaks ([`period_peaks`]).
fn steady_reading(run: &Run, peaks: &[f64], period: f64) -> SteadyState {
    let periods = peaks.len();
    // The measuring window: the last block, or every period when there are too few.
    let window = periods.min(BLOCK_PERIODS);
    let from = (periods - window) as f64 * period;
    let to = periods as f64 * period;
    let impacts = run.impacts.iter().filter(|i| i.t >= from && i.t < to).count();
    let impacts_per_period = if window > 0 { impacts as f64 / window as f64 } else { 0.0 };
    if periods < 2 * BLOCK_PERIODS {
        let amplitude = peaks.iter().fold(0.0, |m: f64, p| m.max(*p));
        return SteadyState { amplitude, steady: false, impacts_per_period };
    }
    let last = &peaks[periods - BLOCK_PERIODS..];
    let before = &peaks[periods - 2 * BLOCK_PERIODS..periods - BLOCK_PERIODS];
    let mean = |b: &[f64]| b.iter().sum::<f64>() / b.len() as f64;
    let (m1, m0) = (mean(last), mean(before));
    let max = last.iter().fold(0.0, |m: f64, p| m.max(*p));
    let min = last.iter().fold(f64::INFINITY, |m: f64, p| m.min(*p));
    let scale = m1.max(f64::MIN_POSITIVE);
    let steady = (m1 - m0).abs() <= STEADY_TOLERANCE * scale && max - min <= 2.0 * STEADY_TOLERANCE * scale;
    SteadyState { amplitude: if steady { m1 } else { max }, steady, impacts_per_period }
}

/// The scene forced at `frequency`, sampled finely enough to read peaks, over at least
/// `2 BLOCK_PERIODS` periods plus three decay times of the bare frame.
pub fn forced_at(scene: &Scene, frequency: f64) -> Scene {
    let mut s = scene.clone();
    let g = s.forcing.as_mut().expect("a forced scene");
    g.frequency = frequency;
    let period = 1.0 / frequency;
    let decay = s.frame.map_or(0.0, |f| if f.damping > 0.0 { 3.0 * 2.0 * f.mass / f.damping } else { 0.0 });
    s.horizon = s.horizon.max(4.0 * BLOCK_PERIODS as f64 * period).max(decay);
    s.sample_dt = s.sample_dt.min(period / SAMPLES_PER_PERIOD);
    s.name = format!("{}[f={} Hz]", scene.name, crate::scene::human(frequency));
    s
}

/// Runs `scene` with `model` until its response is steady (or the horizon has doubled
/// [`MAX_DOUBLINGS`] times), each run within `limits`; returns the reading and the horizon used.
pub fn steady_run(scene: &Scene, model: Model, limits: Limits) -> Result<(SteadyState, f64), ModelError> {
    steady_peaks(scene, model, limits).map(|(reading, horizon, _)| (reading, horizon))
}

/// [`steady_run`], with the per-period peaks of the last two blocks of the last run.
pub fn steady_peaks(scene: &Scene, model: Model, limits: Limits) -> Result<(SteadyState, f64, Vec<f64>), ModelError> {
    steady_runs(scene, model, limits).map(|(reading, horizon, peaks, _)| (reading, horizon, peaks))
}

/// A steady reading, the horizon it took, and each floor's amplitude (empty for a frame).
pub type FloorsReading = (SteadyState, f64, Vec<f64>);

/// [`steady_run`], with every floor's amplitude of a structure (empty for a frame): over the
/// carrying floor's measuring window, each floor's mean peak when the response is steady and
/// its largest otherwise, as for the carrying floor.
pub fn steady_floors(scene: &Scene, model: Model, limits: Limits) -> Result<FloorsReading, ModelError> {
    let period = 1.0 / scene.forcing.expect("a forced scene").frequency;
    let (reading, horizon, _, run) = steady_runs(scene, model, limits)?;
    let s = &run.series;
    let floors = (0..s.floor_count())
        .map(|i| {
            let peaks = peaks_of(&run, period, |k| s.floor(i, k).expect("a structure's series has its floors").0);
            let last = &peaks[peaks.len() - peaks.len().min(BLOCK_PERIODS)..];
            if reading.steady {
                last.iter().sum::<f64>() / last.len() as f64
            } else {
                last.iter().fold(0.0, |m: f64, p| m.max(*p))
            }
        })
        .collect();
    Ok((reading, horizon, floors))
}

/// [`steady_peaks`], with the last run.
fn steady_runs(scene: &Scene, model: Model, limits: Limits) -> Result<(SteadyState, f64, Vec<f64>, Run), ModelError> {
    let period = 1.0 / scene.forcing.expect("a forced scene").frequency;
    let mut s = scene.clone();
    for doubling in 0..=MAX_DOUBLINGS {
        // The horizon and step chosen here (and each doubling) keep the scene file's rules.
        crate::scene::validate_sample_dt(s.horizon, s.sample_dt).map_err(|rule| {
            ModelError::Refused(format!(
                "scene `{}`: reading its steady response needs {} s of motion sampled every {} s: run.sample_dt {rule}",
                s.name,
                crate::scene::human(s.horizon),
                crate::scene::human(s.sample_dt)
            ))
        })?;
        let run = model.simulate(&s, &RunOptions::limited(limits))?;
        let peaks = period_peaks(&run, period);
        let reading = steady_reading(&run, &peaks, period);
        if reading.steady || doubling == MAX_DOUBLINGS {
            let last = peaks[peaks.len().saturating_sub(2 * BLOCK_PERIODS)..].to_vec();
            return Ok((reading, s.horizon, last, run));
        }
        s.horizon *= 2.0;
    }
    unreachable!("the loop returns on its last pass")
}

/// The peak of `|xs|` in each whole forcing period of `run`.
pub fn period_peaks(run: &Run, period: f64) -> Vec<f64> {
    peaks_of(run, period, |k| run.series.xs()[k])
}

/// The peak of `|value(k)|` over the samples `k` of each whole forcing period of `run`.
fn peaks_of(run: &Run, period: f64, value: impl Fn(usize) -> f64) -> Vec<f64> {
    let periods = (run.horizon / period).floor() as usize;
    let mut peaks = vec![0.0f64; periods];
    for (k, t) in run.series.t().iter().enumerate() {
        let j = (t / period) as usize;
        if j < periods {
            peaks[j] = peaks[j].max(value(k).abs());
        }
    }
    peaks
}

/// One frequency of an ensemble's frequency response (`lpc frf --ensemble`): the distribution
/// of the per-period peaks of `|xs|` over the last two blocks of every member, with and
/// without the damper. A response that never settles is described by its spread, not by one
/// peak.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrfBand {
    /// Hz.
    pub frequency: f64,
    /// Members.
    pub members: usize,
    /// Per-period peaks with the damper, m.
    pub amplitude: Stats,
    /// Per-period peaks of the bare frame, m.
    pub amplitude_no_damper: Stats,
    /// Members whose response with the damper was steady.
    pub steady_members: usize,
    /// Impacts per forcing period over the members' last blocks.
    pub impacts_per_period: Stats,
    /// The first member run that failed (its frequency then has no distribution).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// Refuses, with the numbers, an ensemble response whose runs' results (the last blocks'
/// peaks of every member at every frequency, with and without the damper) would not fit in
/// the memory left.
pub fn check_ensemble_memory(members: usize, frequencies: usize) -> Result<(), String> {
    let runs = 2.0 * members as f64 * frequencies as f64;
    let per_run = (std::mem::size_of::<(usize, usize, bool)>()
        + std::mem::size_of::<Result<(Vec<f64>, SteadyState), ModelError>>()
        + 2 * BLOCK_PERIODS * std::mem::size_of::<f64>()) as f64;
    let what = format!("is {members} over {frequencies} frequencies: {} runs whose results", crate::scene::human(runs));
    crate::run::refuse_beyond_memory(runs * per_run, &what, "use fewer members or frequencies")
}

/// The frequency response over `members`: each run per frequency with and without the damper,
/// as [`frf`] runs the nominal scene (the horizon doubling until steady, or to its limit),
/// every run in parallel.
pub fn frf_ensemble(members: &[Member], frequencies: &[f64], model: Model, limits: Limits, progress: &(dyn Fn() + Sync)) -> Vec<FrfBand> {
    let jobs: Vec<(usize, usize, bool)> =
        (0..frequencies.len()).flat_map(|k| (0..members.len()).flat_map(move |m| [(k, m, true), (k, m, false)])).collect();
    let results: Vec<Result<(Vec<f64>, SteadyState), ModelError>> = jobs
        .par_iter()
        .map(|&(k, m, damper)| {
            let scene = &members[m].scene;
            let base = if damper { scene.clone() } else { scene.without_damper() };
            let r = steady_peaks(&forced_at(&base, frequencies[k]), model, limits).map(|(reading, _, peaks)| (peaks, reading));
            progress();
            r
        })
        .collect();
    let per_frequency = 2 * members.len();
    frequencies
        .iter()
        .enumerate()
        .map(|(k, &frequency)| {
            let runs = &results[k * per_frequency..(k + 1) * per_frequency];
            let error = runs.iter().find_map(|r| r.as_ref().err()).map(|e| e.to_string());
            let ok = |damper: bool| runs.iter().skip(if damper { 0 } else { 1 }).step_by(2).filter_map(|r| r.as_ref().ok());
            let pooled = |damper: bool| match error {
                Some(_) => Stats::default(),
                None => Stats::of(ok(damper).flat_map(|(peaks, _)| peaks.iter().map(|&p| Some(p)))),
            };
            FrfBand {
                frequency,
                members: members.len(),
                amplitude: pooled(true),
                amplitude_no_damper: pooled(false),
                steady_members: ok(true).filter(|(_, r)| r.steady).count(),
                impacts_per_period: Stats::of(ok(true).map(|(_, r)| Some(r.impacts_per_period))),
                error,
            }
        })
        .collect()
}

/// Most frequencies one response curve takes.
pub const MAX_FREQUENCIES: usize = 10_000;

/// The rule of a response curve's frequency count (`--steps` of `lpc frf` and `lpc optimize`).
pub fn check_frequency_count(steps: usize) -> Result<(), String> {
    if (1..=MAX_FREQUENCIES).contains(&steps) {
        Ok(())
    } else {
        Err(format!("must lie in 1..={MAX_FREQUENCIES} (got {steps})"))
    }
}

/// `steps` frequencies evenly spaced from `from` to `to` (just `from` when `steps` is 1).
pub fn frequencies(from: f64, to: f64, steps: usize) -> Vec<f64> {
    if steps <= 1 {
        return vec![from];
    }
    (0..steps).map(|k| from + (to - from) * k as f64 / (steps - 1) as f64).collect()
}

/// The frequency response of `scene` (which must be forced) at each frequency, with and
/// without the damper, in parallel, each run within `limits`; `progress` is called after each run. A run that fails
/// leaves its frequency without that amplitude, not steady, with the error.
pub fn frf(scene: &Scene, frequencies: &[f64], model: Model, limits: Limits, progress: &(dyn Fn() + Sync)) -> Vec<FrfPoint> {
    let bare = scene.without_damper();
    let jobs: Vec<(usize, bool)> = (0..frequencies.len()).flat_map(|k| [(k, true), (k, false)]).collect();
    let results: Vec<Result<FloorsReading, ModelError>> = jobs
        .par_iter()
        .map(|&(k, damper)| {
            let base = if damper { scene } else { &bare };
            let r = steady_floors(&forced_at(base, frequencies[k]), model, limits);
            progress();
            r
        })
        .collect();
    frequencies
        .iter()
        .enumerate()
        .map(|(k, &frequency)| {
            let (with, without) = (&results[2 * k], &results[2 * k + 1]);
            let error = [with, without].iter().find_map(|r| r.as_ref().err()).map(|e| e.to_string());
            let floors =
                |r: &Result<(SteadyState, f64, Vec<f64>), ModelError>| r.as_ref().ok().map(|(_, _, f)| f.clone()).filter(|f| !f.is_empty());
            FrfPoint {
                frequency,
                amplitude: with.as_ref().ok().map(|(r, _, _)| r.amplitude),
                amplitude_no_damper: without.as_ref().ok().map(|(r, _, _)| r.amplitude),
                steady: with.as_ref().is_ok_and(|(r, _, _)| r.steady),
                steady_no_damper: without.as_ref().is_ok_and(|(r, _, _)| r.steady),
                horizon: with.as_ref().map_or(0.0, |(_, h, _)| *h),
                impacts_per_period: with.as_ref().ok().map(|(r, _, _)| r.impacts_per_period),
                error,
                floors: floors(with),
                floors_no_damper: floors(without),
            }
        })
        .collect()
}
