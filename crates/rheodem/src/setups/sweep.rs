//! Many shear-box points: a list and/or grid of [`ShearBoxSpec`]s run several at once, each
//! on one thread, resumable (finished points are skipped, interrupted ones resume from
//! their checkpoint), collected into one results table.
//!
//! Paths in the file (`out`, `results`) are relative to the file's directory.
//!
//! ```toml
//! out = "runs/my-sweep"       # optional: default runs/<file name> beside the file
//! [base]                      # fields shared by every point (any ShearBoxSpec field)
//! particles = 4096
//! polydispersity = 3.0
//! inertial = 0.02
//! softness = 0.01
//! cohesion = "reversible"
//! [grid]                      # optional: every combination of the listed values
//! mu_p = [0.01, 0.5]
//! bond = [0.5, 1.0]
//! [[point]]                   # optional: individual points (base ⊕ point)
//! mu_p = 0.01
//! inertial = 0.05
//! bond = 0.0
//! ```
//!
//! Every point, after merging, must be a complete [`ShearBoxSpec`]: here the grid's four
//! points take `inertial`, `softness` and `cohesion` from `[base]`.

pub use super::point_result::{PointResult, results_csv};
use super::shear_box::{ShearBoxSpec, SlabRates, SteadyState, steady_state};
use crate::domain::ShearDynamics;
use crate::io::atomic::write_atomic;
use crate::io::made_by::{self, Maker};
use crate::run::{Run, RunError, io_err};
use crate::scenario::{ScenarioError, invalid};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A sweep file.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepSpec {
    /// Output directory, relative to the sweep file's directory.
    #[serde(default)]
    pub out: Option<String>,
    /// Directory (relative to the sweep file's directory) where every finished point's result is also kept as `<name>.json` (e.g. in
    /// version control): a point found there is not run again.
    #[serde(default)]
    pub results: Option<String>,
    /// Fields shared by every point.
    #[serde(default)]
    pub base: toml::Table,
    /// Cartesian product of value lists.
    #[serde(default)]
    pub grid: toml::Table,
    /// Individual points.
    #[serde(default)]
    pub point: Vec<toml::Table>,
}

