//! The results database from Python: its tables as CSV text (the Python layer makes them
//! a pandas DataFrame or a list of dicts) and the import of a shear-box result archive.

use crate::errors::other;
use pyo3::prelude::*;
use rheodem::setups::archive::read_archive;
use rheodem::setups::results_db::ResultsDb;
use std::path::PathBuf;

/// A table of the results database `db` as CSV text: `"points"` (shear-box points),
/// `"cells"` (split-bottom cells) or `"values"` (every stored number in long form), of
/// one `study` or of all.
#[pyfunction]
#[pyo3(signature = (db, table = "points", study = None))]
pub fn export_results(db: PathBuf, table: &str, study: Option<&str>) -> PyResult<String> {
    if !db.exists() {
        return Err(other(format!("{} does not exist", db.display())));
    }
    let database = ResultsDb::open(&db).map_err(other)?;
    match table {
        "points" => database.export_csv(study),
        "cells" => database.export_cells_csv(study),
        "values" => database.export_values_csv(study),
        _ => {
            return Err(crate::errors::scenario_error(rheodem::scenario::invalid(
                "table",
                table,
                "must be one of points, cells, values",
            )));
        }
    }
    .map_err(other)
}

/// Stores the shear-box points of the result archive `archive` (a folder of
/// point results, as a study writes) in the database `db` under `study` (default: the
/// folder's name), as `rheodem db import` does; returns how many were stored.
#[pyfunction]
#[pyo3(signature = (archive, db, study = None))]
pub fn import_results(archive: PathBuf, db: PathBuf, study: Option<String>) -> PyResult<usize> {
    let points = read_archive(&archive).map_err(other)?;
    let study = study.unwrap_or_else(|| {
        archive
            .file_name()
            .map_or("imported".into(), |s| s.to_string_lossy().into_owned())
    });
    let mut database = ResultsDb::open(&db).map_err(other)?;
    for p in &points {
        database.insert(&study, p).map_err(other)?;
    }
    Ok(points.len())
}
