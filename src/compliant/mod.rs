//! The compliant model: balls and walls deform. Every contact is a Hertz spring with
//! Hunt-Crossley damping ([`contact`]), resolved in time by an adaptive integration of the
//! whole system, so impacts last tens of microseconds instead of an instant, and their peak
//! forces and durations are outputs. Steps are Dormand-Prince 5(4) ([`integrator`]) while that
//! explicit pair is stable, and RODAS4 ([`rosenbrock`], L-stable, with the system's Jacobian
//! solved in O(n): `jacobian`) while an open contact damps faster than an explicit step could
//! follow: a low-restitution contact pressed at a small speed has a damping rate of
//! `c K d^(3/2) / (v m)` with `v` near the floor speed, up to 1e9 per second, which held the
//! explicit steps to nanoseconds for as long as the contact lasted.
//!
//! What it adds to the impulse models, and how it stays comparable with them:
//! - **Restitution.** Each contact's damping is `alpha = c / v0` with `c` chosen once per
//!   scene so that an isolated impact at any approach speed `v0` has the scene's `e`
//!   ([`contact::damping_for`]). `v0` is the contact's largest overlap rate so far: for an
//!   isolated impact the rate is largest at onset, so this is the onset speed and `alpha` stays
//!   fixed through the contact; a pair that starts touching at rest and is then squeezed by a
//!   neighbour (chains with zero gaps) gets the speed it is driven at, not a near-zero onset
//!   speed that would make it plastic. Rates below the floor speed
//!   ([`FLOOR_SPEED_FRACTION`] of the scene's speed scale: resting and grazing contacts) count
//!   as the floor speed, so `alpha` stays bounded. `e` below [`contact::MIN_RESTITUTION`] is
//!   raised to it.
//! - **Frame.** Wall contact forces act on the frame (equal and opposite), so the frame moves
//!   under its true force. The reported acceleration series stays the smooth part
//!   `frame_force / ms` (docs/MODEL.md §6). The frame's true acceleration is
//!   `(frame_force + wall contact force) / ms`; a wall impact's `peak_force` is the wall's
//!   largest contact force, so the true acceleration during it reaches
//!   `|a| + peak_force / ms`.
//! - **Events.** A contact starts when a pair's overlap becomes positive. Every accepted step
//!   is scanned at eight points for a closed pair's overlap turning positive; the first onset
//!   is located on the dense output to round-off and the step is redone up to it, so no stage
//!   sees past it and the onset speed is that of a smooth step: exact for free flight. A step
//!   is never longer than 1.5 times the time any closed pair needs to close at its speed and a
//!   bound on its acceleration, so onsets are found inside steps, not approached by ever
//!   shorter ones. (A graze that enters and leaves between two scan points is not an event,
//!   but its force acts and its dissipation is booked: only its line in the impact list is
//!   missing.) A contact ends when its bodies come apart by more than the pair's rest band
//!   (the largest overlap of an impact at the floor speed, nanometres): bodies resting
//!   against each other tremble across zero overlap, and each tremble is not a new impact nor
//!   a reason to cut a step (the contact force and its slope are continuous at zero overlap,
//!   so nothing needs a step boundary there). Its duration runs to where its overlap last
//!   fell to zero, located on the dense output. An impact is recorded when its contact ends,
//!   at its onset time; a contact still open at the horizon is recorded with its duration so
//!   far. Its energy lost is the Hunt-Crossley dissipation over the contact, and its approach
//!   speed the contact's largest overlap rate (the onset speed of an isolated impact).
//!   [`Run::events`] counts accepted steps.
//! - **Energy.** Damper dissipation, forcing work and each pair's contact dissipation are
//!   integrated with the state, and the final energy includes the elastic energy of open
//!   contacts, so the balance closes to the integration tolerance.
//! - **Steps.** Error control on positions relative to the smallest Hertz length
//!   `(m v^2 / K)^(2/5)` at the scene's speed scale and on velocities relative to that speed:
//!   an error of one scale is an energy error of about the tolerance times the scene's energy
//!   scale, whichever contacts are open. An explicit step within a contact is at most a tenth
//!   of `1 / omega` of the contact's linearised stiffness at its largest overlap, about 40
//!   steps per elastic impact; an explicit step longer than [`STIFF_LIMIT`] over the fastest
//!   contact damping rate is taken by RODAS4 instead, whose steps only the error control and
//!   the closing bound limit. A step shrinking to round-off or a non-finite state end the run
//!   with a [`ModelError`] naming the scene; so does a budget, which keeps the run so far and
//!   says what its steps cost (the impacts so far, the last step, the open contacts, the
//!   stiffest of them).

