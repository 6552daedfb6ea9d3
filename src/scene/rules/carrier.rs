//! The carrier's rules: a `[structure]` of several storeys, and the floor a force record acts on.

use crate::scene::format::{self};
use crate::scene::record::GroundRecord;
use crate::scene::structure::{FloorForce, Structure};
use crate::scene::validator::Validator;
use crate::scene::{human, SceneError};
use crate::storeys::{Building, Load, StoreyDamping};
use std::sync::Arc;

/// The `[structure]` table, checked.
pub(in crate::scene) fn structure(
    st: &format::StructureFile,
    ground: Option<Arc<GroundRecord>>,
    v: &Validator,
) -> Result<Structure, SceneError> {
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
pub(in crate::scene) fn floor_force(
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
