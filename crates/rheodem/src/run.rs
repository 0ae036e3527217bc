//! A run on disk: its directory, outputs, checkpoints and resumption.
//!
//! A run directory holds
//! - `scenario.toml`: the scenario with every default written out, headed by the program
//!   version and seed;
//! - `resolved.json`: the derived values (time step, contact time, particle counts, radius
//!   distribution, preparation outcome, version, seed);
//! - `timeseries.csv`: one row of observables every `T/timeseries_rows`;
//! - `snapshots/*.vtp` and `snapshots.pvd`: particle snapshots for ParaView;
//! - `fields.csv` and `fields.vti`: the fields averaged on the fly (`[fields]`), and under
//!   `fields/` their samples when stored ([`samples`]);
//! - `checkpoint.bin`: the complete state at the last checkpoint;
//! - `summary.json`: status, progress, final observables.
//!
//! Every file is written atomically (see [`crate::io::atomic`]).

use crate::Simulation;
use crate::cg::{self, ContactRecords, periodic::BoxFields};
use crate::io::atomic::write_atomic;
use crate::io::lock::{DirLock, LockError};
use crate::io::made_by::{self, Maker};
use crate::io::{timeseries, vtk};
use crate::measure::Observables;
use crate::neighbor::NeighborError;
use crate::sanity::Instability;
use crate::scenario::{Resolved, Scenario, ScenarioError, build};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

pub mod samples;

/// Errors of a run.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scenario is invalid.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// A coarse-graining setting or a snapshot file is unusable.
    #[error(transparent)]
    Fields(#[from] crate::cg::CgError),
    /// A file could not be written or read.
    #[error("cannot {operation} {}: {source}", path.display())]
    Io {
        /// What was attempted ("write", "read", "create the directory", …).
        operation: &'static str,
        /// The file.
        path: PathBuf,
        /// The cause (the operating system's reason).
        source: std::io::Error,
    },
    /// The checkpoint is unreadable, damaged or from another version.
    #[error("{}: not a usable checkpoint: {reason}", path.display())]
    Checkpoint {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// The run directory already holds a run.
    #[error(
        "{} already holds a run: resume it with `rheodem resume {}`, or pass --force to start over",
        .0.display(), .0.display()
    )]
    Exists(PathBuf),
    /// Another process is running in the run directory.
    #[error(
        "{} is being run by another process (it holds {}/.lock); wait for it to finish",
        .0.display(), .0.display()
    )]
    Busy(PathBuf),
    /// The run directory holds a run of another scenario than the one asked for.
    #[error(
        "{} holds a run of different parameters than this point (changed since it started?): \
         remove the directory to start the point over",
        .0.display()
    )]
    Mismatch(PathBuf),
    /// The state stopped being a meaningful DEM state.
    #[error(
        "the simulation became unstable at step {step} (t = {time:e} s): {cause}. {}. Usual \
         causes: a time step too large for the stiffest contact (`run.dt`), overlapping or \
         coincident initial positions, or velocities or a prescribed motion far beyond what \
         the contacts can resolve",
        match checkpoint {
            Some(k) => format!("The last checkpoint (step {k}) predates it and is kept"),
            None => "No checkpoint was written before it".to_string(),
        }
    )]
    Unstable {
        /// Step at which the state was found unstable.
        step: u64,
        /// Simulated time of that step (s).
        time: f64,
        /// What is wrong, with the particles concerned.
        cause: Instability,
        /// Step of the last checkpoint on disk, if any.
        checkpoint: Option<u64>,
    },
    /// The neighbour search failed (box too small).
    #[error(transparent)]
    Neighbor(#[from] NeighborError),
}

/// Output cadence in steps.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OutputPlan {
    /// Total steps of the run.
    pub steps: u64,
    /// Steps between time-series rows.
    pub timeseries_every: u64,
    /// Steps between snapshots; 0 for none.
    pub snapshot_every: u64,
    /// Steps between checkpoints; 0 for the final one only.
    pub checkpoint_every: u64,
}