pub mod contact;
pub mod integrator;
mod jacobian;
pub mod rosenbrock;

use crate::model::{Checks, Meter, Model, ModelError, OverBudget, RunOptions, Setting, Simulator};
use crate::run::{EnergyAccount, Impact, Record, Recorder, Run};
use crate::scene::{Body, Scene};
use integrator::{bracketed_root, next_step, Dopri5};
use rosenbrock::Rodas4;

/// Default most steps (accepted and rejected) one run may take.
pub const MAX_STEPS: u64 = 50_000_000;
/// Floor of the speed that sets a contact's damping, relative to the scene's speed scale.
pub const FLOOR_SPEED_FRACTION: f64 = 1e-3;
/// Floor of the speed that sets a contact's error scales, relative to the scene's speed scale.
pub const ERROR_SPEED_FRACTION: f64 = 1e-2;
/// Longest step within a contact, times `1 / omega` of its linearised stiffness.
const CONTACT_STEP: f64 = 0.1;
/// An explicit step longer than this many times the inverse of the fastest contact damping
/// rate goes to RODAS4 instead (Dormand-Prince is stable on the negative real axis to about 3.3).
pub const STIFF_LIMIT: f64 = 2.0;
/// Points per step at which every overlap is checked for a sign change.
const SCAN_POINTS: usize = 8;
/// A step may be this many times the estimated time for a pair to close: the onset then lies
/// inside the step and is located, rather than approached by ever shorter steps.
const CLOSE_OVERSHOOT: f64 = 1.5;

/// Steps between two looks at the budgets and two reports of progress.
pub const PROGRESS_STEPS: u64 = 1024;

/// The compliant model.
#[derive(Debug, Clone, Copy)]
pub struct Compliant;

impl Simulator for Compliant {
    fn model(&self) -> Model {
        Model::Compliant
    }

    fn supports(&self, scene: &Scene) -> Result<(), String> {
        let tolerance = scene.compliant.tolerance;
        if !(tolerance > 0.0 && tolerance <= 1e-2) {
            return Err(format!("its error tolerance must lie in (0, 1e-2] (got {})", crate::scene::human(tolerance)));
        }
        Ok(())
    }

    fn simulate(&self, scene: &Scene, options: &RunOptions) -> Result<Run, ModelError> {
        // Without a step budget the model still stops at MAX_STEPS rather than run for ever.
        let meter = Meter::new(&RunOptions { max_steps: Some(options.max_steps.unwrap_or(MAX_STEPS)), ..*options }, PROGRESS_STEPS);
        let system = System::new(scene);
        let mut run = Driver::new(&system, options.record).run(&meter)?;
        run.wall_time_s = meter.elapsed();
        Ok(run)
    }

    fn checks(&self, scene: &Scene, run: &Run) -> Checks {
        // Each step errs by at most the tolerance of the contact's scales; they add up at
        // worst. Contact forces are equal and opposite and Runge-Kutta keeps linear invariants.
        let balance = (run.events as f64 * scene.compliant.tolerance).max(1e-9);
        Checks {
            energy_gain: balance,
            balance: Some(balance),
            impact_gain: 1e-9,
            exact_impacts: false,
            momentum: 1e-9,
            wall_overlap: overlap_bound(scene, run),
            ball_overlap: None,
            stall_by_rate: false,
        }
    }

