//! The results database: every finished point of every study in one SQLite file
//! (docs/studies.md), which many processes may write at once and anyone can query with
//! `sqlite3`, Python or R.
//!
//! Two tables: `points` for shear-box points and `cells` for split-bottom cells (schema
//! version 2; a version-1 file gains the `cells` table when opened). In `points`, one row
//! per `(study, name)`. A row holds the state point's
//! controls, the steady-state averages with their standard errors, and the run's
//! bookkeeping: wall time, commit, insertion time. It also keeps the full JSON of the
//! point's spec and result, so nothing is lost when a column is missing. Writers open the
//! file in WAL mode with a busy timeout (the set-up under a lock on `FILE.lock`), and each
//! insertion is one `IMMEDIATE` transaction. So concurrent writers (the jobs of a sweep,
//! array tasks of a cluster) wait for each other instead of failing, and a killed writer
//! leaves the file consistent.

use super::sweep::PointResult;
use rusqlite::{Connection, OptionalExtension, TransactionBehavior, params};
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// How long a writer waits for another's transaction before giving up.
const BUSY_TIMEOUT: Duration = Duration::from_secs(120);

/// The schema version this code writes (`PRAGMA user_version`): 1 had `points` only.
const SCHEMA_VERSION: i64 = 2;

/// The `points` table. Columns after `commit_id` are the JSON documents.
const SCHEMA: &str = "
CREATE TABLE IF NOT EXISTS points (
    study TEXT NOT NULL,
    name TEXT NOT NULL,
    setup TEXT NOT NULL,
    mu_p REAL NOT NULL,
    inertial REAL NOT NULL,
    softness REAL NOT NULL,
    bond REAL NOT NULL,
    cohesion TEXT NOT NULL,
    shear_dynamics TEXT NOT NULL,
    particles INTEGER NOT NULL,
    polydispersity REAL NOT NULL,
    seed INTEGER NOT NULL,
    strain REAL NOT NULL,
    transient_strain REAL NOT NULL,
    steady INTEGER,
    phi REAL, phi_err REAL,
    mu REAL, mu_err REAL,
    coordination REAL, coordination_err REAL,
    sigma_yy REAL, sigma_yy_err REAL,
    mean_stress REAL, mean_stress_err REAL,
    granular_temperature REAL,
    inertial_measured REAL, softness_measured REAL, bond_measured REAL,
    wall_seconds REAL NOT NULL,
    commit_id TEXT NOT NULL,
    inserted_at TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    spec_json TEXT NOT NULL,
    result_json TEXT NOT NULL,
    PRIMARY KEY (study, name)
);
CREATE TABLE IF NOT EXISTS cells (
    study TEXT NOT NULL,
    name TEXT NOT NULL,
    law TEXT NOT NULL,
    surface_tension REAL,
    volume_nl REAL,
    max_force REAL,
    adhesive_stiffness REAL,
    omega REAL NOT NULL,
    gravity REAL NOT NULL,
    mu_p REAL NOT NULL,
    seed INTEGER NOT NULL,
    duration REAL NOT NULL,
    rupture_scaled REAL,
    tension_scaled REAL,
    mu REAL, mu_err REAL,
    cohesion_scaled REAL, cohesion_scaled_err REAL,
    cohesion_from_torque_scaled REAL,
    torque_scaled REAL, torque_scaled_err REAL,
    torque_macro_scaled REAL,
    pressure_avg_scaled REAL,
    wall_seconds REAL,
    commit_id TEXT,
    inserted_at TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    summary_json TEXT NOT NULL,
    PRIMARY KEY (study, name)
);
";

/// The columns of `cells` that `export_cells_csv` writes, in order.
const CELL_COLUMNS: [&str; 26] = [
    "study",
    "name",
    "law",
    "surface_tension",
    "volume_nl",
    "max_force",
    "adhesive_stiffness",
    "omega",
    "gravity",
    "mu_p",
    "seed",
    "duration",
    "rupture_scaled",
    "tension_scaled",
    "mu",
    "mu_err",
    "cohesion_scaled",
    "cohesion_scaled_err",
    "cohesion_from_torque_scaled",
    "torque_scaled",
    "torque_scaled_err",
    "torque_macro_scaled",
    "pressure_avg_scaled",
    "wall_seconds",
    "commit_id",
    "inserted_at",
];

/// The columns `export_csv` writes, in order (the JSON documents are left out).
const CSV_COLUMNS: [&str; 32] = [
    "study",
    "name",
    "setup",
    "mu_p",
    "inertial",
    "softness",
    "bond",
    "cohesion",
    "shear_dynamics",
    "particles",
    "polydispersity",
    "seed",
    "strain",
    "transient_strain",
    "steady",
    "phi",
    "phi_err",
    "mu",
    "mu_err",
    "coordination",
    "coordination_err",
    "sigma_yy",
    "sigma_yy_err",
    "mean_stress",
    "mean_stress_err",
    "granular_temperature",
    "inertial_measured",
    "softness_measured",
    "bond_measured",
    "wall_seconds",
    "commit_id",
    "inserted_at",
];

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

