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

use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1};
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::MutexExt;
use pyo3::types::PyDict;

use lpc_damper::files::write_atomic;
use lpc_damper::metrics::{Headline, Metric, RunSummary};
use lpc_damper::model::{Limits, ModelError as RustModelError, RunOptions};
use lpc_damper::output::parquet::{provenance, table_parquet, Constant, TOOL_VERSION};
use lpc_damper::scene::{self, Loaded, Overrides, SceneError as RustSceneError, SceneFile, Stepping};
use lpc_damper::studies::{chain as chains, ensemble as ensembles, frf as frfs, sweep as sweeps};
use lpc_damper::Model;

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

/// A scene file, validated: a damper scene (with its `[tolerances]` and `[sweep]`, if any) or
/// a chain experiment.
#[pyclass(module = "lpc_damper", frozen, from_py_object)]
#[derive(Clone)]
struct Scene {
    loaded: Loaded,
}

/// A Python value as TOML: what a scene file's reader sees, so that a dict goes through the
/// very deserializer and rules a file does (NaN and infinities included).
fn to_toml(value: &Bound<'_, PyAny>, at: &str) -> PyResult<toml::Value> {
    use pyo3::types::{PyBool, PyFloat, PyInt, PyList, PyString, PyTuple};
    let field = |s: &str| if at.is_empty() { s.to_string() } else { format!("{at}.{s}") };
    if let Ok(d) = value.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, v) in d.iter() {
            let key: String =
                k.extract().map_err(|_| SceneError::new_err(format!("<dict>: `{at}` has a key that is not a string: {k}")))?;
            let v = to_toml(&v, &field(&key))?;
            table.insert(key, v);
        }
        Ok(toml::Value::Table(table))
    } else if value.is_instance_of::<PyBool>() {
        Ok(toml::Value::Boolean(value.extract()?))
    } else if value.is_instance_of::<PyInt>() {
        Ok(toml::Value::Integer(value.extract().map_err(|_| SceneError::new_err(format!("<dict>: `{at}` is an integer beyond 64 bits")))?))
    } else if value.is_instance_of::<PyFloat>() {
        Ok(toml::Value::Float(value.extract()?))
    } else if value.is_instance_of::<PyString>() {
        Ok(toml::Value::String(value.extract()?))
    } else if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let items = value.try_iter()?.enumerate().map(|(i, v)| to_toml(&v?, &format!("{at}[{i}]"))).collect::<PyResult<_>>()?;
        Ok(toml::Value::Array(items))
    } else if let Ok(x) = value.extract::<f64>() {
        // NumPy scalars and other numbers.
        Ok(toml::Value::Float(x))
    } else {
        Err(SceneError::new_err(format!("<dict>: `{at}` is a {}, which a scene file cannot hold", value.get_type().name()?)))
    }
}

/// A TOML value as Python objects.
fn from_toml<'py>(py: Python<'py>, value: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        toml::Value::String(s) => s.into_pyobject(py)?.into_any(),
        toml::Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        toml::Value::Float(x) => x.into_pyobject(py)?.into_any(),
        toml::Value::Boolean(b) => b.into_pyobject(py)?.to_owned().into_any(),
        toml::Value::Datetime(d) => d.to_string().into_pyobject(py)?.into_any(),
        toml::Value::Array(items) => {
            let list = pyo3::types::PyList::empty(py);
            for v in items {
                list.append(from_toml(py, v)?)?;
            }
            list.into_any()
        }
        toml::Value::Table(t) => {
            let d = PyDict::new(py);
            for (k, v) in t {
                d.set_item(k, from_toml(py, v)?)?;
            }
            d.into_any()
        }
    })
}

impl Scene {
    /// The file as TOML text (what pickling carries).
    fn file_toml(&self) -> String {
        toml::to_string(&self.loaded.file).expect("a scene file serialises")
    }

    /// The damper scene with the settings given as keywords, validated by the file's rules.
    fn damper(&self, settings: &Settings) -> PyResult<scene::Scene> {
        let s = self.loaded.damper().map_err(scene_error)?.clone();
        settings.overrides()?.apply(s, &self.loaded.path).map_err(scene_error)
    }
}

#[pymethods]
impl Scene {
    /// Reads and validates a scene file (TOML).
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Scene> {
        Ok(Scene { loaded: scene::load(path).map_err(scene_error)? })
    }