    fn settings(&self) -> &'static [Setting] {
        &[Setting::Tolerance]
    }

    fn stepping(&self, _scene: &Scene) -> &'static str {
        "adaptive"
    }
}

/// How far the compliant model's balls may legitimately overlap a wall: twice the elastic
/// overlap of the fastest impact (the heaviest ball on the stiffest-to-reach, i.e. softest,
/// wall contact) plus the static overlap of all the balls pressed by the frame's largest
/// acceleration.
fn overlap_bound(scene: &Scene, run: &Run) -> f64 {
    let e_star = contact::effective_modulus(&scene.compliant);
    let r_min = scene.balls.iter().map(|b| b.radius).fold(f64::INFINITY, f64::min);
    let k = contact::stiffness(e_star, contact::effective_radius(r_min, None));
    let m_max = scene.balls.iter().map(|b| b.mass).fold(0.0, f64::max);
    let m_all: f64 = scene.balls.iter().map(|b| b.mass).sum();
    let u_max = run.impacts.iter().map(|i| i.approach_speed).fold(0.0, f64::max);
    let a_max = run.series.a.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    1e-9 * scene.container.map_or(1e-3, |c| c.length.max(1e-3))
        + 2.0 * (contact::max_overlap(m_max, u_max, k) + (m_all * a_max / k).powf(2.0 / 3.0))
}

/// One side of a pair.
#[derive(Debug, Clone, Copy)]
enum Side {
    /// A ball.
    Ball(usize),
    /// A wall of the frame at this offset from `xs`.
    Wall(f64),
}

/// Two neighbouring bodies that can touch.
#[derive(Debug, Clone, Copy)]
struct Pair {
    /// Pair number as the reference counts it: between body `p - 1` and body `p`.
    p: usize,
    left: Side,
    right: Side,
    /// Hertz stiffness `K`.
    k: f64,
    /// Reduced mass, kg.
    mass: f64,
    /// Hertz length at the scene's speed scale.
    length: f64,
    /// How far apart the bodies of an open contact may come and still be in that contact: the
    /// largest overlap of an impact at the floor speed. Bodies resting against each other
    /// tremble across zero overlap; each tremble is not a new impact.
    rest_band: f64,
}

/// The scene as an ODE: state layout, contact geometry, derivative.
struct System<'a> {
    scene: &'a Scene,
    n: usize,
    frame_mass: f64,
    mass: Vec<f64>,
    radius: Vec<f64>,
    pairs: Vec<Pair>,
    /// `c = alpha v0` giving the scene's restitution.
    c: f64,
    /// Overlap rates below this set the damping as if they were this (resting contacts).
    v_floor: f64,
    /// The scene's speed scale: frame swing, initial ball speeds, forcing.
    v_scale: f64,
    /// Position error scale when no contact is open: the smallest Hertz length at `v_scale`.
    length_scale: f64,
    /// Longest step: a twentieth of the frame's natural period and of the forcing period, so
    /// that the acceleration bound used to predict contacts holds over a step.
    h_max: f64,
    /// Shortest step the closing bound may ask for (a tenth of the shortest contact time scale
    /// at `v_scale`): pairs touching at rest would otherwise shrink steps to nothing.
    h_floor: f64,
}

const XS: usize = 0;
const VS: usize = 1;

