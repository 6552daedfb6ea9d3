//! `lpc stability`: the contact model's stability map (step size x impact speed).

use crate::args::{print_json, Format};
use crate::exit::{ExitStatus, Result};
use crate::table::{right, Table};

#[derive(clap::Args)]
pub struct Args {
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    use lpc_damper::studies::stability::{self, Case, CONFIGS, DTS, SPEEDS};
    let work = crate::watch::Work::new(None, "stability map");
    let cells = stability::map(&|| work.inc());
    work.finish();
    match a.format {
        Format::Json => print_json(&cells)?,
        Format::Text => {
            println!("outcome per impact speed (rows, m/s) and step (columns, s); energy error vs the reference in %");
            for case in Case::ALL {
                for config in CONFIGS {
                    println!("\n{} / {}", case.name(), config.name);
                    let mut columns = vec![right("u \\ dt", 8)];
                    columns.extend(DTS.iter().map(|dt| right(format!("{dt:e}"), 22)));
                    let table = Table::new(columns);
                    table.print_header();
                    for speed in SPEEDS {
                        let mut row = vec![speed.to_string()];
                        for dt in DTS {
                            let c = cells
                                .iter()
                                .find(|c| c.case == case && c.config == config.name && c.dt == dt && c.speed == speed)
                                .expect("the map has a cell for every case, setting, step and speed");
                            row.push(format!("{} {:+.1}", c.outcome, 100.0 * c.energy_error));
                        }
                        table.print_row(&row);
                    }
                }
            }
        }
    }
    Ok(ExitStatus::Success)
}
