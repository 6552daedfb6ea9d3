//! The rules of a scene file: every value checked where it is read, and an error that names
//! the file, the field (or the flag it came from) and the rule broken. A [`Scene`] exists only
//! once every rule holds.

use super::excitation::Forcing;
use super::format::{self, Arrangement, Length, SceneFile};
use super::format::{ExcitationKind, ForcingKind};
use super::geometry::{ball_radius, Ball, BallKind, Container};
use super::parameters::{Parameter, Tolerances};
use super::record::{is_at2, read_points, GroundRecord, KanaiTajimi};
use super::settings::{CompliantSettings, RapierSettings, ReferenceSettings};
use super::space::Space;
use super::structure::{FloorForce, Frame, Structure};
use super::{human, ChainCase, Loaded, Scene, SceneError, CHAIN_HORIZON, DEFAULT_HORIZON, DEFAULT_SAMPLE_DT, MAX_SAMPLES};
use crate::storeys::{Building, Load, StoreyDamping};
use std::sync::Arc;

/// Validates an already parsed file.
pub fn from_file(parsed: SceneFile, file: &str, default_name: &str) -> Result<Loaded, SceneError> {
    let v = Validator { file, flags: &[] };
    let name = parsed.name.clone().unwrap_or_else(|| default_name.to_string());
    if parsed.chain.is_some() && (parsed.frame.is_some() || parsed.balls.is_some()) {
        return Err(v.err("chain", "cannot be combined with [frame] or [balls]: a chain file describes only the KER experiment"));
    }
    if parsed.chain.is_some() && parsed.structure.is_some() {
        return Err(v.err("chain", "cannot be combined with [structure]: a chain file describes only the KER experiment"));
    }
    let scene = match (parsed.frame.is_some() || parsed.structure.is_some(), &parsed.chain) {
        (true, _) => Some(build_damper(&parsed, &name, &v)?),
        (false, None) => return Err(v.err("frame", "is missing: a scene needs a [frame] table (or [structure], or [chain])")),
        (false, Some(_)) => None,
    };
    let chain = match &parsed.chain {
        Some(c) => Some(build_chain(c, &parsed.run, reference_settings(&parsed.reference, &v)?, &name, &v)?),
        None => None,
    };
    if let (Some(sweep), Some(_)) = (&parsed.sweep, &scene) {
        if sweep.values.is_empty() {
            return Err(v.err("sweep.values", "is empty: give at least one value"));
        }
        let second = match (&sweep.parameter_y, &sweep.values_y) {
            (Some(p), Some(values)) if !values.is_empty() => Some((p, values)),
            (Some(_), Some(_)) => return Err(v.err("sweep.values_y", "is empty: give at least one value")),
            (None, None) => None,
            (Some(_), None) => return Err(v.err("sweep.values_y", "is missing: `parameter_y` needs its values")),
            (None, Some(_)) => return Err(v.err("sweep.parameter_y", "is missing: `values_y` needs its parameter")),
        };
        // Each value alone must make a valid scene (a grid's combinations are checked when run).
        let axes = std::iter::once(("sweep.parameter", "sweep.values", &sweep.parameter, &sweep.values))
            .chain(second.map(|(p, values)| ("sweep.parameter_y", "sweep.values_y", p, values)));
        for (parameter_field, values_field, parameter, values) in axes {
            for (i, value) in values.iter().enumerate() {
                let varied =
                    parameter.parse::<Parameter>().and_then(|p| p.apply(&parsed, *value)).map_err(|rule| v.err(parameter_field, &rule))?;
                build_damper(&varied, &name, &v).map_err(|e| match e {
                    SceneError::Invalid { file, field, rule } => {
                        SceneError::Invalid { file, field: format!("{values_field}[{i}] (as {field})"), rule }
                    }
                    other => other,
                })?;
            }
        }
    } else if parsed.sweep.is_some() {
        return Err(v.err("sweep", "needs a damper scene ([frame] and [balls])"));
    }
    let tolerances = match (&parsed.tolerances, &scene) {
        (Some(t), Some(s)) => Some(tolerances(t, &parsed, s, &v)?),
        (Some(_), None) => return Err(v.err("tolerances", "needs a damper scene ([frame] and [balls])")),
        (None, _) => None,
    };
    Ok(Loaded { file: parsed, path: file.to_string(), scene, chain, tolerances })
}

/// Checks values against the scene's rules and names what broke one.
pub(super) struct Validator<'a> {
    pub(super) file: &'a str,
    /// Fields whose value came from a command-line flag, and that flag (`run.horizon` ->
    /// `--horizon`): an error names what the user typed.
    pub(super) flags: &'a [(&'static str, &'static str)],
}

