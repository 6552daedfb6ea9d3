//! The adaptive driver: the state, the open contacts and the step loop. Each step is attempted
//! by the explicit or the implicit method, judged and read through one interface
//! ([`super::stepper::Stepper`]), and accepted, cut at the first contact onset in it, or retried
//! shorter.

use super::contact;
use super::integrator::Dopri5;
use super::jacobian;
use super::rosenbrock::{self, Rodas4};
use super::stepper::{Active, Stepper};
use super::system::{Side, System, VS, XS};
use super::{CLOSE_OVERSHOOT, CONTACT_STEP, ERROR_SPEED_FRACTION, STIFF_LIMIT};
use crate::model::{Meter, Model, ModelError, OverBudget};
use crate::run::{Impact, Record, Recorder, Run};

/// An open contact.
#[derive(Debug, Clone, Copy)]
pub(super) struct Contact {
    pub(super) onset: f64,
    /// Largest overlap rate so far (the onset speed for an isolated impact).
    pub(super) v_max: f64,
    /// The pair's dissipation integral at onset.
    pub(super) dissipated_before: f64,
    /// When the overlap last returned to zero, if it has not become positive since.
    pub(super) exit: Option<f64>,
    pub(super) peak_force: f64,
}

pub(super) struct Driver<'s, 'a> {
    pub(super) sys: &'s System<'a>,
    pub(super) rk: Dopri5,
    /// The stiff integrator, its factored stage matrix, the forcing's time derivative and a
    /// scratch state for it.
    pub(super) rodas: Rodas4,
    pub(super) stage: jacobian::Stage,
    pub(super) ft: Vec<f64>,
    pub(super) ft_ahead: Vec<f64>,
    pub(super) ft_now: Vec<f64>,
    /// Whether the last attempted step was a RODAS4 step.
    pub(super) stiff: bool,
    /// Accepted RODAS4 steps.
    pub(super) stiff_steps: u64,
    pub(super) t: f64,
    pub(super) y: Vec<f64>,
    pub(super) dy: Vec<f64>,
    /// Per entry of `sys.pairs`.
    pub(super) contacts: Vec<Option<Contact>>,
    pub(super) v_max: Vec<f64>,
    pub(super) scale: Vec<f64>,
    /// Scratch state for samples.
    pub(super) buf: Vec<f64>,
    pub(super) impacts: Vec<Impact>,
    pub(super) recorder: Recorder,
    pub(super) next_sample: usize,
    pub(super) sample_count: usize,
    pub(super) steps: u64,
    pub(super) accepted: u64,
    /// Largest |frame acceleration| with contact forces, at accepted step ends after one bare
    /// period (within about `(pi / 40)^2 / 2 = 0.3 %` of the true peak, at 40 steps a contact).
    pub(super) peak_true_acceleration: f64,
}

impl<'s, 'a> Driver<'s, 'a> {
    pub(super) fn new(sys: &'s System<'a>, record: Record) -> Self {
        let scene = sys.scene;
        let mut y = vec![0.0; sys.len()];
        if let Some(floors) = &sys.floors {
            // The floors start relative to the ground; the carrying floor is carried absolute.
            let (xg, vg, _) = scene.ground_motion(0.0);
            let s = floors.structure;
            for j in 0..floors.count() {
                let ground = if j == s.floor { (xg, vg) } else { (0.0, 0.0) };
                y[floors.x(j)] = s.initial_displacements[j] + ground.0;
                y[floors.v(j)] = s.initial_velocities[j] + ground.1;
            }
        } else if sys.has_frame() {
            y[XS] = scene.initial_displacement;
        }
        for i in 0..sys.n {
            y[sys.x(i)] = scene.initial_positions[i];
            y[sys.v(i)] = scene.initial_velocities[i];
        }
        let samples = scene.sample_count();
        Driver {
            sys,
            rk: Dopri5::new(sys.len()),
            rodas: Rodas4::new(sys.len()),
            stage: jacobian::Stage::default(),
            ft: vec![0.0; sys.len()],
            ft_ahead: vec![0.0; sys.len()],
            ft_now: vec![0.0; sys.len()],
            stiff: false,
            stiff_steps: 0,
            t: 0.0,
            dy: vec![0.0; y.len()],
            scale: vec![f64::INFINITY; y.len()],
            buf: vec![0.0; y.len()],
            y,
            contacts: vec![None; sys.pairs.len()],
            v_max: vec![0.0; sys.pairs.len()],
            impacts: Vec::new(),
            recorder: Recorder::new(sys.scene, record),
            next_sample: 0,
            sample_count: samples,
            steps: 0,
            accepted: 0,
            peak_true_acceleration: 0.0,
        }
    }

