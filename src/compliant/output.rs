//! What the run leaves: its samples (from the dense output between steps), what its steps cost
//! when a budget stops it, and the finished [`Run`].

use super::contact;
use super::driver::Driver;
use super::system::{Pair, Side, VS, XS};
use crate::model::Model;
use crate::run::{EnergyAccount, Run};

impl Driver<'_, '_> {
    /// Writes every sample with time `<=` the current time, between steps from the last
    /// step's dense output (it started at `step_t0` and was `step_h` long).
    pub(super) fn sample(&mut self, step_t0: f64, step_h: f64, dense: bool) {
        let sys = self.sys;
        let dt = sys.scene.sample_dt;
        let mut buf = std::mem::take(&mut self.buf);
        while self.next_sample < self.sample_count {
            let ts = self.next_sample as f64 * dt;
            if ts > self.t {
                break;
            }
            let state: &[f64] = if ts == self.t || !dense {
                &self.y
            } else {
                let theta = ((ts - step_t0) / step_h).clamp(0.0, 1.0);
                for (i, b) in buf.iter_mut().enumerate() {
                    *b = self.dense_component(i, theta);
                }
                &buf
            };
            if let Some(floors) = &sys.floors {
                // A structure is written in the ground's frame.
                let (xg, vg, _) = sys.scene.ground_motion(ts);
                let (u, v) = floors.relative(|i| state[i], (xg, vg));
                self.recorder.sample_floors(sys.scene, ts, (&u, &v), (xg, vg), |i| (state[sys.x(i)], state[sys.v(i)]));
                self.next_sample += 1;
                continue;
            }
            let (xs, vs) = if sys.has_frame() { (state[XS], state[VS]) } else { (0.0, 0.0) };
            self.recorder.sample(sys.scene, ts, xs, vs, |i| (state[sys.x(i)], state[sys.v(i)]));
            self.next_sample += 1;
        }
        self.buf = buf;
    }

    /// What the steps cost now: the last step, the contacts open and the stiffest of them
    /// (its bodies and the period of its linearised stiffness at its overlap), or free flight.
    pub(super) fn cost_driver(&self, h: f64) -> String {
        let sys = self.sys;
        let mut stiffest: Option<(f64, &Pair)> = None;
        let mut open = 0;
        for (q, pair) in sys.pairs.iter().enumerate() {
            let Some(c) = &self.contacts[q] else { continue };
            open += 1;
            let d = sys.overlap(pair, |i| self.y[i]).0.max(contact::max_overlap(pair.mass, c.v_max, pair.k));
            let omega = (1.5 * pair.k * d.max(0.0).sqrt() / pair.mass).sqrt();
            if stiffest.is_none_or(|(w, _)| omega > w) {
                stiffest = Some((omega, pair));
            }
        }
        let step = format!(
            "{} impacts so far, {} of {} accepted steps implicit (RODAS4); the last step was {} s",
            self.impacts.len(),
            self.stiff_steps,
            self.accepted,
            crate::scene::human(h)
        );
        match stiffest {
            Some((omega, pair)) if omega > 0.0 => {
                let body = |side: Side| match side {
                    Side::Ball(i) => format!("ball{} ({} kg)", i + 1, crate::scene::human(sys.scene.balls[i].mass)),
                    Side::Wall(_) => "the wall".to_string(),
                };
                format!(
                    "{step} with {open} contact{} open, the stiffest {} / {} (a Hertz period of {} s at its overlap); each \
                     impact takes some 40-100 steps at the tolerance asked for",
                    if open == 1 { "" } else { "s" },
                    body(pair.left),
                    body(pair.right),
                    crate::scene::human(2.0 * std::f64::consts::PI / omega),
                )
            }
            _ => format!("{step}, with no contact open"),
        }
    }

    /// The run up to now, as [`Driver::run`] returns a finished one.
    pub(super) fn finish(mut self, initial: f64) -> Run {
        let sys = self.sys;
        let scene = sys.scene;
        // Contacts open at the end are recorded with their duration so far.
        for q in 0..self.contacts.len() {
            if let Some(c) = self.contacts[q] {
                self.close(q, c);
            }
        }
        self.impacts.sort_by(|a, b| a.t.total_cmp(&b.t).then(a.a.cmp(&b.a)));
        let impact_loss: f64 = (0..sys.slots.count()).map(|p| self.y[sys.dissipation(p)]).sum();
        let energy = EnergyAccount::forced(
            initial,
            sys.energy(self.t, &self.y),
            self.y[sys.damping_work()],
            impact_loss,
            self.y[sys.forcing_work()],
        );
        let final_velocities = (0..sys.n).map(|i| self.y[sys.v(i)]).collect();
        let (series, motion) = self.recorder.finish();
        Run {
            scene: scene.name.clone(),
            model: Model::Compliant,
            horizon: self.t,
            sample_dt: scene.sample_dt,
            initial_displacement: scene.initial_displacement,
            damped_period: scene.frame.map_or(0.0, |f| f.damped_period()),
            series,
            motion,
            impacts: self.impacts,
            counted_impacts: crate::run::CountedImpacts::default(),
            energy,
            events: self.accepted,
            final_velocities,
            peak_true_acceleration: sys.has_frame().then_some(self.peak_true_acceleration),
            wall_time_s: 0.0,
        }
    }
}
