//! The `Run` class: one run's series as NumPy arrays, made when first read, and its summary.

use numpy::ndarray::{Array2, Array3};
use numpy::IntoPyArray;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::sync::MutexExt;
use pyo3::types::PyDict;

use lpc_damper::metrics::{DamperSummary, RunSummary};

/// One run: the sampled series as NumPy arrays (moved, not copied), the impacts as a dict of
/// arrays, and the summary's `metrics`, `energy` and `noise` as dicts with `summary.json`'s keys.
///
/// Each is made when first read and kept: a run that is asked only for its metrics never
/// builds the arrays, so the call itself costs the model's run and little more.
#[pyclass(module = "lpc_damper", frozen)]
pub(crate) struct Run {
    /// Scene name.
    #[pyo3(get)]
    pub(crate) scene: String,
    /// Model name.
    #[pyo3(get)]
    pub(crate) model: String,
    /// Simulated time covered, s.
    #[pyo3(get)]
    pub(crate) horizon: f64,
    /// Computing time of the model, s.
    #[pyo3(get)]
    pub(crate) wall_time_s: f64,
    /// How many impacts the run made: `len(impacts["t"])`, or more when it counted them
    /// without keeping them (`impacts = "count"`).
    #[pyo3(get)]
    pub(crate) impact_count: usize,
    /// Each damper's figures, when the scene has several (`summary.json`'s `dampers`).
    pub(crate) damper_figures: Vec<DamperSummary>,
    /// The run, whose series move out as they are read.
    pub(crate) run: std::sync::Mutex<lpc_damper::run::Run>,
    /// Everything read so far, by name.
    pub(crate) made: std::sync::Mutex<std::collections::HashMap<&'static str, Py<PyAny>>>,
}

impl Run {
    /// `name`, made by `make` (from the run) on first reading and kept.
    pub(crate) fn cached(
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
    pub(crate) fn summary(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "summary", |py, run| {
            let summary = RunSummary::of(run);
            let value = serde_json::json!({"metrics": summary.metrics, "energy": summary.energy, "noise": summary.noise});
            Ok(py.import("json")?.call_method1("loads", (value.to_string(),))?.unbind())
        })
    }

    /// The series as one NumPy array `(columns, capacity)`, moved out of the run on first
    /// reading: every series attribute is a view of it.
    pub(crate) fn table(&self, py: Python<'_>, run: &mut lpc_damper::run::Run) -> PyResult<(Py<PyAny>, usize, usize)> {
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
    pub(crate) fn columns(
        &self,
        py: Python<'_>,
        run: &mut lpc_damper::run::Run,
        first: usize,
        balls: Option<usize>,
    ) -> PyResult<Py<PyAny>> {
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
    pub(crate) fn across(&self, py: Python<'_>, run: &mut lpc_damper::run::Run, k: usize) -> PyResult<Py<PyAny>> {
        self.table(py, run)?;
        let across = self.made.lock_py_attached(py).expect("not poisoned").get("across").map(|a| a.clone_ref(py));
        let Some(across) = across.filter(|a| !a.is_none(py)) else { return Ok(py.None()) };
        use pyo3::types::PySlice;
        let all = PySlice::full(py);
        let view = across.bind(py).get_item((all.clone(), all, k))?.getattr("T")?;
        Ok(py.import("numpy")?.call_method1("ascontiguousarray", (view,))?.unbind())
    }

    pub(crate) fn part(&self, py: Python<'_>, key: &str) -> PyResult<Py<PyAny>> {
        Ok(self.summary(py)?.bind(py).get_item(key)?.unbind())
    }
}

#[pymethods]
impl Run {
    /// Sample times, s.
    #[getter]
    pub(crate) fn t(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "t", |py, r| self.columns(py, r, 0, None))
    }
    /// Frame displacement, m.
    #[getter]
    pub(crate) fn xs(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "xs", |py, r| self.columns(py, r, 1, None))
    }
    /// Frame velocity, m/s.
    #[getter]
    pub(crate) fn vs(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "vs", |py, r| self.columns(py, r, 2, None))
    }
    /// Frame acceleration without impulses and contact forces, m/s^2.
    #[getter]
    pub(crate) fn a(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "a", |py, r| self.columns(py, r, 3, None))
    }
    /// Ball centres, `(balls, samples)`, m.
    #[getter]
    pub(crate) fn x(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "x", |py, r| self.columns(py, r, 4, Some(0)))
    }
    /// Ball velocities, `(balls, samples)`, m/s.
    #[getter]
    pub(crate) fn v(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "v", |py, r| self.columns(py, r, 4, Some(1)))
    }
    /// Ball centres across the motion, `y` (the container's axis at 0), `(balls, samples)`, m;
    /// `None` when the balls stay on lines.
    #[getter]
    pub(crate) fn y(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "y", |py, r| self.across(py, r, 0))
    }
    /// Ball centres across the motion, `z` (the container's axis at 0), `(balls, samples)`, m;
    /// `None` when the balls stay on lines.
    #[getter]
    pub(crate) fn z(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.cached(py, "z", |py, r| self.across(py, r, 1))
    }
    /// Impacts: `t`, `body_a`, `body_b`, `approach_speed`, `energy_lost`, `peak_force`,
    /// `contact_duration` (NaN for impulse models).
    #[getter]
    pub(crate) fn impacts(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
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
    pub(crate) fn metrics(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.part(py, "metrics")
    }
    /// The energy account.
    #[getter]
    pub(crate) fn energy(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.part(py, "energy")
    }
    /// The noise proxy.
    #[getter]
    pub(crate) fn noise(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        self.part(py, "noise")
    }
    /// Each damper's floor, balls, impacts, wall impacts and impact loss, as dicts with
    /// `summary.json`'s keys; empty for a scene of one damper.
    #[getter]
    pub(crate) fn dampers(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let value = serde_json::to_string(&self.damper_figures).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        Ok(py.import("json")?.call_method1("loads", (value,))?.unbind())
    }

    pub(crate) fn __repr__(&self) -> String {
        format!("Run(scene={:?}, model={:?}, horizon={}, wall_time_s={:.3e})", self.scene, self.model, self.horizon, self.wall_time_s)
    }
}

pub(crate) fn floats(py: Python<'_>, values: Vec<f64>) -> Py<PyAny> {
    values.into_pyarray(py).into_any().unbind()
}

impl Run {
    /// The run of `scene`.
    pub(crate) fn of(scene: &lpc_damper::scene::Scene, run: lpc_damper::run::Run) -> Run {
        Run {
            damper_figures: DamperSummary::of(scene, &run),
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
