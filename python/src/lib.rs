//! The Python binding of lpc-damper: the extension module `lpc_damper._lpc_damper`, which the
//! `lpc_damper` package re-exports (python/lpc_damper/__init__.py, stubs in `_lpc_damper.pyi`).
//!
//! Scenes, the three models and the studies, with NumPy arrays: series are moved into NumPy
//! without a copy (`into_pyarray`); a study returns a dict of columns, one row per member or
//! cell, so `pandas.DataFrame(result)` works. Every call that computes releases the GIL
//! (`py.detach`), so Python threads and Dask's threaded workers run beside it; batches run on
//! rayon inside the call, and stop at Ctrl-C between batches of members or cells. Nothing here
//! is physics: every rule lives in the library, and errors carry the CLI's messages.

use std::path::PathBuf;

use numpy::{IntoPyArray, PyArray1};
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use lpc_damper::files::write_atomic;
use lpc_damper::metrics::{Headline, Metric};
use lpc_damper::model::{Limits, ModelError as RustModelError, RunOptions};
use lpc_damper::output::parquet::{provenance, table_parquet, Constant, TOOL_VERSION};
use lpc_damper::scene::{Overrides, SceneError as RustSceneError};
use lpc_damper::studies::{chain as chains, ensemble as ensembles, frf as frfs, sweep as sweeps};
use lpc_damper::Model;

mod run_class;
mod scene_class;

use run_class::{floats, Run};
use scene_class::{Scene, Settings};

create_exception!(
    _lpc_damper,
    SceneError,
    PyValueError,
    "A scene (or a setting) that cannot exist; the message names the field and the rule, as the CLI's does."
);
create_exception!(
    _lpc_damper,
    ModelError,
    PyRuntimeError,
    "A model that could not finish a scene (a stall, a refusal, an instability), with the reason."
);

fn scene_error(e: RustSceneError) -> PyErr {
    SceneError::new_err(e.to_string())
}

fn model_error(e: RustModelError) -> PyErr {
    ModelError::new_err(e.to_string())
}

fn parse_model(model: &str) -> PyResult<Model> {
    model.parse::<Model>().map_err(|e| SceneError::new_err(format!("model: {e}")))
}

/// Members or cells computed between two looks for Ctrl-C: a few per thread, so that the
/// threads stay busy and an interrupt is seen within a few runs' time.
fn batch_size() -> usize {
    4 * rayon::current_num_threads().max(1)
}

/// The budgets of every run a function makes, checked by their rules (`max_steps`,
/// `max_wall_time`, as the CLI's `--max-steps` and `--max-wall-time`).
fn limits(max_steps: Option<u64>, max_wall_time: Option<f64>) -> PyResult<Limits> {
    let limits = Limits { max_steps, max_wall_s: max_wall_time };
    limits.check().map_err(|(budget, rule)| SceneError::new_err(format!("{}: {rule}", budget.keyword().unwrap_or_default())))?;
    Ok(limits)
}

/// Runs one model on a damper scene. Every model takes budgets, as the CLI's `--max-steps`
/// and `--max-wall-time`: a run that exceeds one raises `ModelError` whose `partial` attribute
/// is the run so far. `impacts = "count"` (the CLI's `--impacts count`) counts the impacts
/// without keeping them, for runs whose impacts outgrow memory.
#[pyfunction]
#[pyo3(signature = (scene, model = "reference", *, horizon = None, sample_dt = None, stepping = None, dt = None, solver_iterations = None, ccd = false, tolerance = None, max_steps = None, max_wall_time = None, impacts = "every"))]
#[allow(clippy::too_many_arguments)]
fn run(
    py: Python<'_>,
    scene: &Scene,
    model: &str,
    horizon: Option<f64>,
    sample_dt: Option<f64>,
    stepping: Option<String>,
    dt: Option<f64>,
    solver_iterations: Option<u32>,
    ccd: bool,
    tolerance: Option<f64>,
    max_steps: Option<u64>,
    max_wall_time: Option<f64>,
    impacts: &str,
) -> PyResult<Run> {
    let model = parse_model(model)?;
    let s = scene.damper(&Settings { horizon, sample_dt, stepping, dt, solver_iterations, ccd, tolerance })?;
    let impacts = impacts.parse().map_err(|e| SceneError::new_err(format!("impacts: {e}")))?;
    let options = RunOptions { impacts, ..RunOptions::limited(limits(max_steps, max_wall_time)?) };
    match py.detach(|| model.simulate(&s, &options)) {
        Ok(run) => Ok(Run::of(&s, run)),
        Err(RustModelError::OverBudget(stop)) => {
            let err = ModelError::new_err(stop.to_string());
            err.value(py).setattr("partial", Py::new(py, Run::of(&s, stop.partial))?)?;
            Err(err)
        }
        Err(e) => Err(model_error(e)),
    }
}