impl Validator<'_> {
    pub(super) fn err(&self, field: &str, rule: &str) -> SceneError {
        let field = self.flags.iter().find(|(f, _)| *f == field).map_or(field, |(_, flag)| flag);
        SceneError::Invalid { file: self.file.into(), field: field.into(), rule: rule.into() }
    }
    pub(super) fn finite(&self, field: &str, x: f64) -> Result<f64, SceneError> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.err(field, &format!("must be a finite number (got {})", human(x))))
        }
    }
    pub(super) fn positive(&self, field: &str, x: f64) -> Result<f64, SceneError> {
        self.finite(field, x)?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(self.err(field, &format!("must be positive (got {})", human(x))))
        }
    }
    pub(super) fn non_negative(&self, field: &str, x: f64) -> Result<f64, SceneError> {
        self.finite(field, x)?;
        if x >= 0.0 {
            Ok(x)
        } else {
            Err(self.err(field, &format!("must not be negative (got {})", human(x))))
        }
    }
    pub(super) fn restitution(&self, field: &str, e: f64) -> Result<f64, SceneError> {
        self.finite(field, e)?;
        if (0.0..=1.0).contains(&e) {
            Ok(e)
        } else {
            Err(self.err(field, &format!("is a coefficient of restitution and must lie in [0, 1] (got {})", human(e))))
        }
    }
    pub(super) fn run(&self, run: &format::RunFile, default_horizon: f64) -> Result<(f64, f64), SceneError> {
        let horizon = self.positive("run.horizon", run.horizon.unwrap_or(default_horizon))?;
        let dt = self.positive("run.sample_dt", run.sample_dt.unwrap_or(DEFAULT_SAMPLE_DT))?;
        validate_sample_dt(horizon, dt).map_err(|rule| self.err("run.sample_dt", &rule))?;
        Ok((horizon, dt))
    }
}

/// The rule an output step must keep: no longer than the horizon, at most [`MAX_SAMPLES`] samples.
pub fn validate_sample_dt(horizon: f64, dt: f64) -> Result<(), String> {
    if !(dt.is_finite() && dt > 0.0) {
        return Err(format!("must be a positive finite step (got {})", human(dt)));
    }
    if dt > horizon {
        return Err(format!("({} s) is longer than the horizon ({} s): no sample would be written", human(dt), human(horizon)));
    }
    if horizon / dt > MAX_SAMPLES {
        return Err(format!(
            "({} s) would write {} samples over {} s; at most {} are allowed",
            human(dt),
            human(horizon / dt),
            human(horizon),
            human(MAX_SAMPLES)
        ));
    }
    Ok(())
}

pub(super) fn build_damper(f: &SceneFile, name: &str, v: &Validator) -> Result<Scene, SceneError> {
    let record = match &f.forcing {
        Some(g) if g.kind == ExcitationKind::Record => Some(Arc::new(ground_record(g, "record", &["file", "scale"], v)?)),
        Some(g) if g.kind == ExcitationKind::Random => {
            let record = random_ground(g, v)?.record(g.seed.unwrap_or(1));
            within_range(&record, "forcing.intensity", v)?;
            Some(Arc::new(record))
        }
        _ => None,
    };
    let force = match &f.forcing {
        Some(g) if g.kind == ExcitationKind::ForceRecord => {
            Some((g.floor, Arc::new(ground_record(g, "force_record", &["file", "scale", "floor"], v)?)))
        }
        _ => None,
    };
    let Some(st) = &f.structure else {
        if record.is_none() && force.is_none() {
            return build_frame_damper(f, name, v);
        }
        // A frame under a record: a structure of one storey.
        let plain = SceneFile { forcing: None, ..f.clone() };
        let mut scene = build_frame_damper(&plain, name, v)?;
        let fr = scene.frame.expect("a damper scene has a frame");
        if fr.stiffness <= 0.0 {
            return Err(v.err("frame.stiffness", "must be positive under a record (the frame must stand on the ground)"));
        }
        let mut building = Building::new(vec![fr.mass], vec![fr.stiffness], &StoreyDamping::Rayleigh { mass: 0.0, stiffness: 0.0 });
        building.damping[(0, 0)] = fr.damping;
        scene.structure = Some(Arc::new(Structure {
            building,
            floor: 0,
            initial_displacements: vec![scene.initial_displacement],
            initial_velocities: vec![0.0],
            ground: record,
            force: force.map(|(floor, record)| floor_force(floor, record, 1, 0, v)).transpose()?,
        }));
        return Ok(scene);
    };
    if f.frame.is_some() {
        return Err(v.err("structure", "cannot be combined with [frame]: give the primary structure one way"));
    }
    let mut structure = structure(st, record, v)?;
    if let Some((floor, record)) = force {
        structure.force = Some(floor_force(floor, record, structure.floors(), structure.floor, v)?);
    }
    if let Some(g) = f.forcing.as_ref().filter(|g| matches!(g.kind, ExcitationKind::Force | ExcitationKind::Base)) {
        // A sine drives the structure only where it has a steady response: an undamped
        // building has none at a natural frequency (within 1e-12 relative, the round-off of
        // its modes), nor where its dynamic stiffness is singular.
        let b = &structure.building;
        let omega = 2.0 * std::f64::consts::PI * g.frequency.unwrap_or(0.0);
        let undamped = b.damping.iter().all(|&c| c == 0.0);
        let at_mode = undamped && b.undamped_modes().0.iter().any(|w| (omega - w).abs() <= 1e-12 * w);
        let unit = vec![crate::storeys::C64::new(1.0, 0.0); b.floors()];
        if omega.is_finite() && omega > 0.0 && (at_mode || b.harmonic_response(&b.masses, omega, &unit).is_none()) {
            return Err(v.err(
                "forcing.frequency",
                &format!(
                    "({} Hz) drives an undamped structure at a natural frequency: its amplitude grows without bound",
                    human(omega / (2.0 * std::f64::consts::PI))
                ),
            ));
        }
    }
    let d = structure.floor;
    let b = &structure.building;
    // The carrying floor seen alone: its mass takes the balls' impulses, and its spring gives
    // it the structure's fundamental period (the scale of periods, speeds and peaks).
    let (omegas, _) = b.undamped_modes();
    let frame = format::FrameFile {
        mass: b.masses[d],
        stiffness: if b.floors() == 1 { b.stiffnesses[0] } else { b.masses[d] * omegas[0] * omegas[0] },
        damping: b.damping[(d, d)],
        initial_displacement: Length::Metres(structure.initial_displacements[d]),
    };
    let forcing = if structure.is_recorded() { None } else { f.forcing.clone() };
    let plain = SceneFile { structure: None, frame: Some(frame), forcing, ..f.clone() };
    let mut scene = build_frame_damper(&plain, name, v)?;
    let one_storey_at_rest = structure.floors() == 1 && !structure.is_recorded() && structure.initial_velocities[0] == 0.0;
    if !one_storey_at_rest {
        scene.structure = Some(Arc::new(structure));
    }
    Ok(scene)
}