    /// A scene from a dict with the file's tables and keys (as `to_dict` gives, and as
    /// `tomllib.load` reads a scene file), validated by the same rules; `[tolerances]` is its
    /// `"tolerances"` key.
    #[staticmethod]
    #[pyo3(signature = (d, name = None))]
    fn from_dict(d: &Bound<'_, PyAny>, name: Option<String>) -> PyResult<Scene> {
        let file = "<dict>";
        let value = to_toml(d, "")?;
        let parsed: SceneFile = value.try_into().map_err(|e: toml::de::Error| {
            scene_error(RustSceneError::Parse { file: file.into(), message: e.to_string().trim_end().to_string() })
        })?;
        let name = name.unwrap_or_else(|| "scene".into());
        Ok(Scene { loaded: scene::from_file(parsed, file, &name).map_err(scene_error)? })
    }

    /// The scene file as a dict (absent keys left out), as `tomllib` would read it.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let value = toml::Value::try_from(&self.loaded.file).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        from_toml(py, &value)
    }

    /// The scene's name (the file's `name`, else the file's stem).
    #[getter]
    fn name(&self) -> String {
        match (&self.loaded.scene, &self.loaded.chain) {
            (Some(s), _) => s.name.clone(),
            _ => self.loaded.file.name.clone().unwrap_or_else(|| self.loaded.path.clone()),
        }
    }

    /// The path it was read from (`<dict>` when built from a dict).
    #[getter]
    fn path(&self) -> String {
        self.loaded.path.clone()
    }

    /// Whether it is a chain experiment (`lpc_damper.chain`) rather than a damper scene.
    #[getter]
    fn is_chain(&self) -> bool {
        self.loaded.chain.is_some()
    }

    fn __repr__(&self) -> String {
        format!("Scene(name={:?}, path={:?})", self.name(), self.loaded.path)
    }

    /// Pickled as its file's TOML, rebuilt and validated on the other side (Dask workers).
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, String, String))> {
        let restore = py.import("lpc_damper")?.getattr("_restore_scene")?;
        Ok((restore, (self.file_toml(), self.loaded.path.clone(), self.name())))
    }

    /// The inverse of `__reduce__`.
    #[staticmethod]
    fn _restore(text: &str, path: &str, name: &str) -> PyResult<Scene> {
        Ok(Scene { loaded: scene::parse(text, path, name).map_err(scene_error)? })
    }
}

/// The settings a call may override, as the CLI's flags do (validated by the file's rules).
#[derive(Debug, Clone, Default)]
struct Settings {
    horizon: Option<f64>,
    sample_dt: Option<f64>,
    stepping: Option<String>,
    dt: Option<f64>,
    solver_iterations: Option<u32>,
    ccd: bool,
    tolerance: Option<f64>,
}

impl Settings {
    fn overrides(&self) -> PyResult<Overrides> {
        let stepping = match self.stepping.as_deref() {
            None => None,
            Some("aligned") => Some(Stepping::Aligned),
            Some("fixed") => Some(Stepping::Fixed),
            Some(other) => return Err(SceneError::new_err(format!("stepping: `{other}` is not `aligned` or `fixed`"))),
        };
        Ok(Overrides {
            horizon: self.horizon,
            sample_dt: self.sample_dt,
            stepping,
            dt: self.dt,
            solver_iterations: self.solver_iterations,
            ccd: self.ccd,
            tolerance: self.tolerance,
            ..Overrides::default()
        })
    }
}

/// One run: the sampled series as NumPy arrays (moved, not copied), the impacts as a dict of
/// arrays, and the summary's `metrics`, `energy` and `noise` as dicts with `summary.json`'s keys.
///
/// Each is made when first read and kept: a run that is asked only for its metrics never
/// builds the arrays, so the call itself costs the model's run and little more.
#[pyclass(module = "lpc_damper", frozen)]
struct Run {
    /// Scene name.
    #[pyo3(get)]
    scene: String,
    /// Model name.
    #[pyo3(get)]
    model: String,
    /// Simulated time covered, s.
    #[pyo3(get)]
    horizon: f64,
    /// Computing time of the model, s.
    #[pyo3(get)]
    wall_time_s: f64,
    /// How many impacts the run made: `len(impacts["t"])`, or more when it counted them
    /// without keeping them (`impacts = "count"`).
    #[pyo3(get)]
    impact_count: usize,
    /// The run, whose series move out as they are read.
    run: std::sync::Mutex<lpc_damper::run::Run>,
    /// Everything read so far, by name.
    made: std::sync::Mutex<std::collections::HashMap<&'static str, Py<PyAny>>>,
}

