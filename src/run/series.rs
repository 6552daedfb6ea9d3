//! Where a model writes its motion: sample by sample into a [`Recorder`], which keeps the
//! series when asked (thinned when it would not fit in memory) and always tallies the motion
//! metrics, so a run that keeps no series has the same metrics bit for bit.

use super::memory::{series_every, MAX_SERIES_EVERY};
use super::tally::{MotionMetrics, SampleTally};
use crate::scene::Scene;

/// Series sampled every `sample_dt` from `t = 0` to the horizon (inclusive where it falls on a
/// sample): the time, the frame's displacement, velocity and acceleration, and every ball's
/// centre and velocity.
///
/// The columns live in one allocation, each `capacity` long, so that a run's series costs one
/// allocation however many balls it has (and a run repeated in one process reuses it rather
/// than asking the system for fresh pages each time).
#[derive(Debug, Clone, Default)]
pub struct Series {
    /// Column `c` is `data[c * capacity..c * capacity + len]`.
    data: Vec<f64>,
    capacity: usize,
    len: usize,
    balls: usize,
    /// The series keeps every `every`-th sample of the run (1, or 0 for a series built by
    /// hand: all of them): more when the whole series would not fit in memory
    /// ([`series_every`]). The metrics always see every sample.
    pub every: usize,
    /// Each kept sample's balls' centres across the motion, `y1, z1, y2, z2, ...` sample after
    /// sample; empty unless the model moves balls across the motion (the spatial paths of
    /// the Rapier model and the reference).
    across: Vec<f64>,
    /// Each kept sample's floors, `u1, ..., un, v1, ..., vn, a1, ..., an` sample after sample
    /// (displacements and velocities relative to the ground, absolute accelerations without
    /// impulses); empty unless the scene has a structure of several storeys or a moving ground
    /// ([`crate::scene::Structure`]).
    floors: Vec<f64>,
    /// The number of floors in `floors`.
    floor_count: usize,
}

/// Columns before the balls': `t`, `xs`, `vs`, `a`.
const FRAME_COLUMNS: usize = 4;

impl PartialEq for Series {
    fn eq(&self, other: &Self) -> bool {
        self.len == other.len
            && self.balls == other.balls
            && self.every == other.every
            && (0..self.columns()).all(|c| self.column(c) == other.column(c))
            && self.across == other.across
            && self.floors == other.floors
    }
}

