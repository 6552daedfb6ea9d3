//! The compliant model beyond one line (docs/MODEL.md §15): balls free in the plane or in space
//! under the scene's gravity, every contact (ball-ball, ball-wall, ball-divider) a Hertz spring
//! along its normal with the one-line model's Hunt-Crossley damping ([`contact`]), and a
//! tangential force capped by Coulomb friction that spins the balls. The frame moves along x
//! and takes the walls' contact forces.
//!
//! Everything moves by velocity Verlet at a step set by the Hertz contact time of the fastest
//! impact the run can have ([`step_for`]). A grid of cells (`cells`) lists the pairs closer
//! than a skin in O(n), again only when a ball has moved half the skin: every step then costs
//! what its candidate pairs do.

mod contacts;
mod floors;

use super::{contact, FLOOR_SPEED_FRACTION, MAX_STEPS};
use crate::cells::Cells;
use crate::model::{Budget, Checks, Limits, Meter, Model, ModelError, OverBudget, RunOptions};
use crate::run::{EnergyAccount, Impact, Recorder, Run};
use crate::scene::{Body, Chamber, Scene, Wall};
use floors::Floors;

/// Steps per elastic Hertz contact of the fastest impact the run can have: the restitution of
/// an isolated impact then errs by about 1e-3 (velocity Verlet errs as the square of the step).
pub const STEPS_PER_CONTACT: f64 = 50.0;
/// Steps over which a slip relaxes to rolling while friction allows (the tangential force is
/// viscous up to the Coulomb cap, a regularised Coulomb law).
pub const SLIP_RELAXATION_STEPS: f64 = 10.0;
/// Longest step in an open contact, times `1 / omega` of its linearised stiffness (an
/// impact at the design speed takes shorter steps already; a pile's loaded contacts may not).
pub const CONTACT_STEP: f64 = 0.1;
/// Longest step times the fastest damping rate of an open contact (velocity Verlet damps
/// stably below 2).
pub const DAMPING_STEP: f64 = 0.2;
/// Candidate pairs are those closer than this many of the smallest radius: they are listed
/// again when a ball has moved half as far (relative to the container).
pub const SKIN_RADII: f64 = 0.2;
/// Longest step as a fraction of the frame's natural period and of the forcing period.
pub const FRAME_PERIOD_FRACTION: f64 = 1e-3;
/// Share of the energies that flow by which the balance may be off before the run is taken to
/// have gone unstable (far beyond the integration error, `(pi / STEPS_PER_CONTACT)^2`).
pub const UNSTABLE_BALANCE: f64 = 0.1;
/// Steps between two looks at the budgets.
const BUDGET_STEPS: u64 = 1024;

/// Why the spatial compliant model cannot run `scene`, or `None` when it can.
pub(super) fn refusal(scene: &Scene) -> Option<String> {
    let dampers = scene.damper_list();
    if dampers.is_empty() {
        return Some("the scene's balls leave their lines but it has no container".into());
    }
    let several = dampers.len() > 1;
    dampers
        .iter()
        .enumerate()
        .find_map(|(k, d)| Chamber::of_damper(scene, d).err().map(|why| if several { format!("damper[{k}]: {why}") } else { why }))
}

/// The longest step at which an impact at closing speed `speed` takes [`STEPS_PER_CONTACT`]
/// steps, for the pair of largest `m* / K` bound below by `stiffest` (`m / (2 K(r))`, least
/// over the balls): `ELASTIC_DURATION (m* / K)^(2/5) v^(-1/5) / STEPS_PER_CONTACT`.
pub fn step_for(stiffest: f64, speed: f64) -> f64 {
    contact::ELASTIC_DURATION * stiffest.powf(0.4) * speed.powf(-0.2) / STEPS_PER_CONTACT
}

