//! Known-solution problems shared by the integration tests: scenes built in code whose answers
//! are known by hand, and the one way to run the `lpc` binary.
#![allow(dead_code)]
// The known solutions solve small linear systems by index, as their derivations write them.
#![allow(clippy::needless_range_loop)]

pub mod masri_caughey;

use std::ffi::OsStr;
use std::process::{Command, Output};

use lpc_damper::model::{Model, ModelError, RunOptions};
use lpc_damper::run::Run;

/// The reference on `scene` with the default options.
pub fn reference(scene: &Scene) -> Result<Run, ModelError> {
    Model::Reference.simulate(scene, &RunOptions::default())
}

/// The compliant model on `scene` with the default options.
pub fn compliant(scene: &Scene) -> Result<Run, ModelError> {
    Model::Compliant.simulate(scene, &RunOptions::default())
}

/// Property tests draw from a fixed seed, so a run in CI draws what a run here draws, and a
/// failure is reproduced by running the test again. Nothing is written beside the sources.
pub fn proptest_config(cases: u32) -> proptest::test_runner::Config {
    proptest::test_runner::Config {
        cases,
        rng_seed: proptest::test_runner::RngSeed::Fixed(20131),
        failure_persistence: None,
        ..Default::default()
    }
}

/// The round-off of a free run's energy balance, relative to its energy, after `exchanges`
/// momentum exchanges among `balls` balls. An exchange sets two velocities, each within four
/// roundings of the velocities it was computed from, which moves the pair's kinetic energy by at
/// most 16 ulps of the larger body's energy before the impact (squaring doubles the relative
/// error); the loss it books is a product of six roundings and joins a sum with one more. With
/// room, 32 ulps of the run's energy per exchange. The initial and final energies are sums of
/// one term per ball, of two roundings each.
pub fn balance_roundoff(balls: usize, exchanges: u32) -> f64 {
    f64::EPSILON * (4.0 * balls as f64 + 32.0 * f64::from(exchanges))
}

/// The `lpc` binary as a user runs it, from the repository's root (so `scenes/...` resolves).
pub fn lpc_command() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_lpc"));
    command.current_dir(env!("CARGO_MANIFEST_DIR"));
    command
}

/// A valid scene from the text of a scene file (shrunk stress scenes are kept as text).
pub fn scene_from_toml(text: &str) -> Scene {
    lpc_damper::scene::parse(text, "test.toml", "test").expect("the scene parses").scene.expect("a single-run scene")
}

/// The paper's LSL damper (Fig. 9) as scene text, to edit or extend in a test.
pub const LSL_TOML: &str = r#"
name = "t"
[frame]
mass = 1.35
stiffness = 865.0
damping = 1.092
initial_displacement = 0.0185
[balls]
arrangement = "LSL"
large_mass = 0.11
mass_ratio = 10.0
density = 8000.0
restitution = 0.9
gap = "0.25 Rr"
clearance = "2 Rr"
[run]
horizon = 5.0
sample_dt = 0.001
"#;

/// `lpc ARGS...`, run to completion.
pub fn lpc<S: AsRef<OsStr>>(args: impl IntoIterator<Item = S>) -> Output {
    lpc_command().args(args).output().expect("the lpc binary runs")
}

use lpc_damper::scene::{ball_radius, Ball, BallKind, Container, Frame, RapierSettings, Scene};

/// The paper's frame (Table 1).
pub const PAPER_FRAME: Frame = Frame { mass: 1.35, stiffness: 865.0, damping: 1.092 };

/// A damper scene from explicit parts: balls (mass, kind) left to right with gap `gap`,
/// clearance `clearance`, density 8000.
pub fn damper(frame: Frame, xs0: f64, masses: &[f64], e: f64, gap: f64, clearance: f64, horizon: f64) -> Scene {
    let balls: Vec<Ball> = masses.iter().map(|&m| Ball { mass: m, radius: ball_radius(m, 8000.0), kind: BallKind::Custom }).collect();
    let mut positions = Vec::new();
    let mut x = xs0 + gap;
    for b in &balls {
        positions.push(x + b.radius);
        x += 2.0 * b.radius + gap;
    }
    let length = x - gap + clearance - xs0;
    Scene {
        name: "test".into(),
        frame: Some(frame),
        container: Some(Container { length, gap, clearance }),
        initial_velocities: vec![0.0; balls.len()],
        reference_radius: balls.first().map_or(0.0, |b| b.radius),
        space: lpc_damper::scene::Space::line(balls.len()),
        balls,
        restitution: e,
        initial_displacement: xs0,
        initial_positions: positions,
        horizon,
        sample_dt: 1e-3,
        reference: Default::default(),
        rapier: RapierSettings::default(),
        compliant: Default::default(),
        forcing: None,
        structure: None,
        dampers: vec![],
    }
}

