//! The results database: every finished run of every study, of any set-up, in one SQLite
//! file (docs/studies.md), which many processes may write at once and anyone can query
//! with `sqlite3`, Python or R.
//!
//! One schema for every set-up (version 3). The table `runs` holds one row per
//! `(study, name)`: the set-up's name, whether the run reached a steady state, its wall
//! time, commit and insertion time, and the full JSON of its parameters (the spec) and its
//! results (its summary). The table `run_values` holds every number and name of those two
//! documents, one row per key (`kind` `parameter` or `result`, the key as a dotted path
//! such as `cohesion.volume` or `steady_state.friction`, a mean with its standard error
//! folded into one row), so that any set-up's parameter or result can be selected in SQL
//! without a column of its own; a set-up added later is stored without a change here. The
//! views `points` (shear-box points) and `cells` (split-bottom cells) give the columns of
//! schema version 2, which older files had as tables: opening such a file moves their rows
//! into `runs` and `run_values` in one transaction.
//!
//! Writers open the file in WAL mode with a busy timeout (the set-up under a lock on
//! `FILE.lock`), and each insertion is one `IMMEDIATE` transaction. So concurrent writers
//! (the jobs of a sweep, array tasks of a cluster) wait for each other instead of failing,
//! and a killed writer leaves the file consistent.

use super::sweep::PointResult;
use rusqlite::types::Value as Sql;
use rusqlite::{Connection, OptionalExtension, Transaction, TransactionBehavior, params};
use serde_json::Value;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// How long a writer waits for another's transaction before giving up.
const BUSY_TIMEOUT: Duration = Duration::from_secs(120);

/// The schema version this code writes (`PRAGMA user_version`): 1 had the table `points`
/// only, 2 the tables `points` and `cells`, 3 `runs` and `run_values` with those two as
/// views.
const SCHEMA_VERSION: i64 = 3;

/// The tables. `run_values.value` has no declared type, so that SQLite keeps what is
/// stored: whole numbers (counts, seeds) as integers, exactly, the rest as reals.
const TABLES: &str = "
CREATE TABLE IF NOT EXISTS runs (
    study TEXT NOT NULL,
    name TEXT NOT NULL,
    setup TEXT NOT NULL,
    steady INTEGER,
    wall_seconds REAL,
    commit_id TEXT,
    inserted_at TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    parameters_json TEXT NOT NULL,
    results_json TEXT NOT NULL,
    PRIMARY KEY (study, name)
);
CREATE TABLE IF NOT EXISTS run_values (
    study TEXT NOT NULL,
    name TEXT NOT NULL,
    kind TEXT NOT NULL CHECK (kind IN ('parameter', 'result')),
    key TEXT NOT NULL,
    value,
    error REAL,
    text TEXT,
    PRIMARY KEY (study, name, kind, key)
);
CREATE INDEX IF NOT EXISTS run_values_by_key ON run_values (kind, key);
";

