//! A bed settled under gravity (docs/MODEL.md §13, "Settled beds"): the balls start on the
//! lattice, nudged across gravity at random, and sink by projected descent of their height
//! energy (each ball moved down, then every overlap undone from the bottom up, the upper ball
//! of a pair lifted off the lower one) until none can go lower. The result is a frictionless
//! pile at rest on its supports, the same for every model.

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use super::geometry::Ball;
use crate::cells::Cells;

/// How far each ball is nudged across gravity before it settles, as a fraction of its radius:
/// enough that no ball balances on the one below it, as the lattice's columns do.
const NUDGE_RADII: f64 = 0.3;
/// The first descent step, as a fraction of the smallest radius.
const FIRST_STEP_RADII: f64 = 0.05;
/// Descent stops once the step is this fraction of the smallest radius: the pile then lies
/// within about that much of where it would rest (5 um for a 5 mm ball, the deflection of a
/// steel contact under a few layers of balls).
const LAST_STEP_RADII: f64 = 1e-3;
/// Most projection sweeps after each descent step.
const SWEEPS_PER_STEP: usize = 20;
/// Sweeps after a descent step stop once no pair overlaps by more than this fraction of it.
const OVERLAP_PER_STEP: f64 = 0.1;
/// Steps longer than this fraction of the smallest radius lift upper balls off lower ones
/// instead of projecting: the pile forms without the weight of the balls above, which a few
/// sweeps cannot carry, squeezing more balls into a layer than fit in it.
const LIFT_UNTIL_RADII: f64 = 0.01;
/// Descent steps over which the balls' progress is judged: a ball balanced near the top of
/// another rolls off slowly at first, a step's fraction of its lean per step.
const WINDOW: usize = 100;
/// A step is halved once no ball moves more than this fraction of it over a window: the balls
/// sink no further at that step and only jostle.
const STALL_FRACTION: f64 = 0.5;
/// Windows at one step before it is halved anyway.
const WINDOWS_PER_STEP: usize = 10;
/// A pair whose centres differ in height by less than this fraction of their reach is side by
/// side: both balls give way; otherwise the upper one alone is lifted off the lower.
const SIDE_BY_SIDE: f64 = 1e-3;
/// Pairs closer than this many of the smallest radius are listed, and listed again once a ball
/// has moved half as far.
const SKIN_RADII: f64 = 0.2;
/// Sweeps allowed to part the last overlaps before the bed is declared unsettled.
const FINAL_SWEEPS: usize = 10_000;

/// The balls of a bed settled in the box `[length, width, height]` (x from 0, y and z about
/// the axis) under `gravity`, starting from `start` (their lattice centres); the nudges come
/// from `seed`. Fails with the reason when the overlaps cannot all be parted.
pub(super) fn settle(balls: &[Ball], start: &[[f64; 3]], size: [f64; 3], gravity: [f64; 3], seed: u64) -> Result<Vec<[f64; 3]>, String> {
    let g_norm = norm(gravity);
    debug_assert!(g_norm > 0.0, "the caller checks that gravity is set");
    let down = gravity.map(|g| g / g_norm);
    let smallest = balls.iter().map(|b| b.radius).fold(f64::INFINITY, f64::min);
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut centres: Vec<[f64; 3]> = start
        .iter()
        .zip(balls)
        .map(|(c, b)| {
            let mut nudge: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
            let along = dot(nudge, down);
            nudge = std::array::from_fn(|a| nudge[a] - along * down[a]);
            let c = std::array::from_fn(|a| c[a] + NUDGE_RADII * b.radius * nudge[a]);
            clamp(c, b.radius, size)
        })
        .collect();
    let skin = SKIN_RADII * smallest;
    let mut grid = Grid::new(size, balls, skin);
    let mut listed_at = centres.clone();
    grid.list_pairs(&centres, balls, down, skin);
    let mut step = FIRST_STEP_RADII * smallest;
    while step >= LAST_STEP_RADII * smallest {
        let lift = step >= LIFT_UNTIL_RADII * smallest;
        for _ in 0..WINDOWS_PER_STEP {
            let window_start = centres.clone();
            for _ in 0..WINDOW {
                for (c, b) in centres.iter_mut().zip(balls) {
                    *c = clamp(std::array::from_fn(|a| c[a] + step * down[a]), b.radius, size);
                }
                // The pairs are listed again once a ball has moved half the skin since.
                if centres.iter().zip(&listed_at).any(|(c, l)| dot(sub(*c, *l), sub(*c, *l)) > 0.25 * skin * skin) {
                    grid.list_pairs(&centres, balls, down, skin);
                    listed_at.clone_from(&centres);
                }
                for _ in 0..SWEEPS_PER_STEP {
                    if grid.part_overlaps(&mut centres, balls, size, down, lift) <= OVERLAP_PER_STEP * step {
                        break;
                    }
                }
            }
            let farthest = centres.iter().zip(&window_start).map(|(c, c0)| norm(sub(*c, *c0))).fold(0.0, f64::max);
            if farthest < STALL_FRACTION * step {
                break;
            }
        }
        step *= 0.5;
    }
    // The descent leaves overlaps of about its last step: part them to within round-off.
    grid.list_pairs(&centres, balls, down, skin);
    let round_off = super::placement::touching_round_off(size);
    for _ in 0..FINAL_SWEEPS {
        if grid.part_overlaps(&mut centres, balls, size, down, false) <= round_off {
            return Ok(centres);
        }
    }
    Err(format!("cannot be settled: its balls still overlap after {FINAL_SWEEPS} sweeps (the container is too full for a pile)"))
}