/// The `[structure]` table, checked.
fn structure(st: &format::StructureFile, ground: Option<Arc<GroundRecord>>, v: &Validator) -> Result<Structure, SceneError> {
    let n = st.masses.len();
    if n == 0 {
        return Err(v.err("structure.masses", "is empty: give each floor's mass"));
    }
    if st.stiffnesses.len() != n {
        return Err(v.err("structure.stiffnesses", &format!("has {} values for {n} floors: give one per storey", st.stiffnesses.len())));
    }
    for i in 0..n {
        v.positive(&format!("structure.masses[{i}]"), st.masses[i])?;
        v.positive(&format!("structure.stiffnesses[{i}]"), st.stiffnesses[i])?;
    }
    let per_floor = |field: &str, values: &Option<Vec<f64>>| -> Result<Vec<f64>, SceneError> {
        let Some(values) = values else { return Ok(vec![0.0; n]) };
        if values.len() != n {
            return Err(v.err(field, &format!("has {} values for {n} floors: give one per floor", values.len())));
        }
        for (i, &x) in values.iter().enumerate() {
            v.finite(&format!("{field}[{i}]"), x)?;
        }
        Ok(values.clone())
    };
    let initial_displacements = per_floor("structure.initial_displacements", &st.initial_displacements)?;
    let initial_velocities = per_floor("structure.initial_velocities", &st.initial_velocities)?;
    let damping = match (&st.rayleigh, &st.damping_ratios) {
        (Some(_), Some(_)) => return Err(v.err("structure.damping_ratios", "cannot be combined with `rayleigh`: give the damping one way")),
        (Some([a0, a1]), None) => StoreyDamping::Rayleigh {
            mass: v.non_negative("structure.rayleigh[0]", *a0)?,
            stiffness: v.non_negative("structure.rayleigh[1]", *a1)?,
        },
        (None, Some(ratios)) => {
            if ratios.len() != n {
                return Err(v.err("structure.damping_ratios", &format!("has {} values for {n} modes: give one per mode", ratios.len())));
            }
            for (i, &z) in ratios.iter().enumerate() {
                let field = format!("structure.damping_ratios[{i}]");
                if !(v.non_negative(&field, z)? < 1.0) {
                    return Err(
                        v.err(&field, &format!("must be below 1: an overdamped mode is not a mode of vibration (got {})", human(z)))
                    );
                }
            }
            StoreyDamping::Modal(ratios.clone())
        }
        (None, None) => StoreyDamping::Rayleigh { mass: 0.0, stiffness: 0.0 },
    };
    let floor = match st.damper_floor {
        None => n - 1,
        Some(k) if (1..=n as u32).contains(&k) => k as usize - 1,
        Some(k) => return Err(v.err("structure.damper_floor", &format!("must name a floor from 1 (bottom) to {n} (got {k})"))),
    };
    let building = Building::new(st.masses.clone(), st.stiffnesses.clone(), &damping);
    building.modes(floor, 0.0, Load::Ground).map_err(|why| v.err("structure", &why))?;
    Ok(Structure { building, floor, initial_displacements, initial_velocities, ground, force: None })
}

/// The floor a force record acts on: `floor` (1 at the bottom) of `floors`, or the damper's
/// (`carrying`, 0 at the bottom) when it names none.
fn floor_force(
    floor: Option<u32>,
    record: Arc<GroundRecord>,
    floors: usize,
    carrying: usize,
    v: &Validator,
) -> Result<FloorForce, SceneError> {
    let floor = match floor {
        None => carrying,
        Some(k) if (1..=floors as u32).contains(&k) => k as usize - 1,
        Some(k) => return Err(v.err("forcing.floor", &format!("must name a floor from 1 (bottom) to {floors} (got {k})"))),
    };
    Ok(FloorForce { floor, record })
}

/// Refuses the keys of `[forcing]` that belong to another kind than `kind`.
fn only_keys_of(g: &format::ForcingFile, kind: &str, keys: &[&str], v: &Validator) -> Result<(), SceneError> {
    let given = [
        ("amplitude", g.amplitude.is_some()),
        ("frequency", g.frequency.is_some()),
        ("file", g.file.is_some()),
        ("scale", g.scale.is_some()),
        ("ground_frequency", g.ground_frequency.is_some()),
        ("ground_damping", g.ground_damping.is_some()),
        ("intensity", g.intensity.is_some()),
        ("duration", g.duration.is_some()),
        ("step", g.step.is_some()),
        ("envelope", g.envelope.is_some()),
        ("seed", g.seed.is_some()),
        ("floor", g.floor.is_some()),
    ];
    match given.iter().find(|(key, given)| *given && !keys.contains(key)) {
        Some((key, _)) => Err(v.err(&format!("forcing.{key}"), &format!("does not belong to a forcing of kind `{kind}`"))),
        None => Ok(()),
    }
}