impl<'a> System<'a> {
    fn new(scene: &'a Scene) -> Self {
        let n = scene.balls.len();
        let mass: Vec<f64> = scene.balls.iter().map(|b| b.mass).collect();
        let radius: Vec<f64> = scene.balls.iter().map(|b| b.radius).collect();
        let frame_mass = scene.frame.map_or(f64::INFINITY, |f| f.mass);
        let e_star = contact::effective_modulus(&scene.compliant);
        let w0 = scene.frame.map_or(0.0, |f| (f.stiffness / f.mass).sqrt());
        let v_scale = scene.speed_scale();
        let mut pairs = Vec::new();
        let walls = scene.container.map(|c| c.length);
        let range = if walls.is_some() { 0..n + 1 } else { 1..n.max(1) };
        for p in range {
            let left = if p == 0 { Side::Wall(0.0) } else { Side::Ball(p - 1) };
            let right = if p == n { Side::Wall(walls.unwrap_or(0.0)) } else { Side::Ball(p) };
            let (r_star, m_star) = match (left, right) {
                (Side::Ball(i), Side::Ball(j)) => {
                    (contact::effective_radius(radius[i], Some(radius[j])), mass[i] * mass[j] / (mass[i] + mass[j]))
                }
                (Side::Ball(i), Side::Wall(_)) | (Side::Wall(_), Side::Ball(i)) => (
                    contact::effective_radius(radius[i], None),
                    if frame_mass.is_finite() { mass[i] * frame_mass / (mass[i] + frame_mass) } else { mass[i] },
                ),
                (Side::Wall(_), Side::Wall(_)) => continue,
            };
            let k = contact::stiffness(e_star, r_star);
            pairs.push(Pair {
                p,
                left,
                right,
                k,
                mass: m_star,
                length: contact::length_scale(m_star, v_scale, k),
                rest_band: contact::max_overlap(m_star, FLOOR_SPEED_FRACTION * v_scale, k),
            });
        }
        let length_scale = pairs
            .iter()
            .map(|p| p.length)
            .reduce(f64::min)
            .unwrap_or_else(|| scene.length_scale() * 1e-3);
        let h_floor = pairs.iter().map(|p| 0.1 * p.length / v_scale).reduce(f64::min).unwrap_or(scene.horizon);
        let mut h_max = scene.horizon;
        if w0 > 0.0 {
            h_max = h_max.min(2.0 * std::f64::consts::PI / w0 / 20.0);
        }
        if let Some(g) = scene.forcing {
            h_max = h_max.min(1.0 / (20.0 * g.frequency));
        }
        System {
            scene,
            n,
            frame_mass,
            mass,
            radius,
            pairs,
            c: contact::damping_for(scene.restitution),
            v_floor: FLOOR_SPEED_FRACTION * v_scale,
            v_scale,
            length_scale,
            h_max,
            h_floor,
        }
    }

    fn len(&self) -> usize {
        4 + 2 * self.n + (self.n + 1)
    }
    fn x(&self, i: usize) -> usize {
        2 + i
    }
    fn v(&self, i: usize) -> usize {
        2 + self.n + i
    }
    fn damping_work(&self) -> usize {
        2 + 2 * self.n
    }
    fn forcing_work(&self) -> usize {
        3 + 2 * self.n
    }
    fn dissipation(&self, p: usize) -> usize {
        4 + 2 * self.n + p
    }
    fn has_frame(&self) -> bool {
        self.frame_mass.is_finite()
    }

    /// Overlap and overlap rate of `pair`, reading component `i` through `get(i)`.
    #[inline]
    fn overlap(&self, pair: &Pair, get: impl Fn(usize) -> f64) -> (f64, f64) {
        let edge = |s: Side, sign: f64| -> (f64, f64) {
            match s {
                Side::Ball(i) => (get(self.x(i)) + sign * self.radius[i], get(self.v(i))),
                Side::Wall(off) => (get(XS) + off, get(VS)),
            }
        };
        let (xl, vl) = edge(pair.left, 1.0);
        let (xr, vr) = edge(pair.right, -1.0);
        (xl - xr, vl - vr)
    }

    /// The damping of a pair at overlap rate `rate`, the contact's largest rate so far being `v_max`.
    #[inline]
    fn alpha(&self, v_max: f64, rate: f64) -> f64 {
        self.c / v_max.max(rate).max(self.v_floor)
    }

