//! `rheodem.Scenario`: a scenario file, parsed and checked.

use crate::errors::scenario_error;
use pyo3::prelude::*;
use std::path::PathBuf;

/// A scenario (the TOML format of the README's "Scenario files" and `examples/`), read
/// from a file or from text.
/// Relative paths in it (packing files) are read from `base_dir`: the file's folder, or
/// the current folder for text.
#[pyclass(module = "rheodem._rheodem", frozen)]
#[derive(Clone)]
pub struct Scenario {
    /// The parsed scenario.
    pub inner: rheodem::scenario::Scenario,
    /// Folder of relative paths.
    pub base_dir: PathBuf,
}

#[pymethods]
impl Scenario {
    /// Reads a scenario file. Raises ScenarioError naming the key (and line) of an error.
    #[staticmethod]
    fn from_file(path: PathBuf) -> PyResult<Scenario> {
        let inner = rheodem::scenario::Scenario::from_file(&path).map_err(scenario_error)?;
        let base_dir = path
            .parent()
            .map_or_else(|| PathBuf::from("."), PathBuf::from);
        Ok(Scenario { inner, base_dir })
    }

    /// Parses a scenario from TOML text; relative paths are read from `base_dir` (default:
    /// the current folder).
    #[staticmethod]
    #[pyo3(signature = (text, base_dir = None))]
    fn from_toml(text: &str, base_dir: Option<PathBuf>) -> PyResult<Scenario> {
        let inner = rheodem::scenario::Scenario::from_toml(text).map_err(scenario_error)?;
        Ok(Scenario {
            inner,
            base_dir: base_dir.unwrap_or_else(|| PathBuf::from(".")),
        })
    }

    /// The scenario as TOML with every default written out.
    fn to_toml(&self) -> String {
        self.inner.to_toml()
    }

    /// The same scenario with another seed of the random generator.
    fn with_seed(&self, seed: u64) -> Scenario {
        let mut s = self.clone();
        s.inner.seed = seed;
        s
    }

    /// The seed of the random generator.
    #[getter]
    fn seed(&self) -> u64 {
        self.inner.seed
    }

    /// The title, if the file gives one.
    #[getter]
    fn title(&self) -> Option<String> {
        self.inner.title.clone()
    }

    /// Checks the scenario without building it: raises ScenarioError naming the first
    /// key out of range; returns the derived values (particle counts, time step, steps) as
    /// a JSON text.
    fn check(&self) -> PyResult<String> {
        let checked =
            rheodem::scenario::check(&self.inner, &self.base_dir).map_err(scenario_error)?;
        Ok(serde_json::to_string(&checked.resolved).unwrap_or_default())
    }

    fn __repr__(&self) -> String {
        format!(
            "Scenario(title={:?}, seed={}, base_dir={:?})",
            self.inner.title.as_deref().unwrap_or(""),
            self.inner.seed,
            self.base_dir
        )
    }
}