/// Index of a wall among a ball's contacts: after the balls.
fn wall_index(n: usize, wall: Wall) -> u32 {
    let k = match wall {
        Wall::Left => 0,
        Wall::Right => 1,
        Wall::Front => 2,
        Wall::Back => 3,
        Wall::Floor => 4,
        Wall::Ceiling => 5,
        Wall::Divider(k) => 5 + k,
    };
    (n + k) as u32
}

/// A contact that is open: what it started with, and what it has done so far.
#[derive(Debug, Clone, Copy)]
struct Open {
    /// The other ball, or a wall ([`wall_index`]).
    other: u32,
    wall: Option<Wall>,
    /// Hertz stiffness, N/m^(3/2).
    k: f64,
    /// Onset time, s (extrapolated back to zero overlap).
    onset: f64,
    /// Largest overlap rate so far (the approach speed of an isolated impact), m/s: it sets
    /// the Hunt-Crossley damping `alpha = c / approach`.
    approach: f64,
    peak_force: f64,
    /// Energy the normal damping took so far (the impact's loss), J.
    loss: f64,
    /// Power the normal damping took at the last step, W.
    power: f64,
    /// Power friction took at the last step, W.
    friction_power: f64,
    /// Overlap and its rate at the last step.
    overlap: f64,
    rate: f64,
    /// Whether the contact was found this step.
    seen: bool,
}

/// The spatial compliant model's run of one scene.
struct Solver<'a> {
    scene: &'a Scene,
    /// Each damper's container.
    chambers: Vec<Chamber>,
    /// The damper each ball is in.
    damper: Vec<u32>,
    /// Where each damper's container starts along x in the cells' frame: the containers lie
    /// end to end there, far enough apart that balls of two dampers are never neighbours.
    offsets: Vec<f64>,
    /// The floor that carries each damper (0 on a frame), and its mass, kg.
    carrier_floor: Vec<usize>,
    floor_mass: Vec<f64>,
    /// Each damper's floor: its displacement and velocity, m and m/s.
    carried: Vec<(f64, f64)>,
    cells: Cells,
    n: usize,
    x: Vec<[f64; 3]>,
    v: Vec<[f64; 3]>,
    w: Vec<[f64; 3]>,
    force: Vec<[f64; 3]>,
    /// Scratch: velocities at the half step.
    v_half: Vec<[f64; 3]>,
    w_half: Vec<[f64; 3]>,
    torque: Vec<[f64; 3]>,
    mass: Vec<f64>,
    radius: Vec<f64>,
    inertia: Vec<f64>,
    start: Vec<[f64; 3]>,
    /// Pairs of balls and balls and walls closer than the skin when last listed.
    ball_candidates: Vec<(u32, u32)>,
    wall_candidates: Vec<(u32, Wall)>,
    /// Where the balls and each damper's floor were when the candidates were listed.
    listed_at: Vec<[f64; 3]>,
    listed_carried: Vec<f64>,
    /// How much closer than touching a pair must be to be listed, m.
    skin: f64,
    /// Open contacts, listed with the ball of lower index.
    open: Vec<Vec<Open>>,
    /// The frame's (or the first damper's floor's) displacement and velocity.
    xs: f64,
    vs: f64,
    /// Force on each floor beyond the structure's own: the walls' contacts of the dampers it
    /// carries, N; on a frame (one floor) also its spring, damper and excitation.
    wall_forces: Vec<f64>,
    /// A structure's floors, when the container rides one.
    floors: Option<Floors<'a>>,
    frame_mass: f64,
    gravity: [f64; 3],
    e_star: f64,
    friction: f64,
    /// `c = alpha v0` that gives the scene's restitution.
    c: f64,
    /// Approach speeds below this set the damping as if they were this, m/s.
    v_floor: f64,
    /// `m / (2 K(r))`, least over the balls.
    stiffest: f64,
    /// Closing speed the step is always fit for, m/s.
    design_speed: f64,
    /// Longest step, s.
    h_max: f64,
    /// The fastest ball's speed, m/s (kept by each step's last kick).
    fastest: f64,
    /// The largest `omega^2` (linearised stiffness over reduced mass) and damping rate of the
    /// open contacts at the last evaluation of the forces, 1/s^2 and 1/s.
    stiffness_rate: f64,
    damping_rate: f64,
    t: f64,
    steps: u64,
    impacts: Vec<Impact>,
    /// Energy the contacts' normal damping took, J (the impacts' loss).
    impact_loss: f64,
    /// Energy friction took, J.
    friction_loss: f64,
    damping_loss: f64,
    forcing_work: f64,
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Runs the spatial compliant model on `scene` (which [`refusal`] accepts).
pub(super) fn simulate(scene: &Scene, options: &RunOptions) -> Result<Run, ModelError> {
    let limits = Limits { max_steps: Some(options.limits.max_steps.unwrap_or(MAX_STEPS)), ..options.limits };
    let meter = Meter::new(&RunOptions { limits, ..*options }, BUDGET_STEPS);
    let mut s = Solver::new(scene).map_err(ModelError::Refused)?;
    let mut recorder = Recorder::new(scene, options.record);
    let outcome = s.run(&meter, &mut recorder);
    meter.finish(s.t, s.steps);
    match outcome? {
        None => {
            let mut run = s.finish(recorder);
            run.horizon = scene.horizon;
            run.wall_time_s = meter.elapsed();
            Ok(run)
        }
        Some(budget) => {
            let (t, steps, wall_s) = (s.t, s.steps, meter.elapsed());
            let cost = format!("{} impacts so far; {} balls in 3D at steps of {} s", s.impacts.len(), s.n, crate::scene::human(s.step()));
            let mut partial = s.finish(recorder);
            partial.wall_time_s = wall_s;
            Err(ModelError::OverBudget(Box::new(OverBudget {
                scene: scene.name.clone(),
                model: Model::Compliant,
                t,
                horizon: scene.horizon,
                steps,
                wall_s,
                budget,
                limit: meter.limit(budget),
                cost,
                partial,
            })))
        }
    }
}