/// Where a column of a view comes from.
#[derive(Clone, Copy)]
enum Column {
    /// A column of `runs`.
    Run(&'static str),
    /// A parameter's number.
    Parameter(&'static str),
    /// A parameter's name.
    ParameterText(&'static str),
    /// A parameter's number times a factor.
    ParameterTimes(&'static str, f64),
    /// A result's number (a mean).
    Result(&'static str),
    /// A result's standard error.
    ResultError(&'static str),
}

use Column::{
    Parameter as P, ParameterText as PT, ParameterTimes, Result as R, ResultError as RE, Run,
};

/// The view `points`: the shear-box points with the columns of schema version 2.
const POINTS: &[(&str, Column)] = &[
    ("study", Run("study")),
    ("name", Run("name")),
    ("setup", Run("setup")),
    ("mu_p", P("mu_p")),
    ("inertial", P("inertial")),
    ("softness", P("softness")),
    ("bond", P("bond")),
    ("cohesion", PT("cohesion")),
    ("shear_dynamics", PT("shear_dynamics")),
    ("particles", P("particles")),
    ("polydispersity", P("polydispersity")),
    ("seed", P("seed")),
    ("strain", P("strain")),
    ("transient_strain", P("transient_strain")),
    ("steady", Run("steady")),
    ("phi", R("steady_state.volume_fraction")),
    ("phi_err", RE("steady_state.volume_fraction")),
    ("mu", R("steady_state.friction")),
    ("mu_err", RE("steady_state.friction")),
    ("coordination", R("steady_state.coordination")),
    ("coordination_err", RE("steady_state.coordination")),
    ("sigma_yy", R("steady_state.sigma_yy")),
    ("sigma_yy_err", RE("steady_state.sigma_yy")),
    ("mean_stress", R("steady_state.mean_stress")),
    ("mean_stress_err", RE("steady_state.mean_stress")),
    (
        "granular_temperature",
        R("steady_state.granular_temperature"),
    ),
    ("inertial_measured", R("steady_state.inertial_measured")),
    ("softness_measured", R("steady_state.softness_measured")),
    ("bond_measured", R("steady_state.bond_measured")),
    ("wall_seconds", Run("wall_seconds")),
    ("commit_id", Run("commit_id")),
    ("inserted_at", Run("inserted_at")),
    ("spec_json", Run("parameters_json")),
    ("result_json", Run("results_json")),
];

/// The view `cells`: the split-bottom cells with the columns of schema version 2; the
/// band's numbers in the scaled units of `setups::wet_study` (results `scaled.*`).
const CELLS: &[(&str, Column)] = &[
    ("study", Run("study")),
    ("name", Run("name")),
    ("law", PT("cohesion.law")),
    ("surface_tension", P("cohesion.surface_tension")),
    ("volume_nl", ParameterTimes("cohesion.volume", 1e12)),
    ("max_force", P("cohesion.max_force")),
    ("adhesive_stiffness", P("cohesion.stiffness")),
    ("omega", P("omega")),
    ("gravity", P("gravity")),
    ("mu_p", P("friction")),
    ("seed", P("seed")),
    ("duration", P("duration")),
    ("rupture_scaled", R("scaled.rupture")),
    ("tension_scaled", R("scaled.tension")),
    ("mu", R("scaled.mu")),
    ("mu_err", RE("scaled.mu")),
    ("cohesion_scaled", R("scaled.cohesion")),
    ("cohesion_scaled_err", RE("scaled.cohesion")),
    (
        "cohesion_from_torque_scaled",
        R("scaled.cohesion_from_torque"),
    ),
    ("torque_scaled", R("scaled.torque")),
    ("torque_scaled_err", RE("scaled.torque")),
    ("torque_macro_scaled", R("scaled.torque_macro")),
    ("pressure_avg_scaled", R("scaled.pressure")),
    ("wall_seconds", Run("wall_seconds")),
    ("commit_id", Run("commit_id")),
    ("inserted_at", Run("inserted_at")),
    ("summary_json", Run("results_json")),
];

/// `CREATE VIEW` of `view` over the runs of `setup` with `columns`.
fn view_sql(view: &str, setup: &str, columns: &[(&str, Column)]) -> String {
    let value = |column: &str, kind: &str, key: &str| {
        format!(
            "(SELECT v.{column} FROM run_values v WHERE v.study = r.study AND v.name = r.name \
             AND v.kind = '{kind}' AND v.key = '{key}')"
        )
    };
    let select: Vec<String> = columns
        .iter()
        .map(|(name, from)| {
            let expr = match *from {
                Run(c) => format!("r.{c}"),
                P(k) => value("value", "parameter", k),
                PT(k) => value("text", "parameter", k),
                ParameterTimes(k, f) => format!("{f:e} * {}", value("value", "parameter", k)),
                R(k) => value("value", "result", k),
                RE(k) => value("error", "result", k),
            };
            format!("{expr} AS {name}")
        })
        .collect();
    format!(
        "CREATE VIEW IF NOT EXISTS {view} AS SELECT {} FROM runs r WHERE r.setup = '{setup}';",
        select.join(", ")
    )
}

/// Errors of the results database, naming the file.
#[derive(Debug, thiserror::Error)]
pub enum DbError {
    /// SQLite refused an operation.
    #[error("results database {path}: {source}")]
    Sqlite {
        /// The database file.
        path: PathBuf,
        /// What SQLite said.
        source: rusqlite::Error,
    },
    /// The lock that serialises the database's set-up could not be taken.
    #[error("results database: {0}")]
    Lock(#[from] crate::io::lock::LockError),
    /// The file was written by a newer schema.
    #[error(
        "results database {path} has schema version {found}; this rheodem reads version {SCHEMA_VERSION} or older"
    )]
    Schema {
        /// The database file.
        path: PathBuf,
        /// The version found.
        found: i64,
    },
    /// A stored JSON document does not read back.
    #[error("results database {path}, point {name}: {reason}")]
    Corrupt {
        /// The database file.
        path: PathBuf,
        /// The point.
        name: String,
        /// Why.
        reason: String,
    },
}

/// One number or name of a run's parameters or results, as `run_values` stores it.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// The dotted path of the key (`cohesion.volume`, `results.band[0].width`).
    pub key: String,
    /// The number (an integer or a real; `NULL` for a name or a number that is not
    /// finite).
    pub value: Sql,
    /// The standard error of a mean.
    pub error: Option<f64>,
    /// The name, for a text value.
    pub text: Option<String>,
}

/// Longest array whose elements are stored one by one (longer ones are data, kept in the
/// JSON document only).
const MAX_ARRAY: usize = 64;

/// Every number and name of `v` as entries under `key` (see the module documentation): a
/// mean with its error (an object with numbers `mean` and `error`) becomes one entry,
/// booleans 0 or 1, arrays of at most [`MAX_ARRAY`] elements `key[k]`.
pub fn flatten(v: &Value, key: &str, out: &mut Vec<Entry>) {
    let entry = |value: Sql, error: Option<f64>, text: Option<String>| Entry {
        key: key.to_string(),
        value,
        error,
        text,
    };
    let real = |x: f64| {
        if x.is_finite() {
            Sql::Real(x)
        } else {
            Sql::Null
        }
    };
    let join = |k: &str| {
        if key.is_empty() {
            k.to_string()
        } else {
            format!("{key}.{k}")
        }
    };
    match v {
        Value::Null => {}
        Value::Bool(b) => out.push(entry(Sql::Integer(i64::from(*b)), None, None)),
        Value::Number(n) => out.push(entry(
            n.as_i64()
                .map_or_else(|| real(n.as_f64().unwrap_or(f64::NAN)), Sql::Integer),
            None,
            None,
        )),
        Value::String(s) => out.push(entry(Sql::Null, None, Some(s.clone()))),
        Value::Array(items) if items.len() <= MAX_ARRAY => {
            for (k, item) in items.iter().enumerate() {
                flatten(item, &format!("{key}[{k}]"), out);
            }
        }
        Value::Array(_) => {}
        Value::Object(map) => {
            let estimate = map
                .get("mean")
                .and_then(Value::as_f64)
                .zip(map.get("error").and_then(Value::as_f64));
            if let Some((mean, error)) = estimate {
                out.push(entry(real(mean), error.is_finite().then_some(error), None));
            }
            for (k, item) in map {
                if estimate.is_some() && (k == "mean" || k == "error") {
                    continue;
                }
                flatten(item, &join(k), out);
            }
        }
    }
}

/// A finished run as the database stores it.
struct Record {
    setup: &'static str,
    name: String,
    parameters: Value,
    results_json: String,
    results: Value,
    /// Results computed from the summary rather than read from it (`scaled.*`).
    derived: Vec<Entry>,
    steady: Option<bool>,
    wall_seconds: Option<f64>,
    commit: Option<String>,
    /// When it was first stored (`None`: now).
    inserted_at: Option<String>,
}

impl Record {
    /// A shear-box point.
    fn point(r: &PointResult) -> Record {
        let results_json = serde_json::to_string(r).expect("results serialise");
        Record {
            setup: "shear-box",
            name: r.name.clone(),
            parameters: serde_json::to_value(&r.spec).expect("specs serialise"),
            results: serde_json::from_str(&results_json).expect("results read back"),
            results_json,
            derived: Vec::new(),
            steady: r.steady_state.as_ref().map(|s| s.steady),
            wall_seconds: Some(r.wall_seconds),
            commit: Some(r.commit.clone()),
            inserted_at: None,
        }
    }

    /// A split-bottom cell from the text of its `summary.json` (`origin` names it in
    /// errors), with the band's numbers in the scaled units of `setups::wet_study` where
    /// the run has a band rheology.
    fn cell(name: &str, text: &str, origin: &str) -> Result<Record, String> {
        use super::split_bottom::SplitBottomSpec;
        #[derive(serde::Deserialize)]
        struct Recorded {
            spec: SplitBottomSpec,
            #[serde(default)]
            wall_seconds: Option<f64>,
            #[serde(default)]
            commit: Option<String>,
        }
        let rec: Recorded = serde_json::from_str(text)
            .map_err(|e| format!("{origin} is not a split-bottom summary: {e}"))?;
        let mut record = Record::run(
            "split-bottom",
            name,
            serde_json::to_value(&rec.spec).expect("specs serialise"),
            text,
            origin,
        )?;
        record.wall_seconds = rec.wall_seconds;
        record.commit = rec.commit;
        let derived = &mut record.derived;
        if let Ok(r) = super::wet_study::WetRun::from_summary(text, name, origin) {
            let mut add = |key: &str, (value, error): (f64, Option<f64>)| {
                flatten(&serde_json::json!(value), key, derived);
                if let (Some(e), Some(last)) = (error, derived.last_mut()) {
                    last.error = e.is_finite().then_some(e);
                }
            };
            add("scaled.rupture", (r.rupture, None));
            add("scaled.tension", (r.tension, None));
            add("scaled.mu", (r.mu.0, Some(r.mu.1)));
            add("scaled.cohesion", (r.cohesion.0, Some(r.cohesion.1)));
            add(
                "scaled.cohesion_from_torque",
                (r.cohesion_from_torque, None),
            );
            add("scaled.torque", (r.torque.0, Some(r.torque.1)));
            add("scaled.torque_macro", (r.torque_macro, None));
            add("scaled.pressure", (r.pressure, None));
        }
        Ok(record)
    }

    /// A run of the set-up `setup` from its resolved `parameters` and the text of its
    /// result document (`origin` names it in errors), with `wall_seconds`, `commit` and
    /// `steady` read from the document's top level where it has them.
    fn run(
        setup: &'static str,
        name: &str,
        parameters: Value,
        text: &str,
        origin: &str,
    ) -> Result<Record, String> {
        let results: Value =
            serde_json::from_str(text).map_err(|e| format!("{origin} is not JSON: {e}"))?;
        Ok(Record {
            setup,
            name: name.to_string(),
            parameters,
            results_json: text.to_string(),
            wall_seconds: results["wall_seconds"].as_f64(),
            commit: results["commit"].as_str().map(str::to_string),
            steady: results["steady"].as_bool(),
            results,
            derived: Vec::new(),
            inserted_at: None,
        })
    }

    /// Stores the record under `study` in the transaction `tx`, replacing an earlier run of
    /// the same name with its values.
    fn store(&self, tx: &Transaction<'_>, study: &str) -> rusqlite::Result<()> {
        tx.execute(
            "DELETE FROM run_values WHERE study = ?1 AND name = ?2",
            params![study, self.name],
        )?;
        tx.execute(
            "INSERT OR REPLACE INTO runs (study, name, setup, steady, wall_seconds, commit_id,
                parameters_json, results_json, inserted_at)
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8,
                COALESCE(?9, strftime('%Y-%m-%dT%H:%M:%SZ', 'now')))",
            params![
                study,
                self.name,
                self.setup,
                self.steady,
                self.wall_seconds,
                self.commit,
                self.parameters.to_string(),
                self.results_json,
                self.inserted_at,
            ],
        )?;
        let mut insert = tx.prepare_cached(
            "INSERT OR REPLACE INTO run_values (study, name, kind, key, value, error, text)
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
        )?;
        let mut parameters = Vec::new();
        flatten(&self.parameters, "", &mut parameters);
        // Adhesive laws under their registered names (`willett` of earlier files is
        // `liquid_bridge`), so that one query finds a law's runs whatever wrote them.
        for e in &mut parameters {
            if (e.key == "cohesion" || e.key == "cohesion.law")
                && let Some(kind) = e
                    .text
                    .as_deref()
                    .and_then(|t| crate::contact::LawKind::from_name(t).ok())
            {
                e.text = Some(kind.name().to_string());
            }
        }
        let mut results = Vec::new();
        flatten(&self.results, "", &mut results);
        results.extend(self.derived.iter().cloned());
        for (kind, entries) in [("parameter", &parameters), ("result", &results)] {
            for e in entries {
                insert.execute(params![
                    study, self.name, kind, e.key, e.value, e.error, e.text
                ])?;
            }
        }
        Ok(())
    }
}

/// An open results database.
pub struct ResultsDb {
    connection: Connection,
    path: PathBuf,
}

impl ResultsDb {
    /// Opens (creating if needed) the database at `path`; a file of an older schema is
    /// brought to the current one (its rows moved into `runs` and `run_values`).
    ///
    /// The set-up (creating the file, switching it to WAL, creating or converting the
    /// tables) runs under an exclusive lock on `PATH.lock` beside it: SQLite answers a
    /// journal-mode change or a schema write that meets another opener's with "database is
    /// locked" at once, without its busy timeout, so concurrent first openers must take
    /// turns.
    pub fn open(path: &Path) -> Result<ResultsDb, DbError> {
        let err = |source| DbError::Sqlite {
            path: path.to_path_buf(),
            source,
        };
        let mut lock_file = path.as_os_str().to_owned();
        lock_file.push(".lock");
        let _setup = crate::io::lock::DirLock::acquire_file(Path::new(&lock_file))?;
        let mut connection = Connection::open(path).map_err(err)?;
        connection.busy_timeout(BUSY_TIMEOUT).map_err(err)?;
        // WAL lets readers go on while one process writes.
        let mode: String = connection
            .query_row("PRAGMA journal_mode", [], |r| r.get(0))
            .map_err(err)?;
        if !mode.eq_ignore_ascii_case("wal") {
            connection
                .query_row("PRAGMA journal_mode = WAL", [], |_| Ok(()))
                .map_err(err)?;
        }
        let found: i64 = connection
            .query_row("PRAGMA user_version", [], |r| r.get(0))
            .map_err(err)?;
        if found > SCHEMA_VERSION {
            return Err(DbError::Schema {
                path: path.to_path_buf(),
                found,
            });
        }
        if found < SCHEMA_VERSION {
            let tx = connection
                .transaction_with_behavior(TransactionBehavior::Immediate)
                .map_err(err)?;
            upgrade(&tx, path)?;
            tx.commit().map_err(err)?;
        }
        Ok(ResultsDb {
            connection,
            path: path.to_path_buf(),
        })
    }

    fn err(&self) -> impl Fn(rusqlite::Error) -> DbError + '_ {
        |source| DbError::Sqlite {
            path: self.path.clone(),
            source,
        }
    }

    /// Stores `record` under `study` in one transaction.
    fn store(&mut self, study: &str, record: &Record) -> Result<(), DbError> {
        let path = self.path.clone();
        let err = move |source| DbError::Sqlite {
            path: path.clone(),
            source,
        };
        let tx = self
            .connection
            .transaction_with_behavior(TransactionBehavior::Immediate)
            .map_err(&err)?;
        record.store(&tx, study).map_err(&err)?;
        tx.commit().map_err(err)
    }

    /// Stores a finished shear-box point under `study`, replacing an earlier run of the
    /// same name.
    pub fn insert(&mut self, study: &str, r: &PointResult) -> Result<(), DbError> {
        self.store(study, &Record::point(r))
    }

    /// Stores the finished run `name` of the registered set-up `setup` under `study`, for a
    /// set-up without a method of its own here: its resolved `parameters` and the text of
    /// its result document (its `summary.json` or result file, JSON), with `wall_seconds`,
    /// `commit` and `steady` read from the document's top level where it has them; every
    /// number and name of both goes into `run_values`. Replaces an earlier run of the same
    /// name.
    ///
    /// # Errors
    /// [`DbError::Corrupt`] when the document is not JSON, or the database's error.
    pub fn insert_run(
        &mut self,
        study: &str,
        setup: &'static str,
        name: &str,
        parameters: &Value,
        results_json: &str,
    ) -> Result<(), DbError> {
        let record =
            Record::run(setup, name, parameters.clone(), results_json, name).map_err(|reason| {
                DbError::Corrupt {
                    path: self.path.clone(),
                    name: name.into(),
                    reason,
                }
            })?;
        self.store(study, &record)
    }

    /// Stores the finished split-bottom cell `name` under `study` from its `summary.json`
    /// (a run's, or its archived copy), replacing an earlier run of the same name. The
    /// band's numbers, in the scaled units of `setups::wet_study`, are left out where the
    /// run has no band rheology.
    pub fn insert_cell(&mut self, study: &str, name: &str, summary: &Path) -> Result<(), DbError> {
        let corrupt = |reason: String| DbError::Corrupt {
            path: self.path.clone(),
            name: name.into(),
            reason,
        };
        let text = std::fs::read_to_string(summary)
            .map_err(|e| corrupt(format!("cannot read {}: {e}", summary.display())))?;
        let record = Record::cell(name, &text, &summary.display().to_string()).map_err(corrupt)?;
        self.store(study, &record)
    }

    /// Number of stored runs of the set-up `setup` (its registered name) in `study` (in
    /// every study with `None`).
    ///
    /// # Errors
    /// [`DbError`] from the database.
    pub fn count_runs(&self, setup: &str, study: Option<&str>) -> Result<u64, DbError> {
        self.connection
            .query_row(
                "SELECT count(*) FROM runs WHERE setup = ?1 AND (?2 IS NULL OR study = ?2)",
                params![setup, study],
                |r| r.get::<_, i64>(0),
            )
            .map(|n| n as u64)
            .map_err(self.err())
    }

    /// Number of stored split-bottom cells of `study` (of every study with `None`).
    pub fn count_cells(&self, study: Option<&str>) -> Result<u64, DbError> {
        self.count_runs("split-bottom", study)
    }

    /// Number of stored shear-box points of `study` (of every study with `None`).
    pub fn count(&self, study: Option<&str>) -> Result<u64, DbError> {
        self.count_runs("shear-box", study)
    }

    /// The studies with stored runs, in name order.
    pub fn studies(&self) -> Result<Vec<String>, DbError> {
        let mut q = self
            .connection
            .prepare("SELECT DISTINCT study FROM runs ORDER BY study")
            .map_err(self.err())?;
        let rows = q
            .query_map([], |r| r.get::<_, String>(0))
            .map_err(self.err())?;
        rows.collect::<Result<Vec<_>, _>>().map_err(self.err())
    }

    /// The stored result of shear-box point `name` in `study`, if any.
    pub fn get(&self, study: &str, name: &str) -> Result<Option<PointResult>, DbError> {
        let json: Option<String> = self
            .connection
            .query_row(
                "SELECT results_json FROM runs
                 WHERE setup = 'shear-box' AND study = ?1 AND name = ?2",
                params![study, name],
                |r| r.get(0),
            )
            .optional()
            .map_err(self.err())?;
        json.map(|j| {
            serde_json::from_str(&j).map_err(|e| DbError::Corrupt {
                path: self.path.clone(),
                name: name.into(),
                reason: e.to_string(),
            })
        })
        .transpose()
    }

    /// Every stored shear-box result of `study` (every study with `None`), ordered by
    /// study and name.
    pub fn results(&self, study: Option<&str>) -> Result<Vec<(String, PointResult)>, DbError> {
        let mut q = self
            .connection
            .prepare(
                "SELECT study, name, results_json FROM runs
                 WHERE setup = 'shear-box' AND (?1 IS NULL OR study = ?1) ORDER BY study, name",
            )
            .map_err(self.err())?;
        let rows = q
            .query_map(params![study], |r| {
                Ok((
                    r.get::<_, String>(0)?,
                    r.get::<_, String>(1)?,
                    r.get::<_, String>(2)?,
                ))
            })
            .map_err(self.err())?;
        let mut out = Vec::new();
        for row in rows {
            let (study, name, json) = row.map_err(self.err())?;
            let result = serde_json::from_str(&json).map_err(|e| DbError::Corrupt {
                path: self.path.clone(),
                name: name.clone(),
                reason: e.to_string(),
            })?;
            out.push((study, result));
        }
        Ok(out)
    }

    /// The shear-box points of `study` (every study with `None`) as CSV: the columns of
    /// the view `points` without the JSON documents, empty fields for missing values.
    pub fn export_csv(&self, study: Option<&str>) -> Result<String, DbError> {
        self.table_csv("points", &columns(POINTS, "spec_json"), study)
    }

    /// The split-bottom cells of `study` (every study with `None`) as CSV: the columns of
    /// the view `cells` without the summary document.
    pub fn export_cells_csv(&self, study: Option<&str>) -> Result<String, DbError> {
        self.table_csv("cells", &columns(CELLS, "summary_json"), study)
    }

    /// Every stored number and name of the runs of `study` (every study with `None`), of
    /// any set-up, as CSV in long form: `study, name, setup, kind, key, value, error,
    /// text`, one row per key.
    pub fn export_values_csv(&self, study: Option<&str>) -> Result<String, DbError> {
        self.query_csv(
            "SELECT v.study, v.name, r.setup, v.kind, v.key, v.value, v.error, v.text
             FROM run_values v JOIN runs r ON r.study = v.study AND r.name = v.name
             WHERE ?1 IS NULL OR v.study = ?1 ORDER BY v.study, v.name, v.kind, v.key",
            &[
                "study", "name", "setup", "kind", "key", "value", "error", "text",
            ],
            study,
        )
    }

    /// The `columns` of `table`'s rows of `study` as CSV.
    fn table_csv(
        &self,
        table: &str,
        columns: &[&str],
        study: Option<&str>,
    ) -> Result<String, DbError> {
        let sql = format!(
            "SELECT {} FROM {table} WHERE ?1 IS NULL OR study = ?1 ORDER BY study, name",
            columns.join(", ")
        );
        self.query_csv(&sql, columns, study)
    }

    /// The rows of `sql` (with `study` as its one parameter) as CSV under `header`.
    fn query_csv(
        &self,
        sql: &str,
        header: &[&str],
        study: Option<&str>,
    ) -> Result<String, DbError> {
        let mut q = self.connection.prepare(sql).map_err(self.err())?;
        let mut rows = q.query(params![study]).map_err(self.err())?;
        let mut s = header.join(",") + "\n";
        while let Some(row) = rows.next().map_err(self.err())? {
            for k in 0..header.len() {
                if k > 0 {
                    s.push(',');
                }
                use rusqlite::types::ValueRef;
                match row.get_ref(k).map_err(self.err())? {
                    ValueRef::Null => {}
                    ValueRef::Integer(i) => {
                        let _ = write!(s, "{i}");
                    }
                    ValueRef::Real(x) => {
                        let _ = write!(s, "{x}");
                    }
                    ValueRef::Text(t) => {
                        let t = String::from_utf8_lossy(t);
                        if t.contains([',', '"', '\n']) {
                            let _ = write!(s, "\"{}\"", t.replace('"', "\"\""));
                        } else {
                            s.push_str(&t);
                        }
                    }
                    ValueRef::Blob(_) => s.push_str("(blob)"),
                }
            }
            s.push('\n');
        }
        Ok(s)
    }
}

/// The names of `view`'s columns, those from `first_document` on left out.
fn columns(view: &[(&'static str, Column)], first_document: &str) -> Vec<&'static str> {
    view.iter()
        .map(|(name, _)| *name)
        .take_while(|name| *name != first_document)
        .collect()
}

/// Whether the file has a table (not a view) named `name`.
fn has_table(tx: &Transaction<'_>, name: &str) -> rusqlite::Result<bool> {
    tx.query_row(
        "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = ?1",
        params![name],
        |r| r.get::<_, i64>(0),
    )
    .map(|n| n > 0)
}

/// Brings a file of schema version 0 (new), 1 or 2 to version 3 in the transaction `tx`:
/// the tables and views, and the rows of the former tables `points` and `cells` moved into
/// `runs` and `run_values` (a point whose result no longer reads is refused by name).
fn upgrade(tx: &Transaction<'_>, path: &Path) -> Result<(), DbError> {
    let err = |source| DbError::Sqlite {
        path: path.to_path_buf(),
        source,
    };
    tx.execute_batch(TABLES).map_err(err)?;
    let corrupt = |name: &str, reason: String| DbError::Corrupt {
        path: path.to_path_buf(),
        name: name.to_string(),
        reason,
    };
    for (table, document) in [("points", "result_json"), ("cells", "summary_json")] {
        if !has_table(tx, table).map_err(err)? {
            continue;
        }
        let rows: Vec<(String, String, String, Option<String>)> = {
            let mut q = tx
                .prepare(&format!(
                    "SELECT study, name, {document}, inserted_at FROM {table}"
                ))
                .map_err(err)?;
            q.query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?)))
                .map_err(err)?
                .collect::<Result<_, _>>()
                .map_err(err)?
        };
        for (study, name, json, inserted_at) in rows {
            let mut record = if table == "points" {
                let point: PointResult =
                    serde_json::from_str(&json).map_err(|e| corrupt(&name, e.to_string()))?;
                Record::point(&point)
            } else {
                Record::cell(&name, &json, "its stored summary").map_err(|e| corrupt(&name, e))?
            };
            record.inserted_at = inserted_at;
            record.store(tx, &study).map_err(err)?;
        }
        tx.execute_batch(&format!("DROP TABLE {table}"))
            .map_err(err)?;
    }
    tx.execute_batch(&view_sql("points", "shear-box", POINTS))
        .map_err(err)?;
    tx.execute_batch(&view_sql("cells", "split-bottom", CELLS))
        .map_err(err)?;
    tx.execute_batch(&format!("PRAGMA user_version = {SCHEMA_VERSION}"))
        .map_err(err)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::setups::shear_box::ShearBoxSpec;

    fn temp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("rheodem-db-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("temp dir");
        d
    }

    fn point(name: &str, mu_p: f64) -> PointResult {
        let spec: ShearBoxSpec = toml::from_str(&format!(
            "mu_p = {mu_p}\ninertial = 0.02\nsoftness = 0.01\nshear_dynamics = \"affine-drag\""
        ))
        .expect("spec");
        PointResult {
            name: name.into(),
            derived: spec.derive().expect("derives"),
            spec,
            steady_state: None,
            wall_seconds: 12.5,
            commit: "abc".into(),
        }
    }

    #[test]
    fn any_set_up_stores_its_parameters_and_results() {
        let dir = std::env::temp_dir().join(format!("rheodem-db-any-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let file = dir.join("r.sqlite");
        let mut db = ResultsDb::open(&file).expect("open");
        let summary = r#"{"wall_seconds": 3.5, "commit": "abc", "steady": true,
            "flow": {"mean": 1.5, "error": 0.1}, "law": "none"}"#;
        db.insert_run(
            "s",
            "chute",
            "c1",
            &serde_json::json!({"theta_deg": 24.0, "layers": 20}),
            summary,
        )
        .expect("stored");
        assert_eq!(db.count_runs("chute", Some("s")).expect("n"), 1);
        let (steady, wall): (bool, f64) = db
            .connection
            .query_row(
                "SELECT steady, wall_seconds FROM runs WHERE name = 'c1'",
                [],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .expect("the run");
        assert!(steady && wall == 3.5);
        let value = |kind: &str, key: &str| -> (f64, Option<f64>) {
            db.connection
                .query_row(
                    "SELECT value, error FROM run_values WHERE name = 'c1' AND kind = ?1 \
                     AND key = ?2",
                    params![kind, key],
                    |r| Ok((r.get(0)?, r.get(1)?)),
                )
                .expect("a value")
        };
        assert_eq!(value("parameter", "theta_deg"), (24.0, None));
        assert_eq!(value("result", "flow"), (1.5, Some(0.1)));
        let e = db
            .insert_run("s", "chute", "c2", &serde_json::json!({}), "not json")
            .expect_err("not JSON");
        assert!(e.to_string().contains("not JSON"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn points_round_trip_and_replace() {
        let dir = temp("round-trip");
        let file = dir.join("results.sqlite");
        let mut db = ResultsDb::open(&file).expect("opens");
        db.insert("study-a", &point("p1", 0.1)).expect("insert");
        db.insert("study-a", &point("p2", 0.2)).expect("insert");
        db.insert("study-b", &point("p1", 0.3)).expect("insert");
        // A second insertion of the same name replaces the row.
        let mut again = point("p2", 0.2);
        again.wall_seconds = 99.0;
        db.insert("study-a", &again).expect("replace");
        assert_eq!(db.count(None).expect("count"), 3);
        assert_eq!(db.count(Some("study-a")).expect("count"), 2);
        let got = db.get("study-a", "p2").expect("get").expect("stored");
        assert_eq!(
            (got.wall_seconds, &got.spec, &got.name),
            (99.0, &again.spec, &again.name)
        );
        assert!(db.get("study-a", "p9").expect("get").is_none());
        let all = db.results(Some("study-b")).expect("results");
        assert_eq!(all.len(), 1);
        assert_eq!(all[0].1.spec.mu_p, 0.3);
        let csv = db.export_csv(Some("study-a")).expect("csv");
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 3);
        assert!(lines[0].starts_with("study,name,setup,mu_p"));
        assert!(lines[2].starts_with("study-a,p2,shear-box,0.2,0.02,0.01,0,none,affine-drag,"));
        // Missing steady-state values are empty fields.
        assert!(lines[2].contains(",,,"), "{}", lines[2]);
        drop(db);
        // Reopening keeps everything.
        let db = ResultsDb::open(&file).expect("reopens");
        assert_eq!(db.count(None).expect("count"), 3);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A committed split-bottom summary goes into `cells` with its scaled band numbers;
    /// storing it again replaces the row; the CSV export lists it; a file that is not a
    /// summary is refused by name.
    #[test]
    fn split_bottom_cells_are_stored_from_their_summaries() {
        let dir = temp("cells");
        let mut db = ResultsDb::open(&dir.join("results.sqlite")).expect("open");
        let summary = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../validation/runs-split-bottom-fields/wet-g0.02-v75/summary.json");
        db.insert_cell("wet", "v75", &summary).expect("insert");
        db.insert_cell("wet", "v75", &summary).expect("replace");
        assert_eq!(db.count_cells(Some("wet")).expect("count"), 1);
        assert_eq!(db.count(None).expect("count"), 0, "no shear-box point");
        assert_eq!(db.studies().expect("studies"), ["wet"]);
        let csv = db.export_cells_csv(None).expect("csv");
        let row = csv.lines().nth(1).expect("a row");
        assert!(row.starts_with("wet,v75,liquid_bridge,0.02,75"), "{row}");
        let cohesion: f64 = row.split(',').nth(16).expect("c*").parse().expect("number");
        assert!((cohesion - 0.403).abs() < 0.001, "{row}");
        let not_summary = Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml");
        let e = db
            .insert_cell("wet", "x", &not_summary)
            .expect_err("not json");
        assert!(e.to_string().contains("Cargo.toml"), "{e}");
        drop(db);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Every number and name of a run is a row of `run_values`: a parameter of either
    /// set-up selects its runs in SQL, a mean carries its error, counts stay integers.
    #[test]
    fn every_value_of_either_set_up_is_selectable() {
        let dir = temp("values");
        let mut db = ResultsDb::open(&dir.join("results.sqlite")).expect("open");
        db.insert("s", &point("p1", 0.25)).expect("insert");
        let summary = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../validation/runs-split-bottom-fields/wet-g0.02-v75/summary.json");
        db.insert_cell("s", "v75", &summary).expect("insert");
        let value = |kind: &str, key: &str| -> (Option<f64>, Option<String>) {
            db.connection
                .query_row(
                    "SELECT value, text FROM run_values WHERE kind = ?1 AND key = ?2",
                    params![kind, key],
                    |r| Ok((r.get(0)?, r.get(1)?)),
                )
                .expect("one row")
        };
        assert_eq!(value("parameter", "mu_p").0, Some(0.25));
        assert_eq!(
            value("parameter", "shear_dynamics").1.as_deref(),
            Some("affine-drag")
        );
        assert_eq!(value("parameter", "omega").0, Some(0.5));
        assert_eq!(
            value("parameter", "cohesion.law").1.as_deref(),
            Some("liquid_bridge")
        );
        let particles: i64 = db
            .connection
            .query_row(
                "SELECT value FROM run_values WHERE name = 'p1' AND key = 'particles'",
                [],
                |r| r.get(0),
            )
            .expect("stored as an integer");
        assert_eq!(particles, 4096);
        let (c, c_err): (f64, f64) = db
            .connection
            .query_row(
                "SELECT value, error FROM run_values WHERE key = 'scaled.cohesion'",
                [],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .expect("the band's c*");
        assert!(
            (c - 0.403).abs() < 0.001 && c_err > 0.0 && c_err < 0.1,
            "{c} ± {c_err}"
        );
        let csv = db.export_values_csv(Some("s")).expect("csv");
        assert!(csv.starts_with("study,name,setup,kind,key,value,error,text\n"));
        assert!(
            csv.contains("\ns,p1,shear-box,parameter,mu_p,0.25,,\n"),
            "{csv}"
        );
        drop(db);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A file of schema version 2 (tables `points` and `cells`, here with the columns the
    /// upgrade reads) opens as version 3 with its rows in `runs`, their insertion times
    /// kept, and the same columns in the views `points` and `cells`.
    #[test]
    fn a_version_2_file_is_upgraded_in_place() {
        let dir = temp("upgrade");
        let file = dir.join("results.sqlite");
        let summary = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../validation/runs-split-bottom-fields/wet-g0.02-v75/summary.json");
        let c = Connection::open(&file).expect("raw");
        c.execute_batch(
            "CREATE TABLE points (study TEXT, name TEXT, result_json TEXT, inserted_at TEXT);
             CREATE TABLE cells (study TEXT, name TEXT, summary_json TEXT, inserted_at TEXT);
             PRAGMA user_version = 2;",
        )
        .expect("version 2");
        let old = serde_json::to_string(&point("p1", 0.3)).expect("json");
        c.execute(
            "INSERT INTO points VALUES ('a', 'p1', ?1, '2025-01-02T03:04:05Z')",
            params![old],
        )
        .expect("row");
        let text = std::fs::read_to_string(&summary).expect("summary");
        c.execute(
            "INSERT INTO cells VALUES ('wet', 'v75', ?1, '2025-06-07T08:09:10Z')",
            params![text],
        )
        .expect("row");
        drop(c);
        let db = ResultsDb::open(&file).expect("upgrades");
        assert_eq!(
            (db.count(None).expect("n"), db.count_cells(None).expect("n")),
            (1, 1)
        );
        assert_eq!(db.studies().expect("studies"), ["a", "wet"]);
        assert_eq!(
            db.get("a", "p1").expect("get").expect("stored").spec.mu_p,
            0.3
        );
        let csv = db.export_csv(None).expect("csv");
        let row = csv.lines().nth(1).expect("a row");
        assert!(
            row.starts_with("a,p1,shear-box,0.3,0.02,0.01,0,none,affine-drag,4096,3,1,"),
            "{row}"
        );
        assert!(row.ends_with(",12.5,abc,2025-01-02T03:04:05Z"), "{row}");
        let cells = db.export_cells_csv(None).expect("csv");
        assert!(
            cells
                .lines()
                .nth(1)
                .expect("a row")
                .starts_with("wet,v75,liquid_bridge,0.02,75")
        );
        assert!(cells.contains("2025-06-07T08:09:10Z"));
        let version: i64 = db
            .connection
            .query_row("PRAGMA user_version", [], |r| r.get(0))
            .expect("version");
        assert_eq!(version, SCHEMA_VERSION);
        drop(db);
        // Opening again changes nothing.
        let db = ResultsDb::open(&file).expect("reopens");
        assert_eq!(db.export_csv(None).expect("csv"), csv);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn flatten_folds_estimates_and_keeps_integers() {
        let v = serde_json::json!({
            "a": {"mean": 1.5, "error": 0.25, "samples": 9},
            "b": [true, "x", null],
            "c": {"d": f64::MAX},
            "long": vec![0; MAX_ARRAY + 1],
        });
        let mut out = Vec::new();
        flatten(&v, "", &mut out);
        let got: Vec<(String, Sql, Option<f64>, Option<String>)> = out
            .into_iter()
            .map(|e| (e.key, e.value, e.error, e.text))
            .collect();
        assert_eq!(
            got,
            vec![
                ("a".into(), Sql::Real(1.5), Some(0.25), None),
                ("a.samples".into(), Sql::Integer(9), None, None),
                ("b[0]".into(), Sql::Integer(1), None, None),
                ("b[1]".into(), Sql::Null, None, Some("x".into())),
                ("c.d".into(), Sql::Real(f64::MAX), None, None),
            ]
        );
    }

    #[test]
    fn a_newer_schema_is_refused_with_its_version() {
        let dir = temp("schema");
        let file = dir.join("results.sqlite");
        drop(ResultsDb::open(&file).expect("opens"));
        let c = Connection::open(&file).expect("raw");
        c.execute_batch("PRAGMA user_version = 7").expect("set");
        drop(c);
        let e = ResultsDb::open(&file).err().expect("refused");
        assert!(e.to_string().contains("schema version 7"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Four connections (SQLite locks the file the same way for threads with their own
    /// connections as for processes) insert 50 points each at once: all 200 are there.
    #[test]
    fn concurrent_writers_lose_nothing() {
        let dir = temp("concurrent");
        let file = dir.join("results.sqlite");
        drop(ResultsDb::open(&file).expect("creates"));
        std::thread::scope(|scope| {
            for w in 0..4 {
                let file = &file;
                scope.spawn(move || {
                    let mut db = ResultsDb::open(file).expect("opens");
                    for k in 0..50 {
                        db.insert("s", &point(&format!("w{w}-p{k}"), 0.01 * k as f64))
                            .expect("insert under contention");
                    }
                });
            }
        });
        let db = ResultsDb::open(&file).expect("opens");
        assert_eq!(db.count(Some("s")).expect("count"), 200);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Eight connections open a file that does not exist yet at the same moment, twenty
    /// times over: every one of them opens it and stores its point. (Without the set-up
    /// lock, SQLite answers some of them "database is locked" at once.)
    #[test]
    fn concurrent_first_openers_all_succeed() {
        let dir = temp("first-open");
        for round in 0..20 {
            let file = dir.join(format!("round{round}.sqlite"));
            let start = std::sync::Barrier::new(8);
            std::thread::scope(|scope| {
                for w in 0..8 {
                    let (file, start) = (&file, &start);
                    scope.spawn(move || {
                        start.wait();
                        let mut db = ResultsDb::open(file).expect("opens under contention");
                        db.insert("s", &point(&format!("w{w}"), 0.1))
                            .expect("insert");
                    });
                }
            });
            let db = ResultsDb::open(&file).expect("opens");
            assert_eq!(db.count(Some("s")).expect("count"), 8, "round {round}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
