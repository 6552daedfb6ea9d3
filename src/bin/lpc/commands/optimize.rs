//! `lpc optimize`: the design with the shortest settling time (or the lowest resonant amplitude)
//! inside a given container length.

use std::path::PathBuf;

use clap::ValueEnum;

use lpc_damper::scene;
use lpc_damper::Model;

use crate::args::{invalid, parse_range, print_json, quantile_arg, BudgetArgs, EnsembleArgs, Format};
use crate::exit::{ExitStatus, Result};
use crate::table::{left, right, Table};

#[derive(clap::Args)]
pub struct Args {
    /// Scene file (its [balls] table is the starting design).
    scene: PathBuf,
    /// Inner container length (m, or `<k> Rr`); default: the scene's.
    #[arg(long)]
    container_length: Option<String>,
    /// A design parameter and its range: `PARAM=A..B:N` or `PARAM=V1,V2,...` (repeatable).
    #[arg(long = "vary")]
    vary: Vec<String>,
    /// Ball arrangements to try, comma-separated (default: the scene's).
    #[arg(long)]
    arrangements: Option<String>,
    /// What to minimise.
    #[arg(long, value_enum, default_value_t = ObjectiveArg::SettlingTime)]
    objective: ObjectiveArg,
    /// Frequency range `A..B` in Hz for the resonant amplitude.
    #[arg(long)]
    freq: Option<String>,
    /// Frequencies over that range.
    #[arg(long, default_value_t = 9)]
    steps: usize,
    /// Refinements around the best grid point.
    #[arg(long, default_value_t = 2)]
    refinements: u32,
    /// Model to run.
    #[arg(long, default_value = "reference")]
    model: Model,
    /// Designs listed in the text output.
    #[arg(long, default_value_t = 10)]
    top: usize,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    #[command(flatten)]
    ensemble: EnsembleArgs,
    #[command(flatten)]
    budget: BudgetArgs,
    /// With --ensemble: rank designs by this quantile of their members' objectives (default
    /// 0.5, the median; 0.9 asks for a design that is good on nine dampers out of ten).
    #[arg(long, requires = "ensemble")]
    quantile: Option<f64>,
}

#[derive(Clone, Copy, ValueEnum)]
enum ObjectiveArg {
    SettlingTime,
    ResonantAmplitude,
}

pub fn run(a: Args) -> Result<ExitStatus> {
    use lpc_damper::studies::optimize::{optimize, Judging, Objective};
    let limits = a.budget.limits(&a.scene)?;
    let loaded = scene::load(&a.scene)?;
    let invalid = |field: &str, rule: String| invalid(&a.scene, field, rule);
    let Some(base) = loaded.scene.clone() else {
        return Err(invalid("frame", "is missing: a design needs a damper scene".into()).into());
    };
    let length = match &a.container_length {
        Some(text) => match text.trim().parse::<f64>() {
            Ok(x) if x.is_finite() && x > 0.0 => scene::Length::Metres(x),
            _ => scene::Length::try_from_text(text)
                .ok_or_else(|| invalid("--container-length", format!("`{text}` is not a positive length (m or `<k> Rr`)")))?,
        },
        None => scene::Length::Metres(base.container.map_or(0.0, |c| c.length)),
    };
    let axes = a
        .vary
        .iter()
        .map(|v| lpc_damper::studies::sweep::parse_axis(v).map_err(|rule| invalid("--vary", rule)))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let arrangements: Vec<String> = match &a.arrangements {
        Some(list) => list.split(',').map(|s| s.trim().to_string()).filter(|s| !s.is_empty()).collect(),
        None => match &loaded.file.balls.as_ref().map(|b| b.arrangement.clone()) {
            Some(scene::Arrangement::Letters(l)) => vec![l.clone()],
            _ => return Err(invalid("--arrangements", "is needed: the scene lists its balls explicitly".into()).into()),
        },
    };
    if arrangements.is_empty() {
        return Err(invalid("--arrangements", "is empty".into()).into());
    }
    let objective = match a.objective {
        ObjectiveArg::SettlingTime => Objective::SettlingTime,
        ObjectiveArg::ResonantAmplitude => {
            let text = a.freq.as_deref().ok_or_else(|| invalid("--freq", "is needed for the resonant amplitude".into()))?;
            let (from, to) = parse_range(text, &a.scene, "--freq")?;
            lpc_damper::studies::frf::check_frequency_count(a.steps).map_err(|rule| invalid("--steps", rule))?;
            Objective::ResonantAmplitude { from, to, steps: a.steps }
        }
    };
    let robust = match a.ensemble.ensemble {
        Some(members) => {
            Some(lpc_damper::studies::optimize::Robust { members, seed: a.ensemble.seed, quantile: quantile_arg(a.quantile, &a.scene)? })
        }
        None => None,
    };
    let work = crate::watch::Work::new(None, "designs");
    let start = std::time::Instant::now();
    let search = optimize(
        &loaded,
        &axes,
        &arrangements,
        length,
        Judging { objective, model: a.model, limits, refinements: a.refinements, robust },
        &|| work.inc(),
    )?;
    work.finish();
    match a.format {
        Format::Json => print_json(&search)?,
        Format::Text => {
            let unit = match objective {
                Objective::SettlingTime => "settling time s",
                Objective::ResonantAmplitude { .. } => "resonant amplitude mm",
            };
            let scale = if matches!(objective, Objective::SettlingTime) { 1.0 } else { 1e3 };
            println!(
                "{} designs evaluated in {:.2} s ({} infeasible: balls do not fit {length}); container length fixed",
                search.ranking.len() + search.infeasible,
                start.elapsed().as_secs_f64(),
                search.infeasible
            );
            // The parameters column is set off by a second space.
            let unit = match robust {
                Some(r) => format!("{unit} (q {})", r.quantile),
                None => unit.to_string(),
            };
            let table = Table::new(vec![
                right("arrangement", 12),
                right("clearance mm", 12),
                right(unit, 28),
                right("5-95 % band", 20),
                left(" parameters", 0),
            ]);
            table.print_header();
            for d in search.ranking.iter().take(a.top) {
                let params = d.values.iter().map(|(p, v)| format!("{p}={v}")).collect::<Vec<_>>().join(" ");
                table.print_row(&[
                    d.arrangement.clone(),
                    format!("{:.3}", d.clearance * 1e3),
                    d.objective.map_or("not settled".into(), |x| format!("{:.4}", x * scale)),
                    d.band.map_or("-".into(), |(lo, hi)| format!("{:.4}-{:.4}", lo * scale, hi * scale)),
                    format!(" {params}"),
                ]);
            }
            match &search.best {
                Some(b) => println!(
                    "best: {} with {}",
                    b.arrangement,
                    b.values.iter().map(|(p, v)| format!("{p}={v}")).collect::<Vec<_>>().join(" ")
                ),
                None => println!("no feasible design settled"),
            }
            match search.distinguishable {
                Some(true) => println!("the best is distinguishable from the runner-up: their bootstrap 5-95 % bands do not overlap"),
                Some(false) => println!(
                    "the best is NOT distinguishable from the runner-up: their bootstrap 5-95 % bands overlap (more members, or call them equal)"
                ),
                None => {}
            }
        }
    }
    Ok(ExitStatus::Success)
}
