//! Stress tests of numerical stability: seeded random valid scenes through every model, each
//! run checked for panics, non-finite values, energy gained, impacts that lose more than an
//! impact can, momentum drift, balls outside the container and stalls. A failure is shrunk to
//! a minimal scene file that reproduces it.

use std::panic::{catch_unwind, AssertUnwindSafe};

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use serde::Serialize;

use crate::model::{Limits, Model, ModelError, RunOptions};
use crate::run::Run;
use crate::scene::format::{
    BallsFile, BedFile, ContainerFile, DamperFile, ForcingFile, FrameFile, Placement, RunFile, StructureFile, WorldFile,
};
use crate::scene::{self, Arrangement, ForcingKind, Length, Scene, SceneFile};

/// How a run failed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Failure {
    /// Which check: `panic`, `error`, `non-finite`, `energy-gained`, `impact-loss`,
    /// `momentum`, `outside`, `overlap`, `stall`, `invariant` (the reference's postcondition).
    pub check: &'static str,
    /// Details.
    pub detail: String,
}

/// One stressed scene's outcome (the JSON of `lpc stress`).
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    /// Seed of this scene.
    pub seed: u64,
    /// Model.
    pub model: Model,
    /// `None` when every check passed.
    pub failure: Option<Failure>,
    /// The shrunk scene that still fails, as TOML.
    pub minimal_scene: Option<String>,
    /// The model's reason when it refused the scene (before or during the run): a pass.
    pub refused: Option<String>,
    /// The refusal came during the run (the model stopped itself).
    pub refused_during_run: bool,
    /// Why the run stopped before its end without failing: the computing-time budget ran out
    /// (a typed stop, `--max-wall-time`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
    /// Seconds of computing the run and its checks took (on one core; shrinking a failure
    /// not included): the slow tail stays visible.
    pub wall_s: f64,
}

/// What `lpc stress` draws and how long each run may take.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Draws {
    /// Longest horizon drawn, s.
    pub max_horizon: f64,
    /// Harmonic forcing on every scene.
    pub forced: bool,
    /// The extremes a user can type ([`random_extreme_scene_file`]) instead of plausible dampers.
    pub extreme: bool,
    /// Seconds of computing each run may take, if limited.
    pub max_wall_s: Option<f64>,
    /// Each scene as 1 to 4 copies of its chain side by side ([`with_chains`]).
    pub chains: bool,
    /// Each scene's balls as a bed in a box, under gravity and friction ([`with_bed`]).
    pub beds: bool,
    /// Each scene's frame as a floor of a building of 1 to 5 storeys ([`with_structure`]).
    pub structures: bool,
    /// Each scene's bed as two dampers, each on a floor of its own draw ([`with_dampers`]).
    pub dampers: bool,
}

impl Draws {
    /// Plausible scenes run up to `max_horizon`, free, without a time budget, drawn on lines as
    /// [`random_scene_file`] draws them.
    pub fn plausible(max_horizon: f64) -> Draws {
        Draws {
            max_horizon,
            forced: false,
            extreme: false,
            max_wall_s: None,
            chains: false,
            beds: false,
            structures: false,
            dampers: false,
        }
    }
}

