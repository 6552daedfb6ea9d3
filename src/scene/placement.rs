//! Balls placed in the container's box: explicit `[[ball]]` tables checked for overlaps and
//! walls, and generated beds on a lattice or at random (docs/MODEL.md §13).

use std::collections::HashMap;
use std::f64::consts::PI;

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use super::format::{BedFile, ExplicitBallFile, Placement};
use super::geometry::{ball_radius, Ball, BallKind, Body};
use super::validator::Validator;
use super::{human, Scene, SceneError};

/// Most balls a bed may hold: a run keeps every ball's state, and a scene this size already
/// takes minutes per simulated second in the cheapest model.
pub const MAX_BED_BALLS: u64 = 1_000_000;
/// Most balls a settled bed may hold: settling 3000 balls takes some 25 s, and the cost grows
/// faster than the number of balls (docs/MODEL.md §13).
const MAX_SETTLED_BALLS: usize = 10_000;
/// Tries to place one ball at random before the bed is declared impossible to place.
const RANDOM_TRIES: usize = 10_000;
/// Lattice neighbours are this fraction of a diameter apart, so that rounding never makes
/// them overlap and no contact is open at the start.
const LATTICE_SPACING: f64 = 1e-3;

/// Balls with their centres `[x, y, z]` in the container's frame (left wall at x = 0, the
/// axis at y = z = 0), and their velocities.
pub(super) struct Placed {
    pub(super) balls: Vec<Ball>,
    pub(super) centres: Vec<[f64; 3]>,
    pub(super) velocities: Vec<[f64; 3]>,
}

/// How far a ball may reach past a wall or into another ball and still count as touching: the
/// round-off of coordinates of the container's size. A user who types touching positions
/// (centres 0.05 and 0.06 m for radii 0.005 m) gets a distance a few ulps short of the sum of
/// the radii, and means contact, not overlap.
pub(super) fn touching_round_off(size: [f64; 3]) -> f64 {
    8.0 * f64::EPSILON * size.iter().fold(0.0, |m, s| f64::max(m, s.abs()))
}

/// The box `[length, width, height]` a ball of radius `r` centred at `c` must lie within,
/// touching a wall within round-off allowed: the first axis it leaves, or `None`.
fn outside(c: [f64; 3], r: f64, size: [f64; 3]) -> Option<usize> {
    let tol = touching_round_off(size);
    let (lo, hi) = centre_bounds(r, size);
    (0..3).find(|&a| !(lo[a] - tol <= c[a] && c[a] <= hi[a] + tol))
}

/// The lowest and highest centre along each axis of a ball of radius `r` that touches no wall
/// of the box `[length, width, height]` from outside.
pub(super) fn centre_bounds(r: f64, size: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    ([r, r - 0.5 * size[1], r - 0.5 * size[2]], [size[0] - r, 0.5 * size[1] - r, 0.5 * size[2] - r])
}

/// The first pair of balls that overlap by more than the round-off of the container's `size`,
/// found by sweeping along x.
pub(super) fn first_overlap(balls: &[Ball], centres: &[[f64; 3]], size: [f64; 3]) -> Option<(usize, usize)> {
    let tol = touching_round_off(size);
    let mut order: Vec<usize> = (0..balls.len()).collect();
    order.sort_by(|&a, &b| centres[a][0].total_cmp(&centres[b][0]));
    let largest = balls.iter().map(|b| b.radius).fold(0.0, f64::max);
    for (k, &i) in order.iter().enumerate() {
        for &j in &order[k + 1..] {
            if centres[j][0] - centres[i][0] >= balls[i].radius + largest {
                break;
            }
            let d2: f64 = (0..3).map(|a| (centres[j][a] - centres[i][a]).powi(2)).sum();
            let reach = balls[i].radius + balls[j].radius - tol;
            if reach > 0.0 && d2 < reach * reach {
                return Some((i.min(j), i.max(j)));
            }
        }
    }
    None
}

