//! How the contact model steps on a scene and what it tolerates: its defaults, the bounds on its
//! step that keep Rapier's straight-line walls on the frame's path, and Rapier's allowed
//! overlap and round-off.

use super::resources::{StepSettings, LENGTH_UNIT};
use crate::scene::{Scene, Stepping};

/// Default stepping (from the accuracy study in docs/BENCHMARKS.md).
pub const DEFAULT_STEPPING: Stepping = Stepping::Aligned;
/// Default longest step, s.
pub const DEFAULT_DT: f64 = 2e-3;
/// Default solver iterations.
pub const DEFAULT_SOLVER_ITERATIONS: usize = 4;

/// Steps per period of the frame at least: Rapier sees the walls move in a straight line over
/// a step, which must stay close to the frame's true path.
pub const STEPS_PER_FRAME_PERIOD: f64 = 40.0;

/// Rapier's allowed contact overlap (`0.005 length_unit`), m: what a contact may sink before
/// Rapier corrects it.
pub const ALLOWED_OVERLAP: f64 = 0.005 * LENGTH_UNIT as f64;
/// Energy a step's contacts may gain, relative to the energy put in (f32 velocities, one
/// rounding per impulse): beyond it the run stops as unstable.
pub const ENERGY_GAIN_TOLERANCE: f64 = 1e-3;

/// Largest gap between the straight path Rapier gives the walls over a step and the frame's
/// true path, m: a fifth of [`ALLOWED_OVERLAP`], so that the
/// walls a ball meets are where the frame is.
pub const WALL_CHORD_ERROR: f64 = 1e-5;

/// The frame's largest acceleration to expect: its spring at the larger of the initial
/// displacement and the steady forced amplitude, plus the excitation's load, m/s^2.
pub fn peak_frame_acceleration(scene: &Scene) -> f64 {
    if let Some(s) = scene.structure.as_deref() {
        return peak_floor_acceleration(scene, s);
    }
    let Some(f) = scene.frame else { return 0.0 };
    let (steady, load) = scene.harmonic_load().map_or((0.0, 0.0), |(p, q, w)| {
        let osc = crate::oscillator::Oscillator::new(f.mass, f.damping, f.stiffness);
        (osc.harmonic_response(p, q, w).amplitude(), p.hypot(q))
    });
    (f.stiffness * scene.initial_displacement.abs().max(steady) + load) / f.mass
}

/// A structure's carrying floor's largest acceleration to expect: the scene's speed scale at
/// the fastest mode's frequency, plus the record's peak (the ground's acceleration, or a
/// floor's force over its mass) and a sine's, m/s^2.
fn peak_floor_acceleration(scene: &Scene, s: &crate::scene::Structure) -> f64 {
    let fastest = s.building.undamped_modes().0.into_iter().fold(0.0, f64::max);
    let ground = s.ground.as_ref().map_or(0.0, |g| g.peak());
    let force = s.force.as_ref().map_or(0.0, |f| f.record.peak() / s.building.masses[f.floor]);
    let sine = scene.forcing.map_or(0.0, |g| match g.kind {
        crate::scene::ForcingKind::Base => g.amplitude * g.omega() * g.omega(),
        crate::scene::ForcingKind::Force => g.amplitude / s.building.masses[s.floor],
    });
    scene.motion_speed() * fastest + ground + force + sine
}

/// The stepping a scene asks for, with the defaults filled in and the step kept inside the
/// stable region: at most a 40th of the frame's natural period (a structure's fundamental one)
/// and of the forcing period, and short enough that the walls' straight path over a step stays
/// within [`WALL_CHORD_ERROR`] of the frame's (`a h^2 / 8`, where a structure's faster modes
/// count).
pub fn settings(scene: &Scene) -> StepSettings {
    let dt = scene.rapier.dt.unwrap_or(DEFAULT_DT);
    let a = peak_frame_acceleration(scene);
    let chord_bound = if a > 0.0 { (8.0 * WALL_CHORD_ERROR / a).sqrt() } else { f64::INFINITY };
    let forcing_bound = scene.forcing.map_or(f64::INFINITY, |g| 1.0 / (g.frequency * STEPS_PER_FRAME_PERIOD));
    let period_bound = scene
        .frame
        .filter(|f| f.stiffness > 0.0)
        .map_or(f64::INFINITY, |f| 2.0 * std::f64::consts::PI * (f.mass / f.stiffness).sqrt() / STEPS_PER_FRAME_PERIOD)
        .min(forcing_bound);
    StepSettings {
        stepping: scene.rapier.stepping.unwrap_or(DEFAULT_STEPPING),
        dt: dt.min(period_bound).min(chord_bound),
        solver_iterations: scene.rapier.solver_iterations.map_or_else(|| default_iterations(scene), |i| i as usize),
        ccd: scene.rapier.ccd.unwrap_or(false),
        speculative_margin: true,
        safeguards: true,
    }
}

/// Solver iterations when the scene sets none: [`DEFAULT_SOLVER_ITERATIONS`] per decade of
/// the largest mass ratio of neighbouring balls. Rapier's iterative solver converges more
/// slowly the more unequal the masses it couples: a light ball squeezed between a heavy one
/// and a wall sinks into the wall with too few iterations (docs/BENCHMARKS.md, "Stress").
pub fn default_iterations(scene: &Scene) -> usize {
    // Past 16 decades the light ball's momentum is below the heavy one's round-off: more
    // iterations cannot couple them (and an infinite ratio must not ask for infinitely many).
    let decades = neighbour_mass_ratio(scene).log10().ceil();
    DEFAULT_SOLVER_ITERATIONS * if decades.is_nan() { 1 } else { decades.clamp(1.0, 16.0) as usize }
}

/// The largest mass ratio of two neighbouring balls (1 for fewer than two balls).
pub fn neighbour_mass_ratio(scene: &Scene) -> f64 {
    scene.balls.windows(2).map(|w| (w[0].mass / w[1].mass).max(w[1].mass / w[0].mass)).fold(1.0, f64::max)
}