/// A table as a dict of NumPy columns: integers for `integers`, else doubles (NaN undefined).
fn columns<'py>(py: Python<'py>, header: &[String], rows: &[Vec<Option<f64>>], integers: &[&str]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (c, name) in header.iter().enumerate() {
        let values = rows.iter().map(|r| r[c]);
        if integers.contains(&name.as_str()) {
            let ints: Vec<i64> = values.map(|x| x.map_or(-1, |x| x as i64)).collect();
            d.set_item(name, ints.into_pyarray(py))?;
        } else {
            let xs: Vec<f64> = values.map(|x| x.unwrap_or(f64::NAN)).collect();
            d.set_item(name, PyArray1::from_vec(py, xs))?;
        }
    }
    Ok(d)
}

/// Runs `work` over `0..n` in batches on rayon without the GIL, looking for Ctrl-C between
/// batches.
fn batched<T: Send>(
    py: Python<'_>,
    n: usize,
    work: impl Fn(std::ops::Range<usize>) -> Result<Vec<T>, PyErr> + Send + Sync,
) -> PyResult<Vec<T>> {
    let mut out = Vec::with_capacity(n);
    let mut at = 0;
    while at < n {
        let end = (at + batch_size()).min(n);
        let part = py.detach(|| work(at..end))?;
        out.extend(part);
        py.check_signals()?;
        at = end;
    }
    Ok(out)
}

/// Writes `table` as Parquet into `dir` under `name`.
fn write_part(
    dir: &PathBuf,
    name: &str,
    header: &[String],
    rows: &[Vec<Option<f64>>],
    integers: &[&str],
    constants: &[(&str, Constant)],
) -> PyResult<()> {
    let bytes = table_parquet(header, rows, integers, constants).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    std::fs::create_dir_all(dir)
        .and_then(|_| write_atomic(&dir.join(name), &bytes))
        .map_err(|e| PyRuntimeError::new_err(format!("writing {}: {e}", dir.display())))
}

/// Members `start..stop` (default all) of an ensemble of `members` drawn under the scene's
/// `[tolerances]`: a dict of columns `member`, the drawn values, then every metric.
#[pyfunction]
#[pyo3(signature = (scene, members, *, seed = None, model = "reference", start = 0, stop = None, out = None, horizon = None, sample_dt = None, stepping = None, dt = None, solver_iterations = None, ccd = false, tolerance = None, max_steps = None, max_wall_time = None))]
#[allow(clippy::too_many_arguments)]
fn ensemble<'py>(
    py: Python<'py>,
    scene: &Scene,
    members: usize,
    seed: Option<u64>,
    model: &str,
    start: usize,
    stop: Option<usize>,
    out: Option<PathBuf>,
    horizon: Option<f64>,
    sample_dt: Option<f64>,
    stepping: Option<String>,
    dt: Option<f64>,
    solver_iterations: Option<u32>,
    ccd: bool,
    tolerance: Option<f64>,
    max_steps: Option<u64>,
    max_wall_time: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let model = parse_model(model)?;
    let limits = limits(max_steps, max_wall_time)?;
    let nominal = scene.damper(&Settings { horizon, sample_dt, stepping, dt, solver_iterations, ccd, tolerance })?;
    let l = &scene.loaded;
    let stop = stop.unwrap_or(members);
    let drawn = py
        .detach(|| ensembles::draw_range(&l.file, &l.path, &nominal, l.tolerances.as_ref(), members, start..stop, seed))
        .map_err(scene_error)?;
    let all = &drawn.members;
    let metrics = batched(py, all.len(), |range| {
        ensembles::map_members(
            &all[range],
            |m| model.simulate(&m.scene, &RunOptions { limits, ..RunOptions::metrics_only() }).map(|r| Headline::of_run(&r).values()),
            &|| {},
        )
        .map_err(model_error)
    })?;
    let (header, rows) = ensembles::members_table(&drawn.columns, all, &metrics);
    if let Some(dir) = &out {
        let constants = provenance(model, Some(drawn.seed));
        write_part(dir, &format!("part-{start:09}-{stop:09}.parquet"), &header, &rows, ensembles::INTEGER_COLUMNS, &constants)?;
    }
    columns(py, &header, &rows, ensembles::INTEGER_COLUMNS)
}

