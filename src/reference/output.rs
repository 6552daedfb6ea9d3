//! Output: the frame's samples (stepped by the exact transition matrix, re-anchored to the closed
//! form), the energy account and the finished [`Run`].

use super::*;

/// Samples stepped by the transition matrix between two closed-form evaluations.
pub(super) const REANCHOR: u32 = 32;

/// Where frame sampling stands: the last sample's state and the step matrix of its segment.
#[derive(Debug, Clone, Copy)]
pub(super) struct SampleCursor {
    pub(super) seg_t0: f64,
    pub(super) k: usize,
    pub(super) x: f64,
    pub(super) v: f64,
    pub(super) steps: u32,
    pub(super) mass: f64,
    pub(super) transition: [[f64; 2]; 2],
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
            cursor: SampleCursor { seg_t0: f64::NAN, k: 0, x: 0.0, v: 0.0, steps: 0, mass: f64::NAN, transition: [[0.0; 2]; 2] },
        }
    }
}

impl Solver<'_> {
    /// Writes every sample with time `<= until` (strictly before when `inclusive` is false).
    pub(super) fn sample_until(&mut self, until: f64, inclusive: bool) {
        // Samples serve the series, or the metrics when they are not exact.
        if !self.sampler.recorder.keeps_series() && self.sampler.exact.is_some() {
            return;
        }
        let dt = self.scene.sample_dt;
        while self.sampler.next_sample < self.sampler.sample_count {
            let ts = self.sampler.next_sample as f64 * dt;
            if ts > until || (!inclusive && ts == until) {
                break;
            }
            let has_frame = self.has_frame();
            let (xs, vs) = if has_frame { self.frame_sample(ts) } else { (0.0, 0.0) };
            let (hold, x, v, offset, t) = (&self.balls.hold, &self.balls.x, &self.balls.v, &self.balls.offset, self.t);
            self.sampler.recorder.sample(self.scene, ts, xs, vs, |i| match hold[i] {
                Hold::Free => (x[i] + v[i] * (ts - t), v[i]),
                _ => (xs + offset[i], vs),
            });
            self.sampler.next_sample += 1;
        }
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

    /// The frame's state at sample `self.sampler.next_sample` (time `ts`): one step of the exact
    /// transition matrix from the previous sample when it lies in the same segment, the closed
    /// form every [`REANCHOR`] samples so that round-off cannot drift.
    pub(super) fn frame_sample(&mut self, ts: f64) -> (f64, f64) {
        if self.frame.seg.forced.is_some() {
            return self.frame.seg.state(ts);
        }
        let c = &mut self.sampler.cursor;
        let k = self.sampler.next_sample;
        if c.seg_t0 == self.frame.seg.t0 && c.k + 1 == k && c.steps < REANCHOR && k > 0 {
            let [[a, b], [cc, d]] = c.transition;
            (c.x, c.v) = (a * c.x + b * c.v, cc * c.x + d * c.v);
            c.steps += 1;
        } else {
            if c.mass != self.frame.seg.osc.mass {
                c.transition = self.frame.seg.osc.transition(self.scene.sample_dt);
                c.mass = self.frame.seg.osc.mass;
            }
            (c.x, c.v) = self.frame.seg.state(ts);
            c.seg_t0 = self.frame.seg.t0;
            c.steps = 0;
        }
        c.k = k;
        (c.x, c.v)
    }

    pub(super) fn mechanical_energy(&self) -> f64 {
        let (xs, vs) = if self.has_frame() { self.frame.seg.state(self.t) } else { (0.0, 0.0) };
        let frame = self.scene.frame_energy(self.t, xs, vs);
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
        let (_, vs) = if self.has_frame() { self.frame.seg.state(self.t) } else { (0.0, 0.0) };
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
            energy,
            events: self.events,
            final_velocities,
            peak_true_acceleration: None,
            wall_time_s: 0.0,
        }
    }
}
