//! The files of a run's `--out DIR` (`series.csv`, `impacts.csv`, `summary.json`) and CSV
//! tables, each written whole or not at all ([`crate::files`]).

use std::io::Write;
use std::path::Path;

use crate::files::write_atomic_with;
use crate::metrics::RunSummary;
use crate::run::Run;

/// `series.csv`: `t, xs, vs, a`, then `x` and `v` of each ball.
pub fn series_csv(run: &Run) -> Vec<u8> {
    let mut bytes = Vec::new();
    write_series_csv(run, &mut bytes).expect("writing to memory");
    bytes
}

/// Rows of `series.csv` formatted together by one worker.
const SERIES_ROWS_PER_CHUNK: usize = 64;
/// Chunks formatted at once per worker before they are written: the text held in memory stays
/// a few hundred rows a worker, however long the series.
const SERIES_CHUNKS_PER_WORKER: usize = 4;

/// [`series_csv`] into `out`. Its text is several times the series' memory and formatting the
/// numbers is most of the cost, so chunks of rows are formatted on every core, a bounded batch
/// at a time, and written in order: the bytes are the same whatever the number of threads.
/// Numbers need no quoting in CSV, so a row is its values joined by commas.
pub fn write_series_csv(run: &Run, out: &mut dyn Write) -> std::io::Result<()> {
    use rayon::prelude::*;
    use std::fmt::Write as _;
    let s = &run.series;
    let mut header = vec!["t".to_string(), "xs".into(), "vs".into(), "a".into()];
    for i in 0..s.balls() {
        header.push(format!("x{}", i + 1));
        header.push(format!("v{}", i + 1));
    }
    // Balls moving across the motion: their `y` and `z` after every ball's `x` and `v`.
    for i in 0..s.balls() * s.has_across() as usize {
        header.push(format!("y{}", i + 1));
        header.push(format!("z{}", i + 1));
    }
    // A structure: every floor relative to the ground, bottom to top, after the balls, and
    // then every floor's absolute acceleration.
    for i in 0..s.floor_count() {
        header.push(format!("xs{}", i + 1));
        header.push(format!("vs{}", i + 1));
    }
    for i in 0..s.floor_count() {
        header.push(format!("as{}", i + 1));
    }
    writeln!(out, "{}", header.join(","))?;
    let write_row = |k: usize, text: &mut String| {
        let mut put = |x: f64| {
            write!(text, "{x},").expect("writing to memory");
        };
        [s.t()[k], s.xs()[k], s.vs()[k], s.a()[k]].into_iter().for_each(&mut put);
        for i in 0..s.balls() {
            put(s.x(i)[k]);
            put(s.v(i)[k]);
        }
        for i in 0..s.balls() * s.has_across() as usize {
            s.across(i, k).into_iter().for_each(&mut put);
        }
        let floor = |i: usize| s.floor(i, k).unwrap_or((f64::NAN, f64::NAN, f64::NAN));
        for i in 0..s.floor_count() {
            let (u, v, _) = floor(i);
            put(u);
            put(v);
        }
        for i in 0..s.floor_count() {
            put(floor(i).2);
        }
        text.pop();
        text.push('\n');
    };
    let chunks = s.len().div_ceil(SERIES_ROWS_PER_CHUNK);
    let batch = SERIES_CHUNKS_PER_WORKER * rayon::current_num_threads();
    for first in (0..chunks).step_by(batch.max(1)) {
        let texts: Vec<String> = (first..(first + batch).min(chunks))
            .into_par_iter()
            .map(|c| {
                let mut text = String::new();
                for k in c * SERIES_ROWS_PER_CHUNK..((c + 1) * SERIES_ROWS_PER_CHUNK).min(s.len()) {
                    write_row(k, &mut text);
                }
                text
            })
            .collect();
        for text in &texts {
            out.write_all(text.as_bytes())?;
        }
    }
    out.flush()
}

/// `impacts.csv`: `t, body_a, body_b, approach_speed, energy_lost, peak_force,
/// contact_duration` (the last two empty for impulse models).
pub fn impacts_csv(run: &Run) -> Vec<u8> {
    let mut bytes = Vec::new();
    write_impacts_csv(run, &mut bytes).expect("writing to memory");
    bytes
}

/// [`impacts_csv`] into `out`, row by row: a long run keeps millions of impacts, and their
/// text is several times their memory.
pub fn write_impacts_csv(run: &Run, out: &mut dyn Write) -> std::io::Result<()> {
    let mut w = csv::Writer::from_writer(out);
    w.write_record(["t", "body_a", "body_b", "approach_speed", "energy_lost", "peak_force", "contact_duration"])?;
    let optional = |x: Option<f64>| x.map_or(String::new(), |x| x.to_string());
    for i in &run.impacts {
        w.write_record([
            i.t.to_string(),
            i.a.name(),
            i.b.name(),
            i.approach_speed.to_string(),
            i.energy_lost.to_string(),
            optional(i.peak_force),
            optional(i.contact_duration),
        ])?;
    }
    w.flush()
}

/// A CSV table of numbers under `header`; an undefined value (`None`) is an empty cell.
pub fn table_csv(header: &[String], rows: impl IntoIterator<Item = Vec<Option<f64>>>) -> Vec<u8> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header).expect("writing to memory");
    for row in rows {
        w.write_record(row.iter().map(|x| x.map_or(String::new(), |x| x.to_string()))).expect("writing to memory");
    }
    w.into_inner().expect("writing to memory")
}

/// Writes `series.csv`, `impacts.csv` and `summary.json` of `run` into `dir`; without
/// `impacts.csv` (an older one removed) when the run counted its impacts without keeping them.
pub fn write_run_dir(run: &Run, dir: &Path) -> std::io::Result<()> {
    write_run_dir_with(run, &RunSummary::of(run), dir)
}

/// [`write_run_dir`] with the run's `summary` as the caller completed it (a structure's floors
/// without the damper).
pub fn write_run_dir_with(run: &Run, summary: &RunSummary, dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    write_atomic_with(&dir.join("series.csv"), |w| write_series_csv(run, w))?;
    let impacts = dir.join("impacts.csv");
    if run.counted_impacts.count == 0 {
        write_atomic_with(&impacts, |w| write_impacts_csv(run, w))?;
    } else if impacts.exists() {
        // An older run's list would be read as this run's.
        std::fs::remove_file(&impacts)?;
    }
    write_atomic_with(&dir.join("summary.json"), |w| serde_json::to_writer_pretty(w, summary).map_err(std::io::Error::other))
}