impl Run {
    /// `name`, made by `make` (from the run) on first reading and kept.
    fn cached(
        &self,
        py: Python<'_>,
        name: &'static str,
        make: impl FnOnce(Python<'_>, &mut lpc_damper::run::Run) -> PyResult<Py<PyAny>>,
    ) -> PyResult<Py<PyAny>> {
        // Locked without holding up the interpreter: another thread reading the same run waits
        // detached.
        if let Some(v) = self.made.lock_py_attached(py).expect("not poisoned").get(name) {
            return Ok(v.clone_ref(py));
        }
        let mut run = self.run.lock_py_attached(py).expect("not poisoned");
        if let Some(v) = self.made.lock_py_attached(py).expect("not poisoned").get(name) {
            return Ok(v.clone_ref(py)); // made meanwhile by another thread
        }
        let value = make(py, &mut run)?;
        self.made.lock_py_attached(py).expect("not poisoned").insert(name, value.clone_ref(py));
        Ok(value)
    }

    /// The run's summary as a dict (its `metrics`, `energy` and `noise` are read from it).
    fn summary(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "summary", |py, run| {
            let summary = RunSummary::of(run);
            let value = serde_json::json!({"metrics": summary.metrics, "energy": summary.energy, "noise": summary.noise});
            Ok(py.import("json")?.call_method1("loads", (value.to_string(),))?.unbind())
        })
    }

    /// The series as one NumPy array `(columns, capacity)`, moved out of the run on first
    /// reading: every series attribute is a view of it.
    fn table(&self, py: Python<'_>, run: &mut lpc_damper::run::Run) -> PyResult<(Py<PyAny>, usize, usize)> {
        {
            let made = self.made.lock_py_attached(py).expect("not poisoned");
            if let (Some(table), Some(shape)) = (made.get("table"), made.get("table_shape")) {
                let (columns, len): (usize, usize) = shape.extract(py)?;
                return Ok((table.clone_ref(py), columns, len));
            }
        }
        let balls = run.series.balls();
        let across = run.series.take_across();
        let (data, capacity, len, columns) = std::mem::take(&mut run.series).into_buffer();
        let array = Array2::from_shape_vec((columns, capacity), data).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        let table = array.into_pyarray(py).into_any().unbind();
        // The centres across the motion, `(samples, balls, 2)`; `None` for balls on lines.
        let across = if across.is_empty() || balls == 0 {
            py.None()
        } else {
            let samples = across.len() / (2 * balls);
            let array = Array3::from_shape_vec((samples, balls, 2), across).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
            array.into_pyarray(py).into_any().unbind()
        };
        let mut made = self.made.lock_py_attached(py).expect("not poisoned");
        made.insert("across", across);
        made.insert("table", table.clone_ref(py));
        made.insert("table_shape", (columns, len).into_pyobject(py)?.into_any().unbind());
        Ok((table, columns, len))
    }

    /// Row `first` of the series table, or with `balls = Some(k)` the `k`-th block of the balls'
    /// rows from `first` (0 their centres, 1 their velocities: a matrix), its used samples only;
    /// C-contiguous (a view when the series is full, as a finished run's is).
    fn columns(&self, py: Python<'_>, run: &mut lpc_damper::run::Run, first: usize, balls: Option<usize>) -> PyResult<Py<PyAny>> {
        use pyo3::types::PySlice;
        let (table, columns, len) = self.table(py, run)?;
        let samples = PySlice::new(py, 0, len as isize, 1);
        let view = match balls {
            None => table.bind(py).get_item((first, samples))?,
            Some(block) => {
                let n = (columns - first) / 2;
                let rows = PySlice::new(py, (first + block * n) as isize, (first + (block + 1) * n) as isize, 1);
                table.bind(py).get_item((rows, samples))?
            }
        };
        Ok(py.import("numpy")?.call_method1("ascontiguousarray", (view,))?.unbind())
    }

    /// Coordinate `k` (0 for `y`, 1 for `z`) of the balls' centres across the motion,
    /// `(balls, samples)`, C-contiguous; `None` when the balls stay on lines.
    fn across(&self, py: Python<'_>, run: &mut lpc_damper::run::Run, k: usize) -> PyResult<Py<PyAny>> {
        self.table(py, run)?;
        let across = self.made.lock_py_attached(py).expect("not poisoned").get("across").map(|a| a.clone_ref(py));
        let Some(across) = across.filter(|a| !a.is_none(py)) else { return Ok(py.None()) };
        use pyo3::types::PySlice;
        let all = PySlice::full(py);
        let view = across.bind(py).get_item((all.clone(), all, k))?.getattr("T")?;
        Ok(py.import("numpy")?.call_method1("ascontiguousarray", (view,))?.unbind())
    }