/// The Kanai-Tajimi ground motion a `[forcing]` of kind `random` describes, checked.
fn random_ground(g: &format::ForcingFile, v: &Validator) -> Result<KanaiTajimi, SceneError> {
    let keys = ["ground_frequency", "ground_damping", "intensity", "duration", "step", "envelope", "seed"];
    only_keys_of(g, "random", &keys, v)?;
    let needed = |field: &str, x: Option<f64>| x.ok_or_else(|| v.err(field, "is missing: a random ground motion needs it"));
    let kt = KanaiTajimi {
        ground_frequency: v.positive("forcing.ground_frequency", needed("forcing.ground_frequency", g.ground_frequency)?)?,
        ground_damping: v.positive("forcing.ground_damping", needed("forcing.ground_damping", g.ground_damping)?)?,
        intensity: v.non_negative("forcing.intensity", needed("forcing.intensity", g.intensity)?)?,
        duration: v.positive("forcing.duration", needed("forcing.duration", g.duration)?)?,
        step: v.positive("forcing.step", g.step.unwrap_or(0.01))?,
        envelope: match g.envelope {
            None => None,
            Some(e) => {
                for (i, x) in e.iter().enumerate() {
                    v.non_negative(&format!("forcing.envelope[{i}]"), *x)?;
                }
                if !(e[0] <= e[1]) {
                    return Err(v.err("forcing.envelope", "must rise (its first time) before its strong motion ends (its second)"));
                }
                Some(e)
            }
        },
    };
    if kt.duration / kt.step > 1e7 {
        return Err(v.err("forcing.step", &format!("({} s) would draw more than 1e7 points over {} s", human(kt.step), human(kt.duration))));
    }
    Ok(kt)
}

/// The record a `[forcing]` of kind `kind` (`record` or `force_record`, with its `keys`) names,
/// read and scaled. A force is two columns: a PEER `.AT2` file is a ground acceleration in g.
fn ground_record(g: &format::ForcingFile, kind: &str, keys: &[&str], v: &Validator) -> Result<GroundRecord, SceneError> {
    only_keys_of(g, kind, keys, v)?;
    let file = g.file.as_ref().ok_or_else(|| v.err("forcing.file", "is missing: a record needs its file"))?;
    let scale = v.finite("forcing.scale", g.scale.unwrap_or(1.0))?;
    let path = std::path::Path::new(v.file).parent().unwrap_or(std::path::Path::new("")).join(file);
    let text = std::fs::read_to_string(&path).map_err(|e| v.err("forcing.file", &format!("cannot be read ({}): {e}", path.display())))?;
    if g.kind == ExcitationKind::ForceRecord && is_at2(&text) {
        return Err(v.err(
            "forcing.file",
            &format!("({}) is a PEER ground acceleration in g; a force record is two columns, time (s) and force (N)", path.display()),
        ));
    }
    let (times, accel) = read_points(&text).map_err(|why| v.err("forcing.file", &format!("({}) {why}", path.display())))?;
    let record = GroundRecord::new(times, accel, scale);
    within_range(&record, "forcing.scale", v)?;
    Ok(record)
}

/// The largest value a record may reach (m/s^2 or N): the energies it puts in grow as its
/// square, and beyond this they would leave the range of double precision.
const RECORD_LIMIT: f64 = 1e100;

/// Refuses a record (read, or drawn at random) whose values reach [`RECORD_LIMIT`].
fn within_range(record: &GroundRecord, field: &str, v: &Validator) -> Result<(), SceneError> {
    let peak = record.peak();
    if !(peak <= RECORD_LIMIT) {
        return Err(v.err(
            field,
            &format!(
                "puts the record's peak at {}, beyond {}: the energy it gives grows as its square and would leave the range of double precision",
                human(peak),
                human(RECORD_LIMIT)
            ),
        ));
    }
    Ok(())
}