/// `file` with its balls as a bed, drawn from a stream of its own (seeded from `seed` alone):
/// 2 to 200 balls of one or two sizes (radii 2 to 8 mm) filling 20 to 70 % of the cells of a
/// lattice in a box sized to hold them (up to twice as long), on the lattice or (at most 40 %
/// of the cells) at random; gravity along -z three times in four; friction 0 to 0.5 (none a
/// quarter of the time); the reference's contact duration the default half the time, else 1 us
/// to 0.25 ms (log-uniform); the drawn restitution, frame and forcing.
pub fn with_bed(mut file: SceneFile, seed: u64) -> SceneFile {
    let mut rng = Pcg64::seed_from_u64(seed ^ 0xbed0_0000_0000_0000);
    let Some(balls) = file.balls.take() else { return file };
    let count = (rng.random_range(2f64.ln()..200f64.ln())).exp().round() as u32;
    let radius = rng.random_range(0.002..0.008);
    let radii = if rng.random_bool(0.5) { vec![radius] } else { vec![radius, radius * rng.random_range(0.4..0.9)] };
    let fill = rng.random_range(0.2..0.7);
    let side = (count as f64 / fill).cbrt().ceil();
    let pitch = 2.0 * radius * 1.01;
    let length = side * pitch * rng.random_range(1.0..2.0);
    let gravity = if rng.random_bool(0.75) { [0.0, 0.0, -9.81] } else { [0.0; 3] };
    let friction = if rng.random_bool(0.25) { 0.0 } else { rng.random_range(0.0..0.5) };
    let placement = if fill <= 0.4 && rng.random_bool(0.5) { Placement::Random } else { Placement::Lattice };
    file.container = Some(ContainerFile {
        length: Some(Length::Metres(length)),
        width: Some(Length::Metres(side * pitch)),
        height: Some(Length::Metres(side * pitch)),
    });
    file.world = Some(WorldFile { gravity: Some(gravity), friction: Some(friction), restitution: Some(balls.restitution) });
    file.bed =
        Some(BedFile { count: Some(count), fill_fraction: None, radii, proportions: None, density: 7800.0, placement, seed: Some(seed) });
    // Drawn last, so that every draw before it is what it was before the contact duration was.
    if rng.random_bool(0.5) {
        file.reference.contact_duration = Some((rng.random_range(1e-6f64.ln()..2.5e-4f64.ln())).exp());
    }
    // A bed has no reference radius: the displacement drawn in Rr is put in metres.
    if let Some(frame) = file.frame.as_mut() {
        frame.initial_displacement = Length::Metres(frame.initial_displacement.metres(crate::scene::ball_radius(0.11, 8000.0)));
    }
    file
}

/// `file` with its frame as a floor of a shear building, drawn from a stream of its own (seeded
/// from `seed` alone): 1 to 5 storeys whose floors weigh 0.3 to 3 times the frame's mass and
/// whose storeys are 0.3 to 3 times its stiffness (a free frame's: a period of 0.05 to 2 s),
/// damped by Rayleigh coefficients of 0 to 5 % of the fundamental's critical damping each; the
/// container on a floor drawn at random, displaced as the frame was, the others at rest. A
/// scene without forcing is shaken by random ground motion one time in three.
pub fn with_structure(mut file: SceneFile, seed: u64) -> SceneFile {
    let mut rng = Pcg64::seed_from_u64(seed ^ 0x5707_e400_0000_0000);
    let Some(frame) = file.frame.take() else { return file };
    let storeys = rng.random_range(1..=5usize);
    let stiffness = if frame.stiffness > 0.0 {
        frame.stiffness
    } else {
        let period: f64 = (rng.random_range(0.05f64.ln()..2f64.ln())).exp();
        frame.mass * (2.0 * std::f64::consts::PI / period).powi(2)
    };
    let masses: Vec<f64> = (0..storeys).map(|_| frame.mass * rng.random_range(0.3..3.0)).collect();
    let stiffnesses: Vec<f64> = (0..storeys).map(|_| stiffness * rng.random_range(0.3..3.0)).collect();
    // Rayleigh terms each up to 5 % of critical at the frame's own frequency.
    let omega = (stiffness / frame.mass).sqrt();
    let rayleigh = [rng.random_range(0.0..0.1) * omega, rng.random_range(0.0..0.1) / omega];
    let floor = rng.random_range(0..storeys);
    let rr = crate::scene::ball_radius(0.11, 8000.0);
    let mut displacements = vec![0.0; storeys];
    displacements[floor] = frame.initial_displacement.metres(rr);
    if file.forcing.is_none() && rng.random_bool(1.0 / 3.0) {
        // Kanai-Tajimi ground motion about the building's own frequency, up to 1 g or so.
        let frequency = omega / (2.0 * std::f64::consts::PI) * rng.random_range(0.3..3.0);
        let horizon = file.run.horizon.unwrap_or(1.0);
        file.forcing = Some(ForcingFile {
            kind: crate::scene::format::ExcitationKind::Random,
            ground_frequency: Some(frequency),
            ground_damping: Some(rng.random_range(0.2..0.8)),
            intensity: Some((rng.random_range(1e-6f64.ln()..1e-2f64.ln())).exp()),
            duration: Some(horizon),
            step: Some((0.05 / frequency).min(horizon / 10.0)),
            seed: Some(seed),
            ..Default::default()
        });
    }
    file.structure = Some(StructureFile {
        masses,
        stiffnesses,
        rayleigh: Some(rayleigh),
        damping_ratios: None,
        initial_displacements: Some(displacements),
        initial_velocities: None,
        damper_floor: Some(floor as u32 + 1),
    });
    file
}

