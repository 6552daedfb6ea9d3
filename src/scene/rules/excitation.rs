//! The excitation's rules: a sine on the frame or its base, a recorded ground motion or force,
//! and random ground motion, each with only its own keys.

use crate::scene::excitation::Forcing;
use crate::scene::format::{self};
use crate::scene::format::{ExcitationKind, ForcingKind};
use crate::scene::record::{is_at2, named_at2, read_points, GroundRecord, KanaiTajimi};
use crate::scene::structure::Frame;
use crate::scene::validator::Validator;
use crate::scene::{human, SceneError};

/// Refuses the keys of `[forcing]` that belong to another kind than `kind`.
pub(in crate::scene) fn only_keys_of(g: &format::ForcingFile, kind: &str, keys: &[&str], v: &Validator) -> Result<(), SceneError> {
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
pub(in crate::scene) fn random_ground(g: &format::ForcingFile, v: &Validator) -> Result<KanaiTajimi, SceneError> {
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
pub(in crate::scene) fn ground_record(
    g: &format::ForcingFile,
    kind: &str,
    keys: &[&str],
    v: &Validator,
) -> Result<GroundRecord, SceneError> {
    only_keys_of(g, kind, keys, v)?;
    let file = g.file.as_ref().ok_or_else(|| v.err("forcing.file", "is missing: a record needs its file"))?;
    let scale = v.finite("forcing.scale", g.scale.unwrap_or(1.0))?;
    let path = std::path::Path::new(v.file).parent().unwrap_or(std::path::Path::new("")).join(file);
    let text = std::fs::read_to_string(&path).map_err(|e| v.err("forcing.file", &format!("cannot be read ({}): {e}", path.display())))?;
    let at2_name = named_at2(&path);
    if g.kind == ExcitationKind::ForceRecord && is_at2(&text, at2_name) {
        return Err(v.err(
            "forcing.file",
            &format!("({}) is a PEER ground acceleration in g; a force record is two columns, time (s) and force (N)", path.display()),
        ));
    }
    let (times, accel) = read_points(&text, at2_name).map_err(|why| v.err("forcing.file", &format!("({}) {why}", path.display())))?;
    let record = GroundRecord::new(times, accel, scale);
    within_range(&record, "forcing.scale", v)?;
    Ok(record)
}

/// The largest value a record may reach (m/s^2 or N): the energies it puts in grow as its
/// square, and beyond this they would leave the range of double precision.
const RECORD_LIMIT: f64 = 1e100;

/// Refuses a record (read, or drawn at random) whose values reach [`RECORD_LIMIT`].
pub(in crate::scene) fn within_range(record: &GroundRecord, field: &str, v: &Validator) -> Result<(), SceneError> {
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

pub(in crate::scene) fn forcing(g: &format::ForcingFile, frame: &Frame, v: &Validator) -> Result<Forcing, SceneError> {
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
