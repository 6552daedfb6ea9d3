//! Where a model writes its motion: sample by sample into a [`Recorder`], which keeps the
//! series when asked (thinned when it would not fit in memory) and always tallies the motion
//! metrics, so a run that keeps no series has the same metrics bit for bit.

use super::memory::{series_every, MAX_SERIES_EVERY};
use super::tally::{MotionMetrics, SampleTally};
use crate::scene::Scene;

/// Series sampled every `sample_dt` from `t = 0` to the horizon (inclusive where it falls on a sample).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Series {
    /// s.
    pub t: Vec<f64>,
    /// Frame displacement, m.
    pub xs: Vec<f64>,
    /// Frame velocity, m/s.
    pub vs: Vec<f64>,
    /// Frame acceleration without impulses and contact forces, `(Fe - cs vs - ks xs)/ms`
    /// ([`crate::scene::Scene::frame_acceleration`]), m/s^2.
    pub a: Vec<f64>,
    /// Ball centres, `[ball][sample]`, m.
    pub x: Vec<Vec<f64>>,
    /// Ball velocities, `[ball][sample]`, m/s.
    pub v: Vec<Vec<f64>>,
    /// The series keeps every `every`-th sample of the run (1, or 0 for a series built by
    /// hand: all of them): more when the whole series would not fit in memory
    /// ([`series_every`]). The metrics always see every sample.
    pub every: usize,
}

impl Series {
    /// An empty series with room for `samples` samples of `balls` balls.
    pub fn with_capacity(balls: usize, samples: usize) -> Self {
        Series {
            t: Vec::with_capacity(samples),
            xs: Vec::with_capacity(samples),
            vs: Vec::with_capacity(samples),
            a: Vec::with_capacity(samples),
            x: (0..balls).map(|_| Vec::with_capacity(samples)).collect(),
            v: (0..balls).map(|_| Vec::with_capacity(samples)).collect(),
            every: 1,
        }
    }
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }
    /// True when no sample was taken.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
}

/// What a run keeps of its motion besides the metrics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Record {
    /// The sampled series (`series.csv`, plots, comparisons of trajectories).
    #[default]
    Series,
    /// Nothing but the metrics: a run that feeds only statistics (an ensemble member) builds
    /// no series, so it needs no memory per sample.
    MetricsOnly,
}

/// Where a model writes each sample: into the series when they are kept, and always into the
/// [`SampleTally`], so that the metrics of a run are the same, bit for bit, whether the
/// series was kept or not.
#[derive(Debug, Clone)]
pub struct Recorder {
    series: Option<Series>,
    /// Samples taken so far (kept in the series or not).
    taken: usize,
    /// `None` when the model computes the metrics itself ([`Recorder::untallied`]).
    tally: Option<SampleTally>,
    masses: Vec<f64>,
}

impl Recorder {
    /// A recorder for a run of `scene` that keeps what `record` asks for.
    pub fn new(scene: &Scene, record: Record) -> Self {
        // A run that skipped check_memory and cannot fit thins as far as the rule goes.
        Self::thinned(scene, record, series_every(scene).unwrap_or(MAX_SERIES_EVERY))
    }
    /// [`Recorder::new`] keeping every `every`-th sample in the series.
    fn thinned(scene: &Scene, record: Record, every: usize) -> Self {
        let series = (record == Record::Series)
            .then(|| Series { every, ..Series::with_capacity(scene.balls.len(), scene.sample_count().div_ceil(every)) });
        Recorder { series, taken: 0, tally: Some(SampleTally::new(scene)), masses: scene.balls.iter().map(|b| b.mass).collect() }
    }
    /// This recorder keeping the series only: for a model that computes the metrics itself
    /// (the reference, exactly, in free vibration).
    pub fn untallied(self) -> Self {
        Recorder { tally: None, ..self }
    }
    /// Whether the series is kept.
    pub fn keeps_series(&self) -> bool {
        self.series.is_some()
    }
    /// The sample at `t`: the frame's state, and each ball's `(x, v)` from `ball(i)`. The
    /// acceleration is the one every model reports, [`Scene::frame_acceleration`].
    #[inline]
    pub fn sample(&mut self, scene: &Scene, t: f64, xs: f64, vs: f64, ball: impl Fn(usize) -> (f64, f64)) {
        let a = scene.frame_acceleration(t, xs, vs);
        let wants_energy = self.tally.as_ref().is_some_and(|t| t.wants_energy());
        let mut kinetic = 0.0;
        let kept = self.series.as_mut().filter(|s| self.taken.is_multiple_of(s.every.max(1)));
        self.taken += 1;
        if let Some(s) = kept {
            s.t.push(t);
            s.xs.push(xs);
            s.vs.push(vs);
            s.a.push(a);
            for (i, m) in self.masses.iter().enumerate() {
                let (x, v) = ball(i);
                s.x[i].push(x);
                s.v[i].push(v);
                kinetic += 0.5 * m * v * v;
            }
        } else if wants_energy {
            for (i, m) in self.masses.iter().enumerate() {
                let v = ball(i).1;
                kinetic += 0.5 * m * v * v;
            }
        }
        let energy = if wants_energy { scene.frame_energy(t, xs, vs) + kinetic } else { 0.0 };
        if let Some(tally) = &mut self.tally {
            tally.add(t, xs, a, energy);
        }
    }
    /// The series (empty when not kept) and the metrics tallied at the samples (the default
    /// when untallied).
    pub fn finish(self) -> (Series, MotionMetrics) {
        (self.series.unwrap_or_default(), self.tally.map(|t| t.finish()).unwrap_or_default())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A thinned series keeps samples 0, k, 2k, ... and its metrics are those of every sample.
    #[test]
    fn a_thinned_series_keeps_every_kth_sample_and_all_the_metrics() {
        let scene = crate::scene::load_scene(crate::scene::scenes_dir().join("lpc-lsl.toml")).unwrap();
        let feed = |mut r: Recorder| {
            for k in 0..scene.sample_count() {
                let t = k as f64 * scene.sample_dt;
                let (xs, vs) = (0.01 * (9.0 * t).cos() * (-0.3 * t).exp(), -0.09 * (9.0 * t).sin() * (-0.3 * t).exp());
                r.sample(&scene, t, xs, vs, |i| (0.1 * i as f64 + xs, vs));
            }
            r.finish()
        };
        let (all, all_metrics) = feed(Recorder::thinned(&scene, Record::Series, 1));
        let (thin, thin_metrics) = feed(Recorder::thinned(&scene, Record::Series, 7));
        assert_eq!(thin.every, 7);
        assert_eq!(thin.len(), scene.sample_count().div_ceil(7));
        for (j, k) in (0..all.len()).step_by(7).enumerate() {
            assert_eq!((thin.t[j], thin.xs[j], thin.x[2][j]), (all.t[k], all.xs[k], all.x[2][k]));
        }
        assert_eq!(thin_metrics, all_metrics);
    }
}