/// `file` with its bed (`[container]` and `[bed]`) as two dampers, drawn from a stream of its
/// own (seeded from `seed` alone): the drawn bed on the drawn floor, and a copy of its box
/// holding 1 to as many balls, placed from another seed, on a floor drawn at random (maybe the
/// same one). A file without a bed is returned as it is.
pub fn with_dampers(mut file: SceneFile, seed: u64) -> SceneFile {
    let mut rng = Pcg64::seed_from_u64(seed ^ 0xda3b_e500_0000_0000);
    let (Some(container), Some(bed)) = (file.container.take(), file.bed.take()) else { return file };
    let floors = file.structure.as_ref().map_or(1, |s| s.masses.len() as u32);
    let floor = file.structure.as_mut().map_or(1, |s| s.damper_floor.take().unwrap_or(floors));
    let count = bed.count.unwrap_or(1);
    let second = BedFile { count: Some(rng.random_range(1..=count.max(1))), seed: Some(bed.seed.unwrap_or(1) + 1), ..bed.clone() };
    let damper = |floor: u32, bed: BedFile| DamperFile {
        floor: Some(floor),
        container: Some(container.clone()),
        bed: Some(bed),
        ..DamperFile::default()
    };
    file.dampers = Some(vec![damper(floor, bed), damper(rng.random_range(1..=floors), second)]);
    file
}

/// `file` with its arrangement as 1 to 4 chains side by side, drawn from a stream of its own
/// (seeded from `seed` alone), so that the rest of the scene is the one drawn without chains.
pub fn with_chains(mut file: SceneFile, seed: u64) -> SceneFile {
    let mut rng = Pcg64::seed_from_u64(seed ^ 0xc4a1_5000_0000_0000);
    if let Some(balls) = file.balls.as_mut() {
        balls.chains = Some(rng.random_range(1..=4));
    }
    file
}

/// A random scene at the extremes the scene format accepts: 1 to 10 000 balls, frame periods
/// 1 us to 1000 s (a fifth of the frames free), mass ratios 1 to 1e9, densities 1e-3 to 1e6
/// kg/m^3, e of 0, 1 or between, gaps and clearances of 0 or 1e-6 to 1e3 Rr, initial
/// displacements of 0 or up to 1e4 Rr (far beyond the container), horizons 1 ms to
/// `max_horizon` (at most 1e4 s), 2000 samples. A drawn file the scene's rules reject is a
/// typed refusal of the scene, as a user would get.
pub fn random_extreme_scene_file(seed: u64, max_horizon: f64) -> SceneFile {
    let mut rng = Pcg64::seed_from_u64(seed ^ 0x5eed_e87e_3e00_0000);
    let log_uniform = |rng: &mut Pcg64, lo: f64, hi: f64| (rng.random_range(lo.ln()..hi.ln())).exp();
    let n = log_uniform(&mut rng, 1.0, 10_000.5) as usize;
    let letters: String = (0..n.max(1)).map(|_| if rng.random_bool(0.5) { 'L' } else { 'S' }).collect();
    let mass = 1.35;
    let free = rng.random_bool(0.2);
    let period = log_uniform(&mut rng, 1e-6, 1e3);
    let stiffness = if free { 0.0 } else { mass * (2.0 * std::f64::consts::PI / period).powi(2) };
    let damping = if free { 0.0 } else { rng.random_range(0.0..0.5) * 2.0 * (stiffness * mass).sqrt() };
    let zero_or = |rng: &mut Pcg64, lo: f64, hi: f64| if rng.random_bool(0.25) { 0.0 } else { log_uniform(rng, lo, hi) };
    let gap = zero_or(&mut rng, 1e-6, 1e3);
    let clearance = zero_or(&mut rng, 1e-6, 1e3);
    let xs0 = zero_or(&mut rng, 1e-6, 1e4) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    let horizon = log_uniform(&mut rng, 1e-3, max_horizon.clamp(2e-3, 1e4));
    let restitution = match rng.random_range(0..3) {
        0 => 0.0,
        1 => 1.0,
        _ => rng.random_range(0.0..=1.0),
    };
    SceneFile {
        name: Some(format!("extreme-{seed}")),
        frame: Some(FrameFile { mass, stiffness, damping, initial_displacement: Length::Rr(xs0) }),
        balls: Some(BallsFile {
            arrangement: Arrangement::Letters(letters),
            large_mass: 0.11,
            mass_ratio: log_uniform(&mut rng, 1.0, 1e9),
            density: log_uniform(&mut rng, 1e-3, 1e6),
            restitution,
            gap: Length::Rr(gap),
            clearance: Some(Length::Rr(clearance)),
            container_length: None,
            chains: None,
        }),
        run: RunFile { horizon: Some(horizon), sample_dt: Some(horizon / 2000.0) },
        ..SceneFile::default()
    }
}

