//! `lpc check`: headless regression runs of every scene with every model against the goldens.

use std::path::PathBuf;

use lpc_damper::studies::check;
use lpc_damper::Model;

use crate::exit::{ExitStatus, Result};
use crate::table::{left, right, Table};

#[derive(clap::Args)]
pub struct Args {
    /// Directory of scene files.
    #[arg(default_value = "scenes")]
    dir: PathBuf,
    /// Directory of golden files.
    #[arg(long, default_value = "tests/golden")]
    golden: PathBuf,
    /// Models, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "reference,rapier,compliant")]
    models: Vec<Model>,
    /// Rewrite the golden files from this run (the reference's scenes are run eight more times
    /// each, to measure how far round-off moves their values).
    #[arg(long)]
    update: bool,
    /// Print every compared value, not only the failures.
    #[arg(long)]
    verbose: bool,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    let work = crate::watch::Work::new(None, "check");
    let now = check::current(&a.dir, &a.models, a.update, &|| work.inc())?;
    work.finish();
    let mut rows = Vec::new();
    for g in &now {
        if a.update {
            check::write_golden(&a.golden, g)?;
        }
        let golden = if a.update { Some(g.clone()) } else { check::read_golden(&a.golden, g)? };
        rows.extend(check::compare(g, golden.as_ref()));
    }
    let fmt = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.6e}"));
    let table = Table::new(vec![
        left("case", 34),
        right("model", 9),
        left("metric", 18),
        right("golden", 14),
        right("now", 14),
        right("tolerance", 10),
        right("", 6),
    ]);
    table.print_header();
    for r in rows.iter().filter(|r| a.verbose || !r.ok) {
        table.print_row(&[
            r.case.clone(),
            r.model.to_string(),
            r.metric.clone(),
            fmt(r.golden),
            fmt(r.now),
            format!("{:.1e}", r.tolerance),
            (if r.ok { "ok" } else { "FAIL" }).to_string(),
        ]);
    }
    let failed = rows.iter().filter(|r| !r.ok).count();
    println!("{} passed, {} failed", rows.len() - failed, failed);
    if a.update {
        println!("golden files rewritten in {}", a.golden.display());
    }
    Ok(if failed == 0 { ExitStatus::Success } else { ExitStatus::Regression })
}