/// Moves each ball of `scene`, placed in its box, by `by[i]` (`[dx, dy, dz]`, m, in the
/// container's frame): the rule broken, with nothing moved, when a ball would leave the box or
/// overlap another.
pub fn move_placed_balls(scene: &mut Scene, by: &[[f64; 3]]) -> Result<(), String> {
    let x: Vec<f64> = scene.initial_positions.iter().zip(by).map(|(x, d)| x + d[0]).collect();
    let mut lateral = Vec::with_capacity(scene.balls.len());
    // Each damper's balls in its own box, from its floor's start.
    for d in scene.damper_list() {
        let size = [d.container.length, d.section[0], d.section[1]];
        let xs0 = scene.damper_start(&d);
        let centres: Vec<[f64; 3]> = d
            .balls
            .clone()
            .map(|i| {
                let [y, z] = scene.space.lateral_of(i);
                [x[i] - xs0, y + by[i][1], z + by[i][2]]
            })
            .collect();
        let balls = &scene.balls[d.balls.clone()];
        for (k, (c, b)) in centres.iter().zip(balls).enumerate() {
            if let Some(a) = outside(*c, b.radius, size) {
                return Err(format!("moves {} outside the container along {}", Body::Ball(d.balls.start + k).name(), ["x", "y", "z"][a]));
            }
        }
        if let Some((i, j)) = first_overlap(balls, &centres, size) {
            let (i, j) = (d.balls.start + i, d.balls.start + j);
            return Err(format!("makes {} overlap {}", Body::Ball(j).name(), Body::Ball(i).name()));
        }
        lateral.extend(centres.iter().map(|c| [c[1], c[2]]));
    }
    scene.initial_positions = x;
    scene.space.lateral = lateral;
    Ok(())
}

/// The explicit balls, checked: positive masses and sizes, inside the box, no overlaps.
pub(super) fn explicit(list: &[ExplicitBallFile], size: [f64; 3], v: &Validator) -> Result<Placed, SceneError> {
    if list.is_empty() {
        return Err(v.err("ball", "is empty: give at least one [[ball]]"));
    }
    let mut placed = Placed { balls: vec![], centres: vec![], velocities: vec![] };
    for (i, b) in list.iter().enumerate() {
        let field = |name: &str| format!("ball[{i}].{name}");
        let mass = v.positive(&field("mass"), b.mass)?;
        let radius = match (b.radius, b.density) {
            (Some(r), None) => v.positive(&field("radius"), r)?,
            (None, Some(rho)) => ball_radius(mass, v.positive(&field("density"), rho)?),
            (Some(_), Some(_)) => return Err(v.err(&field("radius"), "and its `density` are both given: give one")),
            (None, None) => return Err(v.err(&field("radius"), "is missing: give the ball's radius or its density")),
        };
        if !(mass.is_normal() && radius.is_normal()) {
            return Err(v.err(&field("mass"), &format!("and radius {} m make a ball no number can hold", human(radius))));
        }
        for (a, x) in b.position.iter().enumerate() {
            v.finite(&format!("ball[{i}].position[{a}]"), *x)?;
        }
        let velocity = b.velocity.unwrap_or([0.0; 3]);
        for (a, x) in velocity.iter().enumerate() {
            v.finite(&format!("ball[{i}].velocity[{a}]"), *x)?;
        }
        if let Some(a) = outside(b.position, radius, size) {
            return Err(v.err(
                &field("position"),
                &format!(
                    "puts the ball (radius {} m) outside the container along {}: its centre must lie within {} m of the walls' inside",
                    human(radius),
                    ["x", "y", "z"][a],
                    human(radius)
                ),
            ));
        }
        placed.balls.push(Ball { mass, radius, kind: BallKind::Custom });
        placed.centres.push(b.position);
        placed.velocities.push(velocity);
    }
    if let Some((i, j)) = first_overlap(&placed.balls, &placed.centres, size) {
        return Err(v.err(&format!("ball[{j}].position"), &format!("makes ball[{j}] overlap ball[{i}]")));
    }
    Ok(placed)
}

/// The sizes of a bed's balls in order: each size's share of `count`, interleaved so that
/// every stretch of the order holds the sizes in proportion.
fn sizes_in_order(count: usize, proportions: &[f64]) -> Vec<usize> {
    let total: f64 = proportions.iter().sum();
    let mut placed = vec![0usize; proportions.len()];
    (0..count)
        .map(|j| {
            let due = |k: usize| proportions[k] / total * (j + 1) as f64 - placed[k] as f64;
            let k = (0..proportions.len()).max_by(|&a, &b| due(a).total_cmp(&due(b)).then(b.cmp(&a))).unwrap_or(0);
            placed[k] += 1;
            k
        })
        .collect()
}

