//! Parameter sweeps: one scene file, one `[sweep]` parameter or a grid of two (a design map),
//! every point run in parallel. Axes come from the file's `[sweep]` or from the command line
//! ([`parse_axis`]: `clearance=0.5 Rr,1 Rr` or `mass_ratio=1..20:5`).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::metrics::{Headline, Metric, RunSummary};
use crate::model::{Limits, Model, ModelError, RunOptions};
use crate::scene::{self, Length, Loaded, Parameter, Scene, SceneError};

/// Where a point of a sweep lies (the first fields of `lpc sweep`'s JSON).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Coordinates {
    /// Parameter name.
    pub parameter: String,
    /// Its value as written in the file (metres or Rr multiples for lengths).
    pub value: f64,
    /// The second parameter of a grid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parameter_y: Option<String>,
    /// Its value.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value_y: Option<f64>,
}

impl Coordinates {
    /// The coordinates of a grid point with `values` on the axes `parameters`.
    pub fn of(parameters: &[String], values: &[f64]) -> Self {
        Coordinates {
            parameter: parameters[0].clone(),
            value: values[0],
            parameter_y: parameters.get(1).cloned(),
            value_y: values.get(1).copied(),
        }
    }
}

/// One value of a sweep (the JSON contract of `lpc sweep`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepPoint {
    /// Where.
    #[serde(flatten)]
    pub at: Coordinates,
    /// The run.
    pub summary: RunSummary,
}

/// One value of a sweep whose every point is an ensemble (`lpc sweep --ensemble`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EnsemblePoint {
    /// Where.
    #[serde(flatten)]
    pub at: Coordinates,
    /// Members.
    pub members: usize,
    /// Draws thrown away as invalid.
    pub redraws: u64,
    /// Each metric's distribution.
    pub metrics: std::collections::BTreeMap<String, crate::studies::ensemble::Stats>,
    /// The quantile the map and rankings read.
    pub quantile: f64,
    /// Each metric at that quantile.
    pub at_quantile: std::collections::BTreeMap<String, Option<f64>>,
}

/// One swept parameter and its values.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// The parameter.
    pub parameter: Parameter,
    /// Values (lengths may be Rr multiples).
    pub values: Vec<Length>,
}

/// The axes of the file's `[sweep]`: one, or two for a grid.
pub fn file_axes(loaded: &Loaded) -> Result<Vec<Axis>, SceneError> {
    let sweep = loaded.file.sweep.as_ref().ok_or_else(|| SceneError::Invalid {
        file: loaded.path.clone(),
        field: "sweep".into(),
        rule: "is missing: this command needs a scene file with a [sweep] table (or axes on the command line)".into(),
    })?;
    let parameter = |field: &str, name: &str| name.parse::<Parameter>().map_err(|rule| invalid(loaded, field, &rule));
    let mut axes = vec![Axis { parameter: parameter("sweep.parameter", &sweep.parameter)?, values: sweep.values.clone() }];
    match (&sweep.parameter_y, &sweep.values_y) {
        (Some(p), Some(v)) => axes.push(Axis { parameter: parameter("sweep.parameter_y", p)?, values: v.clone() }),
        (None, None) => {}
        (Some(_), None) => return Err(invalid(loaded, "sweep.values_y", "is missing: `parameter_y` needs its values")),
        (None, Some(_)) => return Err(invalid(loaded, "sweep.parameter_y", "is missing: `values_y` needs its parameter")),
    }
    Ok(axes)
}

fn invalid(loaded: &Loaded, field: &str, rule: &str) -> SceneError {
    SceneError::Invalid { file: loaded.path.clone(), field: field.into(), rule: rule.into() }
}

/// `x` rounded to 12 significant digits: evenly spaced values computed in binary read as
/// written (`0.65`, not `0.6499999999999999`).
pub fn tidy(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let scale = 10f64.powi(11 - x.abs().log10().floor() as i32);
    (x * scale).round() / scale
}

/// Parses `PARAM=V1,V2,...` or `PARAM=A..B:N` (N values evenly spaced; lengths may carry
/// `Rr`, as `0.5Rr..3Rr:6`).
pub fn parse_axis(text: &str) -> Result<Axis, String> {
    let (parameter, values) = text.split_once('=').ok_or_else(|| format!("`{text}`: write `PARAM=V1,V2,...` or `PARAM=A..B:N`"))?;
    let parameter: Parameter = parameter.trim().parse()?;
    let value = |s: &str| -> Result<Length, String> {
        let s = s.trim();
        match s.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(Length::Metres(x)),
            _ => Length::try_from_text(s).ok_or_else(|| format!("`{s}` is not a number or `<k> Rr`")),
        }
    };
    let values = if let Some((range, n)) = values.split_once(':') {
        let (a, b) = range.split_once("..").ok_or_else(|| format!("`{values}`: a range is `A..B:N`"))?;
        let n: usize = n.trim().parse().map_err(|_| format!("`{n}` is not a count"))?;
        if !(2..=1000).contains(&n) {
            return Err(format!("the count `{n}` must lie in 2..=1000"));
        }
        let (a, b) = (value(a)?, value(b)?);
        if std::mem::discriminant(&a) != std::mem::discriminant(&b) {
            return Err(format!("`{range}`: both ends must be in metres or both in Rr"));
        }
        (0..n)
            .map(|k| {
                let x = tidy(a.raw() + (b.raw() - a.raw()) * k as f64 / (n - 1) as f64);
                match a {
                    Length::Metres(_) => Length::Metres(x),
                    Length::Rr(_) => Length::Rr(x),
                }
            })
            .collect()
    } else {
        values.split(',').map(value).collect::<Result<Vec<_>, _>>()?
    };
    if values.is_empty() {
        return Err("no values".into());
    }
    Ok(Axis { parameter, values })
}