    /// The derivative of the state; `v_max[q]` is the largest overlap rate of pair `q`'s open
    /// contact (0 when none is open).
    fn rhs(&self, t: f64, y: &[f64], dy: &mut [f64], v_max: &[f64]) {
        dy.fill(0.0);
        for i in 0..self.n {
            dy[self.x(i)] = y[self.v(i)];
        }
        let mut frame_contact = 0.0;
        for (q, pair) in self.pairs.iter().enumerate() {
            let (d, rate) = self.overlap(pair, |i| y[i]);
            if d <= 0.0 {
                continue;
            }
            let f = contact::force(pair.k, self.alpha(v_max[q], rate), d, rate);
            // Power leaving the bodies minus the rate of elastic storage: what the damping takes.
            dy[self.dissipation(pair.p)] = (f - pair.k * d * d.sqrt()) * rate;
            match pair.left {
                Side::Ball(i) => dy[self.v(i)] -= f,
                Side::Wall(_) => frame_contact -= f,
            }
            match pair.right {
                Side::Ball(j) => dy[self.v(j)] += f,
                Side::Wall(_) => frame_contact += f,
            }
        }
        for i in 0..self.n {
            dy[self.v(i)] /= self.mass[i];
        }
        if self.has_frame() {
            let (xs, vs) = (y[XS], y[VS]);
            dy[XS] = vs;
            dy[VS] = (self.scene.frame_force(t, xs, vs) + frame_contact) / self.frame_mass;
            dy[self.damping_work()] = self.scene.damping_power(t, vs);
            dy[self.forcing_work()] = self.scene.forcing_power(t, xs, vs);
        }
    }

    /// A bound on the frame's smooth acceleration over the next while: now, plus what the
    /// spring and damper can give at the frame's amplitude, plus the largest excitation.
    fn frame_accel_bound(&self, t: f64, xs: f64, vs: f64) -> f64 {
        let Some(f) = self.scene.frame else { return 0.0 };
        let w0sq = f.stiffness / f.mass;
        let amp = if w0sq > 0.0 { (xs * xs + vs * vs / w0sq).sqrt() } else { xs.abs() };
        let forcing = self.scene.forcing.map_or(0.0, |g| {
            let (p, q) = g.harmonic_load(f.damping, f.stiffness);
            p.hypot(q)
        });
        self.scene.frame_acceleration(t, xs, vs).abs() + w0sq * amp + (f.damping * vs.abs() + forcing) / f.mass
    }

    /// Mechanical energy: frame, balls, and elastic energy in open contacts.
    fn energy(&self, t: f64, y: &[f64]) -> f64 {
        let frame = if self.has_frame() { self.scene.frame_energy(t, y[XS], y[VS]) } else { 0.0 };
        let balls: f64 = (0..self.n).map(|i| 0.5 * self.mass[i] * y[self.v(i)] * y[self.v(i)]).sum();
        let elastic: f64 = self.pairs.iter().map(|p| contact::elastic_energy(p.k, self.overlap(p, |i| y[i]).0)).sum();
        frame + balls + elastic
    }

    fn bodies(&self, pair: &Pair) -> (Body, Body) {
        crate::scene::pair_bodies(pair.p, self.n)
    }
}

/// An open contact.
#[derive(Debug, Clone, Copy)]
struct Contact {
    onset: f64,
    /// Largest overlap rate so far (the onset speed for an isolated impact).
    v_max: f64,
    /// The pair's dissipation integral at onset.
    dissipated_before: f64,
    /// When the overlap last returned to zero, if it has not become positive since.
    exit: Option<f64>,
    peak_force: f64,
}

struct Driver<'s, 'a> {
    sys: &'s System<'a>,
    rk: Dopri5,
    /// The stiff integrator, its factored stage matrix, the forcing's time derivative and a
    /// scratch state for it.
    rodas: Rodas4,
    stage: jacobian::Stage,
    ft: Vec<f64>,
    ft_ahead: Vec<f64>,
    /// Whether the last attempted step was a RODAS4 step.
    stiff: bool,
    /// Accepted RODAS4 steps.
    stiff_steps: u64,
    t: f64,
    y: Vec<f64>,
    dy: Vec<f64>,
    /// Per entry of `sys.pairs`.
    contacts: Vec<Option<Contact>>,
    v_max: Vec<f64>,
    scale: Vec<f64>,
    /// Scratch state for samples.
    buf: Vec<f64>,
    impacts: Vec<Impact>,
    recorder: Recorder,
    next_sample: usize,
    sample_count: usize,
    steps: u64,
    accepted: u64,
    /// Largest |frame acceleration| with contact forces, at accepted step ends after one bare
    /// period (within about `(pi / 40)^2 / 2 = 0.3 %` of the true peak, at 40 steps a contact).
    peak_true_acceleration: f64,
}