/// The grid of a sweep: the file's `[sweep]`, or `axes` in the CLI's syntax
/// (`"clearance=0.5 Rr,1 Rr"`, `"mass_ratio=1..20:5"`; two axes make a design map).
fn grid(scene: &Scene, axes: Option<Vec<String>>, settings: &Settings) -> PyResult<(Vec<String>, Vec<sweeps::GridScene>)> {
    let l = &scene.loaded;
    let axes = match axes {
        None => sweeps::file_axes(l).map_err(scene_error)?,
        Some(a) if a.is_empty() || a.len() > 2 => return Err(SceneError::new_err("axes: give one or two axes")),
        Some(a) => {
            a.iter().map(|x| sweeps::parse_axis(x).map_err(|rule| SceneError::new_err(format!("axes: {rule}")))).collect::<PyResult<_>>()?
        }
    };
    l.damper().map_err(scene_error)?;
    let mut grid = sweeps::grid_scenes(l, &axes).map_err(scene_error)?;
    let overrides = settings.overrides()?;
    for g in &mut grid {
        g.scene = overrides.apply(g.scene.clone(), &l.path).map_err(scene_error)?;
    }
    Ok((axes.iter().map(|a| a.parameter.to_string()).collect(), grid))
}

/// The number of cells of a sweep (see `sweep`).
#[pyfunction]
#[pyo3(signature = (scene, axes = None))]
fn sweep_cells(scene: &Scene, axes: Option<Vec<String>>) -> PyResult<usize> {
    Ok(grid(scene, axes, &Settings::default())?.1.len())
}

/// Cells `start..stop` (default all) of a sweep: a dict of columns `cell`, each axis' value
/// as written, then every metric.
#[pyfunction]
#[pyo3(signature = (scene, axes = None, *, model = "reference", start = 0, stop = None, out = None, horizon = None, stepping = None, dt = None, solver_iterations = None, ccd = false, tolerance = None, max_steps = None, max_wall_time = None))]
#[allow(clippy::too_many_arguments)]
fn sweep<'py>(
    py: Python<'py>,
    scene: &Scene,
    axes: Option<Vec<String>>,
    model: &str,
    start: usize,
    stop: Option<usize>,
    out: Option<PathBuf>,
    horizon: Option<f64>,
    stepping: Option<String>,
    dt: Option<f64>,
    solver_iterations: Option<u32>,
    ccd: bool,
    tolerance: Option<f64>,
    max_steps: Option<u64>,
    max_wall_time: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let model = parse_model(model)?;
    let limits = limits(max_steps, max_wall_time)?;
    let (parameters, grid) =
        grid(scene, axes, &Settings { horizon, stepping, dt, solver_iterations, ccd, tolerance, ..Settings::default() })?;
    let stop = stop.unwrap_or(grid.len()).min(grid.len());
    if start >= stop {
        return Err(SceneError::new_err(format!("start: cells {start}..{stop} are not a part of 0..{}", grid.len())));
    }
    let cells = &grid[start..stop];
    let points = batched(py, cells.len(), |range| {
        let offset = range.start;
        sweeps::run_grid(&parameters, &cells[range], model, limits, &|| {})
            .map(|p| p.into_iter().enumerate().map(|(i, p)| (start + offset + i, p)).collect::<Vec<_>>())
            .map_err(model_error)
    })?;
    let (header, rows) = sweeps::cells_table(&parameters, &points);
    if let Some(dir) = &out {
        let constants = provenance(model, None);
        write_part(dir, &format!("part-{start:09}-{stop:09}.parquet"), &header, &rows, sweeps::INTEGER_COLUMNS, &constants)?;
    }
    columns(py, &header, &rows, sweeps::INTEGER_COLUMNS)
}

