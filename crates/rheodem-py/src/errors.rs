//! The package's exceptions and the conversion of the library's errors into them.

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

pyo3::create_exception!(
    rheodem,
    ScenarioError,
    PyValueError,
    "An invalid scenario or set-up parameter. The message names the key and the allowed \
     range; for a value out of range the attributes `key`, `value` and `allowed` hold them."
);

pyo3::create_exception!(
    rheodem,
    RunError,
    PyRuntimeError,
    "A run that could not go on: an unstable state, a run directory held by another process \
     or made by another command, a file not read or written."
);

/// A scenario error as [`ScenarioError`], with `key`, `value` and `allowed` for a value
/// out of range.
pub fn scenario_error(e: rheodem::scenario::ScenarioError) -> PyErr {
    let err = ScenarioError::new_err(e.to_string());
    if let rheodem::scenario::ScenarioError::Invalid {
        key,
        value,
        allowed,
    } = &e
    {
        Python::attach(|py| {
            let v = err.value(py);
            // Setting attributes of a fresh exception object cannot fail in practice; the
            // message already says everything.
            let _ = v.setattr("key", key);
            let _ = v.setattr("value", value);
            let _ = v.setattr("allowed", allowed);
        });
    }
    err
}

/// A run error: a scenario's as [`ScenarioError`], the others as [`RunError`], with the
/// command line's option `--force` said as the keyword `force=True`.
pub fn run_error(e: rheodem::run::RunError) -> PyErr {
    match e {
        rheodem::run::RunError::Scenario(s) => scenario_error(s),
        other => RunError::new_err(other.to_string().replace("--force", "force=True")),
    }
}

/// Any other library error as [`RunError`].
pub fn other(e: impl std::fmt::Display) -> PyErr {
    RunError::new_err(e.to_string())
}

/// A JSON text as the Python value `json.loads` makes of it.
pub fn from_json<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}
