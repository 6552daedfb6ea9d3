//! The contact model's stability map: for which step sizes and impact speeds a ball tunnels
//! through a wall or another ball, or an impact gains energy, under Rapier's defaults, with
//! Rapier's swept CCD, and with the plug-in's speculative margin (fixed and aligned steps).
//!
//! Each cell is one short run of a free frame (no spring, no damper, so momentum is checked
//! too) holding either one ball that strikes the walls or two balls, the first striking the
//! second, at a given speed; it is checked like a stress run and its final energy compared
//! with the reference's.

use serde::Serialize;

use crate::model::{Model, ModelError, RunOptions};
use crate::rapier::{simulate_with, StepSettings, Stepping};
use crate::scene::{self, Scene};

/// The impact a cell simulates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Case {
    /// One large ball crossing a container of one radius' clearance, striking the walls.
    BallWall,
    /// A large ball striking another across a gap of one radius.
    BallBall,
}

impl Case {
    /// Both cases.
    pub const ALL: [Case; 2] = [Case::BallWall, Case::BallBall];

    /// Name in outputs.
    pub fn name(self) -> &'static str {
        match self {
            Case::BallWall => "ball-wall",
            Case::BallBall => "ball-ball",
        }
    }
}

/// One way of configuring the contact model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Config {
    /// Name in outputs.
    pub name: &'static str,
    /// How steps are chosen.
    pub stepping: Stepping,
    /// Rapier's swept CCD.
    pub ccd: bool,
    /// The plug-in's speed-scaled contact prediction (otherwise Rapier's default).
    pub speculative_margin: bool,
}

/// The configurations the map compares.
pub const CONFIGS: [Config; 4] = [
    Config { name: "rapier-defaults", stepping: Stepping::Fixed, ccd: false, speculative_margin: false },
    Config { name: "rapier-ccd", stepping: Stepping::Fixed, ccd: true, speculative_margin: false },
    Config { name: "plug-in-fixed", stepping: Stepping::Fixed, ccd: false, speculative_margin: true },
    Config { name: "plug-in-aligned", stepping: Stepping::Aligned, ccd: false, speculative_margin: true },
];

/// Step sizes of the map, s.
pub const DTS: [f64; 5] = [1e-5, 1e-4, 1e-3, 4e-3, 1e-2];
/// Impact speeds of the map, m/s.
pub const SPEEDS: [f64; 6] = [0.01, 0.1, 1.0, 3.0, 10.0, 100.0];

/// Energy gained or lost relative to the reference above which a cell counts as inaccurate
/// (not unstable): a tenth of the initial energy.
pub const INACCURATE: f64 = 0.1;

/// One cell of the map.
#[derive(Debug, Clone, Serialize)]
pub struct Cell {
    /// Which impact.
    pub case: Case,
    /// Which configuration.
    pub config: &'static str,
    /// Step (longest step when aligned), s.
    pub dt: f64,
    /// Impact speed, m/s.
    pub speed: f64,
    /// Ball travel in one step, in ball radii (`speed dt / R`).
    pub travel_per_step: f64,
    /// `ok`, `inaccurate` (final energy off the reference's by more than [`INACCURATE`] of
    /// the initial energy), or the failed stress check (`outside` is tunnelling,
    /// `energy-gained`, `momentum`, ...).
    pub outcome: String,
    /// (final energy - reference final energy) / initial energy.
    pub energy_error: f64,
}

/// The scene of `case` at impact speed `speed`: a 1.35 kg free frame and large balls of the
/// paper (0.11 kg, e = 0.9), the horizon long enough for a few impacts.
pub fn case_scene(case: Case, speed: f64) -> Scene {
    let (arrangement, gap, clearance) = match case {
        Case::BallWall => ("L", "0 Rr", "1 Rr"),
        Case::BallBall => ("LL", "1 Rr", "20 Rr"),
    };
    let text = format!(
        "name = \"stability-{}\"\n[frame]\nmass = 1.35\nstiffness = 0.0\ndamping = 0.0\ninitial_displacement = 0.0\n\
         [balls]\narrangement = \"{arrangement}\"\nlarge_mass = 0.11\nmass_ratio = 1.0\ndensity = 8000.0\n\
         restitution = 0.9\ngap = \"{gap}\"\nclearance = \"{clearance}\"\n[run]\nhorizon = 1.0\nsample_dt = 1.0\n",
        case.name()
    );
    let mut s = scene::parse(&text, "stability", "stability").expect("valid").scene.expect("damper scene");
    let r = s.balls[0].radius;
    // Three crossings of the free space: the wall case strikes both walls, the ball case
    // strikes the second ball and, after it, the wall.
    s.horizon = 3.0 * r / speed;
    s.sample_dt = s.horizon / 200.0;
    s.initial_velocities[0] = speed;
    s
}

/// Runs one cell.
pub fn cell(case: Case, config: Config, dt: f64, speed: f64) -> Cell {
    let scene = case_scene(case, speed);
    let reference = Model::Reference.simulate(&scene, &RunOptions::default()).expect("two balls never stall");
    let settings = StepSettings {
        stepping: config.stepping,
        dt,
        solver_iterations: crate::rapier::DEFAULT_SOLVER_ITERATIONS,
        ccd: config.ccd,
        speculative_margin: config.speculative_margin,
        // The map measures what the contact model does, so it must not stop itself.
        safeguards: false,
    };
    let e0 = scene.initial_energy();
    let (outcome, energy_error) = match simulate_with(&scene, settings, &RunOptions::default()) {
        Err(ModelError::Refused(_)) => ("refused".to_string(), 0.0),
        Err(e) => (format!("error: {e}"), f64::NAN),
        Ok(run) => {
            let err = (run.energy.final_ - reference.energy.final_) / e0;
            match crate::studies::stress::judge(Model::Rapier, &scene, &run) {
                Err(f) => (f.check.to_string(), err),
                Ok(()) if err.abs() > INACCURATE => ("inaccurate".to_string(), err),
                Ok(()) => ("ok".to_string(), err),
            }
        }
    };
    Cell { case, config: config.name, dt, speed, travel_per_step: speed * dt / scene.balls[0].radius, outcome, energy_error }
}

/// The whole map: every case, configuration, step and speed (in parallel); `progress` is
/// called after each cell.
pub fn map(progress: &(dyn Fn() + Sync)) -> Vec<Cell> {
    use rayon::prelude::*;
    let mut jobs = vec![];
    for case in Case::ALL {
        for config in CONFIGS {
            for dt in DTS {
                for speed in SPEEDS {
                    jobs.push((case, config, dt, speed));
                }
            }
        }
    }
    jobs.into_par_iter()
        .map(|(case, config, dt, speed)| {
            let c = cell(case, config, dt, speed);
            progress();
            c
        })
        .collect()
}
