//! The compliant model of docs/MODEL.md §9: balls and walls deform, every contact a Hertz
//! spring with Hunt-Crossley damping ([`contact`]) chosen so that an isolated impact has the
//! scene's restitution at any speed, and the whole system integrated adaptively through every
//! contact, so impacts last tens of microseconds and have peak forces and durations.
//!
//! `system` is the scene as an ODE; `driver` the step loop, stepping by Dormand-Prince 5(4), or
//! by RODAS4 with the Jacobian solved in O(n) (`jacobian`) while a contact damps faster than an
//! explicit step could follow, both behind one `stepper` interface; `events` finds contact
//! onsets and ends on the dense output; `output` writes the samples and the run.

pub mod contact;
mod driver;
mod events;
mod integrator;
mod jacobian;
mod output;
mod rosenbrock;
pub mod spatial;
mod stepper;
mod system;

use crate::model::{Checks, Limits, Meter, Model, ModelError, RunOptions, Setting, Simulator};
use crate::run::Run;
use crate::scene::Scene;
use driver::Driver;
use system::System;

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
        if beyond_lines(scene) {
            return spatial::refusal(scene).map_or(Ok(()), Err);
        }
        Ok(())
    }

    fn simulate(&self, scene: &Scene, options: &RunOptions) -> Result<Run, ModelError> {
        if beyond_lines(scene) {
            return spatial::simulate(scene, options);
        }
        // Without a step budget the model still stops at MAX_STEPS rather than run for ever.
        let limits = Limits { max_steps: Some(options.limits.max_steps.unwrap_or(MAX_STEPS)), ..options.limits };
        let meter = Meter::new(&RunOptions { limits, ..*options }, PROGRESS_STEPS);
        let system = System::new(scene);
        let mut run = Driver::new(&system, options.record).run(&meter)?;
        run.wall_time_s = meter.elapsed();
        Ok(run)
    }

    fn checks(&self, scene: &Scene, run: &Run) -> Checks {
        if beyond_lines(scene) {
            return spatial::checks(scene, run);
        }
        // Each step errs by at most the tolerance of the contact's scales; they add up at
        // worst. Contact forces are equal and opposite and Runge-Kutta keeps linear invariants.
        let balance = (run.events as f64 * scene.compliant.tolerance).max(1e-9);
        Checks {
            energy_gain: balance,
            balance: Some(balance),
            impact_gain: 1e-9,
            exact_impacts: false,
            momentum: 1e-9,
            wall_overlap: overlap_bound(scene, run, 0.0),
            ball_overlap: None,
            stall_rate: None,
        }
    }

    fn settings(&self) -> &'static [Setting] {
        &[Setting::Tolerance]
    }

    fn stepping(&self, scene: &Scene) -> &'static str {
        if beyond_lines(scene) {
            "velocity Verlet at the fastest contact's Hertz time"
        } else {
            "adaptive"
        }
    }
}

/// Whether `scene` goes to the spatial path: balls off their lines, motion across them,
/// gravity or friction (several chains on lines stay on the one-line path, exactly).
/// Whether `scene` goes to the spatial path: balls beyond lines, or several dampers (which the
/// one-line path does not carry).
fn beyond_lines(scene: &Scene) -> bool {
    scene.has_several_dampers() || scene.space.beyond_lines(&scene.initial_positions).is_some()
}

/// How far the compliant model's balls may legitimately overlap a wall: twice the elastic
/// overlap of the fastest impact (the heaviest ball on the stiffest-to-reach, i.e. softest,
/// wall contact) plus the static overlap of all the balls pressed by the frame's largest
/// acceleration and `pressing` (gravity beyond one line), m/s^2.
fn overlap_bound(scene: &Scene, run: &Run, pressing: f64) -> f64 {
    let e_star = contact::effective_modulus(&scene.compliant);
    let r_min = scene.balls.iter().map(|b| b.radius).fold(f64::INFINITY, f64::min);
    let k = contact::stiffness(e_star, contact::effective_radius(r_min, None));
    let m_max = scene.balls.iter().map(|b| b.mass).fold(0.0, f64::max);
    let m_all: f64 = scene.balls.iter().map(|b| b.mass).sum();
    let u_max = run.impacts.iter().map(|i| i.approach_speed).fold(0.0, f64::max);
    let a_max = run.series.a().iter().fold(0.0f64, |m, a| m.max(a.abs())) + pressing;
    1e-9 * scene.container.map_or(1e-3, |c| c.length.max(1e-3))
        + 2.0 * (contact::max_overlap(m_max, u_max, k) + (m_all * a_max / k).powf(2.0 / 3.0))
}
