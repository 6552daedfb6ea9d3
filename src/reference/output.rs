//! Output: the frame's samples (stepped by the exact transition matrix, re-anchored to the closed
//! form), the energy account and the finished [`Run`].

use super::*;

/// Samples stepped by the transition matrix between two closed-form evaluations.
pub(super) const REANCHOR: u32 = 32;

/// Where frame sampling stands: the last sample's state (of the departure from the steady
/// response, when forced, with the forcing's phase) and the step matrices of its segment.
#[derive(Debug, Clone, Copy)]
pub(super) struct SampleCursor {
    pub(super) seg_t0: f64,
    pub(super) k: usize,
    /// The state, or the departure from the steady response when forced.
    pub(super) x: f64,
    pub(super) v: f64,
    /// `(sin w ts, cos w ts)` of the forcing's phase at the last sample, when forced.
    pub(super) phase: (f64, f64),
    pub(super) steps: u32,
    pub(super) mass: f64,
    pub(super) transition: [[f64; 2]; 2],
    /// `(sin w dt, cos w dt)`: the forcing's phase turns by this each sample.
    pub(super) turn: (f64, f64),
}

/// The run's samples and metrics: the recorder, the exact tally of a free run, and where the
/// sampling of the frame stands.
pub(super) struct Sampler {
    pub(super) recorder: Recorder,
    /// Exact metrics of a free run (`None` when forced or frameless: read at the samples).
    pub(super) exact: Option<ExactTally>,
    pub(super) next_sample: usize,
    pub(super) sample_count: usize,
    pub(super) cursor: SampleCursor,
    /// Scratch: the frame's state at each sample of an interval, and each ball's path over it.
    frame: Vec<(f64, f64)>,
    /// Scratch: a structure's floors at each sample of an interval (`u1..un, v1..vn` each).
    floors: Vec<f64>,
    /// Scratch: the ground's displacement and velocity at each sample, when it moves.
    ground: Vec<(f64, f64)>,
    paths: Vec<BallPath>,
}

impl Sampler {
    pub(super) fn new(scene: &Scene, record: Record) -> Self {
        // Where its metrics are exact the reference tallies no samples, and takes none unless
        // the series is kept.
        let exact = ExactTally::new(scene);
        let recorder = Recorder::new(scene, record);
        Sampler {
            recorder: if exact.is_some() { recorder.untallied() } else { recorder },
            exact,
            next_sample: 0,
            sample_count: scene.sample_count(),
            cursor: SampleCursor {
                seg_t0: f64::NAN,
                k: 0,
                x: 0.0,
                v: 0.0,
                phase: (0.0, 1.0),
                steps: 0,
                mass: f64::NAN,
                transition: [[0.0; 2]; 2],
                turn: scene.forcing.map_or((0.0, 1.0), |g| (g.omega() * scene.sample_dt).sin_cos()),
            },
            frame: Vec::new(),
            floors: Vec::new(),
            ground: Vec::new(),
            paths: Vec::new(),
        }
    }
}