fn build_frame_damper(f: &SceneFile, name: &str, v: &Validator) -> Result<Scene, SceneError> {
    let fr = f.frame.as_ref().expect("checked by caller");
    let frame = Frame {
        mass: v.positive("frame.mass", fr.mass)?,
        stiffness: v.non_negative("frame.stiffness", fr.stiffness)?,
        damping: v.non_negative("frame.damping", fr.damping)?,
    };
    let (horizon, sample_dt) = v.run(&f.run, DEFAULT_HORIZON)?;
    let reference = reference_settings(&f.reference, v)?;
    let rapier = rapier_settings(&f.rapier, v)?;
    let compliant = compliant_settings(&f.compliant, v)?;
    let forcing = match &f.forcing {
        None => None,
        Some(g) => Some(forcing(g, &frame, v)?),
    };
    let world = world(f, v)?;
    let given: Vec<&str> = [("balls", f.balls.is_some()), ("bed", f.bed.is_some()), ("ball", f.explicit_balls.is_some())]
        .iter()
        .filter(|g| g.1)
        .map(|g| g.0)
        .collect();
    if given.len() > 1 {
        return Err(v.err(given[1], &format!("cannot be combined with [{}]: give the balls one way", given[0])));
    }
    if f.balls.is_none() && (f.bed.is_some() || f.explicit_balls.is_some()) {
        let settings = Settings { horizon, sample_dt, reference, rapier, compliant, forcing };
        return placed_damper(f, name, v, frame, world, settings);
    }
    let Some(b) = &f.balls else {
        if f.container.is_some() {
            return Err(v.err("container", "needs balls: give [balls], [bed] or [[ball]]"));
        }
        let xs0 = v.finite("frame.initial_displacement", fr.initial_displacement.metres(0.0))?;
        if matches!(fr.initial_displacement, Length::Rr(_)) {
            return Err(v.err("frame.initial_displacement", "is given in Rr but the scene has no balls to define Rr"));
        }
        return Ok(Scene {
            name: name.into(),
            frame: Some(frame),
            container: None,
            balls: vec![],
            restitution: 1.0,
            initial_displacement: xs0,
            initial_positions: vec![],
            initial_velocities: vec![],
            horizon,
            sample_dt,
            reference,
            rapier,
            compliant,
            forcing,
            reference_radius: 0.0,
            space: Space::line(0),
            structure: None,
        });
    };
    if world.restitution.is_some() {
        return Err(v.err("world.restitution", "is given with [balls], which has its own `restitution`: give one"));
    }
    let large_mass = v.positive("balls.large_mass", b.large_mass)?;
    let mass_ratio = v.positive("balls.mass_ratio", b.mass_ratio)?;
    let density = v.positive("balls.density", b.density)?;
    let restitution = v.restitution("balls.restitution", b.restitution)?;
    let rr = ball_radius(large_mass, density);
    let balls = arrangement_balls(&b.arrangement, large_mass, mass_ratio, density, "balls.arrangement", v)?;
    let xs0 = v.finite("frame.initial_displacement", fr.initial_displacement.metres(rr))?;
    let gap = v.finite("balls.gap", b.gap.metres(rr))?;
    if gap < 0.0 {
        return Err(v.err("balls.gap", &format!("must not be negative: neighbouring balls would overlap (got {gap} m)")));
    }
    let sum_d: f64 = balls.iter().map(|b| 2.0 * b.radius).sum();
    let n = balls.len() as f64;
    let (length, clearance) = match (b.clearance, b.container_length) {
        (Some(_), Some(_)) => {
            return Err(v.err("balls.container_length", "and `balls.clearance` are both given: give one (Eq. 11 ties them)"))
        }
        (None, None) => return Err(v.err("balls.clearance", "is missing: give the clearance or the container length")),
        (Some(lc), None) => {
            let lc = v.non_negative("balls.clearance", lc.metres(rr))?;
            (n * gap + sum_d + lc, lc)
        }
        (None, Some(le)) => {
            let le = v.positive("balls.container_length", le.metres(rr))?;
            let lc = le - n * gap - sum_d;
            if lc < 0.0 {
                return Err(v.err(
                    "balls.container_length",
                    &format!("is {le} m but the balls and gaps need {} m: the balls cannot fit", n * gap + sum_d),
                ));
            }
            (le, lc)
        }
    };
    if !length.is_finite() {
        return Err(
            v.err("balls.gap", &format!("and the clearance make the container {} m long, more than a number can hold", human(length)))
        );
    }
    let mut positions = Vec::with_capacity(balls.len());
    let mut x = xs0 + gap;
    for ball in &balls {
        positions.push(x + ball.radius);
        x += 2.0 * ball.radius + gap;
    }
    let (balls, positions, space) = chains(b, f.container.as_ref(), &world, balls, positions, rr, v)?;
    Ok(Scene {
        name: name.into(),
        frame: Some(frame),
        container: Some(Container { length, gap, clearance }),
        initial_velocities: vec![0.0; balls.len()],
        space,
        balls,
        restitution,
        initial_displacement: xs0,
        initial_positions: positions,
        horizon,
        sample_dt,
        reference,
        rapier,
        compliant,
        forcing,
        reference_radius: rr,
        structure: None,
    })
}

/// What `[world]` sets: gravity, friction and, for balls not from `[balls]`, restitution.
pub(super) struct World {
    gravity: [f64; 3],
    friction: f64,
    restitution: Option<f64>,
}

fn world(f: &SceneFile, v: &Validator) -> Result<World, SceneError> {
    let Some(w) = &f.world else { return Ok(World { gravity: [0.0; 3], friction: 0.0, restitution: None }) };
    let gravity = w.gravity.unwrap_or([0.0; 3]);
    for (a, g) in gravity.iter().enumerate() {
        v.finite(&format!("world.gravity[{a}]"), *g)?;
    }
    let friction = v.non_negative("world.friction", w.friction.unwrap_or(0.0))?;
    let restitution = match w.restitution {
        Some(e) => Some(v.restitution("world.restitution", e)?),
        None => None,
    };
    Ok(World { gravity, friction, restitution })
}

/// A length of `[container]` in metres (`Rr` being `rr`), positive.
fn container_length(field: &str, l: Option<Length>, rr: f64, v: &Validator) -> Result<Option<f64>, SceneError> {
    match l {
        None => Ok(None),
        Some(Length::Rr(_)) if rr == 0.0 => Err(v.err(field, "is given in Rr but the scene has no reference radius")),
        Some(l) => Ok(Some(v.positive(field, l.metres(rr))?)),
    }
}