impl OutputPlan {
    fn every(steps: u64, count: u64) -> u64 {
        steps.checked_div(count).map_or(0, |e| e.max(1))
    }

    fn due(every: u64, step: u64) -> bool {
        every != 0 && step.is_multiple_of(every)
    }
}

/// Progress of a run as the summary reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Still running (or killed; resume it).
    Running,
    /// Reached its last step.
    Completed,
    /// Stopped on an error (see the summary's `error`); resuming repeats it.
    Failed,
}

/// Everything a run needs; serialised whole as its checkpoint.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Run {
    /// The scenario as run (kept as TOML text in the checkpoint).
    #[serde(with = "scenario_text")]
    pub scenario: Scenario,
    /// Derived values.
    pub resolved: Resolved,
    /// Output cadence.
    pub plan: OutputPlan,
    /// Threads of the force loop (results are bit-identical for a given count).
    pub threads: usize,
    /// The simulation state.
    pub simulation: Simulation,
    /// Time-series rows so far.
    pub rows: Vec<Observables>,
    /// Snapshots so far: `(time, file name)`.
    pub snapshots: Vec<(f64, String)>,
    /// Wall-clock seconds spent stepping, over all sessions.
    pub wall_seconds: f64,
    /// Coarse-grained fields averaged on the fly (`[fields]`); absent from checkpoints
    /// written before they existed.
    #[serde(default)]
    pub fields: Option<BoxFields>,
    /// Step of the last checkpoint written or read by this process.
    #[serde(skip)]
    checkpointed: Option<u64>,
    /// The lock on the run directory, held while this run is alive.
    #[serde(skip)]
    lock: Option<Arc<DirLock>>,
}

/// The JSON summary.
#[derive(Serialize)]
struct Summary<'a> {
    program: &'static str,
    version: &'static str,
    commit: &'static str,
    seed: u64,
    status: Status,
    steps_done: u64,
    steps_total: u64,
    time: f64,
    wall_seconds: f64,
    particle_steps_per_second: f64,
    threads: usize,
    neighbor_builds: u64,
    resolved: &'a Resolved,
    last: Option<&'a Observables>,
    last_checkpoint_step: Option<u64>,
    error: Option<String>,
}

/// Header of checkpoint files (format 3): these 8 bytes, the CRC-32 of the body (4 bytes,
/// little endian), then the body: MessagePack with named fields, so a checkpoint stays
/// readable when later versions add fields (with defaults) to the state.
const CHECKPOINT_MAGIC: &[u8; 8] = b"RHEODEM3";
/// Headers of earlier checkpoint formats, recognised to say so.
const OLD_MAGICS: [&[u8; 8]; 1] = [b"RHEODEM2"];

/// An I/O error naming `operation` and `path`.
pub fn io_err<'a>(
    operation: &'static str,
    path: &'a Path,
) -> impl FnOnce(std::io::Error) -> RunError + 'a {
    move |source| RunError::Io {
        operation,
        path: path.to_path_buf(),
        source,
    }
}

/// Takes the lock of the run directory `dir` (creating it if needed), without waiting:
/// [`RunError::Busy`] if another process holds it.
pub fn lock(dir: &Path) -> Result<Arc<DirLock>, RunError> {
    std::fs::create_dir_all(dir).map_err(io_err("create the directory", dir))?;
    match DirLock::try_acquire(dir) {
        Ok(l) => {
            // With the lock held, no other writer is left: a temporary here was left by a
            // killed one.
            crate::io::atomic::remove_stale_temporaries(dir)
                .map_err(io_err("remove stale temporaries in", dir))?;
            Ok(Arc::new(l))
        }
        Err(LockError::Busy(d)) => Err(RunError::Busy(d)),
        Err(LockError::Io { path, source }) => Err(RunError::Io {
            operation: "lock",
            path,
            source,
        }),
    }
}

