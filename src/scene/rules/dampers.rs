//! The rules of several dampers (`[[damper]]`): each damper is checked as the scene's one
//! damper would be, on its own floor, and the dampers are then put side by side in one scene
//! whose balls are theirs in turn.

use super::build_damper;
use crate::scene::dampers::Damper;
use crate::scene::format::{DamperFile, SceneFile, StructureFile};
use crate::scene::validator::Validator;
use crate::scene::{human, Scene, SceneError};

/// The tables of one damper, which `[[damper]]` gives per damper instead of once.
const DAMPER_TABLES: [&str; 4] = ["container", "balls", "bed", "ball"];

/// The scene of a file whose balls are in `[[damper]]` tables.
pub(super) fn build_dampers(f: &SceneFile, list: &[DamperFile], name: &str, v: &Validator) -> Result<Scene, SceneError> {
    let given = [f.container.is_some(), f.balls.is_some(), f.bed.is_some(), f.explicit_balls.is_some()];
    if let Some(k) = given.iter().position(|&g| g) {
        return Err(v.err(
            DAMPER_TABLES[k],
            "cannot be combined with [[damper]]: give each damper's container and balls in its own [[damper]] table",
        ));
    }
    if list.is_empty() {
        return Err(v.err("damper", "is empty: give each damper a [[damper]] table with its container and balls"));
    }
    if f.structure.as_ref().is_some_and(|s| s.damper_floor.is_some()) {
        return Err(v.err("structure.damper_floor", "cannot be combined with [[damper]]: give each damper its `floor`"));
    }
    let floors = f.structure.as_ref().map_or(1, |s| s.masses.len().max(1));
    let carrier = if f.structure.is_some() { "the structure" } else { "a [frame]" };
    let mut built = Vec::with_capacity(list.len());
    for (k, d) in list.iter().enumerate() {
        let field = |key: &str| format!("damper[{k}].{key}");
        let floor = d.floor.unwrap_or(floors as u32) as usize;
        if !(1..=floors).contains(&floor) {
            let rule = format!("is {floor}, but {carrier} has floors 1 to {floors} (1 at the bottom)");
            return Err(v.err(&field("floor"), &rule));
        }
        if d.balls.is_none() && d.bed.is_none() && d.explicit_balls.is_none() {
            return Err(v.err(&format!("damper[{k}]"), "has no balls: give [damper.balls], [damper.bed] or [[damper.ball]]"));
        }
        let structure = f.structure.clone().map(|s| StructureFile { damper_floor: Some(floor as u32), ..s });
        let one = SceneFile {
            dampers: None,
            container: d.container.clone(),
            balls: d.balls.clone(),
            bed: d.bed.clone(),
            explicit_balls: d.explicit_balls.clone(),
            structure,
            ..f.clone()
        };
        let scene = build_damper(&one, name, v).map_err(|e| within_damper(e, k))?;
        built.push((floor - 1, scene));
    }
    side_by_side(built, v)
}

/// An error of one damper's tables, named as the file names them (`damper[1].bed.count`).
fn within_damper(e: SceneError, k: usize) -> SceneError {
    match e {
        SceneError::Invalid { file, field, rule }
            if DAMPER_TABLES.iter().any(|t| field.strip_prefix(t).is_some_and(|rest| rest.is_empty() || rest.starts_with(['.', '[']))) =>
        {
            SceneError::Invalid { file, field: format!("damper[{k}].{field}"), rule }
        }
        other => other,
    }
}

/// One scene of every damper's: the first damper's scene with the others' balls after its own.
fn side_by_side(built: Vec<(usize, Scene)>, v: &Validator) -> Result<Scene, SceneError> {
    let mut parts = built.into_iter();
    let (floor, mut scene) = parts.next().expect("at least one damper");
    if parts.len() == 0 {
        return Ok(scene);
    }
    let damper_of = |floor: usize, s: &Scene, start: usize| Damper {
        floor,
        balls: start..start + s.balls.len(),
        container: s.container.expect("a damper has a container"),
        section: s.space.section,
        channel: s.space.channel,
    };
    let mut dampers = vec![damper_of(floor, &scene, 0)];
    for (k, (floor, s)) in parts.enumerate() {
        if s.restitution != scene.restitution {
            return Err(v.err(
                &format!("damper[{}]", k + 1),
                &format!(
                    "has restitution {} but damper[0] has {}: every impact of a scene has one e",
                    human(s.restitution),
                    human(scene.restitution)
                ),
            ));
        }
        let start = scene.balls.len();
        dampers.push(damper_of(floor, &s, start));
        let space = &mut scene.space;
        // A damper whose balls all sit on its axis lists no places across: its balls get theirs.
        if space.lateral.is_empty() && !s.space.lateral.is_empty() {
            space.lateral = vec![[0.0; 2]; start];
        }
        if !space.lateral.is_empty() {
            space.lateral.extend((0..s.balls.len()).map(|i| s.space.lateral_of(i)));
        }
        if space.lateral_velocities.is_empty() && !s.space.lateral_velocities.is_empty() {
            space.lateral_velocities = vec![[0.0; 2]; start];
        }
        if !space.lateral_velocities.is_empty() {
            space.lateral_velocities.extend((0..s.balls.len()).map(|i| s.space.lateral_velocity_of(i)));
        }
        space.chain_starts.extend(s.space.chain_starts.iter().map(|c| c + start));
        scene.balls.extend(s.balls);
        scene.initial_positions.extend(s.initial_positions);
        scene.initial_velocities.extend(s.initial_velocities);
    }
    scene.dampers = dampers;
    Ok(scene)
}
