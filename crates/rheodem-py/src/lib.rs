//! The native part of the `rheodem` Python package (`rheodem._rheodem`), built by maturin
//! from `pyproject.toml` at the repository's root. It binds the library `rheodem`: scenarios,
//! simulations stepped from Python with their particle arrays as read-only NumPy views,
//! custom measurements on a trigger, the registered set-ups run through the same driver
//! as the command line, the fitted laws of Shi et al. 2020, and the results database. The
//! Python layer (`python/rheodem/`) adds the optional pandas and xarray forms and the
//! documentation stub; docs/python.md is the user's page.

mod contacts;
mod errors;
mod results;
mod scenario;
mod setups;
mod simulation;
mod threads;
mod views;

use pyo3::prelude::*;

/// The module `rheodem._rheodem`.
#[pymodule]
fn _rheodem(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("ScenarioError", py.get_type::<errors::ScenarioError>())?;
    m.add("RunError", py.get_type::<errors::RunError>())?;
    m.add("__version__", rheodem::VERSION)?;
    m.add("COMMIT", rheodem::COMMIT)?;
    m.add_class::<scenario::Scenario>()?;
    m.add_class::<simulation::Simulation>()?;
    m.add_class::<views::Buffer>()?;
    m.add_function(wrap_pyfunction!(setups::run_setup, m)?)?;
    m.add_function(wrap_pyfunction!(setups::setups, m)?)?;
    m.add_function(wrap_pyfunction!(setups::run_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(setups::predict, m)?)?;
    m.add_function(wrap_pyfunction!(results::export_results, m)?)?;
    m.add_function(wrap_pyfunction!(results::import_results, m)?)?;
    Ok(())
}