impl Solver<'_> {
    /// Writes every sample with time `<= until` (strictly before when `inclusive` is false):
    /// the samples of an interval between events, the frame stepped from sample to sample and
    /// the balls on their paths over it.
    pub(super) fn sample_until(&mut self, until: f64, inclusive: bool) {
        // Samples serve the series, or the metrics when they are not exact.
        if !self.sampler.recorder.keeps_series() && self.sampler.exact.is_some() {
            return;
        }
        let dt = self.scene.sample_dt;
        let first = self.sampler.next_sample;
        let mut end = first;
        while end < self.sampler.sample_count {
            let ts = end as f64 * dt;
            if ts > until || (!inclusive && ts == until) {
                break;
            }
            end += 1;
        }
        if end == first {
            return;
        }
        let mut frame = std::mem::take(&mut self.sampler.frame);
        let mut floors = std::mem::take(&mut self.sampler.floors);
        frame.clear();
        floors.clear();
        let mut ground = std::mem::take(&mut self.sampler.ground);
        ground.clear();
        if let Some(storeys) = self.frame.storeys() {
            // A structure: every floor from its closed form at each sample, in the ground's
            // frame (the balls are moved into it by the recorder).
            let n = self.scene.structure.as_ref().map_or(0, |s| s.floors());
            let d = self.scene.structure.as_ref().map_or(0, |s| s.floor);
            for k in first..end {
                let ts = k as f64 * dt;
                let (z, at) = storeys.floors(ts);
                frame.push((z[d], z[n + d]));
                floors.extend_from_slice(&z);
                if storeys.is_driven() {
                    ground.push(at);
                }
            }
        } else if self.has_frame() {
            self.frame_samples(first, end, &mut frame);
        } else {
            frame.resize(end - first, (0.0, 0.0));
        }
        let b = &self.balls;
        self.sampler.paths.clear();
        self.sampler.paths.extend((0..b.n).map(|i| match b.hold[i] {
            Hold::Free => BallPath::Free { x: b.x[i], v: b.v[i], t: self.t },
            _ => BallPath::Held { offset: b.offset[i] },
        }));
        self.sampler.recorder.sample_interval_with_floors(self.scene, first, &frame, &floors, &ground, &self.sampler.paths);
        self.sampler.frame = frame;
        self.sampler.floors = floors;
        self.sampler.ground = ground;
        self.sampler.next_sample = end;
    }

    /// Adds the motion from now to `until` (no event between) to the exact metrics.
    pub(super) fn tally_until(&mut self, until: f64) {
        if self.sampler.exact.is_none() {
            return;
        }
        // The state now is kept by the last event's contact check (`frame_now`); the
        // searches since have evaluated other instants.
        let (xs, vs, _) = self.frame.now(self.t);
        let ends = [(xs, vs), self.frame.state(until)];
        let Some(exact) = &mut self.sampler.exact else { return };
        let free_energy = if exact.wants_energy() {
            (0..self.balls.n)
                .filter(|&i| self.balls.hold[i] == Hold::Free)
                .map(|i| 0.5 * self.balls.mass[i] * self.balls.v[i] * self.balls.v[i])
                .sum()
        } else {
            0.0
        };
        exact.interval(&self.frame.seg, self.t, until, ends, free_energy);
    }

    /// The frame's state at samples `first..end` into `out`: [`Solver::frame_sample`] at each,
    /// with the steps between two anchors taken in one loop.
    fn frame_samples(&mut self, first: usize, end: usize, out: &mut Vec<(f64, f64)>) {
        let dt = self.scene.sample_dt;
        let mut k = first;
        while k < end {
            out.push(self.frame_sample(k, k as f64 * dt));
            k += 1;
            let c = &mut self.sampler.cursor;
            let run = ((REANCHOR - c.steps) as usize).min(end - k);
            let [[a, b], [cc, d]] = c.transition;
            let (mut x, mut v) = (c.x, c.v);
            match &self.frame.seg.forced {
                None => {
                    for _ in 0..run {
                        (x, v) = (a * x + b * v, cc * x + d * v);
                        out.push((x, v));
                    }
                }
                Some(f) => {
                    let ((mut s, mut co), (ts, tc)) = (c.phase, c.turn);
                    let xp = &f.xp;
                    for _ in 0..run {
                        (x, v) = (a * x + b * v, cc * x + d * v);
                        (s, co) = (s * tc + co * ts, co * tc - s * ts);
                        out.push((x + (xp.sin * s + xp.cos * co), v + xp.omega * (xp.sin * co - xp.cos * s)));
                    }
                    c.phase = (s, co);
                }
            }
            (c.x, c.v) = (x, v);
            c.steps += run as u32;
            k += run;
            c.k = k - 1;
        }
    }

    /// The frame's state at sample `k` (time `ts`): one step of the exact transition matrix
    /// from the previous sample when it lies in the same segment (and, when forced, the
    /// forcing's phase turned by its step), the closed form every [`REANCHOR`] samples so
    /// that round-off cannot drift. No sample but an anchor evaluates an `exp` or a `sin_cos`.
    pub(super) fn frame_sample(&mut self, k: usize, ts: f64) -> (f64, f64) {
        let seg = &self.frame.seg;
        let c = &mut self.sampler.cursor;
        if c.seg_t0 == seg.t0 && c.k + 1 == k && c.steps < REANCHOR && k > 0 {
            let [[a, b], [cc, d]] = c.transition;
            (c.x, c.v) = (a * c.x + b * c.v, cc * c.x + d * c.v);
            c.steps += 1;
            c.k = k;
            let Some(f) = &seg.forced else { return (c.x, c.v) };
            let ((s, co), (ts_, tc)) = (c.phase, c.turn);
            c.phase = (s * tc + co * ts_, co * tc - s * ts_);
            let (s, co) = c.phase;
            let xp = &f.xp;
            return (c.x + (xp.sin * s + xp.cos * co), c.v + xp.omega * (xp.sin * co - xp.cos * s));
        }
        if c.mass != seg.osc.mass {
            c.transition = seg.osc.transition(self.scene.sample_dt);
            c.mass = seg.osc.mass;
        }
        c.seg_t0 = seg.t0;
        c.steps = 0;
        c.k = k;
        match &seg.forced {
            None => {
                (c.x, c.v) = seg.state(ts);
                (c.x, c.v)
            }
            Some(f) => {
                (c.x, c.v) = seg.osc.state(f.h0.0, f.h0.1, ts - seg.t0);
                c.phase = (f.xp.omega * ts).sin_cos();
                seg.state(ts)
            }
        }
    }

    pub(super) fn mechanical_energy(&self) -> f64 {
        let (_, vs) = if self.has_frame() { self.frame.state(self.t) } else { (0.0, 0.0) };
        let frame = if self.has_frame() { self.frame.energy(self.t, self.scene) } else { 0.0 };
        frame
            + (0..self.balls.n)
                .map(|i| {
                    let v = if self.balls.hold[i] == Hold::Free { self.balls.v[i] } else { vs };
                    0.5 * self.balls.mass[i] * v * v
                })
                .sum::<f64>()
    }

    /// The run so far, cut at the current time `t` (a budget stopped it there): its samples
    /// before `t`, its impacts, its energy account to `t`.
    pub(super) fn finish_at(mut self, t: f64) -> Run {
        self.horizon = t;
        if let Some(exact) = &mut self.sampler.exact {
            exact.cut_at(t);
        }
        self.finish()
    }

    pub(super) fn finish(mut self) -> Run {
        if self.has_frame() {
            self.book_segment_energy();
        }
        let (_, vs) = if self.has_frame() { self.frame.state(self.t) } else { (0.0, 0.0) };
        let final_velocities = (0..self.balls.n).map(|i| if self.balls.hold[i] == Hold::Free { self.balls.v[i] } else { vs }).collect();
        let energy = EnergyAccount::forced(
            self.scene.initial_energy(),
            self.mechanical_energy(),
            self.ledger.damping_loss,
            self.ledger.impact_loss,
            self.ledger.forcing_work,
        );
        let (series, sampled) = self.sampler.recorder.finish();
        let motion = self.sampler.exact.map_or(sampled, |e| e.finish());
        Run {
            scene: self.scene.name.clone(),
            model: Model::Reference,
            horizon: self.horizon,
            sample_dt: self.scene.sample_dt,
            initial_displacement: self.scene.initial_displacement,
            damped_period: self.scene.frame.map_or(0.0, |f| f.damped_period()),
            series,
            motion,
            impacts: self.ledger.impacts,
            counted_impacts: crate::run::CountedImpacts::default(),
            energy,
            events: self.events,
            final_velocities,
            peak_true_acceleration: None,
            wall_time_s: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The frame's samples stepped by the transition matrix (and, forced, by the turn of the
    /// forcing's phase) are its closed form at every sample to round-off, over segments long
    /// enough to cross many anchors, free and forced.
    #[test]
    fn stepped_samples_are_the_closed_form() {
        for name in ["lpc-lsl", "forced-lsl"] {
            let scene = crate::scene::load_scene(crate::scene::scenes_dir().join(format!("{name}.toml"))).unwrap();
            let mut solver = Solver::new(&scene, Record::Series).unwrap();
            // A segment of the bare frame moving from a state of its own, from t = 0.3 s.
            let t0 = 0.3;
            solver.frame.restart(t0, 0.01, -0.2);
            let first = (t0 / scene.sample_dt).ceil() as usize;
            let mut stepped = Vec::new();
            solver.frame_samples(first, first + 1000, &mut stepped);
            let scale = (0.01f64).hypot(0.2 / 25.0) + scene.harmonic_load().map_or(0.0, |_| 0.07);
            for (j, &(x, v)) in stepped.iter().enumerate() {
                let ts = (first + j) as f64 * scene.sample_dt;
                let (xc, vc) = solver.frame.seg.state(ts);
                assert!((x - xc).abs() <= 1e-12 * scale, "{name}: x at {ts}: {x} vs {xc}");
                assert!((v - vc).abs() <= 1e-12 * 25.0 * scale, "{name}: v at {ts}: {v} vs {vc}");
            }
        }
    }
}