/// The frequency response: per forcing frequency (Hz), the steady amplitude of `xs` with the
/// damper and of the bare frame (m; NaN where a run failed), whether each reached a steady
/// state, the horizon used and the impacts per period.
#[pyfunction]
#[pyo3(signature = (scene, frequencies, *, model = "reference", max_steps = None, max_wall_time = None))]
fn frf<'py>(
    py: Python<'py>,
    scene: &Scene,
    frequencies: Vec<f64>,
    model: &str,
    max_steps: Option<u64>,
    max_wall_time: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let model = parse_model(model)?;
    let limits = limits(max_steps, max_wall_time)?;
    let s = scene.damper(&Settings::default())?;
    let path = &scene.loaded.path;
    if s.forcing.is_none() {
        return Err(SceneError::new_err(format!("{path}: `forcing` is missing: a frequency response needs a forced scene")));
    }
    // Each frequency by the scene file's own rules for `forcing.frequency`.
    for (i, &f) in frequencies.iter().enumerate() {
        Overrides { forcing_frequency: Some(f), ..Overrides::default() }.apply(s.clone(), path).map_err(|e| match e {
            RustSceneError::Invalid { rule, .. } => SceneError::new_err(format!("{path}: `frequencies[{i}]` {rule}")),
            other => scene_error(other),
        })?;
    }
    let points = batched(py, frequencies.len(), |range| Ok(frfs::frf(&s, &frequencies[range], model, limits, &|| {})))?;
    let d = PyDict::new(py);
    let col = |f: &dyn Fn(&frfs::FrfPoint) -> f64| floats(py, points.iter().map(f).collect());
    d.set_item("frequency", col(&|p| p.frequency))?;
    d.set_item("amplitude", col(&|p| p.amplitude.unwrap_or(f64::NAN)))?;
    d.set_item("amplitude_no_damper", col(&|p| p.amplitude_no_damper.unwrap_or(f64::NAN)))?;
    let numpy = py.import("numpy")?;
    d.set_item("steady", numpy.call_method1("asarray", (points.iter().map(|p| p.steady).collect::<Vec<_>>(),))?)?;
    d.set_item("steady_no_damper", numpy.call_method1("asarray", (points.iter().map(|p| p.steady_no_damper).collect::<Vec<_>>(),))?)?;
    d.set_item("horizon", col(&|p| p.horizon))?;
    d.set_item("impacts_per_period", col(&|p| p.impacts_per_period.unwrap_or(f64::NAN)))?;
    Ok(d)
}

/// The KER experiment of a chain scene: per chain, `large` (N_L), `small` and `ker`.
#[pyfunction]
#[pyo3(signature = (scene, *, model = "reference", max_steps = None, max_wall_time = None))]
fn chain<'py>(
    py: Python<'py>,
    scene: &Scene,
    model: &str,
    max_steps: Option<u64>,
    max_wall_time: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let model = parse_model(model)?;
    let limits = limits(max_steps, max_wall_time)?;
    let cases =
        scene.loaded.chain.as_ref().ok_or_else(|| {
            SceneError::new_err(format!("{}: `chain` is missing: the KER experiment needs a chain scene", scene.loaded.path))
        })?;
    let rows = py.detach(|| chains::run_chain(cases, model, limits, &|| {})).map_err(model_error)?;
    let d = PyDict::new(py);
    d.set_item("large", rows.iter().map(|r| r.large as i64).collect::<Vec<_>>().into_pyarray(py))?;
    d.set_item("small", rows.iter().map(|r| r.small as i64).collect::<Vec<_>>().into_pyarray(py))?;
    d.set_item("ker", floats(py, rows.iter().map(|r| r.ker).collect()))?;
    Ok(d)
}

/// Reads and validates a scene file (TOML): `Scene.load`.
#[pyfunction]
fn load_scene(path: PathBuf) -> PyResult<Scene> {
    Scene::load(path)
}

#[pymodule]
fn _lpc_damper(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("ModelError", py.get_type::<ModelError>())?;
    m.add("__version__", TOOL_VERSION)?;
    m.add("MODELS", Model::ALL.iter().map(|m| m.name()).collect::<Vec<_>>())?;
    m.add("METRICS", Metric::ALL.iter().map(|m| m.name()).collect::<Vec<_>>())?;
    m.add_class::<Scene>()?;
    m.add_class::<Run>()?;
    m.add_function(wrap_pyfunction!(load_scene, m)?)?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble, m)?)?;
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_cells, m)?)?;
    m.add_function(wrap_pyfunction!(frf, m)?)?;
    m.add_function(wrap_pyfunction!(chain, m)?)?;
    Ok(())
}
