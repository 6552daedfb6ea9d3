//! `lpc chain`: the chain experiment's kinetic energy ratio against the number of large balls.

use std::path::PathBuf;

use lpc_damper::scene;
use lpc_damper::studies::chain::{run_chain, KerRow};
use lpc_damper::Model;

use crate::args::{invalid, override_scene, print_json, BudgetArgs, Format, ModelArgs};
use crate::exit::{ExitStatus, Result};
use crate::table::{right, Table};

#[derive(clap::Args)]
pub struct Args {
    /// Chain scene file (default: scenes/chain-ker.toml).
    scene: Option<PathBuf>,
    /// Model to run.
    #[arg(long, default_value = "reference")]
    model: Model,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    #[command(flatten)]
    settings: ModelArgs,
    #[command(flatten)]
    budget: BudgetArgs,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    let path = a.scene.unwrap_or_else(|| PathBuf::from("scenes/chain-ker.toml"));
    let limits = a.budget.limits(&path)?;
    let loaded = scene::load(&path)?;
    let mut cases =
        loaded.chain.ok_or_else(|| invalid(&path, "chain", "is missing: `lpc chain` needs a scene file with a [chain] table"))?;
    for c in &mut cases {
        override_scene(&mut c.scene, a.settings.overrides(None, None), &path)?;
    }
    let work = crate::watch::Work::new(Some(cases.len()), "chain");
    let rows: Vec<KerRow> = run_chain(&cases, a.model, limits, &|| work.inc())?;
    work.finish();
    match a.format {
        Format::Json => print_json(&rows)?,
        Format::Text => {
            println!("kinetic energy ratio ({}): KE of all balls after / KE of the incident ball", a.model.name());
            let table = Table::new(vec![right("large", 7), right("small", 7), right("KER", 10)]);
            table.print_header();
            for r in &rows {
                table.print_row(&[r.large.to_string(), r.small.to_string(), format!("{:.4}", r.ker)]);
            }
        }
    }
    Ok(ExitStatus::Success)
}
