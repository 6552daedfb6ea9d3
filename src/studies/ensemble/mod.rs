//! Ensembles: members of a scene drawn under its `[tolerances]`, run in parallel, and their
//! metrics as distributions (docs/MODEL.md §12). Every study that takes `--ensemble` draws and
//! runs its members here. Member k's draws depend only on `(seed, k)` and members are
//! collected in order, so the same seed gives the same bytes at any thread count.

use std::collections::BTreeMap;

use rand::{Rng, SeedableRng};
use rand_distr::{Distribution as _, Normal};
use rand_pcg::Pcg64;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::metrics::{Headline, Metric};
use crate::model::{Limits, Model, ModelError, RunOptions};
use crate::run::{refuse_beyond_memory, ImpactRecord, Record};
use crate::scene::{self, Distribution, Length, Parameter, Scene, SceneError, SceneFile, Tolerances};

mod distributions;

pub use distributions::*;

/// Draws one member may take before its tolerances are declared too wide for it.
pub const MAX_DRAWS_PER_MEMBER: u32 = 100;

/// Most members an ensemble may have.
pub const MAX_MEMBERS: usize = 1_000_000;

/// Seed of the draws when neither the scene nor the command line gives one.
pub const DEFAULT_SEED: u64 = 1;

/// One member: its index, the values drawn for it (in [`Ensemble::columns`] order, in the
/// parameters' units, lengths in metres) and its validated scene.
#[derive(Debug, Clone)]
pub struct Member {
    /// `k`, from 0.
    pub index: usize,
    /// Drawn values.
    pub drawn: Vec<f64>,
    /// The scene.
    pub scene: Scene,
}

/// The members of an ensemble.
#[derive(Debug, Clone)]
pub struct Ensemble {
    /// Names of the drawn values: each toleranced parameter, `gap1 ... gapN` for the gaps.
    pub columns: Vec<String>,
    /// Members, in order.
    pub members: Vec<Member>,
    /// Draws thrown away because they made an invalid scene (overlapping bodies, a parameter
    /// out of its range).
    pub redraws: u64,
    /// Seed of the draws.
    pub seed: u64,
}

/// Member `k`'s random numbers, which depend on `(seed, k)` and nothing else (not on the
/// threads, nor on which members are drawn first): a generator seeded from the seed's first
/// number XOR `k` (distinct for every `k`), each step through `seed_from_u64`'s mixing.
/// PCG's streams (one increment per member from one state) are not used: across 400 streams
/// the first numbers kept away from the ends of [0, 1) (largest 0.987 and 0.990 for two
/// seeds, where 0.9975 is expected), and spread more evenly than independent draws do.
pub fn member_rng(seed: u64, k: usize) -> Pcg64 {
    Pcg64::seed_from_u64(Pcg64::seed_from_u64(seed).random::<u64>() ^ k as u64)
}

/// Whether `file` places a bed at random (or settles one from random nudges): its members
/// then each place their own.
pub fn places_bed_at_random(file: &SceneFile) -> bool {
    let random = |b: &scene::format::BedFile| matches!(b.placement, scene::format::Placement::Random | scene::format::Placement::Settled);
    file.bed.as_ref().is_some_and(random) || file.dampers.iter().flatten().filter_map(|d| d.bed.as_ref()).any(random)
}

/// Whether `file` shakes its ground at random: its members then each draw their own motion.
pub fn shakes_at_random(file: &SceneFile) -> bool {
    file.forcing.as_ref().is_some_and(|g| g.kind == scene::format::ExcitationKind::Random)
}

/// A draw that made no valid scene: the tolerance to blame (a parameter's name, or
/// `position`) and why.
struct Failure {
    tolerance: &'static str,
    rule: String,
}

impl Failure {
    fn of(parameter: Parameter, rule: String) -> Failure {
        Failure { tolerance: parameter.name(), rule }
    }
}

/// The name of the ball positions' tolerance, in `[tolerances]` and in the members' table.
const POSITION: &str = "position";

/// Draws `count` members of `nominal` (built from `file`, perhaps with command-line
/// overrides) under `tolerances`. A bed placed at random is placed anew in every member, from a
/// seed drawn from `(seed, k)` (the members' column `bed_seed`), and a random ground motion is
/// drawn anew likewise (`ground_seed`). A tolerance on the balls' positions moves every ball of
/// a bed by its own draw (the column `position_rms`, the displacements' root mean square).
/// Without tolerances, a random bed or a random ground every member is the nominal scene.
/// A tolerance so wide that a member finds no valid scene in [`MAX_DRAWS_PER_MEMBER`] draws,
/// or that more draws fail than succeed, is an error naming it.
pub fn draw(
    file: &SceneFile,
    path: &str,
    nominal: &Scene,
    tolerances: Option<&Tolerances>,
    count: usize,
    seed: Option<u64>,
) -> Result<Ensemble, SceneError> {
    draw_range(file, path, nominal, tolerances, count, 0..count, seed)
}