/// `[balls]`' line copied into `chains` channels side by side, with the container's
/// cross-section and the world: the balls, their centres along x and the space they are in.
fn chains(
    b: &format::BallsFile,
    container: Option<&format::ContainerFile>,
    world: &World,
    line: Vec<Ball>,
    positions: Vec<f64>,
    rr: f64,
    v: &Validator,
) -> Result<(Vec<Ball>, Vec<f64>, Space), SceneError> {
    let count = b.chains.unwrap_or(1);
    if !(1..=10_000).contains(&count) {
        return Err(v.err("balls.chains", &format!("must lie in 1..=10000 (got {count})")));
    }
    let n = line.len();
    if count as usize * n > super::placement::MAX_BED_BALLS as usize {
        return Err(v.err(
            "balls.chains",
            &format!("makes {} balls; a scene may hold at most {}", count as usize * n, super::placement::MAX_BED_BALLS),
        ));
    }
    let spatial = count > 1 || container.is_some() || world.gravity != [0.0; 3] || world.friction != 0.0;
    if !spatial {
        return Ok((line, positions, Space::line(n)));
    }
    let c = container.cloned().unwrap_or_default();
    if c.length.is_some() {
        return Err(v.err("container.length", "is set by [balls] (Eq. 11): give `balls.clearance` or `balls.container_length` instead"));
    }
    let diameter = 2.0 * line.iter().map(|b| b.radius).fold(0.0, f64::max);
    let count_f = count as f64;
    let width = container_length("container.width", c.width, rr, v)?;
    let height = container_length("container.height", c.height, rr, v)?.unwrap_or(diameter);
    let channel = width.map_or(diameter, |w| w / count_f);
    let width = width.unwrap_or(count_f * diameter);
    if channel < diameter {
        return Err(v.err(
            "container.width",
            &format!(
                "({} m) gives each of the {count} chains a channel {} m wide, narrower than its largest ball ({} m)",
                human(width),
                human(channel),
                human(diameter)
            ),
        ));
    }
    if height < diameter {
        return Err(v.err("container.height", &format!("({} m) is lower than the largest ball ({} m)", human(height), human(diameter))));
    }
    // Balls rest on the floor gravity presses them to, or sit on the channel's axis.
    let z = |r: f64| match world.gravity[2] {
        g if g < 0.0 => r - 0.5 * height,
        g if g > 0.0 => 0.5 * height - r,
        _ => 0.0,
    };
    let mut balls = Vec::with_capacity(n * count as usize);
    let mut xs = Vec::with_capacity(n * count as usize);
    let mut lateral = Vec::with_capacity(n * count as usize);
    for k in 0..count as usize {
        let y = (k as f64 + 0.5) * channel - 0.5 * width;
        balls.extend_from_slice(&line);
        xs.extend_from_slice(&positions);
        lateral.extend(line.iter().map(|b| [y, z(b.radius)]));
    }
    let space = Space {
        chain_starts: (0..count as usize).map(|k| k * n).collect(),
        lateral,
        lateral_velocities: vec![],
        section: [width, height],
        channel: if count > 1 { channel } else { 0.0 },
        gravity: world.gravity,
        friction: world.friction,
    };
    Ok((balls, xs, space))
}

/// The run settings every damper scene carries, read before its balls.
struct Settings {
    horizon: f64,
    sample_dt: f64,
    reference: ReferenceSettings,
    rapier: RapierSettings,
    compliant: CompliantSettings,
    forcing: Option<Forcing>,
}

/// A damper whose balls come from `[bed]` or `[[ball]]`: placed in the box `[container]`
/// sizes, under `[world]`.
fn placed_damper(f: &SceneFile, name: &str, v: &Validator, frame: Frame, world: World, s: Settings) -> Result<Scene, SceneError> {
    let which = if f.bed.is_some() { "[bed]" } else { "[[ball]]" };
    let c = f
        .container
        .clone()
        .ok_or_else(|| v.err("container", &format!("is missing: {which} balls need the container's length, width and height")))?;
    let mut size = [0.0; 3];
    for (a, (field, l)) in
        [("container.length", c.length), ("container.width", c.width), ("container.height", c.height)].into_iter().enumerate()
    {
        if matches!(l, Some(Length::Rr(_))) {
            return Err(v.err(field, &format!("is given in Rr, which {which} scenes do not define: give metres")));
        }
        size[a] = container_length(field, l, 0.0, v)?.ok_or_else(|| v.err(field, &format!("is missing: {which} balls need it")))?;
    }
    let restitution = world
        .restitution
        .ok_or_else(|| v.err("world.restitution", &format!("is missing: {which} balls need a coefficient of restitution")))?;
    let fr = f.frame.as_ref().expect("checked by caller");
    if matches!(fr.initial_displacement, Length::Rr(_)) {
        return Err(v.err("frame.initial_displacement", &format!("is given in Rr, which {which} scenes do not define: give metres")));
    }
    let xs0 = v.finite("frame.initial_displacement", fr.initial_displacement.metres(0.0))?;
    let placed = match (&f.bed, &f.explicit_balls) {
        (Some(bed), _) => super::placement::bed(bed, size, v)?,
        (None, Some(list)) => super::placement::explicit(list, size, v)?,
        (None, None) => unreachable!("checked by caller"),
    };
    let largest = placed.balls.iter().map(|b| b.radius).fold(0.0, f64::max);
    let lateral_velocities: Vec<[f64; 2]> = placed.velocities.iter().map(|u| [u[1], u[2]]).collect();
    let moving_across = lateral_velocities.iter().any(|u| *u != [0.0; 2]);
    let space = Space {
        chain_starts: vec![0],
        lateral: placed.centres.iter().map(|c| [c[1], c[2]]).collect(),
        lateral_velocities: if moving_across { lateral_velocities } else { vec![] },
        section: [size[1], size[2]],
        channel: 0.0,
        gravity: world.gravity,
        friction: world.friction,
    };
    Ok(Scene {
        name: name.into(),
        frame: Some(frame),
        container: Some(Container { length: size[0], gap: 0.0, clearance: 0.0 }),
        initial_positions: placed.centres.iter().map(|c| xs0 + c[0]).collect(),
        initial_velocities: placed.velocities.iter().map(|u| u[0]).collect(),
        balls: placed.balls,
        restitution,
        initial_displacement: xs0,
        horizon: s.horizon,
        sample_dt: s.sample_dt,
        reference: s.reference,
        rapier: s.rapier,
        compliant: s.compliant,
        forcing: s.forcing,
        reference_radius: largest,
        space,
        structure: None,
    })
}