/// A random valid scene file: 1 to 50 balls, mass ratios 1 to 1000, e in [0, 1], gaps from 0
/// to large, clearance from 0, frame periods 1 ms to 10 s, xs0 up to ten times the clearance,
/// horizons up to `max_horizon`; a fifth of the frames are free (no spring, no damper) so that
/// momentum can be checked.
///
/// `forced` adds harmonic forcing (drawn after the rest, so the same seed gives the same
/// damper): a force or base motion half the time each (a force on a free frame, which base
/// motion could not move), at 0.1 to 10 times the frame's natural frequency (a free frame: 1
/// to 100 periods over the horizon), with an amplitude that would drive the bare frame to
/// 0.01 to 100 times the container's free travel: from barely impacting to violent.
pub fn random_scene_file(seed: u64, max_horizon: f64, forced: bool) -> SceneFile {
    let mut rng = Pcg64::seed_from_u64(seed);
    let log_uniform = |rng: &mut Pcg64, lo: f64, hi: f64| (rng.random_range(lo.ln()..hi.ln())).exp();
    let n = if rng.random_bool(0.5) { rng.random_range(1..=5) } else { rng.random_range(1..=50) };
    let letters: String = (0..n).map(|_| if rng.random_bool(0.5) { 'L' } else { 'S' }).collect();
    let mass = 1.35;
    let free = rng.random_bool(0.2);
    let period = log_uniform(&mut rng, 1e-3, 10.0);
    let stiffness = if free { 0.0 } else { mass * (2.0 * std::f64::consts::PI / period).powi(2) };
    let damping = if free { 0.0 } else { rng.random_range(0.0..0.3) * 2.0 * (stiffness * mass).sqrt() };
    let gap = if rng.random_bool(0.2) { 0.0 } else { log_uniform(&mut rng, 1e-3, 5.0) };
    let clearance = if rng.random_bool(0.2) { 0.0 } else { log_uniform(&mut rng, 1e-2, 5.0) };
    let xs0 = rng.random_range(0.0..=10.0) * clearance.max(0.1) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    let horizon = log_uniform(&mut rng, 0.05, max_horizon.max(0.06));
    let mass_ratio = log_uniform(&mut rng, 1.0, 1000.0);
    let restitution = if rng.random_bool(0.1) {
        0.0
    } else if rng.random_bool(0.1) {
        1.0
    } else {
        rng.random_range(0.0..=1.0)
    };
    let forcing = forced.then(|| {
        let kind = if free || rng.random_bool(0.5) { ForcingKind::Force } else { ForcingKind::Base };
        let frequency = if free { log_uniform(&mut rng, 1.0, 100.0) / horizon } else { log_uniform(&mut rng, 0.1, 10.0) / period };
        // The bare frame's steady amplitude X as a multiple of the free travel (in metres:
        // the large ball's radius is what Rr stands for).
        let rr = crate::scene::ball_radius(0.11, 8000.0);
        let travel = (gap * (n as f64 + 1.0) + clearance).max(1e-3) * rr;
        let x = log_uniform(&mut rng, 1e-2, 1e2) * travel;
        let w = 2.0 * std::f64::consts::PI * frequency;
        let dynamic = (stiffness - mass * w * w).hypot(damping * w);
        let amplitude = match kind {
            ForcingKind::Force => x * dynamic,
            ForcingKind::Base => x * dynamic / stiffness.hypot(damping * w),
        };
        ForcingFile { kind: kind.into(), amplitude: Some(amplitude), frequency: Some(frequency), ..Default::default() }
    });
    SceneFile {
        name: Some(format!("stress-{seed}")),
        frame: Some(FrameFile { mass, stiffness, damping, initial_displacement: Length::Rr(xs0) }),
        balls: Some(BallsFile {
            arrangement: Arrangement::Letters(letters),
            large_mass: 0.11,
            mass_ratio,
            density: 8000.0,
            restitution,
            gap: Length::Rr(gap),
            clearance: Some(Length::Rr(clearance)),
            container_length: None,
            chains: None,
        }),
        run: RunFile { horizon: Some(horizon), sample_dt: Some((horizon / 2000.0).max(1e-4)) },
        forcing,
        ..SceneFile::default()
    }
}

