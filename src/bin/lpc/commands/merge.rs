//! `lpc merge`: joins the shards of an ensemble (`lpc run --ensemble N --shard I/K --out DIR`,
//! one per job of an array) into the table the unsharded run writes: `members.csv` and
//! `members.parquet` equal to its own, and `ensemble.json` with every metric's distribution.

use std::path::{Path, PathBuf};

use anyhow::Context;

use lpc_damper::files::write_atomic;
use lpc_damper::metrics::Metric;
use lpc_damper::scene::SceneError;
use lpc_damper::studies::ensemble::{self, EnsembleSummary, ShardInfo};

use crate::args::Format;
use crate::commands::run::{print_ensemble, write_table};
use crate::exit::{ExitStatus, Result};

#[derive(clap::Args)]
pub struct Args {
    /// Shard directories, each written by `lpc run SCENE --ensemble N --shard I/K --out DIR`.
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Where to write the merged members.csv, members.parquet and ensemble.json.
    #[arg(long)]
    out: PathBuf,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

/// A shard as read back: its `shard.json`, and its members' table.
struct Shard {
    dir: PathBuf,
    info: ShardInfo,
    header: Vec<String>,
    rows: Vec<Vec<Option<f64>>>,
}

fn bad(dir: &Path, field: &str, rule: impl Into<String>) -> SceneError {
    SceneError::Invalid { file: dir.display().to_string(), field: field.into(), rule: rule.into() }
}

fn read_shard(dir: &Path) -> std::result::Result<Shard, SceneError> {
    let read = |name: &str| {
        std::fs::read(dir.join(name)).map_err(|e| SceneError::Io { file: dir.join(name).display().to_string(), message: e.to_string() })
    };
    let info: ShardInfo =
        serde_json::from_slice(&read("shard.json")?).map_err(|e| bad(dir, "shard.json", format!("is not a shard's description: {e}")))?;
    if info.stop < info.start {
        return Err(bad(dir, "shard.json", format!("ends (member {}) before it starts ({})", info.stop, info.start)));
    }
    let bytes = read("members.csv")?;
    let mut reader = csv::Reader::from_reader(bytes.as_slice());
    let header: Vec<String> = reader.headers().map_err(|e| bad(dir, "members.csv", e.to_string()))?.iter().map(String::from).collect();
    // The table ends with the summary's metrics, in order: the merged summary reads them there.
    let tail = header.len().checked_sub(Metric::ALL.len()).map(|k| &header[k..]);
    if tail.is_none_or(|t| t.iter().zip(Metric::ALL).any(|(h, m)| h.as_str() != m.name())) {
        let names: Vec<&str> = Metric::ALL.iter().map(|m| m.name()).collect();
        return Err(bad(dir, "members.csv", format!("does not end with the metrics columns {}", names.join(", "))));
    }
    let mut rows = vec![];
    for (r, record) in reader.records().enumerate() {
        let record = record.map_err(|e| bad(dir, "members.csv", e.to_string()))?;
        let row = record
            .iter()
            .map(|cell| if cell.is_empty() { Ok(None) } else { cell.parse::<f64>().map(Some) })
            .collect::<std::result::Result<Vec<_>, _>>()
            .map_err(|e| bad(dir, &format!("members.csv row {}", r + 1), e.to_string()))?;
        rows.push(row);
    }
    if rows.len() != info.stop - info.start {
        return Err(bad(dir, "members.csv", format!("has {} rows where shard.json says {}..{}", rows.len(), info.start, info.stop)));
    }
    Ok(Shard { dir: dir.to_path_buf(), info, header, rows })
}

pub fn run(a: Args) -> Result<ExitStatus> {
    let mut shards = a.dirs.iter().map(|d| read_shard(d)).collect::<std::result::Result<Vec<_>, _>>()?;
    shards.sort_by_key(|s| s.info.start);
    let first = &shards[0];
    // Shards of one ensemble: the same scene, model, seed, size and table, covering it once.
    let mut next = 0;
    for s in &shards {
        let (i, f) = (&s.info, &first.info);
        if i.scene != f.scene || i.model != f.model || i.seed != f.seed || i.members != f.members || s.header != first.header {
            return Err(bad(
                &s.dir,
                "shard.json",
                format!(
                    "is a shard of another ensemble ({} / {} / seed {} / {} members) than {} ({} / {} / seed {} / {} members)",
                    i.scene,
                    i.model,
                    i.seed,
                    i.members,
                    first.dir.display(),
                    f.scene,
                    f.model,
                    f.seed,
                    f.members
                ),
            )
            .into());
        }
        if i.start != next {
            let what = if i.start < next { "overlaps the shard before it" } else { "leaves a gap after the shard before it" };
            return Err(bad(&s.dir, "shard.json", format!("{what}: members {}..{} after ..{next}", i.start, i.stop)).into());
        }
        next = i.stop;
    }
    if next != first.info.members {
        return Err(bad(
            &shards[shards.len() - 1].dir,
            "shard.json",
            format!("the shards end at member {next} of {}: some are missing", first.info.members),
        )
        .into());
    }
    let header = first.header.clone();
    let rows: Vec<Vec<Option<f64>>> = shards.iter().flat_map(|s| s.rows.iter().cloned()).collect();
    let metrics: Vec<Vec<Option<f64>>> = rows.iter().map(|r| r[r.len() - Metric::ALL.len()..].to_vec()).collect();
    let info = &first.info;
    let summary = EnsembleSummary {
        scene: info.scene.clone(),
        model: info.model,
        members: info.members,
        redraws: shards.iter().map(|s| s.info.redraws).sum(),
        seed: info.seed,
        metrics: ensemble::metric_stats(&metrics),
        wall_time_s: shards.iter().map(|s| s.info.wall_time_s).sum(),
    };
    (|| -> anyhow::Result<()> {
        std::fs::create_dir_all(&a.out)?;
        write_table(&a.out, "members", &header, &rows, info.model, info.seed)?;
        write_atomic(&a.out.join("ensemble.json"), &serde_json::to_vec_pretty(&summary)?)?;
        Ok(())
    })()
    .with_context(|| format!("writing outputs to {}", a.out.display()))?;
    print_ensemble(&summary, a.format, Some((&a.out, "members.csv, members.parquet and ensemble.json")))
}