/// Members `range` of an ensemble of `count` (a shard or a chunk of it): the very members
/// [`draw`] gives those indices, since member `k` depends only on `(seed, k)`. The redraw
/// rule (no more failed draws than members) is judged over the range.
pub fn draw_range(
    file: &SceneFile,
    path: &str,
    nominal: &Scene,
    tolerances: Option<&Tolerances>,
    count: usize,
    range: std::ops::Range<usize>,
    seed: Option<u64>,
) -> Result<Ensemble, SceneError> {
    let invalid = |field: &str, rule: String| SceneError::Invalid { file: path.into(), field: field.into(), rule };
    if count == 0 || count > MAX_MEMBERS {
        return Err(invalid("--ensemble", format!("must lie in 1..={MAX_MEMBERS} (got {count})")));
    }
    if range.start >= range.end || range.end > count {
        return Err(invalid("members", format!("{}..{} are not a part of 0..{count}", range.start, range.end)));
    }
    let count = range.len();
    check_members_memory(nominal, count).map_err(|rule| invalid("--ensemble", rule))?;
    let spreads: &[(Parameter, f64)] = tolerances.map_or(&[], |t| &t.spreads);
    let position = tolerances.and_then(|t| t.position);
    let normal = tolerances.is_some_and(|t| t.distribution == Distribution::Normal);
    let seed = seed.or(tolerances.map(|t| t.seed)).unwrap_or(DEFAULT_SEED);
    let n = nominal.balls.len();
    let mut base = scene::with_settings_of(file, nominal);
    base.sweep = None;
    base.tolerances = None;
    let random_bed = places_bed_at_random(&base);
    let random_ground = shakes_at_random(&base);
    let columns = spreads
        .iter()
        .flat_map(|&(p, _)| if p == Parameter::Gap { (1..=n).map(|i| format!("gap{i}")).collect() } else { vec![p.to_string()] })
        .chain(random_bed.then(|| "bed_seed".to_string()))
        .chain(random_ground.then(|| "ground_seed".to_string()))
        .chain(position.map(|_| format!("{POSITION}_rms")))
        .collect();
    let drawer = Drawer { base, path, nominal, spreads, position, normal, random_bed, random_ground };
    let drawn: Vec<(Member, Vec<Failure>)> = range.into_par_iter().map(|k| drawer.member(seed, k)).collect::<Result<_, _>>()?;
    let redraws: u64 = drawn.iter().map(|d| d.1.len() as u64).sum();
    if redraws > count as u64 {
        let mut blame: BTreeMap<&str, (usize, &str)> = BTreeMap::new();
        for f in drawn.iter().flat_map(|d| &d.1) {
            let e = blame.entry(f.tolerance).or_insert((0, &f.rule));
            e.0 += 1;
        }
        let (tolerance, (times, rule)) = blame.into_iter().max_by_key(|b| b.1 .0).unwrap_or(("gap", (0, "")));
        return Err(invalid(
            &format!("tolerances.{tolerance}"),
            format!(
                "is too wide: {redraws} of {} draws made an invalid scene ({times} by this parameter, e.g. {rule}); narrow it",
                redraws + count as u64
            ),
        ));
    }
    Ok(Ensemble { columns, members: drawn.into_iter().map(|d| d.0).collect(), redraws, seed })
}

/// The table of an ensemble's members (`members.csv`, `members.parquet`, the Python
/// binding's columns): `member`, the drawn values, then every metric ([`Metric::ALL`]),
/// one row per member in member order; `metrics` is `[member][metric]`.
pub fn members_table(columns: &[String], members: &[Member], metrics: &[Vec<Option<f64>>]) -> (Vec<String>, Vec<Vec<Option<f64>>>) {
    let mut header = vec!["member".to_string()];
    header.extend(columns.iter().cloned());
    header.extend(Metric::ALL.iter().map(|m| m.name().to_string()));
    let rows = members
        .iter()
        .zip(metrics)
        .map(|(m, metrics)| {
            let mut row = vec![Some(m.index as f64)];
            row.extend(m.drawn.iter().map(|&x| Some(x)));
            row.extend(metrics.iter().copied());
            row
        })
        .collect();
    (header, rows)
}