impl Series {
    /// An empty series with room for `samples` samples of `balls` balls.
    pub fn with_capacity(balls: usize, samples: usize) -> Self {
        Series {
            data: vec![0.0; (FRAME_COLUMNS + 2 * balls) * samples],
            capacity: samples,
            len: 0,
            balls,
            every: 1,
            across: vec![],
            floors: vec![],
            floor_count: 0,
        }
    }
    /// A series of the given columns (all of one length): times, the frame's displacement,
    /// velocity and acceleration, and each ball's centre and velocity.
    pub fn from_columns(t: Vec<f64>, xs: Vec<f64>, vs: Vec<f64>, a: Vec<f64>, x: Vec<Vec<f64>>, v: Vec<Vec<f64>>) -> Self {
        let mut s = Series::with_capacity(x.len(), t.len());
        s.len = t.len();
        let columns = [t, xs, vs, a].into_iter().chain(x).chain(v);
        for (c, column) in columns.enumerate() {
            assert_eq!(column.len(), s.len, "every column of a series has one length");
            s.column_mut(c).copy_from_slice(&column);
        }
        s
    }
    /// This series with the balls' centres across the motion: `across` holds, sample after
    /// sample, `y1, z1, y2, z2, ...` (as [`Series::across`] reads them).
    pub fn with_across(mut self, across: Vec<f64>) -> Self {
        assert_eq!(across.len(), 2 * self.balls * self.len, "every sample has each ball's y and z");
        self.across = across;
        self
    }
    /// This series with a structure's `count` floors: `floors` holds, sample after sample,
    /// `u1, ..., un, v1, ..., vn, a1, ..., an` (as [`Series::floor`] reads them).
    pub fn with_floors(mut self, count: usize, floors: Vec<f64>) -> Self {
        assert_eq!(floors.len(), 3 * count * self.len, "every sample has each floor's u, v and a");
        self.floor_count = count;
        self.floors = floors;
        self
    }
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.len
    }
    /// True when no sample was taken.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
    /// Number of balls.
    pub fn balls(&self) -> usize {
        self.balls
    }
    fn columns(&self) -> usize {
        FRAME_COLUMNS + 2 * self.balls
    }
    fn column(&self, c: usize) -> &[f64] {
        &self.data[c * self.capacity..c * self.capacity + self.len]
    }
    fn column_mut(&mut self, c: usize) -> &mut [f64] {
        &mut self.data[c * self.capacity..c * self.capacity + self.len]
    }
    /// Sample times, s.
    pub fn t(&self) -> &[f64] {
        self.column(0)
    }
    /// Frame displacement, m.
    pub fn xs(&self) -> &[f64] {
        self.column(1)
    }
    /// Frame velocity, m/s.
    pub fn vs(&self) -> &[f64] {
        self.column(2)
    }
    /// Frame acceleration without impulses and contact forces, `(Fe - cs vs - ks xs)/ms`
    /// ([`crate::scene::Scene::frame_acceleration`]), m/s^2.
    pub fn a(&self) -> &[f64] {
        self.column(3)
    }
    /// The column of ball `i`'s centre: every ball's centres come first, then their velocities.
    fn x_column(&self, i: usize) -> usize {
        FRAME_COLUMNS + i
    }
    /// The column of ball `i`'s velocity.
    fn v_column(&self, i: usize) -> usize {
        FRAME_COLUMNS + self.balls + i
    }
    /// Ball `i`'s centre, m.
    pub fn x(&self, i: usize) -> &[f64] {
        self.column(self.x_column(i))
    }
    /// Ball `i`'s velocity, m/s.
    pub fn v(&self, i: usize) -> &[f64] {
        self.column(self.v_column(i))
    }
    /// Whether the series has the balls' centres across the motion ([`Series::across`]).
    pub fn has_across(&self) -> bool {
        !self.across.is_empty()
    }
    /// Ball `i`'s centre across the motion at sample `k`, `[y, z]`, m (the container's axis at
    /// 0); `[0, 0]` when the series has none.
    pub fn across(&self, i: usize, k: usize) -> [f64; 2] {
        let at = 2 * (k * self.balls + i);
        match self.across.get(at..at + 2) {
            Some(yz) => [yz[0], yz[1]],
            None => [0.0; 2],
        }
    }
    /// The number of floors whose motion the series holds (0 without a structure).
    pub fn floor_count(&self) -> usize {
        self.floor_count
    }
    /// Floor `i`'s (0 at the bottom) displacement and velocity relative to the ground, and its
    /// absolute acceleration without impulses, at kept sample `k` (m, m/s, m/s^2); `None` when
    /// the series has no floors.
    pub fn floor(&self, i: usize, k: usize) -> Option<(f64, f64, f64)> {
        let n = self.floor_count;
        if i >= n {
            return None;
        }
        let at = 3 * n * k;
        self.floors.get(at..at + 3 * n).map(|z| (z[i], z[n + i], z[2 * n + i]))
    }
    /// The balls' centres across the motion, moved out: `y1, z1, y2, z2, ...` for each kept
    /// sample in turn (empty when the series has none).
    pub fn take_across(&mut self) -> Vec<f64> {
        std::mem::take(&mut self.across)
    }
    /// Every column, as vectors: `t`, `xs`, `vs`, `a`, then every ball's `x`, then every ball's `v`.
    pub fn into_columns(self) -> Vec<Vec<f64>> {
        (0..self.columns()).map(|c| self.column(c).to_vec()).collect()
    }
    /// The columns as one buffer, moved out: `(data, capacity, len, columns)`, column `c` being
    /// `data[c * capacity..c * capacity + len]` (`t`, `xs`, `vs`, `a`, then every ball's `x`, then
    /// every ball's `v`). For handing the whole series to another owner (NumPy) without a copy.
    pub fn into_buffer(self) -> (Vec<f64>, usize, usize, usize) {
        let columns = self.columns();
        (self.data, self.capacity, self.len, columns)
    }
    /// Makes room for `more` samples (moving the columns apart when the capacity grows).
    fn reserve(&mut self, more: usize) {
        let need = self.len + more;
        if need <= self.capacity {
            return;
        }
        let capacity = need.max(2 * self.capacity);
        let mut data = vec![0.0; self.columns() * capacity];
        for c in 0..self.columns() {
            data[c * capacity..c * capacity + self.len].copy_from_slice(self.column(c));
        }
        (self.data, self.capacity) = (data, capacity);
    }
    /// Appends one sample.
    #[inline]
    fn push(&mut self, t: f64, xs: f64, vs: f64, a: f64, mut ball: impl FnMut(usize) -> (f64, f64)) {
        self.reserve(1);
        let (k, cap) = (self.len, self.capacity);
        for (c, value) in [t, xs, vs, a].into_iter().enumerate() {
            self.data[c * cap + k] = value;
        }
        for i in 0..self.balls {
            let (x, v) = ball(i);
            self.data[(FRAME_COLUMNS + i) * cap + k] = x;
            self.data[(FRAME_COLUMNS + self.balls + i) * cap + k] = v;
        }
        self.len += 1;
    }
    /// Appends the samples `first, first + 1, ...` of an interval a column at a time: the frame
    /// at `frame[j]` with acceleration `accelerations[j]`, ball `i` on `paths[i]`.
    fn write_interval(&mut self, first: usize, dt: f64, frame: &[(f64, f64)], accelerations: &[f64], paths: &[BallPath]) {
        let count = frame.len();
        self.reserve(count);
        for (j, t) in self.spare(0, count).iter_mut().enumerate() {
            *t = (first + j) as f64 * dt;
        }
        for (x, f) in self.spare(1, count).iter_mut().zip(frame) {
            *x = f.0;
        }
        for (v, f) in self.spare(2, count).iter_mut().zip(frame) {
            *v = f.1;
        }
        self.spare(3, count).copy_from_slice(accelerations);
        for (i, path) in paths.iter().enumerate() {
            match *path {
                BallPath::Free { x, v, t } => {
                    let (times, positions) = self.time_and_column(self.x_column(i), count);
                    for (out, &ts) in positions.iter_mut().zip(times) {
                        *out = x + v * (ts - t);
                    }
                    self.spare(self.v_column(i), count).fill(v);
                }
                BallPath::Held { offset } => {
                    for (out, f) in self.spare(self.x_column(i), count).iter_mut().zip(frame) {
                        *out = f.0 + offset;
                    }
                    for (out, f) in self.spare(self.v_column(i), count).iter_mut().zip(frame) {
                        *out = f.1;
                    }
                }
            }
        }
        self.len += count;
    }
    /// The free balls of the last `count` samples moved into the ground's frame: less the
    /// ground's displacement and velocity at each (a held ball is written from the frame,
    /// already in it).
    fn shift_free_balls(&mut self, count: usize, ground: &[(f64, f64)], paths: &[BallPath]) {
        let (cap, start) = (self.capacity, self.len - count);
        for (i, path) in paths.iter().enumerate() {
            if let BallPath::Free { .. } = path {
                let (xc, vc) = (self.x_column(i), self.v_column(i));
                for (j, &(xg, vg)) in ground.iter().enumerate().take(count) {
                    self.data[xc * cap + start + j] -= xg;
                    self.data[vc * cap + start + j] -= vg;
                }
            }
        }
    }
    /// The next `count` times, written already, and the next `count` entries of column `c`
    /// (after the time column), to be written.
    fn time_and_column(&mut self, c: usize, count: usize) -> (&[f64], &mut [f64]) {
        let (times, rest) = self.data.split_at_mut(c * self.capacity);
        (&times[self.len..self.len + count], &mut rest[self.len..self.len + count])
    }
    /// The next `count` entries of column `c`, to be written (the caller then sets `len`).
    fn spare(&mut self, c: usize, count: usize) -> &mut [f64] {
        let start = c * self.capacity + self.len;
        &mut self.data[start..start + count]
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

/// How a ball moves over an interval between events: in free flight from `x` at time `t`, or
/// held by the frame at `offset` from it (moving with it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BallPath {
    /// At `x + v (ts - t)`, velocity `v`.
    Free {
        /// Position at `t`, m.
        x: f64,
        /// Velocity, m/s.
        v: f64,
        /// The time of `x`, s.
        t: f64,
    },
    /// At `xs + offset`, the frame's velocity.
    Held {
        /// Centre less the frame's displacement, m.
        offset: f64,
    },
}

