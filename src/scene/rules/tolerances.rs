//! The rules of `[tolerances]`: how a built damper scatters, for ensembles.

use crate::scene::format::{self, Length, SceneFile};
use crate::scene::parameters::{Parameter, Tolerances};
use crate::scene::validator::Validator;
use crate::scene::{Scene, SceneError};

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

pub(in crate::scene) fn tolerances(
    t: &format::TolerancesFile,
    parsed: &SceneFile,
    scene: &Scene,
    v: &Validator,
) -> Result<Tolerances, SceneError> {
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
        Some(_) if !places_balls_in_a_box(parsed) => {
            return Err(v.err("tolerances.position", "needs balls placed in a box ([bed] or [[ball]]); a chain's balls take `gap`"))
        }
        Some(Length::Rr(_)) => {
            return Err(v.err("tolerances.position", "is given in Rr, which [bed] and [[ball]] scenes do not define: give metres"))
        }
        Some(Length::Metres(x)) => Some(v.non_negative("tolerances.position", x)?),
    };
    Ok(Tolerances { spreads, position, distribution: t.distribution, seed: t.seed.unwrap_or(1) })
}

/// Whether the file's balls are placed in a box (`[bed]` or `[[ball]]`, or in every damper).
fn places_balls_in_a_box(f: &SceneFile) -> bool {
    match &f.dampers {
        Some(list) => list.iter().all(|d| d.bed.is_some() || d.explicit_balls.is_some()),
        None => f.bed.is_some() || f.explicit_balls.is_some(),
    }
}