/// Members `[start, stop)` of shard `shard` of `shards` of an ensemble of `count`: consecutive
/// members, the shards as even as integers allow. Each shard of a Slurm job array
/// (`lpc run --ensemble N --shard I/K`) and each chunk of the Python binding's distributed
/// ensemble is such a range, so its members are the ones the whole ensemble has there.
pub fn shard_range(count: usize, shard: usize, shards: usize) -> std::ops::Range<usize> {
    let at = |i: usize| ((count as u128 * i as u128) / shards as u128) as usize;
    at(shard)..at(shard + 1)
}

/// What a shard of an ensemble was (`shard.json` beside its `members.csv`): what
/// `lpc merge` checks the shards against each other with, and sums.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShardInfo {
    /// Scene name.
    pub scene: String,
    /// Model.
    pub model: Model,
    /// Seed of the draws.
    pub seed: u64,
    /// Members of the whole ensemble.
    pub members: usize,
    /// This shard, from 0.
    pub shard: usize,
    /// Shards in all.
    pub shards: usize,
    /// First member of the shard.
    pub start: usize,
    /// One past its last member.
    pub stop: usize,
    /// Draws thrown away as invalid in this shard.
    pub redraws: u64,
    /// Computing time of this shard, s.
    pub wall_time_s: f64,
}

/// Columns of [`members_table`] that hold integers.
pub const INTEGER_COLUMNS: &[&str] = &["member", "impact_count"];

/// Bytes an ensemble of `count` members of `scene` holds at once: each member's scene (its
/// balls, positions and velocities), its drawn values and its metrics.
pub fn members_bytes(scene: &Scene, count: usize) -> f64 {
    let balls = scene.balls.len() as f64;
    let per_member = std::mem::size_of::<Member>() as f64
        + balls * (std::mem::size_of::<crate::scene::Ball>() as f64 + 16.0)
        + (balls + 12.0) * 8.0
        + Metric::ALL.len() as f64 * 16.0
        // The allocator's overhead on the name, the balls, positions, velocities, draws, metrics.
        + 6.0 * 32.0;
    count as f64 * per_member
}

/// Refuses, with the numbers, an ensemble whose members would not fit in the memory left.
fn check_members_memory(scene: &Scene, count: usize) -> Result<(), String> {
    let what = format!("is {count}: its members ({} balls each)", scene.balls.len());
    refuse_beyond_memory(members_bytes(scene, count), &what, "use fewer members")
}

struct Drawer<'a> {
    base: SceneFile,
    path: &'a str,
    nominal: &'a Scene,
    spreads: &'a [(Parameter, f64)],
    /// The spread of each ball's centre along each axis, m, when the balls' positions are
    /// toleranced.
    position: Option<f64>,
    normal: bool,
    /// Whether the scene places a bed at random: each member then places its own, from a seed
    /// of its own.
    random_bed: bool,
    /// Whether the scene shakes its ground at random: each member then draws its own motion,
    /// from a seed of its own.
    random_ground: bool,
}

