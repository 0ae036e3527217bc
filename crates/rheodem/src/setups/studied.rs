//! Studies of any registered set-up: what a set-up supplies so that the points of a study
//! file (docs/studies.md) can be expanded, followed, run, archived, stored in the results
//! database and reported without code of its own anywhere else. A set-up implements
//! [`Studied`] beside its [`Experiment`]; the registry keeps it type-erased
//! ([`StudyFns`]), with each point as its spec's table, so that a front end handles every
//! set-up's studies with one code path and runs a point by name
//! ([`super::registry::SetUpInfo::run`] with the point's table).
//!
//! A finished point is known by its *result file*: the shear box's `steady_state.json`,
//! the split-bottom cell's `summary.json`, or the copy of either in the study's archive.

use super::results_db::ResultsDb;
use super::runner::Experiment;
use super::schema::table_of;
use super::study::{Report, StudySpec};
use super::sweep::{PointStatus, SweepSpec};
use crate::scenario::ScenarioError;
use serde::Serialize;
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};

/// A study's points: each name with its spec's table.
pub type PointTables = Vec<(String, toml::Table)>;

/// Finished points: each name with its result file.
pub type ResultFiles = [(String, PathBuf)];

/// What studies of a set-up need from it, besides running a point.
pub trait Studied: Experiment + Clone + Serialize + DeserializeOwned {
    /// The named points of a study's variant (its base, grid and points), checked.
    ///
    /// # Errors
    /// [`ScenarioError`] naming the point and the key of a value out of range.
    fn points(variant: &SweepSpec) -> Result<Vec<(String, Self)>, ScenarioError>;

    /// Where the point `name` stands, run in `dir` and archived (if at all) in `archive`:
    /// finished with its result file only when the result is of this spec.
    fn status(&self, name: &str, dir: &Path, archive: Option<&Path>) -> PointStatus<PathBuf>;

    /// Copies the finished point's result file into `archive` as `<name>.json` (and
    /// refreshes whatever table the archive keeps).
    ///
    /// # Errors
    /// A message naming the file not read or written.
    fn archive(archive: &Path, name: &str, result: &Path) -> Result<(), String>;

    /// Stores the finished point's result file in `db` under `study`.
    ///
    /// # Errors
    /// A message for a result file not read or not a result, or from the database.
    fn store(db: &mut ResultsDb, study: &str, name: &str, result: &Path) -> Result<(), String>;

    /// The study's report over its finished points (`(name, result file)`), `total`
    /// points in all.
    ///
    /// # Errors
    /// A message when a figure cannot be drawn.
    fn report(
        study: &StudySpec,
        variant: &str,
        total: usize,
        finished: &ResultFiles,
    ) -> Result<Report, String>;

    /// The finished point's outcome in one line (`μ = …`, `c* = …`), from its result file.
    fn outcome(name: &str, result: &Path) -> String;
}

/// [`Studied`] type-erased, as the registry holds it: each point is its spec's table.
#[derive(Clone, Copy, Debug)]
pub struct StudyFns {
    /// [`Studied::points`], each spec as its table.
    pub points: fn(&SweepSpec) -> Result<PointTables, ScenarioError>,
    /// [`Studied::status`] of the point given by its table.
    pub status: fn(&toml::Table, &str, &Path, Option<&Path>) -> PointStatus<PathBuf>,
    /// [`Studied::archive`].
    pub archive: fn(&Path, &str, &Path) -> Result<(), String>,
    /// [`Studied::store`].
    pub store: fn(&mut ResultsDb, &str, &str, &Path) -> Result<(), String>,
    /// [`Studied::report`].
    pub report: fn(&StudySpec, &str, usize, &ResultFiles) -> Result<Report, String>,
    /// [`Studied::outcome`].
    pub outcome: fn(&str, &Path) -> String,
}

fn points<S: Studied>(variant: &SweepSpec) -> Result<PointTables, ScenarioError> {
    Ok(S::points(variant)?
        .into_iter()
        .map(|(name, spec)| (name, table_of(&spec)))
        .collect())
}

fn status<S: Studied>(
    table: &toml::Table,
    name: &str,
    dir: &Path,
    archive: Option<&Path>,
) -> PointStatus<PathBuf> {
    // The table is one that `points` made of a spec: it reads back.
    match toml::Value::Table(table.clone()).try_into::<S>() {
        Ok(spec) => spec.status(name, dir, archive),
        Err(e) => PointStatus::Failed(0.0, format!("not a point of {}: {e}", S::NAME)),
    }
}

impl StudyFns {
    /// The functions of `S`.
    pub const fn of<S: Studied>() -> StudyFns {
        StudyFns {
            points: points::<S>,
            status: status::<S>,
            archive: S::archive,
            store: S::store,
            report: S::report,
            outcome: S::outcome,
        }
    }
}

/// The point of `points` named `name`.
pub fn point<'a>(points: &'a PointTables, name: &str) -> Option<&'a toml::Table> {
    points.iter().find(|(n, _)| n == name).map(|(_, t)| t)
}

/// The finished points of `statuses` (in the order of `points`): name and result file.
pub fn finished(points: &PointTables, statuses: &[PointStatus<PathBuf>]) -> Vec<(String, PathBuf)> {
    points
        .iter()
        .zip(statuses)
        .filter_map(|((name, _), st)| match st {
            PointStatus::Finished(file) => Some((name.clone(), file.clone())),
            _ => None,
        })
        .collect()
}