impl BallPath {
    /// Position and velocity at `ts`, the frame being at `(xs, vs)`.
    #[inline]
    pub fn at(&self, ts: f64, xs: f64, vs: f64) -> (f64, f64) {
        match *self {
            BallPath::Free { x, v, t } => (x + v * (ts - t), v),
            BallPath::Held { offset } => (xs + offset, vs),
        }
    }
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
    /// Whether the series kept the last sample taken (for [`Recorder::sample_across`]).
    kept_last: bool,
    masses: Vec<f64>,
    /// Scratch: the frame's acceleration at each sample of an interval.
    accelerations: Vec<f64>,
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
        Recorder {
            series,
            taken: 0,
            tally: Some(SampleTally::new(scene)),
            kept_last: false,
            masses: scene.balls.iter().map(|b| b.mass).collect(),
            accelerations: Vec::new(),
        }
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
        let frame_energy = |t: f64, xs: f64, vs: f64| scene.frame_energy(t, xs, vs);
        self.sample_with(t, xs, vs, a, frame_energy, ball);
    }
    /// [`Recorder::sample`] with the frame's acceleration `a` and its energy given.
    #[inline]
    fn sample_with(
        &mut self,
        t: f64,
        xs: f64,
        vs: f64,
        a: f64,
        frame_energy: impl Fn(f64, f64, f64) -> f64,
        ball: impl Fn(usize) -> (f64, f64),
    ) {
        let wants_energy = self.tally.as_ref().is_some_and(|t| t.wants_energy());
        let mut kinetic = 0.0;
        let kept = self.series.as_mut().filter(|s| self.taken.is_multiple_of(s.every.max(1)));
        self.kept_last = kept.is_some();
        self.taken += 1;
        if let Some(s) = kept {
            s.push(t, xs, vs, a, |i| {
                let (x, v) = ball(i);
                kinetic += 0.5 * self.masses[i] * v * v;
                (x, v)
            });
        } else if wants_energy {
            for (i, m) in self.masses.iter().enumerate() {
                let v = ball(i).1;
                kinetic += 0.5 * m * v * v;
            }
        }
        let energy = if wants_energy { frame_energy(t, xs, vs) + kinetic } else { 0.0 };
        if let Some(tally) = &mut self.tally {
            tally.add(t, xs, a, energy);
        }
    }
    /// The sample at `t` of a scene with a structure, in the ground's frame as
    /// [`Recorder::sample_interval_with_floors`] writes it: the floors at `u` and moving at `v`
    /// relative to the ground, the ground at `(xg, vg)`, and each ball at its inertial `(x, v)`
    /// from `ball(i)`.
    pub fn sample_floors(
        &mut self,
        scene: &Scene,
        t: f64,
        (u, v): (&[f64], &[f64]),
        (xg, vg): (f64, f64),
        ball: impl Fn(usize) -> (f64, f64),
    ) {
        let s = scene.structure.as_deref().expect("floors come with a structure");
        let a = scene.floor_accelerations(t, u, v);
        if let Some(series) = &mut self.series {
            series.floor_count = s.floors();
            if self.taken.is_multiple_of(series.every.max(1)) {
                series.floors.extend_from_slice(u);
                series.floors.extend_from_slice(v);
                series.floors.extend_from_slice(&a);
            }
        }
        let energy = s.energy(u, v, 0.0);
        let d = s.floor;
        self.sample_with(
            t,
            u[d],
            v[d],
            a[d],
            |_, _, _| energy,
            |i| {
                let (x, w) = ball(i);
                (x - xg, w - vg)
            },
        );
        if let Some(tally) = &mut self.tally {
            tally.add_floors(t, u, &a);
        }
    }
    /// The sample at `t` of balls that move in space: the frame's state, and each ball's centre
    /// and velocity `[x, y, z]` from `ball(i)` (`x` as [`Recorder::sample`] takes it, `y` and
    /// `z` in the container's frame). The energy the dissipation times read is then every
    /// ball's whole kinetic energy (without spin) and its height energy
    /// ([`Scene::height_energy`]).
    pub fn sample_in_space(&mut self, scene: &Scene, t: f64, xs: f64, vs: f64, ball: impl Fn(usize) -> ([f64; 3], [f64; 3])) {
        let a = scene.frame_acceleration(t, xs, vs);
        let wants_energy = self.tally.as_ref().is_some_and(|t| t.wants_energy());
        // What `sample_with` adds to the kinetic energy along the motion.
        let beyond_along: f64 = if wants_energy {
            (0..scene.balls.len())
                .map(|i| {
                    let (p, v) = ball(i);
                    0.5 * self.masses[i] * (v[1] * v[1] + v[2] * v[2]) + scene.height_energy(i, p)
                })
                .sum()
        } else {
            0.0
        };
        let frame_energy = |t: f64, xs: f64, vs: f64| scene.frame_energy(t, xs, vs) + beyond_along;
        self.sample_with(t, xs, vs, a, frame_energy, |i| {
            let (p, v) = ball(i);
            (p[0], v[0])
        });
        self.sample_across(|i| {
            let p = ball(i).0;
            [p[1], p[2]]
        });
    }
    /// The sample at `t` of balls that move in space on a structure's floor: the floors as
    /// [`Recorder::sample_floors`] takes them, and each ball's inertial centre and velocity
    /// `[x, y, z]` from `ball(i)` (`y` and `z` in the container's frame).
    pub fn sample_floors_in_space(
        &mut self,
        scene: &Scene,
        t: f64,
        floors: (&[f64], &[f64]),
        ground: (f64, f64),
        ball: impl Fn(usize) -> ([f64; 3], [f64; 3]),
    ) {
        self.sample_floors(scene, t, floors, ground, |i| {
            let (p, v) = ball(i);
            (p[0], v[0])
        });
        self.sample_across(|i| {
            let p = ball(i).0;
            [p[1], p[2]]
        });
    }
    /// The balls' centres across the motion, `[y, z]` from `across(i)`, at the sample
    /// [`Recorder::sample`] has just taken (kept with it, or not at all).
    fn sample_across(&mut self, across: impl Fn(usize) -> [f64; 2]) {
        if let (true, Some(s)) = (self.kept_last, &mut self.series) {
            // Room for every sample at once: growing by doubling would copy the whole of a
            // long run's positions several times over.
            if s.across.is_empty() {
                s.across.reserve_exact(2 * s.balls * s.capacity);
            }
            s.across.extend((0..s.balls).flat_map(across));
        }
    }
    /// Samples `first, first + 1, ...` (at `k sample_dt`) of an interval in which the frame is
    /// at `frame[j]` at sample `first + j` and each ball `i` follows `paths[i]`: the same values
    /// as [`Recorder::sample`] at each, written a column at a time unless the series is thinned.
    pub fn sample_interval(&mut self, scene: &Scene, first: usize, frame: &[(f64, f64)], paths: &[BallPath]) {
        self.sample_interval_with_floors(scene, first, frame, &[], &[], paths);
    }
    /// [`Recorder::sample_interval`] for a scene with a structure, in the ground's frame:
    /// `frame` is the carrying floor relative to the ground, `floors` each sample's floors
    /// relative to it (`u1, ..., un, v1, ..., vn`, sample after sample), from which the
    /// carrying floor's (absolute) acceleration and the structure's energy come, and `ground`
    /// the ground's displacement and velocity at each sample (empty when it is still), taken
    /// from the free balls' positions and velocities.
    pub fn sample_interval_with_floors(
        &mut self,
        scene: &Scene,
        first: usize,
        frame: &[(f64, f64)],
        floors: &[f64],
        ground: &[(f64, f64)],
        paths: &[BallPath],
    ) {
        let in_ground_frame = |j: usize, path: &BallPath, (x, v): (f64, f64)| match (path, ground.get(j)) {
            (BallPath::Free { .. }, Some(&(xg, vg))) => (x - xg, v - vg),
            _ => (x, v),
        };
        let dt = scene.sample_dt;
        let time = |j: usize| (first + j) as f64 * dt;
        let structure = scene.structure.as_deref().filter(|_| !floors.is_empty());
        let width = structure.map_or(0, |s| 2 * s.floors());
        let floor_state = |j: usize| floors[j * width..(j + 1) * width].split_at(width / 2);
        // The carrying floor's acceleration and the structure's energy (in free vibration,
        // where the ground is still) at sample `j`.
        let structure_acceleration = |j: usize| {
            let s = structure.expect("floors come with a structure");
            let (u, v) = floor_state(j);
            scene.floor_accelerations(time(j), u, v)[s.floor]
        };
        if let (Some(s), Some(series)) = (structure, &mut self.series) {
            series.floor_count = s.floors();
            let every = series.every.max(1);
            for j in 0..frame.len() {
                if (self.taken + j).is_multiple_of(every) {
                    let (u, v) = floor_state(j);
                    series.floors.extend_from_slice(&floors[j * width..(j + 1) * width]);
                    series.floors.extend(scene.floor_accelerations(time(j), u, v));
                }
            }
        }
        if self.series.as_ref().is_some_and(|s| s.every > 1) {
            for (j, &(xs, vs)) in frame.iter().enumerate() {
                let ts = time(j);
                match structure {
                    None => self.sample(scene, ts, xs, vs, |i| paths[i].at(ts, xs, vs)),
                    Some(s) => {
                        let (u, v) = floor_state(j);
                        let energy = s.energy(u, v, 0.0);
                        let ball = |i: usize| in_ground_frame(j, &paths[i], paths[i].at(ts, xs, vs));
                        let a = scene.floor_accelerations(ts, u, v);
                        self.sample_with(ts, xs, vs, a[s.floor], |_, _, _| energy, ball);
                        if let Some(tally) = &mut self.tally {
                            tally.add_floors(ts, u, &a);
                        }
                    }
                }
            }
            return;
        }
        let count = frame.len();
        let mut accelerations = std::mem::take(&mut self.accelerations);
        accelerations.clear();
        match (scene.frame, scene.forcing) {
            _ if structure.is_some() => accelerations.extend((0..count).map(structure_acceleration)),
            // Free vibration: the acceleration needs no time (a loop the compiler vectorises).
            (Some(f), None) => accelerations.extend(frame.iter().map(|&(xs, vs)| f.acceleration(xs, vs))),
            _ => accelerations.extend(frame.iter().enumerate().map(|(j, &(xs, vs))| scene.frame_acceleration(time(j), xs, vs))),
        }
        if let Some(s) = &mut self.series {
            s.write_interval(first, dt, frame, &accelerations, paths);
            if !ground.is_empty() {
                s.shift_free_balls(count, ground, paths);
            }
        }
        if let Some(tally) = &mut self.tally {
            let wants_energy = tally.wants_energy();
            // The balls' kinetic energy, summed ball by ball in order as `sample` does so that
            // the bits agree; the same at every sample when no ball moves with the frame.
            let kinetic = |vs: f64| {
                let mut kinetic = 0.0;
                for (path, m) in paths.iter().zip(&self.masses) {
                    let v = match *path {
                        BallPath::Free { v, .. } => v,
                        BallPath::Held { .. } => vs,
                    };
                    kinetic += 0.5 * m * v * v;
                }
                kinetic
            };
            let all_free = paths.iter().all(|p| matches!(p, BallPath::Free { .. }));
            let free_kinetic = if wants_energy && all_free { kinetic(0.0) } else { 0.0 };
            let frame_energy = |j: usize, ts: f64, xs: f64, vs: f64| match structure {
                None => scene.frame_energy(ts, xs, vs),
                Some(s) => {
                    let (u, v) = floor_state(j);
                    s.energy(u, v, 0.0)
                }
            };
            for (j, (&(xs, vs), &a)) in frame.iter().zip(&accelerations).enumerate() {
                let ts = time(j);
                let energy = match (wants_energy, all_free) {
                    (false, _) => 0.0,
                    (true, true) => frame_energy(j, ts, xs, vs) + free_kinetic,
                    (true, false) => frame_energy(j, ts, xs, vs) + kinetic(vs),
                };
                tally.add(ts, xs, a, energy);
                if structure.is_some() {
                    let (u, v) = floor_state(j);
                    tally.add_floors(ts, u, &scene.floor_accelerations(ts, u, v));
                }
            }
        }
        self.taken += count;
        self.accelerations = accelerations;
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
            assert_eq!((thin.t()[j], thin.xs()[j], thin.x(2)[j]), (all.t()[k], all.xs()[k], all.x(2)[k]));
        }
        assert_eq!(thin_metrics, all_metrics);
    }
}