    /// Attempts a step of length `h` from the current state, with RODAS4 if `self.stiff`.
    pub(super) fn attempt(&mut self, h: f64) {
        let (sys, v_max) = (self.sys, &self.v_max);
        let mut f = |t: f64, y: &[f64], dy: &mut [f64]| sys.rhs(t, y, dy, v_max);
        if !self.stiff {
            self.rk.step(&mut f, self.t, &self.y, &self.dy, h);
            return;
        }
        sys.factor(self.t, &self.y, &self.dy, v_max, h * rosenbrock::GAMMA, &mut self.stage);
        // Only the excitation depends on time: a central difference over a ten-thousandth of
        // its radian period (or of the fastest floor's, for a record linear between its points)
        // is exact to about 1e-9 of it.
        let recorded = sys.floors.as_ref().filter(|f| f.structure.is_recorded());
        let time_step = match (sys.scene.forcing, recorded) {
            (Some(g), _) => Some(1e-4 / g.omega()),
            (None, Some(f)) => Some(1e-4 / f.fastest),
            (None, None) => None,
        };
        // A step starting on a record's point sees only the stretch ahead (steps end on the
        // points): there the difference is one-sided, of the same order.
        let at_point =
            recorded.and_then(|f| f.structure.record_stretch(self.t)).is_some_and(|s| s.start > self.t - time_step.unwrap_or(0.0));
        let ft = match time_step {
            Some(dt) if at_point => {
                sys.rhs(self.t, &self.y, &mut self.ft_now, v_max);
                sys.rhs(self.t + dt, &self.y, &mut self.ft_ahead, v_max);
                sys.rhs(self.t + 2.0 * dt, &self.y, &mut self.ft, v_max);
                for ((d, a), f) in self.ft.iter_mut().zip(&self.ft_ahead).zip(&self.ft_now) {
                    *d = (4.0 * a - *d - 3.0 * f) / (2.0 * dt);
                }
                Some(&self.ft[..])
            }
            Some(dt) => {
                sys.rhs(self.t + dt, &self.y, &mut self.ft_ahead, v_max);
                sys.rhs(self.t - dt, &self.y, &mut self.ft, v_max);
                for (d, a) in self.ft.iter_mut().zip(&self.ft_ahead) {
                    *d = (a - *d) / (2.0 * dt);
                }
                Some(&self.ft[..])
            }
            None => None,
        };
        let stage = &mut self.stage;
        let mut solve = |r: &mut [f64]| sys.solve(stage, r);
        self.rodas.step(&mut f, &mut solve, self.t, &self.y, &self.dy, ft, h);
    }

