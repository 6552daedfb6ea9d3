//! The models' settings in a scene file: `[reference]`, `[compliant]` and `[rapier]`.

use crate::scene::format::{self};
use crate::scene::settings::{CompliantSettings, RapierSettings, ReferenceSettings};
use crate::scene::validator::Validator;
use crate::scene::{human, SceneError};

/// The most a contact duration may be, s: a contact lasting longer is no impact.
const LONGEST_CONTACT_DURATION: f64 = 1e-2;

pub(in crate::scene) fn reference_settings(r: &format::ReferenceFile, v: &Validator) -> Result<ReferenceSettings, SceneError> {
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

pub(in crate::scene) fn compliant_settings(c: &format::CompliantFile, v: &Validator) -> Result<CompliantSettings, SceneError> {
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

pub(in crate::scene) fn rapier_settings(r: &format::RapierFile, v: &Validator) -> Result<RapierSettings, SceneError> {
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