/// A run that passed the checks.
#[derive(Debug)]
pub enum Passed {
    /// The run, checked.
    Run(Box<Run>),
    /// The model refused the scene with this reason (a correct answer); `during_run` when it
    /// stopped itself part way rather than refusing up front.
    Refused {
        /// Why.
        reason: String,
        /// Stopped during the run.
        during_run: bool,
    },
    /// The run's computing-time budget ran out: a typed stop, with where it stood.
    Stopped(String),
}

/// Runs `model` on `scene` within `max_wall_s` seconds of computing (if given) and checks the
/// run.
pub fn judge_run(model: Model, scene: &Scene, max_wall_s: Option<f64>) -> Result<Passed, Failure> {
    let options = RunOptions::limited(Limits { max_wall_s, ..Limits::NONE });
    let outcome = catch_unwind(AssertUnwindSafe(|| model.simulate(scene, &options)));
    let run = match outcome {
        Err(panic) => {
            let msg =
                panic.downcast_ref::<String>().cloned().or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string())).unwrap_or_default();
            return Err(Failure { check: "panic", detail: msg });
        }
        Ok(Ok(run)) => run,
        // Refusing with a reason, before or during the run, is a correct answer; so is a stop
        // at the budget.
        Ok(Err(e)) => {
            let detail = e.to_string();
            return match e {
                ModelError::Refused(_) => Ok(Passed::Refused { reason: detail, during_run: false }),
                ModelError::Unstable { .. } => Ok(Passed::Refused { reason: detail, during_run: true }),
                ModelError::OverBudget(_) => Ok(Passed::Stopped(detail)),
                ModelError::Broken { .. } => Err(Failure { check: "invariant", detail }),
                ModelError::Stalled { .. } => Err(Failure { check: "stall", detail }),
            };
        }
    };
    judge(model, scene, &run)?;
    Ok(Passed::Run(Box::new(run)))
}

