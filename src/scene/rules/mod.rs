//! The rules of a scene file: every value checked where it is read, and an error that names
//! the file, the field (or the flag it came from) and the rule broken. A [`Scene`] exists only
//! once every rule holds. A room per family of rules: the carrier (a frame or a structure),
//! the excitation, the damper's balls and settings, the chain experiment and the tolerances;
//! this room reads a file and composes them.

use crate::scene::format::ExcitationKind;
use crate::scene::format::{self, Length, SceneFile};
use crate::scene::parameters::Parameter;
use crate::scene::structure::Structure;
use crate::scene::validator::Validator;
use crate::scene::{human, Loaded, Scene, SceneError};
use crate::storeys::{Building, StoreyDamping};
use carrier::{floor_force, structure};
use chain::build_chain;
use damper::build_frame_damper;
use excitation::{ground_record, random_ground, within_range};
use settings::reference_settings;
use std::sync::Arc;
use tolerances::tolerances;

mod carrier;
mod chain;
mod damper;
mod dampers;
mod excitation;
mod settings;
mod tolerances;

pub(super) use excitation::forcing;
pub(super) use settings::{compliant_settings, rapier_settings};

/// Validates an already parsed file.
pub fn from_file(parsed: SceneFile, file: &str, default_name: &str) -> Result<Loaded, SceneError> {
    let v = Validator { file, flags: &[] };
    let name = parsed.name.clone().unwrap_or_else(|| default_name.to_string());
    if parsed.chain.is_some() && (parsed.frame.is_some() || parsed.balls.is_some()) {
        return Err(v.err("chain", "cannot be combined with [frame] or [balls]: a chain file describes only the KER experiment"));
    }
    if parsed.chain.is_some() && parsed.dampers.is_some() {
        return Err(v.err("chain", "cannot be combined with [[damper]]: a chain file describes only the KER experiment"));
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

pub(super) fn build_damper(f: &SceneFile, name: &str, v: &Validator) -> Result<Scene, SceneError> {
    if let Some(list) = &f.dampers {
        return dampers::build_dampers(f, list, name, v);
    }
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