impl Drawer<'_> {
    /// Member `k`: its first valid draw, and why each draw before it was thrown away.
    fn member(&self, seed: u64, k: usize) -> Result<(Member, Vec<Failure>), SceneError> {
        let mut rng = member_rng(seed, k);
        let mut failures = vec![];
        for _ in 0..MAX_DRAWS_PER_MEMBER {
            match self.attempt(&mut rng, k) {
                Ok(member) => return Ok((member, failures)),
                Err(f) => failures.push(f),
            }
        }
        let last = failures.pop().unwrap_or(Failure::of(Parameter::Gap, String::new()));
        Err(SceneError::Invalid {
            file: self.path.into(),
            field: format!("tolerances.{}", last.tolerance),
            rule: format!(
                "is too wide: {MAX_DRAWS_PER_MEMBER} draws in a row for member {k} made an invalid scene (the last: {}); narrow it",
                last.rule
            ),
        })
    }

    fn deviation(&self, rng: &mut Pcg64, spread: f64) -> f64 {
        if self.normal {
            Normal::new(0.0, spread).map_or(0.0, |d| d.sample(rng))
        } else {
            // Uniform on [-w, w) without forming the range's width (a huge w cannot overflow).
            spread * (2.0 * rng.random::<f64>() - 1.0)
        }
    }

    fn attempt(&self, rng: &mut Pcg64, k: usize) -> Result<Member, Failure> {
        let n = self.nominal.balls.len();
        // Every deviation is drawn first, in a fixed order, so a member's numbers never
        // depend on which of its draws fail.
        let deviations: Vec<Vec<f64>> = self
            .spreads
            .iter()
            .map(|&(p, w)| (0..if p == Parameter::Gap { n } else { 1 }).map(|_| self.deviation(rng, w)).collect())
            .collect();
        // Below 2^53, so that the members' table holds it exactly.
        let bed_seed = self.random_bed.then(|| rng.random::<u64>() >> 11);
        let ground_seed = self.random_ground.then(|| rng.random::<u64>() >> 11);
        let mut file: Option<SceneFile> = (bed_seed.is_some() || ground_seed.is_some()).then(|| {
            let mut f = self.base.clone();
            if let (Some(bed), Some(seed)) = (f.bed.as_mut(), bed_seed) {
                bed.seed = Some(seed);
            }
            // Several dampers' beds each from their own seed: the member's plus the bed's place among them.
            for (d, bed) in f.dampers.iter_mut().flatten().filter_map(|d| d.bed.as_mut()).enumerate() {
                if let Some(seed) = bed_seed {
                    bed.seed = Some(seed + d as u64);
                }
            }
            if let (Some(g), Some(seed)) = (f.forcing.as_mut(), ground_seed) {
                g.seed = Some(seed);
            }
            f
        });
        let mut values = vec![];
        for (&(p, _), d) in self.spreads.iter().zip(&deviations) {
            if p == Parameter::Gap {
                continue;
            }
            let value = p.value(&self.base, self.nominal).unwrap_or(f64::NAN) + d[0];
            values.push(value);
            let f = file.as_ref().unwrap_or(&self.base);
            file = Some(p.apply(f, Length::Metres(value)).map_err(|rule| Failure::of(p, rule))?);
        }
        let name = format!("{}#{k}", self.nominal.name);
        // A failure the scene's rules cannot pin on a drawn parameter is blamed on the first.
        let first = self.spreads.first().map(|s| s.0.name()).or(self.position.map(|_| POSITION)).unwrap_or(Parameter::FillFraction.name());
        let mut scene = match file {
            None => self.nominal.clone(),
            Some(f) => scene::from_file(f, self.path, &name)
                .map_err(|e| match e {
                    SceneError::Invalid { field, rule, .. } => {
                        Failure { tolerance: Parameter::of_field(&field).map_or(first, Parameter::name), rule: format!("{field} {rule}") }
                    }
                    other => Failure { tolerance: first, rule: other.to_string() },
                })?
                .scene
                .ok_or(Failure { tolerance: first, rule: "no damper scene".into() })?,
        };
        scene.name = name;
        let mut drawn = vec![];
        let mut values = values.into_iter();
        for (&(p, _), d) in self.spreads.iter().zip(&deviations) {
            if p == Parameter::Gap {
                drawn.extend(shift_gaps(&mut scene, d)?);
            } else {
                drawn.extend(values.next());
            }
        }
        drawn.extend(bed_seed.map(|seed| seed as f64));
        drawn.extend(ground_seed.map(|seed| seed as f64));
        if let Some(spread) = self.position {
            drawn.push(self.move_balls(rng, &mut scene, spread)?);
        }
        Ok(Member { index: k, drawn, scene })
    }

    /// Moves every ball of `scene` by its own draw along each axis, less the draw's component
    /// along gravity (a ball resting on the floor stays on it): the displacements' root mean
    /// square, m, or the failure when a ball would leave the box or overlap another. The
    /// draws follow the member's scene, whose number of balls a drawn fill fraction sets.
    fn move_balls(&self, rng: &mut Pcg64, scene: &mut Scene, spread: f64) -> Result<f64, Failure> {
        let g = scene.space.gravity;
        let g_norm = g.iter().map(|x| x * x).sum::<f64>().sqrt();
        let down = if g_norm > 0.0 { g.map(|x| x / g_norm) } else { [0.0; 3] };
        let by: Vec<[f64; 3]> = (0..scene.balls.len())
            .map(|_| {
                let d = [(); 3].map(|_| self.deviation(rng, spread));
                let along: f64 = (0..3).map(|a| d[a] * down[a]).sum();
                [0, 1, 2].map(|a| d[a] - along * down[a])
            })
            .collect();
        scene::move_placed_balls(scene, &by).map_err(|rule| Failure { tolerance: POSITION, rule })?;
        let sum: f64 = by.iter().flatten().map(|x| x * x).sum();
        Ok((sum / by.len().max(1) as f64).sqrt())
    }
}