/// The checks of a run of `model` on `scene` (see the module docs).
pub fn judge(model: Model, scene: &Scene, run: &Run) -> Result<(), Failure> {
    let fail = |check, detail: String| Err(Failure { check, detail });
    let s = &run.series;
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    let series_finite = finite(s.xs()) && finite(s.vs()) && finite(s.a()) && (0..s.balls()).all(|i| finite(s.x(i)) && finite(s.v(i)));
    let account_finite =
        [run.energy.final_, run.energy.damping_loss, run.energy.impact_loss, run.energy.contact_loss].iter().all(|x| x.is_finite());
    if !(series_finite && account_finite) {
        return fail("non-finite", "a series or the energy account holds NaN or infinity".into());
    }
    // Energy scale: the initial energy, or for a scene at rest the work its impacts could do
    // (none), so that round-off on zero is not "energy gained".
    let e0 = run.energy.initial.max(1e-12);
    let checks = model.checks(scene, run);
    let (balance_tol, impact_tol) = (checks.energy_gain, checks.impact_gain);
    // Losses are never negative, so the energy at the end is at most what there was plus what
    // the excitation put in.
    let work = run.energy.forcing_work;
    // The energy put in: the initial energy and what the excitation did (a steady forced
    // response's energy where the excitation is a sine).
    let put_in = e0 + work.abs() + forced_energy_scale(scene);
    if run.energy.final_ > (e0 + work) * (1.0 + balance_tol) + balance_tol * work.abs() {
        return fail("energy-gained", format!("final energy {} > initial {} + forcing work {work}", run.energy.final_, e0));
    }
    // The balance closes to round-off in the reference and to the integration error in the
    // compliant model (Rapier's f32 velocities have no such balance). It is judged in joules
    // against the energies that flow, not a relative error: a scene at rest whose balls touch
    // a wall starts with the elastic energy of a round-off overlap (1e-36 J), and a forced
    // frame can take in and give back far more than it keeps; what the impacts and the damping
    // took is counted too (a bed falling under gravity loses in impacts what it had as height).
    if let Some(balance_tol) = checks.balance {
        let a = &run.energy;
        let residual = a.residual();
        let flow = put_in + a.impact_loss.abs() + a.damping_loss.abs() + a.contact_loss.abs();
        if residual.abs() > balance_tol * flow {
            return fail("energy-gained", format!("energy balance off by {residual:e} J (energy flows of {flow:e} J)"));
        }
    }
    // What an impact may appear to gain is judged against the energy put in: a scene that
    // starts at rest under a record gets all its energy from the ground, and the collapse
    // rule's gift to a contact pressed by the floor's acceleration grows with that
    // acceleration (docs/MODEL.md §14).
    for imp in &run.impacts {
        // A perfectly inelastic impact at approach speed u loses mu u^2 / 2. A side held by
        // the frame moves with the frame's mass, so mu is bounded by the free ball's mass: at
        // most the larger of the pair's ball masses (the ball's mass for a wall).
        let ball_mass = |b: scene::Body| match b {
            scene::Body::Ball(i) => scene.balls[i].mass,
            _ => 0.0,
        };
        let most = 0.5 * ball_mass(imp.a).max(ball_mass(imp.b)) * imp.approach_speed.powi(2);
        // (Only a single impulse is so bounded: a cascade at one instant or a merged run can
        // pass on energy from the neighbours.)
        let single = checks.exact_impacts && imp.impulses == 1;
        if imp.energy_lost < -impact_tol * put_in || (single && imp.energy_lost > most * (1.0 + 1e-9) + 1e-12 * e0) {
            return fail("impact-loss", format!("impact at t = {} loses {} J (at most {most} J)", imp.t, imp.energy_lost));
        }
    }
    if let (Some(f), true) = (scene.frame, !s.is_empty()) {
        // Only an unforced free frame conserves momentum (a force on it does work).
        if f.stiffness == 0.0 && f.damping == 0.0 && scene.forcing.is_none() {
            let p = |k: usize| f.mass * s.vs()[k] + (0..scene.balls.len()).map(|i| scene.balls[i].mass * s.v(i)[k]).sum::<f64>();
            let scale = f.mass * s.vs().iter().fold(0.0f64, |m, v| m.max(v.abs()))
                + scene.balls.iter().enumerate().map(|(i, b)| b.mass * s.v(i).iter().fold(0.0f64, |m, v| m.max(v.abs()))).sum::<f64>();
            let tol = checks.momentum * scale.max(1e-300);
            for k in 0..s.len() {
                if (p(k) - p(0)).abs() > tol {
                    return fail("momentum", format!("total momentum {} at t = {} (was {})", p(k), s.t()[k], p(0)));
                }
            }
        }
    }
    // Balls on lines can be checked pair by pair along x; a bed's balls only against the walls.
    let on_lines = scene.space.beyond_lines(&scene.initial_positions).is_none();
    let dampers = scene.damper_list();
    if !dampers.is_empty() {
        let tol = checks.wall_overlap;
        // Each damper's container moves with its floor (the series' carrying floor for one).
        let floor_at = |i: usize, k: usize| {
            let floor = dampers[scene.damper_of(i)].floor;
            let own = scene.has_several_dampers().then(|| s.floor(floor, k)).flatten();
            own.map_or(s.xs()[k], |f| f.0)
        };
        for k in 0..s.len() {
            for (i, b) in scene.balls.iter().enumerate() {
                let (xs, c) = (floor_at(i, k), dampers[scene.damper_of(i)].container);
                let (lo, hi) = (s.x(i)[k] - b.radius - xs, xs + c.length - s.x(i)[k] - b.radius);
                if lo < -tol || hi < -tol {
                    return fail("outside", format!("ball{} outside the container by {:e} m at t = {}", i + 1, -lo.min(hi), s.t()[k]));
                }
                // A chain's first ball has no left neighbour (the last ball of the chain
                // before it is in another channel).
                let first_of_chain = scene.space.chain_starts.binary_search(&i).is_ok();
                if let (Some(tol), true) = (checks.ball_overlap, on_lines && i > 0 && !first_of_chain) {
                    // Balls never pass each other (docs/MODEL.md §1).
                    let g = (s.x(i)[k] - b.radius) - (s.x(i - 1)[k] + scene.balls[i - 1].radius);
                    if g < -tol {
                        return fail("overlap", format!("ball{} and ball{} overlap by {:e} m at t = {}", i, i + 1, -g, s.t()[k]));
                    }
                }
            }
        }
    }
    let rate = run.events as f64 / run.horizon.max(1e-300);
    if checks.stall_rate.is_some_and(|most| rate > most) {
        return fail("stall", format!("{rate:.3e} events per simulated second"));
    }
    Ok(())
}