/// The most a contact duration may be, s: a contact lasting longer is no impact.
const LONGEST_CONTACT_DURATION: f64 = 1e-2;

pub(super) fn reference_settings(r: &format::ReferenceFile, v: &Validator) -> Result<ReferenceSettings, SceneError> {
    let d = ReferenceSettings::default();
    let contact_duration = v.positive("reference.contact_duration", r.contact_duration.unwrap_or(d.contact_duration))?;
    if contact_duration > LONGEST_CONTACT_DURATION {
        return Err(v.err(
            "reference.contact_duration",
            &format!(
                "must lie in (0, {}] s: a contact lasting longer is no impact (got {})",
                human(LONGEST_CONTACT_DURATION),
                human(contact_duration)
            ),
        ));
    }
    Ok(ReferenceSettings { contact_duration })
}

pub(super) fn compliant_settings(c: &format::CompliantFile, v: &Validator) -> Result<CompliantSettings, SceneError> {
    let d = CompliantSettings::default();
    let youngs_modulus = v.positive("compliant.youngs_modulus", c.youngs_modulus.unwrap_or(d.youngs_modulus))?;
    let poisson_ratio = v.finite("compliant.poisson_ratio", c.poisson_ratio.unwrap_or(d.poisson_ratio))?;
    if !(poisson_ratio > -1.0 && poisson_ratio < 0.5) {
        return Err(v.err("compliant.poisson_ratio", &format!("must lie in (-1, 0.5) for a stable solid (got {poisson_ratio})")));
    }
    let tolerance = v.positive("compliant.tolerance", c.tolerance.unwrap_or(d.tolerance))?;
    if tolerance > 1e-2 {
        return Err(v.err("compliant.tolerance", &format!("must lie in (0, 1e-2] (got {})", human(tolerance))));
    }
    Ok(CompliantSettings { youngs_modulus, poisson_ratio, tolerance })
}

pub(super) fn forcing(g: &format::ForcingFile, frame: &Frame, v: &Validator) -> Result<Forcing, SceneError> {
    only_keys_of(g, if g.kind == ExcitationKind::Base { "base" } else { "force" }, &["amplitude", "frequency"], v)?;
    let missing = |field: &str| v.err(field, "is missing: a sine needs its amplitude and frequency");
    let amplitude = v.non_negative("forcing.amplitude", g.amplitude.ok_or_else(|| missing("forcing.amplitude"))?)?;
    let frequency = v.positive("forcing.frequency", g.frequency.ok_or_else(|| missing("forcing.frequency"))?)?;
    let kind = match g.kind {
        ExcitationKind::Force => ForcingKind::Force,
        ExcitationKind::Base => ForcingKind::Base,
        ExcitationKind::Record | ExcitationKind::Random | ExcitationKind::ForceRecord => {
            return Err(v.err("forcing.kind", "is a record, which is not a sine"))
        }
    };
    let forcing = Forcing { kind, amplitude, frequency };
    // An undamped frame driven exactly at resonance has no bounded particular solution.
    if frame.resonance_without_steady_state(frequency, frequency).is_some() {
        return Err(v.err(
            "forcing.frequency",
            &format!("({frequency} Hz) drives an undamped frame exactly at resonance: its amplitude grows without bound"),
        ));
    }
    Ok(forcing)
}

pub(super) fn rapier_settings(r: &format::RapierFile, v: &Validator) -> Result<RapierSettings, SceneError> {
    if let Some(dt) = r.dt {
        v.positive("rapier.dt", dt)?;
        if dt > 0.1 {
            return Err(v.err("rapier.dt", &format!("({dt} s) is longer than 0.1 s: far too long for centimetre balls")));
        }
    }
    if let Some(it) = r.solver_iterations {
        if it == 0 || it > 1000 {
            return Err(v.err("rapier.solver_iterations", &format!("must lie in 1..=1000 (got {it})")));
        }
    }
    Ok(RapierSettings { stepping: r.stepping, dt: r.dt, solver_iterations: r.solver_iterations, ccd: r.ccd })
}

pub(super) fn arrangement_balls(
    a: &Arrangement,
    large_mass: f64,
    mass_ratio: f64,
    density: f64,
    field: &str,
    v: &Validator,
) -> Result<Vec<Ball>, SceneError> {
    let small_mass = large_mass / mass_ratio;
    let balls: Vec<Ball> = match a {
        Arrangement::Letters(s) => s
            .chars()
            .filter(|c| !c.is_whitespace() && *c != '-')
            .map(|c| match c.to_ascii_uppercase() {
                'L' => Ok(Ball { mass: large_mass, radius: ball_radius(large_mass, density), kind: BallKind::Large }),
                'S' => Ok(Ball { mass: small_mass, radius: ball_radius(small_mass, density), kind: BallKind::Small }),
                other => Err(v.err(field, &format!("has the unknown letter `{other}`: use L (large) and S (small)"))),
            })
            .collect::<Result<_, _>>()?,
        Arrangement::List(list) => list
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let m = v.positive(&format!("{field}[{i}].mass"), b.mass)?;
                let rho = v.positive(&format!("{field}[{i}].density"), b.density.unwrap_or(density))?;
                Ok(Ball { mass: m, radius: ball_radius(m, rho), kind: BallKind::Custom })
            })
            .collect::<Result<_, _>>()?,
    };
    // What the typed values make must be numbers too: a mass below the smallest normal f64,
    // or a radius beyond the largest, is not a ball any model can move.
    if balls.iter().any(|b| b.kind == BallKind::Small) && !small_mass.is_normal() {
        return Err(v.err(
            "balls.mass_ratio",
            &format!("makes the small balls' mass large_mass / mass_ratio = {} kg, too small for a number to hold", human(small_mass)),
        ));
    }
    if let Some(b) = balls.iter().find(|b| !(b.mass.is_normal() && b.radius.is_normal())) {
        return Err(v.err(
            field,
            &format!(
                "has a ball of mass {} kg and radius {} m (from its density): not a size a number can hold",
                human(b.mass),
                human(b.radius)
            ),
        ));
    }
    Ok(balls)
}