/// The tolerances a spatial compliant run is checked with.
pub(super) fn checks(scene: &Scene, run: &Run) -> Checks {
    // Velocity Verlet errs in what each contact exchanges by about the square of its phase
    // step: `(pi / STEPS_PER_CONTACT)^2` for the stiffness, `DAMPING_STEP^2 / 12` for the
    // damping, the larger 4e-3. What the contacts exchange is at most what is put in, what
    // they lose and what gravity does on the balls' fall and rise (from the samples).
    let per_contact = (std::f64::consts::PI / STEPS_PER_CONTACT).powi(2).max(DAMPING_STEP * DAMPING_STEP / 12.0);
    // Relative to what was put in, as the stress checks measure it (at least a picojoule).
    let put_in = run.energy.initial.abs().max(1e-12) + run.energy.forcing_work.abs();
    let exchanged = put_in + 2.0 * run.energy.impact_loss.abs() + gravity_exchange(scene, run);
    let balance = (per_contact * exchanged / put_in).max(1e-9);
    let g = dot(scene.space.gravity, scene.space.gravity).sqrt();
    let wall_overlap = super::overlap_bound(scene, run, g);
    Checks {
        energy_gain: balance,
        balance: Some(balance),
        impact_gain: balance,
        exact_impacts: false,
        momentum: 1e-6,
        wall_overlap,
        ball_overlap: None,
        stall_rate: None,
    }
}

/// The work gravity can have done on the balls over `run`: each ball's weight times the span of
/// its height along gravity over the samples (or across the container without samples), J.
fn gravity_exchange(scene: &Scene, run: &Run) -> f64 {
    let g = scene.space.gravity;
    let g_norm = dot(g, g).sqrt();
    if g_norm == 0.0 {
        return 0.0;
    }
    let s = &run.series;
    let across = Chamber::new(scene).map_or(0.0, |c| c.diagonal());
    (0..scene.balls.len())
        .map(|i| {
            let span = if s.is_empty() {
                across
            } else {
                let heights = (0..s.len()).map(|k| {
                    let [y, z] = s.across(i, k);
                    -(g[0] * s.x(i)[k] + g[1] * y + g[2] * z) / g_norm
                });
                let (lo, hi) = heights.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), h| (lo.min(h), hi.max(h)));
                hi - lo
            };
            scene.balls[i].mass * g_norm * span
        })
        .sum()
}

