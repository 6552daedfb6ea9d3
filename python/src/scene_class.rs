//! The `Scene` class (a validated scene file, to and from a dict through the file's own rules)
//! and the settings a call may override.

use std::path::PathBuf;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use lpc_damper::scene::{self, Loaded, Overrides, SceneError as RustSceneError, SceneFile, Stepping};

use crate::{scene_error, SceneError};

/// A scene file, validated: a damper scene (with its `[tolerances]` and `[sweep]`, if any) or
/// a chain experiment.
#[pyclass(module = "lpc_damper", frozen, from_py_object)]
#[derive(Clone)]
pub(crate) struct Scene {
    pub(crate) loaded: Loaded,
}

/// A Python value as TOML: what a scene file's reader sees, so that a dict goes through the
/// very deserializer and rules a file does (NaN and infinities included).
pub(crate) fn to_toml(value: &Bound<'_, PyAny>, at: &str) -> PyResult<toml::Value> {
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
pub(crate) fn from_toml<'py>(py: Python<'py>, value: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
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
    pub(crate) fn file_toml(&self) -> String {
        toml::to_string(&self.loaded.file).expect("a scene file serialises")
    }

    /// The damper scene with the settings given as keywords, validated by the file's rules.
    pub(crate) fn damper(&self, settings: &Settings) -> PyResult<scene::Scene> {
        let s = self.loaded.damper().map_err(scene_error)?.clone();
        settings.overrides()?.apply(s, &self.loaded.path).map_err(scene_error)
    }
}

#[pymethods]
impl Scene {
    /// Reads and validates a scene file (TOML).
    #[staticmethod]
    pub(crate) fn load(path: PathBuf) -> PyResult<Scene> {
        Ok(Scene { loaded: scene::load(path).map_err(scene_error)? })
    }

    /// A scene from a dict with the file's tables and keys (as `to_dict` gives, and as
    /// `tomllib.load` reads a scene file), validated by the same rules; `[tolerances]` is its
    /// `"tolerances"` key.
    #[staticmethod]
    #[pyo3(signature = (d, name = None))]
    pub(crate) fn from_dict(d: &Bound<'_, PyAny>, name: Option<String>) -> PyResult<Scene> {
        let file = "<dict>";
        let value = to_toml(d, "")?;
        let parsed: SceneFile = value.try_into().map_err(|e: toml::de::Error| {
            scene_error(RustSceneError::Parse { file: file.into(), message: e.to_string().trim_end().to_string() })
        })?;
        let name = name.unwrap_or_else(|| "scene".into());
        Ok(Scene { loaded: scene::from_file(parsed, file, &name).map_err(scene_error)? })
    }

    /// The scene file as a dict (absent keys left out), as `tomllib` would read it.
    pub(crate) fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let value = toml::Value::try_from(&self.loaded.file).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        from_toml(py, &value)
    }

    /// The scene's name (the file's `name`, else the file's stem).
    #[getter]
    pub(crate) fn name(&self) -> String {
        match (&self.loaded.scene, &self.loaded.chain) {
            (Some(s), _) => s.name.clone(),
            _ => self.loaded.file.name.clone().unwrap_or_else(|| self.loaded.path.clone()),
        }
    }

    /// The path it was read from (`<dict>` when built from a dict).
    #[getter]
    pub(crate) fn path(&self) -> String {
        self.loaded.path.clone()
    }

    /// Whether it is a chain experiment (`lpc_damper.chain`) rather than a damper scene.
    #[getter]
    pub(crate) fn is_chain(&self) -> bool {
        self.loaded.chain.is_some()
    }

    pub(crate) fn __repr__(&self) -> String {
        format!("Scene(name={:?}, path={:?})", self.name(), self.loaded.path)
    }

    /// Pickled as its file's TOML, rebuilt and validated on the other side (Dask workers).
    pub(crate) fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, String, String))> {
        let restore = py.import("lpc_damper")?.getattr("_restore_scene")?;
        Ok((restore, (self.file_toml(), self.loaded.path.clone(), self.name())))
    }

    /// The inverse of `__reduce__`.
    #[staticmethod]
    pub(crate) fn _restore(text: &str, path: &str, name: &str) -> PyResult<Scene> {
        Ok(Scene { loaded: scene::parse(text, path, name).map_err(scene_error)? })
    }
}

/// The settings a call may override, as the CLI's flags do (validated by the file's rules).
#[derive(Debug, Clone, Default)]
pub(crate) struct Settings {
    pub(crate) horizon: Option<f64>,
    pub(crate) sample_dt: Option<f64>,
    pub(crate) stepping: Option<String>,
    pub(crate) dt: Option<f64>,
    pub(crate) solver_iterations: Option<u32>,
    pub(crate) ccd: bool,
    pub(crate) tolerance: Option<f64>,
}

impl Settings {
    pub(crate) fn overrides(&self) -> PyResult<Overrides> {
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
