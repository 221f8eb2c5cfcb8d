//! The Python methods of `bisph.Case`: reading TOML or a dict, `--set`, building.

use super::Case;
use crate::errors::{bad_argument, case_error};
use crate::sim::{build, Simulation};
use bisph_io::case::{load_case, parse_case};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use std::path::PathBuf;

#[pymethods]
impl Case {
    /// Reads a case file (TOML). Paths inside it (meshes, particle files) are relative to
    /// the file's folder, as for `bisph run`.
    #[staticmethod]
    fn from_toml(path: PathBuf) -> PyResult<Case> {
        let loaded = load_case(Some(&path), &[]).map_err(|e| case_error(&e))?;
        Ok(Case { loaded })
    }

    /// A case from a dict shaped like the TOML file (nested dicts for sections, lists of
    /// dicts for `fluid_block`, `wall`, `probe`...). Relative paths inside it are relative to
    /// the current folder. `source` names it in error messages.
    #[staticmethod]
    #[pyo3(signature = (d, source = "<dict>"))]
    fn from_dict(d: &Bound<'_, PyDict>, source: &str) -> PyResult<Case> {
        let table = table_of(d, "")?;
        let text = toml::to_string(&table).map_err(|e| bad_argument(e.to_string()))?;
        let loaded = parse_case(source, &text, &[]).map_err(|e| case_error(&e))?;
        Ok(Case { loaded })
    }

    /// The built-in default case of `bisph run` (the 2-D dam break,
    /// `cases/dam-break-2d.toml`).
    #[staticmethod]
    fn default() -> PyResult<Case> {
        let loaded = load_case(None, &[]).map_err(|e| case_error(&e))?;
        Ok(Case { loaded })
    }

    /// Sets one key, as `bisph run --set key=value` does: a dotted path (`resolution.dx`,
    /// `fluid_block.0.max`), created when missing. A `str` value is read as the command
    /// line reads it (TOML when it parses as a number, bool or array, else a string);
    /// numbers, bools, lists and dicts are taken as they are. The case is checked again: a
    /// mistake raises `bisph.CaseError` and leaves the case unchanged.
    fn set(&mut self, key: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let literal = match value.cast::<PyString>() {
            Ok(s) => s.to_cow()?.into_owned(),
            Err(_) => toml_value(value, key)?.to_string(),
        };
        let l = &self.loaded;
        let loaded = parse_case(&l.source, &l.text, &[format!("{key}={literal}")])
            .map_err(|e| case_error(&e))?;
        self.loaded = loaded;
        Ok(())
    }

    /// The case as a dict (what `from_dict` reads back).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let table: toml::Table = self
            .loaded
            .text
            .parse()
            .map_err(|e: toml::de::Error| bad_argument(e.to_string()))?;
        python_value(py, &toml::Value::Table(table))
    }

    /// The case as TOML, overrides applied (what a run writes as `case.toml`).
    #[getter]
    fn text(&self) -> &str {
        &self.loaded.text
    }

    /// Where the case came from (its file, `<dict>` or the built-in default).
    #[getter]
    fn source(&self) -> &str {
        &self.loaded.source
    }

    /// The case's name (`name`).
    #[getter]
    fn name(&self) -> &str {
        &self.loaded.case.name
    }

    /// The dimension, 2 or 3 (`dim`).
    #[getter]
    fn dim(&self) -> usize {
        self.loaded.case.dim as usize
    }

    /// The end time [s] (`time.end`).
    #[getter]
    fn end(&self) -> f64 {
        self.loaded.case.time.end
    }

    /// Builds the simulation as `bisph run` does before its first step: the memory check,
    /// the fluid blocks and walls, the geometry checks, then settling before `t = 0` when
    /// the case settles (`[settle]`; still water resting against walls does by default).
    ///
    /// `threads`: the size of this simulation's own thread pool (all cores when `None`);
    /// results do not depend on it. `progress`: a callable given a `bisph.Progress` after
    /// every settling step, or `True` for progress lines on stderr. The GIL is released
    /// while building; Ctrl-C stops settling after the step in progress and raises
    /// KeyboardInterrupt (no simulation is returned).
    #[pyo3(signature = (threads = None, progress = None))]
    fn build(
        &self,
        py: Python<'_>,
        threads: Option<usize>,
        progress: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Simulation> {
        build(py, self.loaded.clone(), threads, progress)
    }

    fn __repr__(&self) -> String {
        format!(
            "Case(name={:?}, dim={}, source={:?})",
            self.loaded.case.name, self.loaded.case.dim, self.loaded.source
        )
    }
}

/// A Python dict as a TOML table (`key` is the dotted path of the dict, for messages).
fn table_of(d: &Bound<'_, PyDict>, key: &str) -> PyResult<toml::Table> {
    let mut table = toml::Table::new();
    for (k, v) in d.iter() {
        let name: String = k
            .extract()
            .map_err(|_| PyTypeError::new_err(format!("{key}: keys must be strings")))?;
        let path = if key.is_empty() {
            name.clone()
        } else {
            format!("{key}.{name}")
        };
        table.insert(name, toml_value(&v, &path)?);
    }
    Ok(table)
}

/// A Python value as a TOML value: bool, int, float, str, list or tuple, dict.
fn toml_value(v: &Bound<'_, PyAny>, key: &str) -> PyResult<toml::Value> {
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(toml::Value::Integer(v.extract()?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(toml::Value::String(s.to_cow()?.into_owned()));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        return Ok(toml::Value::Table(table_of(d, key)?));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() || v.hasattr("tolist")? {
        let items = if v.hasattr("tolist")? {
            v.call_method0("tolist")?
        } else {
            v.clone()
        };
        let mut array = Vec::new();
        for (k, item) in items.try_iter()?.enumerate() {
            array.push(toml_value(&item?, &format!("{key}.{k}"))?);
        }
        return Ok(toml::Value::Array(array));
    }
    Err(PyTypeError::new_err(format!(
        "{key}: expected a bool, number, string, list or dict, found {}",
        v.get_type().name()?
    )))
}

/// A TOML value as a Python object (tables as dicts, arrays as lists).
fn python_value<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        toml::Value::String(s) => s.into_pyobject(py)?.into_any(),
        toml::Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        toml::Value::Float(f) => f.into_pyobject(py)?.into_any(),
        toml::Value::Boolean(b) => PyBool::new(py, *b).to_owned().into_any(),
        toml::Value::Datetime(d) => d.to_string().into_pyobject(py)?.into_any(),
        toml::Value::Array(a) => {
            let list = PyList::empty(py);
            for item in a {
                list.append(python_value(py, item)?)?;
            }
            list.into_any()
        }
        toml::Value::Table(t) => {
            let dict = PyDict::new(py);
            for (k, item) in t {
                dict.set_item(k, python_value(py, item)?)?;
            }
            dict.into_any()
        }
    })
}