    /// The method of the last attempted step.
    #[inline]
    pub(super) fn stepper(&self) -> Active<'_> {
        if self.stiff {
            Active::Implicit(&self.rodas)
        } else {
            Active::Explicit(&self.rk)
        }
    }

    /// Component `i` of the last step's dense output at `theta`.
    #[inline]
    pub(super) fn dense_component(&self, i: usize, theta: f64) -> f64 {
        self.stepper().dense_component(i, theta)
    }

    /// The last step's error norm against the current scales.
    pub(super) fn error_norm(&self) -> f64 {
        self.stepper().error_norm(&self.scale)
    }

    /// The next step after one of length `h` with error norm `err`, by the last step's method.
    pub(super) fn next_step(&self, h: f64, err: f64) -> f64 {
        self.stepper().next_step(h, err)
    }

    /// The derivative at the current state, after a contact opened, closed or changed damping.
    pub(super) fn derivative(&mut self) {
        let (sys, v_max) = (self.sys, &self.v_max);
        sys.rhs(self.t, &self.y, &mut self.dy, v_max);
    }

    /// Error scales: positions against the smallest Hertz length of the open contacts, velocities
    /// against the slowest open contact's speed (or the scene's scales when none is open), each
    /// contact's speed counted as at least [`ERROR_SPEED_FRACTION`] of the scene's speed scale.
    /// An impact is then resolved to the tolerance relative to its own scales, and a contact
    /// pressed or resting at a far smaller speed cannot hold every body to errors far below
    /// anything its energy could show (`tolerance x ERROR_SPEED_FRACTION^2` of the scene's energy
    /// scale at worst).
    pub(super) fn update_scales(&mut self) {
        let sys = self.sys;
        let (mut length, mut speed) = (sys.length_scale, sys.v_scale);
        let slowest = ERROR_SPEED_FRACTION * sys.v_scale;
        for (q, c) in self.contacts.iter().enumerate() {
            if let Some(c) = c {
                let pair = &sys.pairs[q];
                let v = c.v_max.max(slowest);
                length = length.min(contact::length_scale(pair.mass, v, pair.k));
                speed = speed.min(v);
            }
        }
        let tol = sys.scene.compliant.tolerance;
        // Positions are absolute coordinates: no scale below a few ulps of the largest.
        let ulps = 8.0 * f64::EPSILON * (0..sys.n).map(|i| self.y[sys.x(i)].abs()).fold(self.y[XS].abs(), f64::max);
        let (ex, ev) = ((tol * length).max(ulps), tol * speed);
        self.scale[XS] = if sys.has_frame() { ex } else { f64::INFINITY };
        self.scale[VS] = if sys.has_frame() { ev } else { f64::INFINITY };
        if let Some(floors) = &sys.floors {
            for j in 0..floors.count() {
                self.scale[floors.x(j)] = ex;
                self.scale[floors.v(j)] = ev;
            }
        }
        for i in 0..sys.n {
            self.scale[sys.x(i)] = ex;
            self.scale[sys.v(i)] = ev;
        }
    }

    /// Longest steps allowed from the current state: no open pair closing much before the step
    /// ends, and for the explicit method (the first number) contacts resolved in many steps.
    pub(super) fn step_bound(&self) -> (f64, f64) {
        let sys = self.sys;
        let mut bound = sys.h_max;
        let mut contact_bound = f64::INFINITY;
        let frame_accel = if sys.has_frame() { sys.frame_accel_bound(self.t, &self.y) } else { 0.0 };
        for (q, pair) in sys.pairs.iter().enumerate() {
            let (d, rate) = sys.overlap(pair, |i| self.y[i]);
            if let Some(c) = &self.contacts[q] {
                let d_ref = d.max(contact::max_overlap(pair.mass, c.v_max, pair.k));
                if d_ref > 0.0 {
                    let omega = (1.5 * pair.k * d_ref.sqrt() / pair.mass).sqrt();
                    contact_bound = contact_bound.min(CONTACT_STEP / omega);
                }
            } else {
                let (_, accel) = sys.overlap(pair, |i| self.dy[i]);
                let walls = matches!(pair.left, Side::Wall(_)) || matches!(pair.right, Side::Wall(_));
                let a = 2.0 * accel.abs() + if walls { frame_accel } else { 0.0 };
                let g = (-d).max(0.0);
                let t_close = if rate > 0.0 {
                    2.0 * g / (rate + (rate * rate + 2.0 * a * g).sqrt())
                } else if a > 0.0 {
                    (-rate + (rate * rate + 2.0 * a * g).sqrt()) / a
                } else {
                    f64::INFINITY
                };
                bound = bound.min((CLOSE_OVERSHOOT * t_close).max(sys.h_floor));
            }
        }
        (bound.min(contact_bound), bound)
    }

    pub(super) fn run(mut self, meter: &Meter) -> Result<Run, ModelError> {
        let sys = self.sys;
        let scene = sys.scene;
        let horizon = scene.horizon;
        let initial = sys.energy(0.0, &self.y);
        let period = scene.frame.map_or(0.0, |f| f.damped_period());
        self.update_contacts(None);
        self.derivative();
        self.sample(0.0, 1.0, false);
        let mut h = sys.h_floor.min(sys.h_max);
        while self.t < horizon {
            self.steps += 1;
            if let Some(budget) = meter.look(self.t, self.steps) {
                let wall_s = meter.elapsed();
                let cost = self.cost_driver(h);
                let (t, steps) = (self.t, self.steps - 1);
                let mut partial = self.finish(initial);
                partial.wall_time_s = wall_s;
                return Err(ModelError::OverBudget(Box::new(OverBudget {
                    scene: scene.name.clone(),
                    model: Model::Compliant,
                    t,
                    horizon,
                    steps,
                    wall_s,
                    budget,
                    limit: meter.limit(budget),
                    cost,
                    partial,
                })));
            }
            // A record's load is linear between its points, with kinks at them: steps end on
            // them, so that the error estimate sees a smooth load.
            let point = sys.floors.as_ref().and_then(|f| f.structure.record_stretch(self.t)).map_or(f64::INFINITY, |s| s.end);
            let remaining = (horizon - self.t).min(point - self.t);
            let (explicit_bound, implicit_bound) = self.step_bound();
            let h_explicit = h.min(explicit_bound).min(remaining);
            // A contact damped faster than the explicit method's stability allows at this step
            // hands the step to RODAS4, which also lets steps outgrow the contacts' periods.
            self.stiff = sys.damping_rate(&self.y, &self.dy, &self.v_max) * explicit_bound.min(remaining) > STIFF_LIMIT;
            let h_try = if self.stiff { h.min(implicit_bound).min(remaining) } else { h_explicit };
            if self.t + h_try == self.t {
                let why = format!("its step fell to {h_try:e} s");
                return Err(ModelError::Stalled { scene: scene.name.clone(), model: Model::Compliant, t: self.t, steps: self.steps, why });
            }
            self.update_scales();
            self.attempt(h_try);
            let err = self.error_norm();
            if !err.is_finite() {
                // A stage went far into an overlap: try a much shorter step.
                h = 0.1 * h_try;
                continue;
            }
            h = self.next_step(h_try, err);
            if err > 1.0 {
                continue;
            }
            self.accepted += 1;
            let t0 = self.t;
            let mut h_done = h_try;
            let event = self.first_event();
            if let Some((theta, _)) = event {
                // Redo the step up to the event, so that no stage sees past it: the state there
                // (an onset speed, an exit speed) is that of a step on one side of the kink.
                h_done = theta * h_try;
                if h_done > 0.0 {
                    self.steps += 1;
                    self.attempt(h_done);
                    let err = self.error_norm();
                    if !(err <= 1.0) {
                        h = if err.is_finite() { self.next_step(h_done, err) } else { 0.1 * h_done };
                        continue;
                    }
                    self.accepted += 1;
                }
            }
            let mut faster = false;
            if h_done > 0.0 {
                faster = self.track_contacts(t0, h_done);
                self.stiff_steps += self.stiff as u64;
                let stepper = if self.stiff { Active::Implicit(&self.rodas) } else { Active::Explicit(&self.rk) };
                self.y.copy_from_slice(stepper.solution());
                self.dy.copy_from_slice(stepper.end_derivative());
                self.t = match (event, h_try == remaining) {
                    (None, true) if point < horizon => point,
                    (None, true) => horizon,
                    _ => t0 + h_done,
                };
                if sys.has_frame() && self.t >= period {
                    self.peak_true_acceleration = self.peak_true_acceleration.max(self.dy[VS].abs());
                }
                if !self.y.iter().all(|v| v.is_finite()) {
                    let reason = format!("its state became non-finite at t = {} s", crate::scene::human(self.t));
                    return Err(ModelError::Unstable { scene: scene.name.clone(), model: Model::Compliant, t: self.t, reason });
                }
                self.sample(t0, h_done, true);
            }
            let changed = self.update_contacts(event.map(|e| e.1));
            if changed || faster {
                self.derivative();
            }
        }
        meter.finish(self.t, self.steps);
        Ok(self.finish(initial))
    }
}