/// Sets `key` in `table`; a dotted key (`cohesion.volume`) sets a field of a nested table,
/// creating it where missing.
fn set_dotted(table: &mut toml::Table, key: &str, value: toml::Value) {
    match key.split_once('.') {
        Some((head, rest)) => {
            let entry = table
                .entry(head.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            if !entry.is_table() {
                *entry = toml::Value::Table(toml::Table::new());
            }
            if let toml::Value::Table(inner) = entry {
                set_dotted(inner, rest, value);
            }
        }
        None => {
            table.insert(key.to_string(), value);
        }
    }
}

/// The tables of a sweep's points: `base` merged with each combination of `grid`'s value
/// lists (in key order, the last key varying fastest), then with each of `points`. Keys of
/// `grid` and `points` may be dotted to set a field of a nested table of `base`
/// (`"cohesion.volume" = [14e-12, 75e-12]`).
pub fn point_tables(
    base: &toml::Table,
    grid: &toml::Table,
    points: &[toml::Table],
) -> Result<Vec<toml::Table>, ScenarioError> {
    let mut combos: Vec<Vec<(String, toml::Value)>> = Vec::new();
    if !grid.is_empty() {
        combos.push(Vec::new());
        for (key, values) in grid {
            let list = values.as_array().ok_or_else(|| {
                invalid(format!("grid.{key}"), values, "must be a list of values")
            })?;
            if list.is_empty() {
                return Err(invalid(
                    format!("grid.{key}"),
                    "[]",
                    "must list at least one value",
                ));
            }
            combos = combos
                .into_iter()
                .flat_map(|c| {
                    list.iter().map(move |v| {
                        let mut c = c.clone();
                        c.push((key.clone(), v.clone()));
                        c
                    })
                })
                .collect();
        }
    }
    combos.extend(
        points
            .iter()
            .map(|p| p.iter().map(|(k, v)| (k.clone(), v.clone())).collect()),
    );
    if combos.is_empty() {
        return Err(invalid("point", "[]", "give [[point]] entries or a [grid]"));
    }
    Ok(combos
        .into_iter()
        .map(|c| {
            let mut t = base.clone();
            for (k, v) in c {
                set_dotted(&mut t, &k, v);
            }
            t
        })
        .collect())
}

/// Expands the sweep into its points, each with a directory name built from its controls.
pub fn expand(spec: &SweepSpec) -> Result<Vec<(String, ShearBoxSpec)>, ScenarioError> {
    // A typo in [base] is named even in a sweep without points (the controls a point must
    // give, missing from [base] alone, are not an error there).
    if let Err(e) = ShearBoxSpec::from_table(spec.base.clone())
        && !e.to_string().contains("missing field")
    {
        return Err(ScenarioError::Parse(format!("[base]: {e}")));
    }
    let tables = point_tables(&spec.base, &spec.grid, &spec.point)?;
    let mut out = Vec::new();
    for (k, t) in tables.into_iter().enumerate() {
        let point = ShearBoxSpec::from_table(t)
            .map_err(|e| ScenarioError::Parse(format!("sweep point {k}: {e}")))?;
        point
            .derive()
            .map_err(|e| ScenarioError::Parse(format!("sweep point {k}: {e}")))?;
        let name = format!(
            "mu{}_I{}_p{}_Bo{}_{:?}_w{}_N{}_s{}",
            point.mu_p,
            point.inertial,
            point.softness,
            point.bond,
            point.cohesion,
            point.polydispersity,
            point.particles,
            point.seed
        )
        .to_lowercase()
            + match point.shear_dynamics {
                ShearDynamics::Lab => "",
                ShearDynamics::PeculiarContacts => "_peculiar",
                ShearDynamics::AffineDrag => "_affine",
            };
        if out.iter().any(|(n, _)| *n == name) {
            return Err(invalid(
                format!("point {k}"),
                name,
                "duplicates an earlier point",
            ));
        }
        out.push((name, point));
    }
    Ok(out)
}

/// File in a point's run directory that holds its [`ShearBoxSpec`] (JSON) and marks the
/// directory as a sweep point.
pub const POINT_FILE: &str = "point.json";

/// Runs (or resumes, or skips when finished) one point in `dir` with the current rayon
/// pool, writing `steady_state.json` at the end.
///
/// The smallest sensible point: 80 nearly monodisperse spheres (`w = 1.2`, close to the
/// fewest the box allows), sheared at `I = 0.1` over one strain unit, the first half
/// discarded (about a second). It gives a dense, compressed packing with a macroscopic
/// friction between 0.1 and 1; half a strain unit is too short a window to be steady,
/// and the result says so. A second call finds the point finished:
///
/// ```
/// use rheodem::setups::shear_box::ShearBoxSpec;
/// use rheodem::setups::sweep::run_point;
///
/// let spec: ShearBoxSpec = toml::from_str(
///     "mu_p = 0.5\ninertial = 0.1\nsoftness = 0.01\npolydispersity = 1.2\n\
///      particles = 80\nstrain = 1.0\ntransient_strain = 0.5\ncheckpoints = 1\nsnapshots = 0",
/// )?;
/// let dir = std::env::temp_dir().join(format!("rheodem-doc-point-{}", std::process::id()));
/// let result = run_point("doc", &spec, &dir, 1, &mut |_, _| {})?;
/// let ss = result.steady_state.expect("rows past the transient");
/// assert!(ss.volume_fraction.mean > 0.5 && ss.volume_fraction.mean < 0.7);
/// assert!(ss.sigma_yy.mean > 0.0);
/// assert!(ss.friction.mean > 0.1 && ss.friction.mean < 1.0);
/// assert_eq!(ss.strain_window[1].round(), 1.0);
/// assert!(!ss.steady && ss.note.contains("strain units past the transient"), "{}", ss.note);
/// let again = run_point("doc", &spec, &dir, 1, &mut |_, _| panic!("finished already"))?;
/// assert_eq!(again.spec, spec);
/// std::fs::remove_dir_all(&dir)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn run_point(
    name: &str,
    spec: &ShearBoxSpec,
    dir: &Path,
    threads: usize,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<PointResult, RunError> {
    let result_path = dir.join("steady_state.json");
    let finished = |path: &Path| {
        std::fs::read_to_string(path)
            .ok()
            .and_then(|text| serde_json::from_str::<PointResult>(&text).ok())
            .filter(|done| done.spec == *spec)
    };
    if let Some(done) = finished(&result_path) {
        return Ok(done);
    }
    let derived = spec.derive()?;
    let scenario = spec.scenario()?;
    // The lock first, then a second look: another process may have finished the point
    // while this one waited for nothing (the lock is never waited for).
    let existed = dir.exists();
    let lock = crate::run::lock(dir)?;
    if let Some(done) = finished(&result_path) {
        return Ok(done);
    }
    // The point file names the point being run; a refused run keeps its own.
    let marker = dir.join(POINT_FILE);
    let write_marker = || {
        let text = serde_json::to_string_pretty(spec).map_err(|e| RunError::Io {
            operation: "serialise",
            path: marker.clone(),
            source: e.into(),
        })?;
        write_atomic(&marker, text.as_bytes()).map_err(io_err("write", &marker))
    };
    let mut run = if dir.join("checkpoint.bin").exists() {
        let run = Run::resume_locked(lock, dir)?;
        // The directory name does not encode every field (strain, material, …): a run
        // started with other values must not be continued under this point's name.
        if run.scenario != scenario {
            return Err(RunError::Mismatch(dir.to_path_buf()));
        }
        write_marker()?;
        run
    } else {
        // Written before the start, whose preparation may take a while: the point shows
        // as running meanwhile.
        std::fs::create_dir_all(dir).map_err(io_err("create the directory", dir))?;
        write_marker()?;
        Run::start_locked(lock, existed, scenario, Path::new("."), dir, threads, true)?
    };
    made_by::mark(dir, Maker::ShearBox).map_err(io_err("write", &dir.join(made_by::FILE)))?;
    let steps = run.plan.steps;
    run.advance_until(dir, steps, &mut |p| progress(p.done, p.total))?;
    let result = PointResult {
        name: name.to_string(),
        spec: spec.clone(),
        derived,
        steady_state: steady_state(&run.rows, spec, &derived).map(|ss| SteadyState {
            slab_rates: run
                .fields
                .as_ref()
                .and_then(|f| f.points())
                .and_then(|(_, points)| SlabRates::of(&points, derived.shear_rate)),
            ..ss
        }),
        wall_seconds: run.wall_seconds,
        commit: crate::COMMIT.to_string(),
    };
    let json = serde_json::to_string_pretty(&result).map_err(|e| RunError::Io {
        operation: "serialise",
        path: result_path.clone(),
        source: e.into(),
    })?;
    write_atomic(&result_path, json.as_bytes()).map_err(io_err("write", &result_path))?;
    Ok(result)
}

/// Where one point of a sweep or study stands, read from its run directory; `R` is what a
/// finished point gives (a shear-box [`PointResult`] by default).
#[derive(Clone, Debug)]
pub enum PointStatus<R = Box<PointResult>> {
    /// Finished, with its result.
    Finished(R),
    /// A process is running it now (it holds the directory's lock); the fraction of its
    /// steps done at its last checkpoint.
    Running(f64),
    /// Started and checkpointed, but no process is on it: the next sweep or study run
    /// resumes it from the fraction of its steps given.
    Stopped(f64),
    /// Its last run failed at the fraction of its steps given, with the message.
    Failed(f64, String),
    /// Not started.
    Waiting,
}

impl<R> std::fmt::Display for PointStatus<R> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PointStatus::Finished(_) => write!(f, "finished"),
            PointStatus::Running(x) => write!(f, "running, {:.0} % of its steps", 100.0 * x),
            PointStatus::Stopped(x) => write!(
                f,
                "stopped at {:.0} % of its steps (checkpointed; the next run resumes it)",
                100.0 * x
            ),
            PointStatus::Failed(x, e) => {
                write!(f, "failed at {:.0} % of its steps: {e}", 100.0 * x)
            }
            PointStatus::Waiting => write!(f, "not started"),
        }
    }
}