    fn part(&self, py: Python<'_>, key: &str) -> PyResult<Py<PyAny>> {
        Ok(self.summary(py)?.bind(py).get_item(key)?.unbind())
    }
}

#[pymethods]
impl Run {
    /// Sample times, s.
    #[getter]
    fn t(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "t", |py, r| self.columns(py, r, 0, None))
    }
    /// Frame displacement, m.
    #[getter]
    fn xs(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "xs", |py, r| self.columns(py, r, 1, None))
    }
    /// Frame velocity, m/s.
    #[getter]
    fn vs(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "vs", |py, r| self.columns(py, r, 2, None))
    }
    /// Frame acceleration without impulses and contact forces, m/s^2.
    #[getter]
    fn a(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "a", |py, r| self.columns(py, r, 3, None))
    }
    /// Ball centres, `(balls, samples)`, m.
    #[getter]
    fn x(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "x", |py, r| self.columns(py, r, 4, Some(0)))
    }
    /// Ball velocities, `(balls, samples)`, m/s.
    #[getter]
    fn v(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "v", |py, r| self.columns(py, r, 4, Some(1)))
    }
    /// Ball centres across the motion, `y` (the container's axis at 0), `(balls, samples)`, m;
    /// `None` when the balls stay on lines.
    #[getter]
    fn y(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "y", |py, r| self.across(py, r, 0))
    }
    /// Ball centres across the motion, `z` (the container's axis at 0), `(balls, samples)`, m;
    /// `None` when the balls stay on lines.
    #[getter]
    fn z(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "z", |py, r| self.across(py, r, 1))
    }
    /// Impacts: `t`, `body_a`, `body_b`, `approach_speed`, `energy_lost`, `peak_force`,
    /// `contact_duration` (NaN for impulse models).
    #[getter]
    fn impacts(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "impacts", |py, run| {
            let impacts = PyDict::new(py);
            let column = |f: &dyn Fn(&lpc_damper::run::Impact) -> f64| floats(py, run.impacts.iter().map(f).collect());
            impacts.set_item("t", column(&|i| i.t))?;
            let names = |left: bool| -> Vec<String> { run.impacts.iter().map(|i| if left { i.a } else { i.b }.name()).collect() };
            let numpy = py.import("numpy")?;
            impacts.set_item("body_a", numpy.call_method1("asarray", (names(true),))?)?;
            impacts.set_item("body_b", numpy.call_method1("asarray", (names(false),))?)?;
            impacts.set_item("approach_speed", column(&|i| i.approach_speed))?;
            impacts.set_item("energy_lost", column(&|i| i.energy_lost))?;
            impacts.set_item("peak_force", column(&|i| i.peak_force.unwrap_or(f64::NAN)))?;
            impacts.set_item("contact_duration", column(&|i| i.contact_duration.unwrap_or(f64::NAN)))?;
            Ok(impacts.into_any().unbind())
        })
    }
    /// The summary's metrics.
    #[getter]
    fn metrics(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.part(py, "metrics")
    }
    /// The energy account.
    #[getter]
    fn energy(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.part(py, "energy")
    }
    /// The noise proxy.
    #[getter]
    fn noise(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.part(py, "noise")
    }

    fn __repr__(&self) -> String {
        format!("Run(scene={:?}, model={:?}, horizon={}, wall_time_s={:.3e})", self.scene, self.model, self.horizon, self.wall_time_s)
    }
}

fn floats(py: Python<'_>, values: Vec<f64>) -> Py<PyAny> {
    values.into_pyarray(py).into_any().unbind()
}

impl Run {
    fn of(run: lpc_damper::run::Run) -> Run {
        Run {
            scene: run.scene.clone(),
            model: run.model.name().into(),
            horizon: run.horizon,
            wall_time_s: run.wall_time_s,
            impact_count: run.impact_count(),
            run: std::sync::Mutex::new(run),
            made: Default::default(),
        }
    }
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
        Ok(run) => Ok(Run::of(run)),
        Err(RustModelError::OverBudget(stop)) => {
            let err = ModelError::new_err(stop.to_string());
            err.value(py).setattr("partial", Py::new(py, Run::of(stop.partial))?)?;
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