impl<'s, 'a> Driver<'s, 'a> {
    fn new(sys: &'s System<'a>, record: Record) -> Self {
        let scene = sys.scene;
        let mut y = vec![0.0; sys.len()];
        if sys.has_frame() {
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
    fn attempt(&mut self, h: f64) {
        let (sys, v_max) = (self.sys, &self.v_max);
        let mut f = |t: f64, y: &[f64], dy: &mut [f64]| sys.rhs(t, y, dy, v_max);
        if !self.stiff {
            self.rk.step(&mut f, self.t, &self.y, &self.dy, h);
            return;
        }
        sys.factor(self.t, &self.y, &self.dy, v_max, h * rosenbrock::GAMMA, &mut self.stage);
        let ft = match sys.scene.forcing {
            Some(g) => {
                // Only the excitation depends on time: a central difference over a ten-thousandth
                // of its radian period is exact to about 1e-9 of it.
                let dt = 1e-4 / g.omega();
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

    /// Component `i` of the last step's dense output at `theta`.
    #[inline]
    fn dense_component(&self, i: usize, theta: f64) -> f64 {
        if self.stiff {
            self.rodas.dense_component(i, theta)
        } else {
            self.rk.dense_component(i, theta)
        }
    }

    /// The last step's error norm against the current scales.
    fn error_norm(&self) -> f64 {
        if self.stiff {
            self.rodas.error_norm(&self.scale)
        } else {
            self.rk.error_norm(&self.scale)
        }
    }

    /// The next step after one of length `h` with error norm `err`, by the last step's method.
    fn next_step(&self, h: f64, err: f64) -> f64 {
        if self.stiff {
            rosenbrock::next_step(h, err)
        } else {
            next_step(h, err)
        }
    }

    fn derivative(&mut self) {
        let (sys, v_max) = (self.sys, &self.v_max);
        sys.rhs(self.t, &self.y, &mut self.dy, v_max);
    }

    /// Opens contacts of pairs that overlap, or touch and approach, and closes those that no
    /// longer overlap, at the current time; pair `event` (whose crossing was just located, its
    /// overlap now zero to round-off) changes state whatever the sign of that round-off.
    /// Returns whether anything changed.
    fn update_contacts(&mut self, event: Option<usize>) -> bool {
        let sys = self.sys;
        let mut changed = false;
        for (q, pair) in sys.pairs.iter().enumerate() {
            let (d, rate) = sys.overlap(pair, |i| self.y[i]);
            let toggle = event == Some(q);
            match self.contacts[q] {
                None if toggle || d > 0.0 || (d == 0.0 && rate > 0.0) => {
                    self.contacts[q] = Some(Contact {
                        onset: self.t,
                        v_max: rate.max(0.0),
                        dissipated_before: self.y[sys.dissipation(pair.p)],
                        exit: None,
                        peak_force: 0.0,
                    });
                    self.v_max[q] = rate.max(0.0);
                    changed = true;
                }
                Some(c) if d <= -pair.rest_band => {
                    self.close(q, c);
                    changed = true;
                }
                Some(ref mut c) if rate > c.v_max => {
                    c.v_max = rate;
                    self.v_max[q] = rate;
                    changed = true;
                }
                _ => {}
            }
        }
        changed
    }

    fn close(&mut self, q: usize, c: Contact) {
        let sys = self.sys;
        let pair = &sys.pairs[q];
        let (a, b) = sys.bodies(pair);
        self.impacts.push(Impact {
            t: c.onset,
            a,
            b,
            approach_speed: c.v_max,
            energy_lost: self.y[sys.dissipation(pair.p)] - c.dissipated_before,
            impulses: 1,
            peak_force: Some(c.peak_force),
            contact_duration: Some(c.exit.unwrap_or(self.t) - c.onset),
        });
        self.contacts[q] = None;
        self.v_max[q] = 0.0;
    }

    /// Error scales: positions against the smallest Hertz length of the open contacts, velocities
    /// against the slowest open contact's speed (or the scene's scales when none is open), each
    /// contact's speed counted as at least [`ERROR_SPEED_FRACTION`] of the scene's speed scale.
    /// An impact is then resolved to the tolerance relative to its own scales, and a contact
    /// pressed or resting at a far smaller speed cannot hold every body to errors far below
    /// anything its energy could show (`tolerance x ERROR_SPEED_FRACTION^2` of the scene's energy
    /// scale at worst).
    fn update_scales(&mut self) {
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
        for i in 0..sys.n {
            self.scale[sys.x(i)] = ex;
            self.scale[sys.v(i)] = ev;
        }
    }

    /// Longest steps allowed from the current state: no open pair closing much before the step
    /// ends, and for the explicit method (the first number) contacts resolved in many steps.
    fn step_bound(&self) -> (f64, f64) {
        let sys = self.sys;
        let mut bound = sys.h_max;
        let mut contact_bound = f64::INFINITY;
        let frame_accel = if sys.has_frame() { sys.frame_accel_bound(self.t, self.y[XS], self.y[VS]) } else { 0.0 };
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

    /// The earliest point of the last step where a pair's contact state changes: the first
    /// scan point where an open pair's overlap is no longer positive, or a closed pair's is,
    /// refined to the crossing.
    fn first_event(&self) -> Option<(f64, usize)> {
        let sys = self.sys;
        let mut earliest: Option<(f64, usize)> = None;
        for (q, pair) in sys.pairs.iter().enumerate() {
            if self.contacts[q].is_some() {
                continue;
            }
            let overlap = |th: f64| sys.overlap(pair, |i| self.dense_component(i, th)).0;
            let crossed = |d: f64| d > 0.0;
            let limit = earliest.map_or(1.0, |e| e.0);
            let mut prev = 0.0;
            for j in 1..=SCAN_POINTS {
                let th = (j as f64 / SCAN_POINTS as f64).min(limit);
                if crossed(overlap(th)) {
                    let root = if crossed(overlap(prev)) {
                        prev
                    } else {
                        // Sign of g follows "crossed": the root returned lies on the crossed side.
                        bracketed_root(|x| if crossed(overlap(x)) { 1.0 } else { -1.0 } * overlap(x).abs().max(f64::MIN_POSITIVE), prev, th, 1e-15)
                    };
                    if earliest.is_none_or(|e| root < e.0) {
                        earliest = Some((root, q));
                    }
                    break;
                }
                if th >= limit {
                    break;
                }
                prev = th;
            }
        }
        earliest
    }

    /// Tracks each open contact's peak force and largest overlap rate over the last step (on
    /// the dense output, refined around a new peak). Returns whether a contact's largest rate,
    /// and so its damping, changed.
    fn track_contacts(&mut self, t0: f64, h: f64) -> bool {
        let sys = self.sys;
        let mut changed = false;
        let (rk, rodas, stiff) = (&self.rk, &self.rodas, self.stiff);
        let dense = |i: usize, th: f64| if stiff { rodas.dense_component(i, th) } else { rk.dense_component(i, th) };
        for (q, pair) in sys.pairs.iter().enumerate() {
            let Some(c) = self.contacts[q].as_mut() else { continue };
            let v_max0 = c.v_max;
            // Force, overlap rate and overlap at `th`.
            let at = |th: f64| -> (f64, f64, f64) {
                let (d, rate) = sys.overlap(pair, |i| dense(i, th));
                (contact::force(pair.k, sys.alpha(v_max0, rate), d, rate), rate, d)
            };
            let mut best = (f64::NEG_INFINITY, 0usize);
            let mut rates = 0.0f64;
            let mut d_prev = 0.0;
            for j in 0..=SCAN_POINTS {
                let th = j as f64 / SCAN_POINTS as f64;
                let (f, rate, d) = at(th);
                // The contact's last exit: where the overlap last fell to zero in this step.
                if j > 0 && d_prev > 0.0 && d <= 0.0 {
                    let lo = (j - 1) as f64 / SCAN_POINTS as f64;
                    c.exit = Some(t0 + h * bracketed_root(|x| -at(x).2, lo, th, 1e-15));
                } else if d > 0.0 {
                    c.exit = None;
                }
                d_prev = d;
                rates = rates.max(rate);
                if f > best.0 {
                    best = (f, j);
                }
            }
            if best.0 > c.peak_force {
                c.peak_force = best.0;
                let j = best.1;
                if j > 0 && j < SCAN_POINTS {
                    // Golden-section search for the maximum between the neighbouring points.
                    let step = 1.0 / SCAN_POINTS as f64;
                    let (mut a, mut b) = ((j - 1) as f64 * step, (j + 1) as f64 * step);
                    let r = 0.5 * (5f64.sqrt() - 1.0);
                    let (mut x1, mut x2) = (b - r * (b - a), a + r * (b - a));
                    let (mut f1, mut f2) = (at(x1).0, at(x2).0);
                    for _ in 0..60 {
                        if f1 < f2 {
                            a = x1;
                            x1 = x2;
                            f1 = f2;
                            x2 = a + r * (b - a);
                            f2 = at(x2).0;
                        } else {
                            b = x2;
                            x2 = x1;
                            f2 = f1;
                            x1 = b - r * (b - a);
                            f1 = at(x1).0;
                        }
                        if b - a <= 1e-13 {
                            break;
                        }
                    }
                    c.peak_force = c.peak_force.max(f1).max(f2);
                }
            }
            // The rate may peak inside the step (a pair squeezed by a neighbour).
            if rates > c.v_max {
                c.v_max = rates;
                self.v_max[q] = rates;
                changed = true;
            }
        }
        changed
    }

    /// Writes every sample with time `<=` the current time, between steps from the last
    /// step's dense output (it started at `step_t0` and was `step_h` long).
    fn sample(&mut self, step_t0: f64, step_h: f64, dense: bool) {
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
            let (xs, vs) = if sys.has_frame() { (state[XS], state[VS]) } else { (0.0, 0.0) };
            self.recorder.sample(sys.scene, ts, xs, vs, |i| (state[sys.x(i)], state[sys.v(i)]));
            self.next_sample += 1;
        }
        self.buf = buf;
    }

    /// What the steps cost now: the last step, the contacts open and the stiffest of them
    /// (its bodies and the period of its linearised stiffness at its overlap), or free flight.
    fn cost_driver(&self, h: f64) -> String {
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
    fn finish(mut self, initial: f64) -> Run {
        let sys = self.sys;
        let scene = sys.scene;
        // Contacts open at the end are recorded with their duration so far.
        for q in 0..self.contacts.len() {
            if let Some(c) = self.contacts[q] {
                self.close(q, c);
            }
        }
        self.impacts.sort_by(|a, b| a.t.total_cmp(&b.t).then(a.a.cmp(&b.a)));
        let impact_loss: f64 = (0..=sys.n).map(|p| self.y[sys.dissipation(p)]).sum();
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
            energy,
            events: self.accepted,
            final_velocities,
            peak_true_acceleration: sys.has_frame().then_some(self.peak_true_acceleration),
            wall_time_s: 0.0,
        }
    }

    fn run(mut self, meter: &Meter) -> Result<Run, ModelError> {
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
            let remaining = horizon - self.t;
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
                if self.stiff {
                    self.stiff_steps += 1;
                    self.y.copy_from_slice(&self.rodas.y1);
                    self.dy.copy_from_slice(self.rodas.last_derivative());
                } else {
                    self.y.copy_from_slice(&self.rk.y1);
                    self.dy.copy_from_slice(self.rk.last_derivative());
                }
                self.t = if event.is_none() && h_try == remaining { horizon } else { t0 + h_done };
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