/// Free balls on a line (no frame): `balls` left to right, `gaps[i]` between ball `i` and
/// ball `i + 1`, the first centred at 0, moving at `speeds`.
pub fn free_chain(balls: Vec<Ball>, gaps: &[f64], speeds: &[f64], e: f64, horizon: f64, sample_dt: f64) -> Scene {
    let mut positions: Vec<f64> = Vec::with_capacity(balls.len());
    for (i, b) in balls.iter().enumerate() {
        positions.push(if i == 0 { 0.0 } else { positions[i - 1] + balls[i - 1].radius + gaps[i - 1] + b.radius });
    }
    Scene {
        name: "free-chain".into(),
        frame: None,
        container: None,
        reference_radius: balls.first().map_or(0.0, |b| b.radius),
        space: lpc_damper::scene::Space::line(balls.len()),
        balls,
        restitution: e,
        initial_displacement: 0.0,
        initial_positions: positions,
        initial_velocities: speeds.to_vec(),
        horizon,
        sample_dt,
        reference: Default::default(),
        rapier: RapierSettings::default(),
        compliant: Default::default(),
        forcing: None,
        structure: None,
        dampers: vec![],
    }
}

/// Every scene file shipped in `scenes/`, expanded: damper scenes, every sweep value and every
/// chain case.
pub fn all_paper_scenes() -> Vec<Scene> {
    let mut out = Vec::new();
    let mut paths: Vec<_> = std::fs::read_dir(lpc_damper::scene::scenes_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    for p in paths {
        let loaded = lpc_damper::scene::load(&p).unwrap();
        if loaded.file.sweep.is_some() {
            out.extend(lpc_damper::studies::sweep::sweep_scenes(&loaded).unwrap().into_iter().map(|(_, s)| s));
        } else if let Some(s) = loaded.scene {
            out.push(s);
        }
        if let Some(cases) = loaded.chain {
            out.extend(cases.into_iter().map(|c| c.scene));
        }
    }
    out
}

/// Smallest gap between neighbours (walls included) over every sample, relative to nothing:
/// negative means overlap or a ball outside the container.
pub fn min_gap(scene: &Scene, run: &lpc_damper::run::Run) -> f64 {
    if scene.space.beyond_lines(&scene.initial_positions).is_some() {
        return min_gap_in_space(scene, run);
    }
    let s = &run.series;
    let n = scene.balls.len();
    let pairs = lpc_damper::scene::Pairs::new(n, &scene.space.chain_starts, scene.container.is_some());
    let mut min = f64::INFINITY;
    let mut x = vec![0.0; n];
    for k in 0..s.len() {
        for (i, xi) in x.iter_mut().enumerate() {
            *xi = s.x(i)[k];
        }
        let walls = scene.container.map(|c| (s.xs()[k], c.length));
        for p in pairs.range() {
            if let Some(g) = pairs.gap(&scene.balls, &x, walls, p) {
                min = min.min(g);
            }
        }
    }
    min
}

/// [`min_gap`] for balls off their lines: every pair of balls and every ball against every wall
/// of its chamber, at every sample.
fn min_gap_in_space(scene: &Scene, run: &lpc_damper::run::Run) -> f64 {
    let s = &run.series;
    let chamber = lpc_damper::scene::Chamber::new(scene).expect("a spatial scene has a chamber");
    let n = scene.balls.len();
    let mut min = f64::INFINITY;
    for k in 0..s.len() {
        let p: Vec<[f64; 3]> = (0..n)
            .map(|i| {
                let [y, z] = s.across(i, k);
                [s.x(i)[k] - s.xs()[k], y, z]
            })
            .collect();
        for i in 0..n {
            let r = scene.balls[i].radius;
            for wall in chamber.walls() {
                min = min.min(chamber.gap(wall, p[i], r).0);
            }
            for j in i + 1..n {
                let d: f64 = (0..3).map(|c| (p[j][c] - p[i][c]).powi(2)).sum::<f64>().sqrt();
                min = min.min(d - r - scene.balls[j].radius);
            }
        }
    }
    min
}