impl<'a> Solver<'a> {
    fn new(scene: &'a Scene) -> Result<Self, String> {
        let dampers = scene.damper_list();
        let chambers = dampers.iter().map(|d| Chamber::of_damper(scene, d)).collect::<Result<Vec<_>, _>>()?;
        let n = scene.balls.len();
        let mut damper = vec![0u32; n];
        for (k, d) in dampers.iter().enumerate() {
            damper[d.balls.clone()].fill(k as u32);
        }
        let largest = scene.balls.iter().map(|b| b.radius).fold(0.0, f64::max);
        let smallest = scene.balls.iter().map(|b| b.radius).fold(f64::INFINITY, f64::min).min(largest);
        let skin = SKIN_RADII * smallest;
        // Listed pairs may be a skin apart: the cells are as wide as that reach.
        let reach = 2.0 * largest + skin;
        let mut offsets = Vec::with_capacity(chambers.len());
        let mut inside = [0.0f64; 3];
        for c in &chambers {
            offsets.push(if inside[0] > 0.0 { inside[0] + 2.0 * reach } else { 0.0 });
            inside = [offsets[offsets.len() - 1] + c.length, inside[1].max(c.width), inside[2].max(c.height)];
        }
        let cells = Cells::new(inside, reach, n);
        let mass: Vec<f64> = scene.balls.iter().map(|b| b.mass).collect();
        let radius: Vec<f64> = scene.balls.iter().map(|b| b.radius).collect();
        let e_star = contact::effective_modulus(&scene.compliant);
        let x: Vec<[f64; 3]> = (0..n)
            .map(|i| {
                let [y, z] = scene.space.lateral_of(i);
                [scene.initial_positions[i], y, z]
            })
            .collect();
        let v: Vec<[f64; 3]> = (0..n)
            .map(|i| {
                let [vy, vz] = scene.space.lateral_velocity_of(i);
                [scene.initial_velocities[i], vy, vz]
            })
            .collect();
        let stiffest = (0..n).map(|i| 0.5 * mass[i] / contact::stiffness(e_star, radius[i])).fold(f64::INFINITY, f64::min);
        let g = dot(scene.space.gravity, scene.space.gravity).sqrt();
        // The fastest closing the scene sets going, or gravity across the container's diagonal.
        let diagonal = chambers.iter().map(Chamber::diagonal).fold(0.0, f64::max);
        let design_speed = (2.0 * scene.speed_scale()).max((2.0 * g * diagonal).sqrt()).max(f64::MIN_POSITIVE);
        let mut h_max = scene.horizon;
        if let Some(f) = scene.frame.filter(|f| f.stiffness > 0.0) {
            h_max = h_max.min(FRAME_PERIOD_FRACTION * 2.0 * std::f64::consts::PI * (f.mass / f.stiffness).sqrt());
        }
        if let Some(forcing) = scene.forcing {
            h_max = h_max.min(FRAME_PERIOD_FRACTION / forcing.frequency);
        }
        let floors = Floors::new(scene);
        if let Some(f) = &floors {
            let fastest = f.structure.building.undamped_modes().0.into_iter().fold(0.0, f64::max);
            h_max = h_max.min(FRAME_PERIOD_FRACTION * 2.0 * std::f64::consts::PI / fastest);
        }
        let (xs, vs) = floors.as_ref().map_or((scene.initial_displacement, 0.0), |f| f.carrying(scene, 0.0));
        let carrier_floor: Vec<usize> = dampers.iter().map(|d| d.floor).collect();
        let frame_mass = scene.frame.map_or(f64::INFINITY, |f| f.mass);
        let floor_mass = match &floors {
            Some(f) => carrier_floor.iter().map(|&j| f.structure.building.masses[j]).collect(),
            None => vec![frame_mass; dampers.len()],
        };
        let carried = match &floors {
            Some(f) => carrier_floor.iter().map(|&j| f.at(scene, 0.0, j)).collect(),
            None => vec![(xs, vs); dampers.len()],
        };
        let floor_count = floors.as_ref().map_or(1, |f| f.u.len());
        let inertia = (0..n).map(|i| 0.4 * mass[i] * radius[i] * radius[i]).collect();
        let mut solver = Solver {
            scene,
            chambers,
            damper,
            offsets,
            listed_carried: vec![0.0; carried.len()],
            carrier_floor,
            floor_mass,
            carried,
            cells,
            n,
            start: x.clone(),
            x,
            v,
            w: vec![[0.0; 3]; n],
            force: vec![[0.0; 3]; n],
            v_half: vec![[0.0; 3]; n],
            w_half: vec![[0.0; 3]; n],
            torque: vec![[0.0; 3]; n],
            mass,
            radius,
            inertia,
            ball_candidates: Vec::new(),
            wall_candidates: Vec::new(),
            listed_at: vec![[0.0; 3]; n],
            skin,
            open: vec![Vec::new(); n],
            xs,
            vs,
            wall_forces: vec![0.0; floor_count],
            floors,
            frame_mass,
            gravity: scene.space.gravity,
            e_star,
            friction: scene.space.friction,
            c: contact::damping_for(scene.restitution),
            v_floor: FLOOR_SPEED_FRACTION * scene.speed_scale(),
            stiffest,
            design_speed,
            h_max,
            fastest: 0.0,
            stiffness_rate: 0.0,
            damping_rate: 0.0,
            t: 0.0,
            steps: 0,
            impacts: Vec::new(),
            impact_loss: 0.0,
            friction_loss: 0.0,
            damping_loss: 0.0,
            forcing_work: 0.0,
        };
        solver.fastest = solver.v.iter().map(|v| dot(*v, *v)).fold(0.0, f64::max).sqrt();
        let h = solver.step();
        solver.forces(h);
        Ok(solver)
    }

