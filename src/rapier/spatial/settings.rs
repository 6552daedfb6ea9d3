//! What the spatial path accepts and the settings and checks it runs with: which scenes go to
//! it or are refused, Rapier's settings for a scene, and how much energy and sinking a run may
//! show (docs/MODEL.md §9).

use super::world::{self, SolverSettings, SpatialWorld};
use crate::model::{Checks, STALL_EVENTS_PER_SIM_S};
use crate::run::Run;
use crate::scene::{Chamber, Scene};

/// Default step of the spatial path, s: Rapier's steps are plastic and the bounces come from
/// the impact law, so a millisecond resolves the flights between impacts of centimetre balls.
pub const DEFAULT_SPATIAL_DT: f64 = 1e-3;
/// Default solver iterations of the spatial path (Rapier's default).
pub const DEFAULT_SPATIAL_ITERATIONS: usize = 4;
/// Natural frequency of Rapier's contact springs, as a fraction of its substep rate (Rapier
/// takes as many substeps in a step as it has solver iterations): a quarter, the stiffest its
/// soft contacts stay stable at (docs/MODEL.md §9, "Stiff contacts"). Softer, a contact passes
/// only a share of a load in each substep, and a pile shaken below friction's hold loses energy
/// as a viscous body: at a quarter of the step rate (250 Hz at 1 ms) a settled bed on a rigidly
/// shaken floor lost seven times what it loses at a quarter of the substep rate (1000 Hz).
pub const CONTACT_FREQUENCY_PER_SUBSTEP_RATE: f64 = 0.25;
/// Damping ratio of Rapier's contact springs (Rapier's default: overdamped, no rebound).
pub const CONTACT_DAMPING_RATIO: f64 = 10.0;
/// The least distance ahead at which Rapier predicts contacts, in its length unit (the largest
/// diameter): a pair closer than that is in Rapier's solve even when nothing moves it, so that
/// what the step's own solve sets moving (a ball squeezed out between two others) is caught.
pub const LEAST_PREDICTION: f32 = 0.02;
/// Pairs closer than this fraction of Rapier's length unit (the largest diameter) touch: the
/// impacts of a step set touching pairs approaching, which then strike in turn.
pub const TOUCHING_FRACTION: f64 = 2e-3;
/// Energy the spatial path may gain, relative to the energy put in, besides what gravity does
/// in Rapier's resting contacts (see [`energy_gain_allowance`]).
pub const SPATIAL_ENERGY_GAIN: f64 = 1e-3;
/// How deep Rapier's resting contacts may sink, as a fraction of a ball's radius: Rapier pushes
/// sunk balls back out, lifting them by up to this much, which gravity turns into energy.
pub const RESTING_SINK_FRACTION: f64 = 0.05;
/// The most the fastest motion of a scene may carry a body in one step, as a fraction of the
/// smallest ball's radius.
pub const STEP_TRAVEL: f64 = 0.2;
/// Whether `scene` goes to the spatial path: several chains or dampers, or anything a line
/// cannot hold (balls off their chain's line, motion across, gravity, friction).
pub fn needs_spatial(scene: &Scene) -> bool {
    scene.space.chains() > 1 || scene.has_several_dampers() || scene.space.beyond_lines(&scene.initial_positions).is_some()
}

/// Why the spatial path cannot run `scene`, or `None` when it can.
pub fn refusal(scene: &Scene) -> Option<String> {
    if scene.frame.is_none() {
        return Some("the scene has no frame; the spatial contact model needs a container on a frame".into());
    }
    let dampers = scene.damper_list();
    let several = dampers.len() > 1;
    for (k, d) in dampers.iter().enumerate() {
        if let Err(reason) = Chamber::of_damper(scene, d) {
            return Some(if several { format!("damper[{k}]: {reason}") } else { reason });
        }
    }
    if scene.balls.is_empty() {
        return Some("the scene has no balls".into());
    }
    if scene.rapier.stepping == Some(crate::scene::Stepping::Aligned) {
        return Some(
            "aligned stepping follows contacts on one line; the spatial contact model takes fixed steps (`rapier.stepping = \"fixed\"`)"
                .into(),
        );
    }
    if scene.rapier.ccd == Some(true) {
        return Some("the spatial contact model finds contacts with Rapier's speculative margin and has no swept CCD".into());
    }
    None
}