/// The energy a harmonic excitation moves in and out of the bare frame each period: its
/// steady response's kinetic energy at the peak speed, J (0 unforced).
fn forced_energy_scale(scene: &Scene) -> f64 {
    let (Some(f), Some((p, q, w))) = (scene.frame, scene.harmonic_load()) else { return 0.0 };
    let osc = crate::oscillator::Oscillator::new(f.mass, f.damping, f.stiffness);
    let speed = osc.harmonic_response(p, q, w).amplitude() * w;
    0.5 * f.mass * speed * speed
}

/// The damper scene of `file`, or why the scene's rules reject it.
fn validate(file: &SceneFile) -> Result<Scene, String> {
    scene::from_file(file.clone(), "stress", "stress").map_err(|e| e.to_string())?.scene.ok_or_else(|| "no damper scene".to_string())
}

/// The scene run for half as long, unless it is 10 ms or shorter already.
fn shorter(f: &SceneFile) -> Option<SceneFile> {
    let horizon = f.run.horizon.unwrap_or(5.0);
    (horizon > 0.01).then(|| {
        let mut g = f.clone();
        g.run.horizon = Some(horizon / 2.0);
        g.run.sample_dt = Some((horizon / 2.0 / 2000.0).max(1e-5));
        g
    })
}

/// Smaller and simpler variants of a scene file, for shrinking.
fn simplifications(f: &SceneFile) -> Vec<SceneFile> {
    let mut out = vec![];
    if let Some(list) = &f.dampers {
        // Dampers: one fewer, a shorter run.
        if list.len() > 1 {
            let mut g = f.clone();
            g.dampers = Some(list[..list.len() - 1].to_vec());
            out.push(g);
        }
        out.extend(shorter(f));
        return out;
    }
    if let Some(bed) = &f.bed {
        // A bed: fewer balls, a shorter run.
        if let Some(count) = bed.count.filter(|&c| c > 1) {
            let mut g = f.clone();
            g.bed.as_mut().unwrap().count = Some(count / 2);
            out.push(g);
        }
        out.extend(shorter(f));
        return out;
    }
    let balls = f.balls.as_ref().expect("damper");
    if let Arrangement::Letters(l) = &balls.arrangement {
        for cut in [l.len() / 2, l.len() - 1] {
            if cut >= 1 && cut < l.len() {
                for keep in [&l[..cut], &l[l.len() - cut..]] {
                    let mut g = f.clone();
                    g.balls.as_mut().unwrap().arrangement = Arrangement::Letters(keep.to_string());
                    out.push(g);
                }
            }
        }
    }
    out.extend(shorter(f));
    let mut tweak = |edit: &dyn Fn(&mut SceneFile)| {
        let mut g = f.clone();
        edit(&mut g);
        if toml::to_string(&g).ok() != toml::to_string(f).ok() {
            out.push(g);
        }
    };
    tweak(&|g| g.balls.as_mut().unwrap().mass_ratio = 10.0);
    tweak(&|g| g.balls.as_mut().unwrap().restitution = 0.9);
    tweak(&|g| g.balls.as_mut().unwrap().gap = Length::Rr(0.25));
    tweak(&|g| g.balls.as_mut().unwrap().clearance = Some(Length::Rr(1.0)));
    tweak(&|g| {
        if let Some(frame) = g.frame.as_mut() {
            frame.damping = 0.0;
        }
    });
    tweak(&|g| g.balls.as_mut().unwrap().chains = None);
    // A building: without its ground motion, and with its top storey taken off while the
    // container stays below it.
    tweak(&|g| {
        if g.structure.is_some() {
            g.forcing = None;
        }
    });
    tweak(&|g| {
        if let Some(s) = g.structure.as_mut() {
            let floor = s.damper_floor.unwrap_or(s.masses.len() as u32);
            if s.masses.len() > 1 && (floor as usize) < s.masses.len() {
                s.masses.pop();
                s.stiffnesses.pop();
                if let Some(x) = s.initial_displacements.as_mut() {
                    x.pop();
                }
            }
        }
    });
    out
}