    /// The step now: [`step_for`] the fastest closing the balls and the frame can have now, or
    /// the design speed if faster; short enough for every open contact (a tenth of `1 / omega`
    /// of its linearised stiffness and half the inverse of its damping rate, which a pile's
    /// loaded contacts can exceed); within the frame's and the forcing's periods.
    fn step(&self) -> f64 {
        let floor_speed = self.carried.iter().fold(0.0, |m: f64, (_, v)| m.max(v.abs()));
        let speed = self.design_speed.max(2.0 * (self.fastest + floor_speed));
        let mut h = self.h_max;
        if self.stiffest.is_finite() {
            h = h.min(step_for(self.stiffest, speed));
        }
        if self.stiffness_rate > 0.0 {
            h = h.min(CONTACT_STEP / self.stiffness_rate.sqrt());
        }
        if self.damping_rate > 0.0 {
            h = h.min(DAMPING_STEP / self.damping_rate);
        }
        h
    }

    /// The velocity of damper `d`'s walls.
    fn wall_velocity(&self, d: usize) -> [f64; 3] {
        [if self.frame_mass.is_finite() { self.carried[d].1 } else { 0.0 }, 0.0, 0.0]
    }

    /// Each damper's floor now, from the frame's state or the floors'.
    fn carry(&mut self) {
        match &self.floors {
            Some(f) => {
                for (d, &j) in self.carrier_floor.iter().enumerate() {
                    self.carried[d] = f.at(self.scene, self.t, j);
                }
            }
            None => self.carried.fill((self.xs, self.vs)),
        }
    }