/// The pairs of balls that may touch, found on a grid of cells.
struct Grid {
    cells: Cells,
    /// Pairs within the skin of touching, listed by `list_pairs`, the lower ball first.
    pairs: Vec<(u32, u32)>,
}

impl Grid {
    /// A grid over the box `size` for `balls`, finding pairs up to `skin` apart.
    fn new(size: [f64; 3], balls: &[Ball], skin: f64) -> Grid {
        let largest = balls.iter().map(|b| b.radius).fold(0.0, f64::max);
        Grid { cells: Cells::new(size, 2.0 * largest + skin, balls.len()), pairs: vec![] }
    }

    /// Lists the pairs of balls closer than `skin`, the lower ball of each first, lowest
    /// pairs first.
    fn list_pairs(&mut self, centres: &[[f64; 3]], balls: &[Ball], down: [f64; 3], skin: f64) {
        self.cells.rebuild(|i| centres[i]);
        self.pairs.clear();
        let depth = |c: [f64; 3]| dot(c, down);
        for (i, c) in centres.iter().enumerate() {
            let pairs = &mut self.pairs;
            self.cells.neighbours(i, |j| {
                let reach = balls[i].radius + balls[j].radius + skin;
                let d = sub(centres[j], *c);
                if dot(d, d) < reach * reach {
                    let (lower, upper) = if depth(*c) >= depth(centres[j]) { (i, j) } else { (j, i) };
                    pairs.push((lower as u32, upper as u32));
                }
            });
        }
        self.pairs.sort_by(|a, b| depth(centres[b.0 as usize]).total_cmp(&depth(centres[a.0 as usize])));
    }

    /// One sweep over the listed pairs, lowest first: each overlapping pair moved apart along
    /// its centres' line until it touches, kept in the box. With `lift` the upper ball is
    /// lifted off the lower one (side by side, and without `lift`, the lighter ball moves the
    /// more: the projection that finds the pile's rest). Returns the deepest overlap met, m.
    fn part_overlaps(&self, centres: &mut [[f64; 3]], balls: &[Ball], size: [f64; 3], down: [f64; 3], lift: bool) -> f64 {
        let mut worst = 0.0f64;
        for &(lower, upper) in &self.pairs {
            let (i, j) = (lower as usize, upper as usize);
            let reach = balls[i].radius + balls[j].radius;
            let d = sub(centres[j], centres[i]);
            let distance = norm(d);
            if distance >= reach {
                continue;
            }
            worst = worst.max(reach - distance);
            // Coincident centres part along x.
            let n = if distance > 0.0 { d.map(|x| x / distance) } else { [1.0, 0.0, 0.0] };
            let push = reach - distance;
            let wi = if !lift || -dot(d, down) < SIDE_BY_SIDE * reach {
                let (mi, mj) = (balls[i].mass, balls[j].mass);
                mj / (mi + mj)
            } else {
                0.0
            };
            centres[i] = clamp(std::array::from_fn(|a| centres[i][a] - wi * push * n[a]), balls[i].radius, size);
            centres[j] = clamp(std::array::from_fn(|a| centres[j][a] + (1.0 - wi) * push * n[a]), balls[j].radius, size);
        }
        worst
    }
}

/// `c` moved into the box where a ball of radius `r` touches no wall from outside.
fn clamp(c: [f64; 3], r: f64, size: [f64; 3]) -> [f64; 3] {
    let (lo, hi) = super::placement::centre_bounds(r, size);
    std::array::from_fn(|a| c[a].clamp(lo[a], hi[a]))
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