/// The Rapier world the spatial path steps for `scene`: the frame's walls and a sphere per
/// ball, every contact plastic, Rapier set as [`solver_settings`] gives; or why the path
/// cannot run the scene.
pub fn rapier_world(scene: &Scene) -> Result<SpatialWorld, String> {
    if let Some(why) = refusal(scene) {
        return Err(why);
    }
    Ok(world::build(scene, &chambers(scene)?, solver_settings(scene)))
}

/// Each damper's container.
pub(super) fn chambers(scene: &Scene) -> Result<Vec<Chamber>, String> {
    scene.damper_list().iter().map(|d| Chamber::of_damper(scene, d)).collect()
}

/// Rapier's settings for `scene` on the spatial path: the scene's `[rapier] dt` (default
/// [`DEFAULT_SPATIAL_DT`]) within the one-line path's bounds on the frame's motion, the
/// largest ball's diameter as length unit, and contact springs stiffened to the step.
pub fn solver_settings(scene: &Scene) -> SolverSettings {
    let bounded = crate::rapier::settings(scene);
    let dt = if scene.rapier.dt.is_some() { bounded.dt } else { bounded.dt.min(DEFAULT_SPATIAL_DT) };
    let largest = scene.balls.iter().map(|b| b.radius).fold(0.0, f64::max);
    // Nothing may cross more than a fraction of the smallest ball in a step at the scene's
    // speed: Rapier's speculative contacts and stiffened springs catch that much, no more (a
    // wall swung at hundreds of metres per second otherwise passes through balls).
    let smallest = scene.balls.iter().map(|b| b.radius).fold(f64::INFINITY, f64::min);
    let dt = if smallest.is_finite() { dt.min(STEP_TRAVEL * smallest / scene.speed_scale()) } else { dt };
    let iterations = scene.rapier.solver_iterations.map_or(DEFAULT_SPATIAL_ITERATIONS, |i| i as usize);
    SolverSettings {
        dt,
        length_unit: (2.0 * largest).max(1e-6),
        solver_iterations: iterations,
        contact_frequency: CONTACT_FREQUENCY_PER_SUBSTEP_RATE * iterations as f64 / dt,
        contact_damping: CONTACT_DAMPING_RATIO,
    }
}

/// Energy the spatial path may gain over a run of `scene`, J: [`SPATIAL_ENERGY_GAIN`] of the
/// energy put in, plus every ball lifted by [`RESTING_SINK_FRACTION`] of its radius against
/// gravity (Rapier pushing resting balls back out of the contacts they sank into).
pub fn energy_gain_allowance(scene: &Scene, energy_in: f64) -> f64 {
    let g = scene.space.gravity.iter().map(|c| c * c).sum::<f64>().sqrt();
    let lift: f64 = scene.balls.iter().map(|b| b.mass * g * RESTING_SINK_FRACTION * b.radius).sum();
    SPATIAL_ENERGY_GAIN * energy_in.abs() + lift
}

/// Rapier's resting sink on the spatial path, m: [`RESTING_SINK_FRACTION`] of the largest
/// radius of `scene`, to which a ball sunk deeper into a wall is put back.
pub fn resting_wall_sink(scene: &Scene) -> f64 {
    let largest = scene.balls.iter().map(|b| b.radius).fold(0.0, f64::max);
    RESTING_SINK_FRACTION * largest
}

/// The deepest a ball of `scene` may sink into a wall on the spatial path, m: Rapier's resting
/// sink ([`resting_wall_sink`]) and a micrometre beyond it. Deeper, Rapier's soft contacts have
/// given too far, and the ball is put back to the resting sink.
pub fn wall_sink_limit(scene: &Scene) -> f64 {
    resting_wall_sink(scene) + 1e-6
}

/// The tolerances a spatial run is checked with: its energy allowance, Rapier's resting sink
/// as the overlap a ball may have with a wall, and the one-line path's momentum bound.
pub fn checks(scene: &Scene, run: &Run) -> Checks {
    let put_in = (run.energy.initial.abs() + run.energy.forcing_work.abs()).max(f64::MIN_POSITIVE);
    let energy_gain = energy_gain_allowance(scene, put_in) / put_in;
    Checks {
        energy_gain,
        // The account books every step's energy change beyond the impacts as its contact
        // loss (see `SpatialReport::contact_loss`), so its balance closes by construction and
        // says nothing; the energy gain does.
        balance: None,
        impact_gain: energy_gain,
        exact_impacts: false,
        momentum: 1e-5,
        wall_overlap: wall_sink_limit(scene),
        ball_overlap: None,
        stall_rate: Some(STALL_EVENTS_PER_SIM_S),
    }
}