/// A point of a sweep: its coordinates and its validated scene.
#[derive(Debug, Clone)]
pub struct GridScene {
    /// Value on each axis, as written.
    pub values: Vec<f64>,
    /// The scene.
    pub scene: Scene,
    /// The file it was built from (what an ensemble about it varies).
    pub file: scene::SceneFile,
}

/// The scenes of a sweep over `axes` (the first varies fastest), each validated; an invalid
/// point is an error naming its axis and value.
pub fn grid_scenes(loaded: &Loaded, axes: &[Axis]) -> Result<Vec<GridScene>, SceneError> {
    let base = loaded.scene.as_ref().map(|s| s.name.clone()).unwrap_or_default();
    let mut points: Vec<(Vec<(usize, Length)>, scene::SceneFile)> = vec![(vec![], loaded.file.clone())];
    for (a, axis) in axes.iter().enumerate() {
        let mut next = Vec::new();
        for (coords, file) in &points {
            for (i, value) in axis.values.iter().enumerate() {
                let field = if a == 0 { format!("sweep.values[{i}]") } else { format!("sweep.values_y[{i}]") };
                let varied = axis.parameter.apply(file, *value).map_err(|rule| SceneError::Invalid {
                    file: loaded.path.clone(),
                    field: field.clone(),
                    rule,
                })?;
                let mut c = coords.clone();
                c.push((i, *value));
                next.push((c, varied));
            }
        }
        points = next;
    }
    // First axis fastest: order by the later axes' indices first.
    points.sort_by(|a, b| a.0.iter().rev().map(|c| c.0).cmp(b.0.iter().rev().map(|c| c.0)));
    points
        .into_iter()
        .map(|(coords, file)| {
            let label = axes.iter().zip(&coords).map(|(ax, (_, v))| format!("{}={}", ax.parameter, v.raw())).collect::<Vec<_>>().join(",");
            let mut s = scene::from_file(file.clone(), &loaded.path, &base)
                .map_err(|e| match e {
                    SceneError::Invalid { file, field, rule } => {
                        SceneError::Invalid { file, field: format!("sweep point {label} (as {field})"), rule }
                    }
                    other => other,
                })?
                .scene
                .expect("damper scene");
            s.name = format!("{base}[{label}]");
            Ok(GridScene { values: coords.iter().map(|(_, v)| v.raw()).collect(), scene: s, file })
        })
        .collect()
}

/// The scenes of the file's one-parameter sweep, one per value, each validated.
pub fn sweep_scenes(loaded: &Loaded) -> Result<Vec<(f64, Scene)>, SceneError> {
    let axes = file_axes(loaded)?;
    Ok(grid_scenes(loaded, &axes[..1])?.into_iter().map(|g| (g.values[0], g.scene)).collect())
}

/// Runs every scene with `model` in parallel, each within `limits`; `progress` is called after
/// each run.
pub fn run_sweep(
    parameter: &str,
    scenes: &[(f64, Scene)],
    model: Model,
    limits: Limits,
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<SweepPoint>, ModelError> {
    let axes = [parameter.to_string()];
    let grid: Vec<GridScene> =
        scenes.iter().map(|(v, s)| GridScene { values: vec![*v], scene: s.clone(), file: Default::default() }).collect();
    run_grid(&axes, &grid, model, limits, progress)
}

/// Runs every point of a grid with `model` in parallel, each within `limits`.
pub fn run_grid(
    parameters: &[String],
    grid: &[GridScene],
    model: Model,
    limits: Limits,
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<SweepPoint>, ModelError> {
    grid.par_iter()
        .map(|g| {
            let run = model.simulate(&g.scene, &RunOptions::limited(limits))?;
            progress();
            Ok(SweepPoint { at: Coordinates::of(parameters, &g.values), summary: RunSummary::of(&run) })
        })
        .collect()
}

/// The table of a sweep (`sweep.parquet`, the Python binding's columns): `cell` (its index,
/// the first axis varying fastest), each axis' value as written, then every metric
/// ([`Metric::ALL`]), one row per cell.
pub fn cells_table(parameters: &[String], cells: &[(usize, SweepPoint)]) -> (Vec<String>, Vec<Vec<Option<f64>>>) {
    let mut header = vec!["cell".to_string()];
    header.extend(parameters.iter().cloned());
    header.extend(Metric::ALL.iter().map(|m| m.name().to_string()));
    let rows = cells
        .iter()
        .map(|(cell, p)| {
            let mut row = vec![Some(*cell as f64), Some(p.at.value)];
            if parameters.len() > 1 {
                row.push(p.at.value_y);
            }
            row.extend(Headline::of_summary(&p.summary).values());
            row
        })
        .collect();
    (header, rows)
}

/// Columns of [`cells_table`] that hold integers.
pub const INTEGER_COLUMNS: &[&str] = &["cell", "impact_count"];