    /// One velocity Verlet step of length `h`: a half kick, a drift, the forces at the new
    /// positions (with the velocities predicted at the step's end for the damping and
    /// friction), and the second half kick.
    fn advance(&mut self, h: f64) {
        let (t0, xs0, vs0) = (self.t, self.xs, self.vs);
        let scene = self.scene;
        let half = 0.5 * h;
        let frame_a = if self.frame_mass.is_finite() && self.floors.is_none() { self.wall_forces[0] / self.frame_mass } else { 0.0 };
        for i in 0..self.n {
            let (im, ii) = (1.0 / self.mass[i], 1.0 / self.inertia[i]);
            for k in 0..3 {
                self.v_half[i][k] = self.v[i][k] + half * self.force[i][k] * im;
                self.w_half[i][k] = self.w[i][k] + half * self.torque[i][k] * ii;
                self.x[i][k] += h * self.v_half[i][k];
                self.v[i][k] = self.v_half[i][k] + half * self.force[i][k] * im;
                self.w[i][k] = self.w_half[i][k] + half * self.torque[i][k] * ii;
            }
        }
        let vs_half = self.vs + half * frame_a;
        if let Some(f) = &mut self.floors {
            f.kick_and_drift(scene, t0, h, &self.wall_forces);
            (self.xs, self.vs) = f.carrying(scene, t0 + h);
        } else {
            self.xs += h * vs_half;
            self.vs = vs_half + half * frame_a;
        }
        self.t = t0 + h;
        self.carry();
        self.forces(h);
        let mut fastest_squared = 0.0f64;
        for i in 0..self.n {
            let (im, ii) = (1.0 / self.mass[i], 1.0 / self.inertia[i]);
            for k in 0..3 {
                self.v[i][k] = self.v_half[i][k] + half * self.force[i][k] * im;
                self.w[i][k] = self.w_half[i][k] + half * self.torque[i][k] * ii;
            }
            fastest_squared = fastest_squared.max(dot(self.v[i], self.v[i]));
        }
        self.fastest = fastest_squared.sqrt();
        if let Some(f) = &mut self.floors {
            let (d0, w0) = f.powers_now;
            f.kick(scene, self.t, h, &self.wall_forces);
            (self.xs, self.vs) = f.carrying(scene, self.t);
            let (d1, w1) = f.powers_now;
            self.damping_loss += half * (d0 + d1);
            self.forcing_work += half * (w0 + w1);
        } else {
            if self.frame_mass.is_finite() {
                self.vs = vs_half + half * self.wall_forces[0] / self.frame_mass;
            }
            self.damping_loss += half * (scene.damping_power(t0, vs0) + scene.damping_power(self.t, self.vs));
            self.forcing_work += half * (scene.forcing_power(t0, xs0, vs0) + scene.forcing_power(self.t, self.xs, self.vs));
        }
        self.carry();
        self.steps += 1;
    }

    /// The energy the system holds: the balls' kinetic and rotational energy, their height
    /// energy ([`Scene::height_energy`]), the frame's energy and the open contacts' elastic
    /// energy, J.
    fn energy(&self) -> f64 {
        let carrier = match &self.floors {
            Some(f) => f.energy(self.scene, self.t),
            None => self.scene.frame_energy(self.t, self.xs, self.vs),
        };
        let mut e = carrier + self.scene.height_energy_at_start();
        for i in 0..self.n {
            let (v, w) = (self.v[i], self.w[i]);
            e += 0.5 * self.mass[i] * dot(v, v) + 0.5 * self.inertia[i] * dot(w, w);
            e += self.mass[i] * dot(self.gravity, std::array::from_fn(|k| self.start[i][k] - self.x[i][k]));
            e += self.open[i].iter().map(|c| contact::elastic_energy(c.k, c.overlap)).sum::<f64>();
        }
        e
    }

