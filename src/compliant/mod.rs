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
mod driver;
mod events;
pub mod integrator;
mod jacobian;
mod output;
pub mod rosenbrock;
mod stepper;
mod system;

use crate::model::{Checks, Meter, Model, ModelError, RunOptions, Setting, Simulator};
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