/// A generated bed in a box `[length, width, height]` under `gravity`.
pub(super) fn bed(b: &BedFile, size: [f64; 3], gravity: [f64; 3], v: &Validator) -> Result<Placed, SceneError> {
    let density = v.positive("bed.density", b.density)?;
    if b.radii.is_empty() {
        return Err(v.err("bed.radii", "is empty: give the radius of each size of ball"));
    }
    for (k, r) in b.radii.iter().enumerate() {
        v.positive(&format!("bed.radii[{k}]"), *r)?;
    }
    let proportions = b.proportions.clone().unwrap_or_else(|| vec![1.0; b.radii.len()]);
    if proportions.len() != b.radii.len() {
        return Err(v.err(
            "bed.proportions",
            &format!("has {} entries but `bed.radii` has {}: give one per size", proportions.len(), b.radii.len()),
        ));
    }
    for (k, p) in proportions.iter().enumerate() {
        v.non_negative(&format!("bed.proportions[{k}]"), *p)?;
    }
    if proportions.iter().sum::<f64>() <= 0.0 {
        return Err(v.err("bed.proportions", "are all zero: at least one size needs balls"));
    }
    let volume = size[0] * size[1] * size[2];
    let count = match (b.count, b.fill_fraction) {
        (Some(_), Some(_)) => return Err(v.err("bed.fill_fraction", "and `bed.count` are both given: give one")),
        (None, None) => return Err(v.err("bed.count", "is missing: give the number of balls or `fill_fraction`")),
        (Some(n), None) => n as u64,
        (None, Some(phi)) => {
            let phi = v.positive("bed.fill_fraction", phi)?;
            if phi > PI / 6.0 {
                return Err(v.err(
                    "bed.fill_fraction",
                    &format!("({}) is more than a cubic lattice of equal balls holds (pi/6 = 0.524)", human(phi)),
                ));
            }
            let total: f64 = proportions.iter().sum();
            let mean: f64 = b.radii.iter().zip(&proportions).map(|(r, p)| p / total * 4.0 / 3.0 * PI * r.powi(3)).sum();
            (phi * volume / mean).round() as u64
        }
    };
    if count == 0 {
        return Err(v.err(if b.count.is_some() { "bed.count" } else { "bed.fill_fraction" }, "makes a bed of no balls"));
    }
    if count > MAX_BED_BALLS {
        return Err(v.err(
            if b.count.is_some() { "bed.count" } else { "bed.fill_fraction" },
            &format!("makes {count} balls; a bed may hold at most {MAX_BED_BALLS}"),
        ));
    }
    let count = count as usize;
    let kinds = sizes_in_order(count, &proportions);
    let largest = b.radii.iter().copied().fold(0.0, f64::max);
    let balls: Vec<Ball> = kinds
        .iter()
        .map(|&k| {
            let radius = b.radii[k];
            let mass = density * 4.0 / 3.0 * PI * radius.powi(3);
            Ball { mass, radius, kind: if radius == largest { BallKind::Large } else { BallKind::Small } }
        })
        .collect();
    if let Some(ball) = balls.iter().find(|b| !(b.mass.is_normal() && b.radius.is_normal())) {
        return Err(v.err("bed.density", &format!("makes a ball of mass {} kg: not a mass a number can hold", human(ball.mass))));
    }
    let centres = match b.placement {
        Placement::Lattice => lattice(&balls, largest, size, v)?,
        Placement::Random => random(&balls, largest, size, b.seed.unwrap_or(1), v)?,
        Placement::Settled => {
            if gravity == [0.0; 3] {
                return Err(v.err("bed.placement", "is \"settled\", which needs gravity to settle the balls: give `world.gravity`"));
            }
            if count > MAX_SETTLED_BALLS {
                return Err(v.err(
                    if b.count.is_some() { "bed.count" } else { "bed.fill_fraction" },
                    &format!(
                        "makes {count} balls; a settled bed holds at most {MAX_SETTLED_BALLS} (settling costs some 25 s per 3000 balls, more than linearly): use placement = \"lattice\" or \"random\""
                    ),
                ));
            }
            let start = lattice(&balls, largest, size, v)?;
            let centres = super::settle::settle(&balls, &start, size, gravity, b.seed.unwrap_or(1)).map_err(|why| v.err("bed", &why))?;
            if let Some((i, j)) = first_overlap(&balls, &centres, size) {
                return Err(v.err("bed", &format!("cannot be settled: ball {} still overlaps ball {}", j + 1, i + 1)));
            }
            centres
        }
    };
    let velocities = vec![[0.0; 3]; count];
    Ok(Placed { balls, centres, velocities })
}