    /// Steps to the horizon, sampling on the way; `Some(budget)` when a budget ran out first.
    fn run(&mut self, meter: &Meter, recorder: &mut Recorder) -> Result<Option<Budget>, ModelError> {
        let scene = self.scene;
        let sample_count = scene.sample_count();
        self.sample(recorder, 0.0, 0.0);
        let mut next_sample = 1;
        let energy_in = scene.initial_energy();
        while !scene.reached_horizon(self.t) {
            if let Some(budget) = meter.look(self.t, self.steps) {
                return Ok(Some(budget));
            }
            let h = self.step().min(scene.horizon - self.t);
            self.advance(h);
            // Samples in the step, from the state at its end along the velocities (the step
            // is far shorter than the sampling interval).
            let mut sampled = false;
            while next_sample < sample_count {
                let ts = next_sample as f64 * scene.sample_dt;
                if ts > self.t + 1e-9 * h && !scene.sample_at_step_end(ts, self.t, h) {
                    break;
                }
                self.sample(recorder, ts, (self.t - ts).max(0.0));
                next_sample += 1;
                sampled = true;
            }
            if sampled {
                self.watch_balance(energy_in, h)?;
            }
        }
        Ok(None)
    }

    /// Takes the sample at `ts`, `back` before the state now, along the velocities now.
    fn sample(&self, recorder: &mut Recorder, ts: f64, back: f64) {
        let (x, v) = (&self.x, &self.v);
        let ball = |i: usize| (std::array::from_fn(|k| x[i][k] - back * v[i][k]), v[i]);
        match &self.floors {
            None => recorder.sample_in_space(self.scene, ts, self.xs - back * self.vs, self.vs, ball),
            Some(f) => {
                let u: Vec<f64> = f.u.iter().zip(&f.v).map(|(u, v)| u - back * v).collect();
                let (xg, vg, _) = self.scene.ground_motion(ts);
                recorder.sample_floors_in_space(self.scene, ts, (&u, &f.v), (xg, vg), ball);
            }
        }
    }

    /// Stops the run when its energy balance is off by more than a tenth of the energies that
    /// flow: the step (`h`, the last) has not resolved some contact.
    fn watch_balance(&self, energy_in: f64, h: f64) -> Result<(), ModelError> {
        let held = self.energy();
        let taken = self.impact_loss + self.friction_loss;
        let residual = energy_in + self.forcing_work - held - self.damping_loss - taken;
        let flow = energy_in.abs() + self.forcing_work.abs() + taken + self.gravity_allowance();
        if held.is_finite() && residual.is_finite() && residual.abs() <= UNSTABLE_BALANCE * flow {
            return Ok(());
        }
        Err(ModelError::Unstable {
            scene: self.scene.name.clone(),
            model: Model::Compliant,
            t: self.t,
            reason: format!(
                "at t = {:.6e} s the energy balance is off by {residual:.6e} J of {flow:.6e} J that flowed: the step of {} s does not resolve its contacts",
                self.t,
                crate::scene::human(h)
            ),
        })
    }

    /// Energy gravity can give the balls falling across the container, J.
    fn gravity_allowance(&self) -> f64 {
        let g = dot(self.gravity, self.gravity).sqrt();
        let diagonal = self.chambers.iter().map(Chamber::diagonal).fold(0.0, f64::max);
        self.mass.iter().sum::<f64>() * g * diagonal
    }

    /// The run so far, ended at the current time; open contacts stay out of the impacts.
    fn finish(self, recorder: Recorder) -> Run {
        let scene = self.scene;
        let final_ = self.energy();
        let (series, motion) = recorder.finish();
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
            energy: EnergyAccount::forced(scene.initial_energy(), final_, self.damping_loss, self.impact_loss, self.forcing_work)
                .with_contact_loss(self.friction_loss),
            events: self.steps,
            final_velocities: self.v.iter().map(|v| v[0]).collect(),
            peak_true_acceleration: None,
            wall_time_s: 0.0,
        }
    }
}