/// An open results database.
pub struct ResultsDb {
    connection: Connection,
    path: PathBuf,
}

impl ResultsDb {
    /// Opens (creating if needed) the database at `path`.
    ///
    /// The set-up (creating the file, switching it to WAL, creating the tables) runs under
    /// an exclusive lock on `PATH.lock` beside it: SQLite answers a journal-mode change or a
    /// schema write that meets another opener's with "database is locked" at once, without
    /// its busy timeout, so concurrent first openers must take turns.
    pub fn open(path: &Path) -> Result<ResultsDb, DbError> {
        let err = |source| DbError::Sqlite {
            path: path.to_path_buf(),
            source,
        };
        let mut lock_file = path.as_os_str().to_owned();
        lock_file.push(".lock");
        let _setup = crate::io::lock::DirLock::acquire_file(Path::new(&lock_file))?;
        let connection = Connection::open(path).map_err(err)?;
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
            connection.execute_batch(SCHEMA).map_err(err)?;
            connection
                .execute_batch(&format!("PRAGMA user_version = {SCHEMA_VERSION}"))
                .map_err(err)?;
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

    /// Stores a finished point under `study`, replacing an earlier row of the same name.
    pub fn insert(&mut self, study: &str, r: &PointResult) -> Result<(), DbError> {
        let path = self.path.clone();
        let err = move |source| DbError::Sqlite {
            path: path.clone(),
            source,
        };
        let spec_json = serde_json::to_string(&r.spec).expect("specs serialise");
        let result_json = serde_json::to_string(r).expect("results serialise");
        let s = &r.spec;
        let ss = r.steady_state.as_ref();
        let est = |f: fn(&super::shear_box::SteadyState) -> crate::analysis::Estimate| ss.map(&f);
        let (phi, mu, z, syy, p) = (
            est(|x| x.volume_fraction),
            est(|x| x.friction),
            est(|x| x.coordination),
            est(|x| x.sigma_yy),
            est(|x| x.mean_stress),
        );
        let tx = self
            .connection
            .transaction_with_behavior(TransactionBehavior::Immediate)
            .map_err(&err)?;
        tx.execute(
            "INSERT OR REPLACE INTO points (study, name, setup, mu_p, inertial, softness, bond,
                cohesion, shear_dynamics, particles, polydispersity, seed, strain,
                transient_strain, steady, phi, phi_err, mu, mu_err, coordination,
                coordination_err, sigma_yy, sigma_yy_err, mean_stress, mean_stress_err,
                granular_temperature, inertial_measured, softness_measured, bond_measured,
                wall_seconds, commit_id, spec_json, result_json)
             VALUES (?1, ?2, 'shear-box', ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14,
                ?15, ?16, ?17, ?18, ?19, ?20, ?21, ?22, ?23, ?24, ?25, ?26, ?27, ?28, ?29,
                ?30, ?31, ?32)",
            params![
                study,
                r.name,
                s.mu_p,
                s.inertial,
                s.softness,
                s.bond,
                format!("{:?}", s.cohesion).to_lowercase(),
                s.shear_dynamics.name(),
                s.particles as i64,
                s.polydispersity,
                s.seed as i64,
                s.strain,
                s.transient_strain,
                ss.map(|x| x.steady),
                phi.map(|e| e.mean),
                phi.map(|e| e.error),
                mu.map(|e| e.mean),
                mu.map(|e| e.error),
                z.map(|e| e.mean),
                z.map(|e| e.error),
                syy.map(|e| e.mean),
                syy.map(|e| e.error),
                p.map(|e| e.mean),
                p.map(|e| e.error),
                ss.map(|x| x.granular_temperature.mean),
                ss.map(|x| x.inertial_measured),
                ss.map(|x| x.softness_measured),
                ss.map(|x| x.bond_measured),
                r.wall_seconds,
                r.commit,
                spec_json,
                result_json,
            ],
        )
        .map_err(&err)?;
        tx.commit().map_err(err)
    }