/// The status of the point whose run directory is `dir`; with `spec`, a finished result
/// of other parameters does not count (the point is then waiting to be rerun).
pub fn point_status(dir: &Path, spec: Option<&ShearBoxSpec>) -> PointStatus {
    if let Some(r) = std::fs::read_to_string(dir.join("steady_state.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<PointResult>(&t).ok())
        .filter(|r| spec.is_none_or(|s| r.spec == *s))
    {
        return PointStatus::Finished(Box::new(r));
    }
    if !dir.join(POINT_FILE).exists() {
        return PointStatus::Waiting;
    }
    let summary = std::fs::read_to_string(dir.join("summary.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok());
    let done = summary.as_ref().map_or(0.0, |v| {
        v["steps_done"].as_f64().unwrap_or(0.0) / v["steps_total"].as_f64().unwrap_or(1.0).max(1.0)
    });
    let running = matches!(
        crate::io::lock::DirLock::try_acquire(dir),
        Err(crate::io::lock::LockError::Busy(_))
    );
    match summary.as_ref().and_then(|v| v["status"].as_str()) {
        _ if running => PointStatus::Running(done),
        Some("failed") => PointStatus::Failed(
            done,
            summary
                .as_ref()
                .and_then(|v| v["error"].as_str())
                .unwrap_or("(no message)")
                .to_string(),
        ),
        _ => PointStatus::Stopped(done),
    }
}

/// Default output directory of a sweep file: `runs/<file name>` beside the file.
pub fn default_out(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map_or("sweep".into(), |s| s.to_string_lossy().into_owned());
    path.parent()
        .unwrap_or(Path::new(""))
        .join("runs")
        .join(stem)
}

/// A finished point of the shear-box spec `spec` (TOML) whose steady state has the volume
/// fraction `phi` ± `phi_err` (and plausible other values), for tests of what reads results.
#[cfg(test)]
pub(crate) fn synthetic_result(spec: &str, phi: f64, phi_err: f64) -> PointResult {
    use crate::analysis::Estimate;
    let spec: ShearBoxSpec = toml::from_str(spec).expect("spec");
    let e = |mean, error| Estimate {
        mean,
        error,
        samples: 100,
    };
    let ss = SteadyState {
        steady: true,
        note: String::new(),
        strain_window: [spec.transient_strain, spec.strain],
        volume_fraction: e(phi, phi_err),
        friction: e(0.3, 0.001),
        coordination: e(4.5, 0.01),
        coordination_without_rattlers: None,
        sigma_yy: e(1.0, 0.01),
        shear_stress: e(0.3, 0.01),
        mean_stress: e(1.0, 0.01),
        granular_temperature: e(0.0, 0.0),
        sliding_fraction: e(0.1, 0.01),
        bridges_per_particle: e(0.0, 0.0),
        inertial_measured: spec.inertial,
        softness_measured: spec.softness,
        bond_measured: spec.bond,
        slab_rates: None,
    };
    PointResult {
        name: format!("{}-{}-{}", spec.mu_p, spec.bond, spec.strain),
        derived: spec.derive().expect("derived"),
        spec,
        steady_state: Some(ss),
        wall_seconds: 0.0,
        commit: String::new(),
    }
}