/// Shrinks a failing scene: keeps applying simplifications while the same check still fails
/// (each candidate run within `max_wall_s`).
pub fn shrink(model: Model, file: &SceneFile, check_name: &str, max_wall_s: Option<f64>) -> SceneFile {
    let mut current = file.clone();
    'outer: for _ in 0..200 {
        for candidate in simplifications(&current) {
            if let Ok(scene) = validate(&candidate) {
                if matches!(judge_run(model, &scene, max_wall_s), Err(f) if f.check == check_name) {
                    current = candidate;
                    continue 'outer;
                }
            }
        }
        break;
    }
    current
}

/// Stresses `model` with `count` scenes from `seed` on, drawn as `draws` says; failing scenes
/// are shrunk.
pub fn stress(model: Model, seed: u64, count: u64, draws: Draws, progress: &(dyn Fn() + Sync)) -> Vec<Outcome> {
    use rayon::prelude::*;
    (seed..seed + count)
        .into_par_iter()
        .map(|s| {
            let file = if draws.extreme {
                random_extreme_scene_file(s, draws.max_horizon)
            } else {
                random_scene_file(s, draws.max_horizon, draws.forced)
            };
            let file = if draws.chains { with_chains(file, s) } else { file };
            let file = if draws.beds { with_bed(file, s) } else { file };
            let file = if draws.structures { with_structure(file, s) } else { file };
            let file = if draws.dampers { with_dampers(file, s) } else { file };
            let start = std::time::Instant::now();
            let outcome = |failure: Option<Failure>, minimal_scene, refused, refused_during_run, stopped, wall_s| Outcome {
                seed: s,
                model,
                failure,
                minimal_scene,
                refused,
                refused_during_run,
                stopped,
                wall_s,
            };
            let scene = match validate(&file) {
                Ok(scene) => scene,
                // An extreme draw the scene's rules reject: the user gets that refusal.
                Err(why) => {
                    progress();
                    return outcome(None, None, Some(why), false, None, start.elapsed().as_secs_f64());
                }
            };
            let (failure, refused, refused_during_run, stopped) = match judge_run(model, &scene, draws.max_wall_s) {
                Ok(Passed::Run(_)) => (None, None, false, None),
                Ok(Passed::Refused { reason, during_run }) => (None, Some(reason), during_run, None),
                Ok(Passed::Stopped(why)) => (None, None, false, Some(why)),
                Err(f) => (Some(f), None, false, None),
            };
            let wall_s = start.elapsed().as_secs_f64();
            let minimal_scene =
                failure.as_ref().map(|f| toml::to_string(&shrink(model, &file, f.check, draws.max_wall_s)).unwrap_or_default());
            progress();
            outcome(failure, minimal_scene, refused, refused_during_run, stopped, wall_s)
        })
        .collect()
}