/// A cubic lattice of cells a little wider than the largest ball, filled x first, then y,
/// then layer by layer from the floor (z low) up; each ball centred in its cell across and
/// resting on its cell's floor.
fn lattice(balls: &[Ball], largest: f64, size: [f64; 3], v: &Validator) -> Result<Vec<[f64; 3]>, SceneError> {
    let pitch = 2.0 * largest * (1.0 + LATTICE_SPACING);
    let cells = size.map(|s| (s / pitch).floor().max(0.0) as u64);
    let capacity = cells[0].saturating_mul(cells[1]).saturating_mul(cells[2]);
    if (balls.len() as u64) > capacity {
        return Err(v.err(
            "bed",
            &format!(
                "cannot be placed: a lattice of {} m cells holds at most {capacity} balls in this container ({} asked)",
                human(pitch),
                balls.len()
            ),
        ));
    }
    let margin = [0, 1].map(|a| 0.5 * (size[a] - cells[a] as f64 * pitch));
    Ok(balls
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let i = i as u64;
            let (ix, iy, iz) = (i % cells[0], (i / cells[0]) % cells[1], i / (cells[0] * cells[1]));
            let x = margin[0] + (ix as f64 + 0.5) * pitch;
            let y = margin[1] + (iy as f64 + 0.5) * pitch - 0.5 * size[1];
            let z = -0.5 * size[2] + iz as f64 * pitch + b.radius * (1.0 + LATTICE_SPACING);
            [x, y, z]
        })
        .collect())
}

/// Random sequential placement: each ball at uniformly drawn centres until one overlaps no
/// ball placed before it (cells as wide as the largest ball find the neighbours).
fn random(balls: &[Ball], largest: f64, size: [f64; 3], seed: u64, v: &Validator) -> Result<Vec<[f64; 3]>, SceneError> {
    let mut rng = Pcg64::seed_from_u64(seed);
    let cell = 2.0 * largest;
    let key = |c: [f64; 3]| c.map(|x| (x / cell).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    let mut centres: Vec<[f64; 3]> = Vec::with_capacity(balls.len());
    for (i, b) in balls.iter().enumerate() {
        let r = b.radius;
        let half = [0.5 * size[0] - r, 0.5 * size[1] - r, 0.5 * size[2] - r];
        if half.iter().any(|h| *h < 0.0) {
            return Err(v.err("bed.radii", &format!("has a ball of radius {} m that does not fit in the container", human(r))));
        }
        let mut found = None;
        for _ in 0..RANDOM_TRIES {
            let c = [
                0.5 * size[0] + rng.random_range(-half[0]..=half[0]),
                rng.random_range(-half[1]..=half[1]),
                rng.random_range(-half[2]..=half[2]),
            ];
            let k = key(c);
            let mut free = true;
            'cells: for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        for &j in grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]).map_or(&[][..], |v| v) {
                            let d2: f64 = (0..3).map(|a| (c[a] - centres[j][a]).powi(2)).sum();
                            if d2 < (r + balls[j].radius).powi(2) * (1.0 + 4.0 * LATTICE_SPACING) {
                                free = false;
                                break 'cells;
                            }
                        }
                    }
                }
            }
            if free {
                found = Some(c);
                break;
            }
        }
        let Some(c) = found else {
            return Err(v.err(
                "bed",
                &format!(
                    "cannot be placed at random: ball {} of {} found no free place in {RANDOM_TRIES} tries (random placement jams near a fill fraction of 0.3; use placement = \"lattice\")",
                    i + 1,
                    balls.len()
                ),
            ));
        };
        grid.entry(key(c)).or_default().push(i);
        centres.push(c);
    }
    Ok(centres)
}

#[cfg(test)]
mod tests {
    use super::sizes_in_order;

    #[test]
    fn sizes_interleave_in_proportion() {
        let order = sizes_in_order(9, &[2.0, 1.0]);
        assert_eq!(order.iter().filter(|&&k| k == 1).count(), 3);
        // Every stretch of three holds two of the first size and one of the second.
        for chunk in order.chunks(3) {
            assert_eq!(chunk.iter().filter(|&&k| k == 0).count(), 2, "{order:?}");
        }
    }
}