    /// Stores the finished split-bottom cell `name` under `study` from its `summary.json`
    /// (a run's, or its archived copy), replacing an earlier row of the same name. The
    /// band's numbers, in the scaled units of `setups::wet_study`, are empty where the run
    /// has no band rheology.
    pub fn insert_cell(&mut self, study: &str, name: &str, summary: &Path) -> Result<(), DbError> {
        use super::split_bottom::{Cohesion, SplitBottomSpec};
        #[derive(serde::Deserialize)]
        struct Recorded {
            spec: SplitBottomSpec,
            #[serde(default)]
            wall_seconds: Option<f64>,
            #[serde(default)]
            commit: Option<String>,
        }
        let corrupt = |reason: String| DbError::Corrupt {
            path: self.path.clone(),
            name: name.into(),
            reason,
        };
        let text = std::fs::read_to_string(summary)
            .map_err(|e| corrupt(format!("cannot read {}: {e}", summary.display())))?;
        let rec: Recorded = serde_json::from_str(&text).map_err(|e| {
            corrupt(format!(
                "{} is not a split-bottom summary: {e}",
                summary.display()
            ))
        })?;
        let run = super::wet_study::WetRun::read_summary(summary, name).ok();
        let (law, tension, volume, force, stiffness) = match rec.spec.cohesion {
            Cohesion::Dry => ("dry", None, None, None, None),
            Cohesion::Willett {
                surface_tension,
                volume,
                ..
            } => (
                "willett",
                Some(surface_tension),
                Some(volume * 1e12),
                None,
                None,
            ),
            Cohesion::Linear {
                max_force,
                stiffness,
            } => ("linear", None, None, Some(max_force), Some(stiffness)),
        };
        let r = run.as_ref();
        let s = &rec.spec;
        let path = self.path.clone();
        let err = move |source| DbError::Sqlite {
            path: path.clone(),
            source,
        };
        let tx = self
            .connection
            .transaction_with_behavior(TransactionBehavior::Immediate)
            .map_err(&err)?;
        tx.execute(
            "INSERT OR REPLACE INTO cells (study, name, law, surface_tension, volume_nl,
                max_force, adhesive_stiffness, omega, gravity, mu_p, seed, duration,
                rupture_scaled, tension_scaled, mu, mu_err, cohesion_scaled,
                cohesion_scaled_err, cohesion_from_torque_scaled, torque_scaled,
                torque_scaled_err, torque_macro_scaled, pressure_avg_scaled, wall_seconds,
                commit_id, summary_json)
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16,
                ?17, ?18, ?19, ?20, ?21, ?22, ?23, ?24, ?25, ?26)",
            params![
                study,
                name,
                law,
                tension,
                volume,
                force,
                stiffness,
                s.omega,
                s.gravity,
                s.friction,
                s.seed as i64,
                s.duration,
                r.map(|r| r.rupture),
                r.map(|r| r.tension),
                r.map(|r| r.mu.0),
                r.map(|r| r.mu.1),
                r.map(|r| r.cohesion.0),
                r.map(|r| r.cohesion.1),
                r.map(|r| r.cohesion_from_torque),
                r.map(|r| r.torque.0),
                r.map(|r| r.torque.1),
                r.map(|r| r.torque_macro),
                r.map(|r| r.pressure),
                rec.wall_seconds,
                rec.commit,
                text,
            ],
        )
        .map_err(&err)?;
        tx.commit().map_err(err)
    }

    /// Number of stored split-bottom cells of `study` (of every study with `None`).
    pub fn count_cells(&self, study: Option<&str>) -> Result<u64, DbError> {
        self.connection
            .query_row(
                "SELECT count(*) FROM cells WHERE ?1 IS NULL OR study = ?1",
                params![study],
                |r| r.get::<_, i64>(0),
            )
            .map(|n| n as u64)
            .map_err(self.err())
    }

    /// The studies with stored points or cells, in name order.
    pub fn studies(&self) -> Result<Vec<String>, DbError> {
        let mut q = self
            .connection
            .prepare("SELECT study FROM points UNION SELECT study FROM cells ORDER BY study")
            .map_err(self.err())?;
        let rows = q
            .query_map([], |r| r.get::<_, String>(0))
            .map_err(self.err())?;
        rows.collect::<Result<Vec<_>, _>>().map_err(self.err())
    }

    /// The stored result of point `name` in `study`, if any.
    pub fn get(&self, study: &str, name: &str) -> Result<Option<PointResult>, DbError> {
        let json: Option<String> = self
            .connection
            .query_row(
                "SELECT result_json FROM points WHERE study = ?1 AND name = ?2",
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

    /// Every stored result of `study` (every study with `None`), ordered by study and name.
    pub fn results(&self, study: Option<&str>) -> Result<Vec<(String, PointResult)>, DbError> {
        let mut q = self
            .connection
            .prepare(
                "SELECT study, name, result_json FROM points
                 WHERE ?1 IS NULL OR study = ?1 ORDER BY study, name",
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

    /// Number of stored points of `study` (of every study with `None`).
    pub fn count(&self, study: Option<&str>) -> Result<u64, DbError> {
        self.connection
            .query_row(
                "SELECT count(*) FROM points WHERE ?1 IS NULL OR study = ?1",
                params![study],
                |r| r.get::<_, i64>(0),
            )
            .map(|n| n as u64)
            .map_err(self.err())
    }

    /// The table of `study` (every study with `None`) as CSV: the columns of the `points`
    /// table without the JSON documents, empty fields for missing values.
    pub fn export_csv(&self, study: Option<&str>) -> Result<String, DbError> {
        self.table_csv("points", &CSV_COLUMNS, study)
    }

    /// The split-bottom cells of `study` (every study with `None`) as CSV: the columns of
    /// the `cells` table without the summary document.
    pub fn export_cells_csv(&self, study: Option<&str>) -> Result<String, DbError> {
        self.table_csv("cells", &CELL_COLUMNS, study)
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
        let mut q = self.connection.prepare(&sql).map_err(self.err())?;
        let mut rows = q.query(params![study]).map_err(self.err())?;
        let mut s = columns.join(",") + "\n";
        while let Some(row) = rows.next().map_err(self.err())? {
            for k in 0..columns.len() {
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
        assert!(row.starts_with("wet,v75,willett,0.02,75"), "{row}");
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
