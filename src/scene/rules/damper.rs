//! The damper's rules on a frame: the frame, the run's settings, and the balls, from `[balls]`
//! (a line, copied into side-by-side chains) or placed in the box (`[bed]`, `[[ball]]`), under
//! `[world]`.

use super::excitation::forcing;
use super::settings::{compliant_settings, rapier_settings, reference_settings};
use crate::scene::excitation::Forcing;
use crate::scene::format::{self, Arrangement, Length, SceneFile};
use crate::scene::geometry::{ball_radius, Ball, BallKind, Container};
use crate::scene::settings::{CompliantSettings, RapierSettings, ReferenceSettings};
use crate::scene::space::Space;
use crate::scene::structure::Frame;
use crate::scene::validator::Validator;
use crate::scene::{human, Scene, SceneError, DEFAULT_HORIZON};

pub(in crate::scene) fn build_frame_damper(f: &SceneFile, name: &str, v: &Validator) -> Result<Scene, SceneError> {
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
            dampers: vec![],
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
        dampers: vec![],
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
    if count as usize * n > crate::scene::placement::MAX_BED_BALLS as usize {
        return Err(v.err(
            "balls.chains",
            &format!("makes {} balls; a scene may hold at most {}", count as usize * n, crate::scene::placement::MAX_BED_BALLS),
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
        (Some(bed), _) => crate::scene::placement::bed(bed, size, world.gravity, v)?,
        (None, Some(list)) => crate::scene::placement::explicit(list, size, v)?,
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
        dampers: vec![],
    })
}

pub(in crate::scene) fn arrangement_balls(
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