/// The checkpoint file's bytes for `body`.
fn checkpoint_bytes(body: &[u8]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(body.len() + 12);
    bytes.extend_from_slice(CHECKPOINT_MAGIC);
    bytes.extend_from_slice(&crc32fast::hash(body).to_le_bytes());
    bytes.extend_from_slice(body);
    bytes
}

/// Writes `state` atomically as a checkpoint file (header, CRC-32, MessagePack of the
/// program version and the state).
pub fn write_checkpoint<T: Serialize>(path: &Path, state: &T) -> Result<(), RunError> {
    let body =
        rmp_serde::to_vec_named(&(crate::VERSION, state)).map_err(|e| RunError::Checkpoint {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
    write_atomic(path, &checkpoint_bytes(&body)).map_err(io_err("write", path))
}

/// Reads a checkpoint file written by [`write_checkpoint`] in this checkpoint format (the
/// header) by this program version or an earlier one: the state's fields are named, and
/// fields added since take their defaults (docs/compatibility.md). A checkpoint of a newer
/// version is refused before its state is read, since fields this version does not know
/// would be dropped.
pub fn read_checkpoint<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, RunError> {
    let bytes = std::fs::read(path).map_err(io_err("read", path))?;
    let bad = |reason: String| RunError::Checkpoint {
        path: path.to_path_buf(),
        reason,
    };
    let body = checkpoint_body(&bytes).map_err(bad)?;
    let (version, _): (String, serde::de::IgnoredAny) =
        rmp_serde::from_slice(body).map_err(|e| bad(e.to_string()))?;
    if !readable_version(&version) {
        return Err(bad(format!(
            "written by rheodem {version}, newer than this rheodem {}: resume it with that \
             version or a later one",
            crate::VERSION
        )));
    }
    let (_, state): (String, T) = rmp_serde::from_slice(body).map_err(|e| bad(e.to_string()))?;
    Ok(state)
}

/// Whether a checkpoint body written by program `version` (`major.minor.patch`) may be
/// read here: not newer than [`crate::VERSION`].
fn readable_version(version: &str) -> bool {
    let parse = |v: &str| -> Option<Vec<u64>> {
        let core = v.split(['-', '+']).next()?;
        let parts: Option<Vec<u64>> = core.split('.').map(|x| x.parse().ok()).collect();
        parts.filter(|p| p.len() == 3)
    };
    matches!((parse(version), parse(crate::VERSION)), (Some(a), Some(b)) if a <= b)
}

/// The verified body of a checkpoint file, or why it is unusable.
fn checkpoint_body(bytes: &[u8]) -> Result<&[u8], String> {
    if let Some(rest) = bytes.strip_prefix(CHECKPOINT_MAGIC.as_slice()) {
        let (sum, body) = rest
            .split_first_chunk::<4>()
            .ok_or("truncated after its header")?;
        let (stored, actual) = (u32::from_le_bytes(*sum), crc32fast::hash(body));
        if stored != actual {
            return Err(format!(
                "checksum mismatch (stored {stored:08x}, computed {actual:08x}): the file is \
                 damaged; start the run over, or restore the file from a backup"
            ));
        }
        return Ok(body);
    }
    if OLD_MAGICS.iter().any(|m| bytes.starts_with(m.as_slice())) {
        return Err(format!(
            "written in an earlier checkpoint format ({}); this rheodem reads format {} \
             only: start the run over",
            String::from_utf8_lossy(&bytes[..8]),
            String::from_utf8_lossy(CHECKPOINT_MAGIC)
        ));
    }
    Err("missing rheodem checkpoint header".into())
}

impl Run {
    /// Builds the scenario (relative paths from `base_dir`) and creates the run directory
    /// `dir`, refusing one that already holds a run unless `force` (which also removes the
    /// old run's snapshots). The directory stays locked against other processes while the
    /// returned run lives.
    pub fn start(
        scenario: Scenario,
        base_dir: &Path,
        dir: &Path,
        threads: usize,
        force: bool,
    ) -> Result<Run, RunError> {
        let existed = dir.exists();
        let lock = lock(dir)?;
        Run::start_locked(lock, existed, scenario, base_dir, dir, threads, force)
    }

    /// [`Run::start`] in a directory whose `lock` the caller holds; `existed` says whether
    /// the directory was there before (a failed start removes a directory it created).
    pub fn start_locked(
        lock: Arc<DirLock>,
        existed: bool,
        scenario: Scenario,
        base_dir: &Path,
        dir: &Path,
        threads: usize,
        force: bool,
    ) -> Result<Run, RunError> {
        if dir.join("checkpoint.bin").exists() && !force {
            return Err(RunError::Exists(dir.to_path_buf()));
        }
        // Marked before the preparation, so that a directory killed during it says what it
        // is.
        let marker = dir.join(made_by::FILE);
        made_by::mark(dir, Maker::Run).map_err(io_err("write", &marker))?;
        let built = match build(&scenario, base_dir) {
            Ok(b) => b,
            Err(e) => {
                if !existed {
                    drop(lock);
                    let _ = std::fs::remove_dir_all(dir);
                }
                return Err(e.into());
            }
        };
        let snapshots = dir.join("snapshots");
        remove_snapshots(&snapshots)?;
        samples::remove_all(dir)?;
        std::fs::create_dir_all(&snapshots).map_err(io_err("create the directory", &snapshots))?;
        let steps = built.resolved.steps;
        let plan = OutputPlan {
            steps,
            timeseries_every: OutputPlan::every(steps, scenario.output.timeseries_rows),
            snapshot_every: OutputPlan::every(steps, scenario.output.snapshots),
            checkpoint_every: OutputPlan::every(steps, scenario.output.checkpoints),
        };
        // Checked by `build`.
        let fields = scenario.fields.as_ref().map(BoxFields::new).transpose()?;
        let mut run = Run {
            scenario,
            resolved: built.resolved,
            plan,
            threads,
            simulation: built.simulation,
            rows: Vec::new(),
            snapshots: Vec::new(),
            wall_seconds: 0.0,
            fields,
            checkpointed: None,
            lock: Some(lock),
        };
        let header = format!(
            "# rheodem {} (commit {}) — scenario as run, every default written out; seed {}\n",
            crate::VERSION,
            crate::COMMIT,
            run.scenario.seed
        );
        let path = dir.join("scenario.toml");
        write_atomic(&path, (header + &run.scenario.to_toml()).as_bytes())
            .map_err(io_err("write", &path))?;
        let path = dir.join("resolved.json");
        let json = serde_json::to_string_pretty(&run.resolved).unwrap_or_default();
        write_atomic(&path, json.as_bytes()).map_err(io_err("write", &path))?;
        run.guard(dir, |run| run.record(dir))?;
        run.checkpoint(dir, Status::Running)?;
        Ok(run)
    }

    /// Loads the checkpoint of the run directory `dir`, after taking the directory's lock
    /// (so that a checkpoint is never read while another process advances it).
    pub fn resume(dir: &Path) -> Result<Run, RunError> {
        let path = dir.join("checkpoint.bin");
        if !path.exists() {
            return Err(RunError::Checkpoint {
                path,
                reason: "no such file: this directory holds no rheodem run".into(),
            });
        }
        Run::resume_locked(lock(dir)?, dir)
    }

    /// [`Run::resume`] of a directory whose `lock` the caller holds.
    pub fn resume_locked(lock: Arc<DirLock>, dir: &Path) -> Result<Run, RunError> {
        let mut state: Run = read_checkpoint(&dir.join("checkpoint.bin"))?;
        state.checkpointed = Some(state.simulation.step);
        state.lock = Some(lock);
        Ok(state)
    }

    /// Whether every step has been taken.
    pub fn is_complete(&self) -> bool {
        self.simulation.step >= self.plan.steps
    }

    /// Steps until the end, reporting progress `(done, total)` after every step and writing
    /// outputs and checkpoints on their cadence; ends with a final checkpoint and summary.
    pub fn advance(
        &mut self,
        dir: &Path,
        mut progress: impl FnMut(u64, u64),
    ) -> Result<(), RunError> {
        self.advance_until(dir, self.plan.steps, &mut progress)
    }

    /// Like [`Run::advance`] but stops after step `stop` (used to test resumption). A run
    /// already complete only rewrites its outputs (repairing a summary that a kill left
    /// saying "running"). On an error the summary says "failed" and why.
    pub fn advance_until(
        &mut self,
        dir: &Path,
        stop: u64,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<(), RunError> {
        if self.is_complete() {
            return self.write_outputs(dir, Status::Completed, None);
        }
        let stop = stop.min(self.plan.steps);
        self.guard(dir, |run| run.steps_until(dir, stop, progress))
    }

    /// Runs `f`; if it fails, records the failure in the summary before passing it on.
    fn guard(
        &mut self,
        dir: &Path,
        f: impl FnOnce(&mut Run) -> Result<(), RunError>,
    ) -> Result<(), RunError> {
        let outcome = f(self);
        if let Err(e) = &outcome {
            // The error itself matters more than a summary that cannot be written.
            let _ = self.write_summary(dir, Status::Failed, Some(e.to_string()));
        }
        outcome
    }

    fn steps_until(
        &mut self,
        dir: &Path,
        stop: u64,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<(), RunError> {
        let mut clock = Instant::now();
        while self.simulation.step < stop {
            let next = self.simulation.step + 1;
            let row = OutputPlan::due(self.plan.timeseries_every, next) || next == self.plan.steps;
            let end = self.simulation.time + self.simulation.dt;
            if row && self.fields.as_ref().is_some_and(|f| f.wants(end)) {
                let contacts = self.simulation.step_with::<ContactRecords>()?;
                let fields = self.fields.as_mut().expect("checked");
                let view = cg::periodic::LabView::of(&self.simulation);
                if fields.spec.records {
                    samples::write(dir, &view, &contacts.0)?;
                }
                fields.add(&view, &contacts.0)?;
            } else {
                self.simulation.step(row)?;
            }
            if row {
                self.record(dir)?;
            } else if OutputPlan::due(self.plan.snapshot_every, next) {
                self.snapshot(dir)?;
            }
            if OutputPlan::due(self.plan.checkpoint_every, next) || next == self.plan.steps {
                self.wall_seconds += clock.elapsed().as_secs_f64();
                clock = Instant::now();
                let status = if next == self.plan.steps {
                    Status::Completed
                } else {
                    Status::Running
                };
                // Never checkpoint a state that is not sane.
                self.sane()?;
                self.checkpoint(dir, status)?;
            }
            progress(next, self.plan.steps);
        }
        self.wall_seconds += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// The current state's sanity as a run error.
    fn sane(&self) -> Result<(), RunError> {
        self.simulation
            .check_sanity()
            .map_err(|cause| RunError::Unstable {
                step: self.simulation.step,
                time: self.simulation.time,
                cause,
                checkpoint: self.checkpointed,
            })
    }

    /// Appends a time-series row for the current (measured) state, and a snapshot if due.
    fn record(&mut self, dir: &Path) -> Result<(), RunError> {
        self.sane()?;
        let row = self.simulation.observables();
        if !row.is_finite() {
            return Err(RunError::Unstable {
                step: row.step,
                time: row.time,
                cause: Instability::NonFiniteMeasurement,
                checkpoint: self.checkpointed,
            });
        }
        self.rows.push(row);
        if OutputPlan::due(self.plan.snapshot_every, self.simulation.step) {
            self.snapshot(dir)?;
        }
        Ok(())
    }

    fn snapshot(&mut self, dir: &Path) -> Result<(), RunError> {
        let name = format!("snapshots/particles_{:010}.vtp", self.simulation.step);
        let path = dir.join(&name);
        write_atomic(
            &path,
            vtk::particles_vtp(&self.simulation.particles, &[]).as_bytes(),
        )
        .map_err(io_err("write", &path))?;
        self.snapshots.push((self.simulation.time, name));
        Ok(())
    }

    /// Writes the checkpoint, then the time series, snapshot collection and summary.
    fn checkpoint(&mut self, dir: &Path, status: Status) -> Result<(), RunError> {
        write_checkpoint(&dir.join("checkpoint.bin"), &*self)?;
        self.checkpointed = Some(self.simulation.step);
        self.write_outputs(dir, status, None)
    }

    /// Writes the time series, snapshot collection and summary of the state in memory.
    fn write_outputs(
        &self,
        dir: &Path,
        status: Status,
        error: Option<String>,
    ) -> Result<(), RunError> {
        let path = dir.join("timeseries.csv");
        write_atomic(&path, timeseries::to_csv(&self.rows).as_bytes())
            .map_err(io_err("write", &path))?;
        let path = dir.join("snapshots.pvd");
        write_atomic(&path, vtk::collection_pvd(&self.snapshots).as_bytes())
            .map_err(io_err("write", &path))?;
        if let Some(fields) = &self.fields {
            write_fields(fields, dir)?;
        }
        self.write_summary(dir, status, error)
    }

    fn write_summary(
        &self,
        dir: &Path,
        status: Status,
        error: Option<String>,
    ) -> Result<(), RunError> {
        let done = self.simulation.step;
        let summary = Summary {
            program: "rheodem",
            version: crate::VERSION,
            commit: crate::COMMIT,
            seed: self.scenario.seed,
            status,
            steps_done: done,
            steps_total: self.plan.steps,
            time: self.simulation.time,
            wall_seconds: self.wall_seconds,
            particle_steps_per_second: if self.wall_seconds > 0.0 {
                done as f64 * self.simulation.particles.len() as f64 / self.wall_seconds
            } else {
                0.0
            },
            threads: self.threads,
            neighbor_builds: self.simulation.neighbors.builds,
            resolved: &self.resolved,
            last: self.rows.last(),
            last_checkpoint_step: self.checkpointed,
            error,
        };
        let path = dir.join("summary.json");
        let json = serde_json::to_string_pretty(&summary).unwrap_or_default();
        write_atomic(&path, json.as_bytes()).map_err(io_err("write", &path))
    }
}

/// Writes the time-averaged `fields` as `fields.csv` and `fields.vti` into `dir`; nothing
/// before their first sample.
///
/// # Errors
/// [`RunError::Io`] when a file cannot be written.
pub fn write_fields(fields: &BoxFields, dir: &Path) -> Result<(), RunError> {
    if let Some((grid, points)) = fields.points() {
        let path = dir.join("fields.csv");
        write_atomic(&path, cg::output::to_csv(grid, &points).as_bytes())
            .map_err(io_err("write", &path))?;
        let path = dir.join("fields.vti");
        write_atomic(&path, cg::output::to_vti(grid, &points).as_bytes())
            .map_err(io_err("write", &path))?;
    }
    Ok(())
}

/// Removes the snapshot files (`particles_*.vtp`) of an earlier run from `snapshots`.
fn remove_snapshots(snapshots: &Path) -> Result<(), RunError> {
    let Ok(entries) = std::fs::read_dir(snapshots) else {
        return Ok(());
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if name.starts_with("particles_") && name.ends_with(".vtp") {
            std::fs::remove_file(&path).map_err(io_err("remove", &path))?;
        }
    }
    Ok(())
}

/// Checkpoints carry the scenario as TOML text: the binary format cannot hold its
/// internally tagged enums.
mod scenario_text {
    use crate::scenario::Scenario;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(s: &Scenario, ser: S) -> Result<S::Ok, S::Error> {
        ser.serialize_str(&s.to_toml())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(de: D) -> Result<Scenario, D::Error> {
        let text = String::deserialize(de)?;
        Scenario::from_toml(&text).map_err(serde::de::Error::custom)
    }
}