/// Moves ball `i`'s gap to its left neighbour (a wall for the first) by `deviation[i]`, the
/// container held: the balls right of it shift with it and the clearance takes up the sum.
/// Returns the gaps, or the failure when bodies would overlap.
fn shift_gaps(scene: &mut Scene, deviation: &[f64]) -> Result<Vec<f64>, Failure> {
    let Some(container) = scene.container.as_mut() else { return Ok(vec![]) };
    let gaps: Vec<f64> = deviation.iter().map(|d| container.gap + d).collect();
    // Each chain's balls shift with their own gaps; its clearance takes up its own sum.
    let n = scene.initial_positions.len();
    let chains: Vec<_> = (0..scene.space.chains()).map(|k| scene.space.chain(k, n)).collect();
    let clearance = chains.iter().map(|c| container.clearance - deviation[c.clone()].iter().sum::<f64>()).fold(f64::INFINITY, f64::min);
    let clearance = if chains.is_empty() { container.clearance } else { clearance };
    if let Some((i, g)) = gaps.iter().enumerate().find(|(_, g)| **g < 0.0) {
        return Err(Failure::of(Parameter::Gap, format!("gap {} of {} m overlaps its neighbours", i + 1, scene::human(*g))));
    }
    if clearance < 0.0 {
        return Err(Failure::of(
            Parameter::Gap,
            format!("the gaps leave a clearance of {} m: the last ball overlaps the wall", scene::human(clearance)),
        ));
    }
    container.clearance = clearance;
    for chain in chains {
        let mut shift = 0.0;
        for i in chain {
            shift += deviation[i];
            scene.initial_positions[i] += shift;
        }
    }
    Ok(gaps)
}

/// Runs `f` on every member in parallel, in member order; `progress` is called after each.
pub fn map_members<T: Send, E: Send>(
    members: &[Member],
    f: impl Fn(&Member) -> Result<T, E> + Sync,
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<T>, E> {
    members
        .par_iter()
        .map(|m| {
            let r = f(m);
            progress();
            r
        })
        .collect()
}

/// What an ensemble's runs leave: every member's metrics ([`Metric::ALL`] order) and, when
/// asked for, every member's frame displacement at the common sample times.
#[derive(Debug, Clone, Default)]
pub struct EnsembleRuns {
    /// `[member][metric]`.
    pub metrics: Vec<Vec<Option<f64>>>,
    /// Sample times of `xs`, s (empty unless kept).
    pub t: Vec<f64>,
    /// `[member][sample]`, m (empty unless kept).
    pub xs: Vec<Vec<f64>>,
}

/// Runs every member with `model`, each within `limits`. Members count their impacts rather
/// than keep them, and build no series unless `keep_xs`, which keeps each member's frame
/// displacement (the ensemble's band) and drops the rest.
pub fn run_members(
    ensemble: &Ensemble,
    model: Model,
    limits: Limits,
    keep_xs: bool,
    progress: &(dyn Fn() + Sync),
) -> Result<EnsembleRuns, ModelError> {
    let options = RunOptions {
        record: if keep_xs { Record::Series } else { Record::MetricsOnly },
        impacts: ImpactRecord::Count,
        limits,
        progress: None,
    };
    if keep_xs {
        if let Some(first) = ensemble.members.first() {
            check_band_memory(&first.scene, ensemble.members.len())?;
        }
    }
    let runs = map_members(
        &ensemble.members,
        |m| {
            let run = model.simulate(&m.scene, &options)?;
            let metrics = Headline::of_run(&run).values();
            let series = keep_xs.then_some(run.series);
            Ok::<_, ModelError>((metrics, series))
        },
        progress,
    )?;
    let mut out = EnsembleRuns::default();
    let mut every = None;
    for (metrics, series) in runs {
        out.metrics.push(metrics);
        if let Some(s) = series {
            // Each run thins its series by the memory left when it starts (run::series_every):
            // a band needs every member sampled at the same times.
            if *every.get_or_insert(s.every) != s.every {
                return Err(ModelError::Refused(format!(
                    "the members' series had to be thinned differently (one sample in {} and in {}) to fit in the memory \
                     left, so their band would mix times; raise run.sample_dt or leave out --out",
                    every.unwrap_or(1),
                    s.every
                )));
            }
            if out.t.is_empty() {
                out.t = s.t().to_vec();
            }
            out.xs.push(s.xs().to_vec());
        }
    }
    Ok(out)
}

/// Refuses, with the numbers, a band whose members' displacements would not fit in memory.
fn check_band_memory(scene: &Scene, members: usize) -> Result<(), ModelError> {
    let need = scene.sample_count() as f64 * members as f64 * 8.0;
    let what = format!("the band of {members} members x {} samples", scene.sample_count());
    refuse_beyond_memory(need, &what, "raise run.sample_dt, use fewer members, or leave out --out (the metrics need no series)")
        .map_err(ModelError::Refused)
}