pub(super) fn build_chain(
    c: &format::ChainFile,
    run: &format::RunFile,
    reference: ReferenceSettings,
    name: &str,
    v: &Validator,
) -> Result<Vec<ChainCase>, SceneError> {
    let large_mass = v.positive("chain.large_mass", c.large_mass)?;
    let mass_ratio = v.positive("chain.mass_ratio", c.mass_ratio)?;
    let density = v.positive("chain.density", c.density)?;
    let restitution = v.restitution("chain.restitution", c.restitution)?;
    let speed = v.positive("chain.incident_speed", c.incident_speed)?;
    let rr = ball_radius(large_mass, density);
    let gap = v.non_negative("chain.gap", c.gap.metres(rr))?;
    let (horizon, sample_dt) = v.run(run, CHAIN_HORIZON)?;
    if c.large_counts.is_empty() {
        return Err(v.err("chain.large_counts", "is empty"));
    }
    if c.small_balls.is_empty() {
        return Err(v.err("chain.small_balls", "is empty: give [false], [true] or both"));
    }
    let mut cases = Vec::new();
    for &small in &c.small_balls {
        for &nl in &c.large_counts {
            if !(1..=1000).contains(&nl) {
                return Err(v.err("chain.large_counts", &format!("must lie in 1..=1000 (got {nl})")));
            }
            let mut letters = String::from("L");
            for i in 0..nl {
                if i > 0 && small {
                    letters.push('S');
                }
                letters.push('L');
            }
            let balls = arrangement_balls(&Arrangement::Letters(letters), large_mass, mass_ratio, density, "chain", v)?;
            let mut positions = Vec::with_capacity(balls.len());
            let mut x = 0.0;
            for (i, b) in balls.iter().enumerate() {
                if i > 0 {
                    x += gap + b.radius;
                }
                positions.push(x);
                x += b.radius;
            }
            let mut velocities = vec![0.0; balls.len()];
            velocities[0] = speed;
            let balls_len = balls.len();
            cases.push(ChainCase {
                large: nl,
                small,
                scene: Scene {
                    name: format!("{name}-{nl}L{}", if small { format!("-{}S", nl - 1) } else { String::new() }),
                    frame: None,
                    container: None,
                    balls,
                    restitution,
                    initial_displacement: 0.0,
                    initial_positions: positions,
                    initial_velocities: velocities,
                    horizon,
                    sample_dt,
                    reference,
                    rapier: RapierSettings::default(),
                    compliant: CompliantSettings::default(),
                    forcing: None,
                    reference_radius: rr,
                    space: Space::line(balls_len),
                    structure: None,
                },
            });
        }
    }
    Ok(cases)
}

/// Each parameter's spread as written in `[tolerances]`, in [`Parameter::ALL`] order.
fn tolerance_spreads(t: &format::TolerancesFile) -> [(Parameter, Option<Length>); 12] {
    [
        (Parameter::Clearance, t.clearance),
        (Parameter::Gap, t.gap),
        (Parameter::MassRatio, t.mass_ratio),
        (Parameter::Restitution, t.restitution),
        (Parameter::LargeMass, t.large_mass),
        (Parameter::Density, t.density),
        (Parameter::FrameMass, t.frame_mass),
        (Parameter::Stiffness, t.stiffness),
        (Parameter::Damping, t.damping),
        (Parameter::InitialDisplacement, t.initial_displacement),
        (Parameter::ForcingAmplitude, t.forcing_amplitude),
        (Parameter::ForcingFrequency, t.forcing_frequency),
    ]
}

pub(super) fn tolerances(t: &format::TolerancesFile, parsed: &SceneFile, scene: &Scene, v: &Validator) -> Result<Tolerances, SceneError> {
    let mut spreads = vec![];
    for (parameter, spread) in tolerance_spreads(t) {
        let Some(spread) = spread else { continue };
        let field = format!("tolerances.{parameter}");
        let x = match spread {
            Length::Rr(k) if parameter.is_length() => k * scene.reference_radius,
            Length::Rr(_) => return Err(v.err(&field, &format!("is not a length: `{parameter}`'s spread must be a plain number"))),
            Length::Metres(x) => x,
        };
        v.non_negative(&field, x)?;
        parameter.apply(parsed, Length::Metres(0.0)).map_err(|rule| v.err(&field, &rule))?;
        spreads.push((parameter, x));
    }
    let position = match t.position {
        None => None,
        Some(_) if parsed.bed.is_none() && parsed.explicit_balls.is_none() => {
            return Err(v.err("tolerances.position", "needs balls placed in a box ([bed] or [[ball]]); a chain's balls take `gap`"))
        }
        Some(Length::Rr(_)) => {
            return Err(v.err("tolerances.position", "is given in Rr, which [bed] and [[ball]] scenes do not define: give metres"))
        }
        Some(Length::Metres(x)) => Some(v.non_negative("tolerances.position", x)?),
    };
    Ok(Tolerances { spreads, position, distribution: t.distribution, seed: t.seed.unwrap_or(1) })
}
