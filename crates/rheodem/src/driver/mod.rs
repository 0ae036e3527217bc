//! The staged run driver: what every set-up's run shares, written once.
//!
//! A set-up (a scenario file's run, the shear box, the split-bottom cell) is a state that
//! implements [`SetUp`]: its stages, the operations each step triggers (time-series rows,
//! samples of fields and profiles, snapshots, stage changes) and its outputs. The
//! [`Driver`] owns the rest:
//! - the run directory: its lock against other processes, its `made-by` marker, the
//!   refusal to overwrite a run without `force`, the removal of a directory a failed start
//!   created;
//! - the step loop: the step each set-up asks for (measured or not, with its contact
//!   records or not), stopping at a step, at the end of the current stage or at the end;
//! - checkpoints on the set-up's cadence, never of a state that fails its sanity checks,
//!   and resumption from the last one ([`checkpoint`]: header, CRC-32, version);
//! - the wall clock, progress reports and `summary.json`: the set-up's summary with the
//!   run's status, version, commit, last checkpoint and, after a failure, the error and
//!   where it happened.
//!
//! Every file is written atomically ([`crate::io::atomic`]).

pub mod checkpoint;
pub mod error;
pub mod trigger;

pub use checkpoint::{read_checkpoint, write_checkpoint};
pub use error::{RunError, io_err};
pub use trigger::Every;

use crate::Simulation;
use crate::cg::{ContactRecord, ContactRecords};
use crate::io::atomic::write_atomic;
use crate::io::lock::{DirLock, LockError};
use crate::io::made_by::{self, Maker};
use crate::sanity::Instability;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::ops::{Deref, DerefMut};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

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

/// Where a run stands, for progress reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    /// Name of the current stage (`"run"`, `"settle"`, `"shear"`, …).
    pub stage: &'static str,
    /// Steps done in the stage.
    pub done: u64,
    /// Steps of the stage (for an open-ended stage, its step limit).
    pub total: u64,
}

/// What the next step must compute.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepNeeds {
    /// The step's observers measure (pressure tensor, loads, contact statistics).
    pub measure: bool,
    /// The step returns its contact records (implies measuring).
    pub contacts: bool,
}

/// What a set-up supplies to the [`Driver`]: its state (serialised whole as the
/// checkpoint), its stages, the operations each step triggers and its outputs.
pub trait SetUp: Serialize + DeserializeOwned {
    /// The command family whose marker the run directory carries.
    const MAKER: Maker;
    /// The simulation state.
    fn simulation(&self) -> &Simulation;
    /// The simulation state, to step it.
    fn simulation_mut(&mut self) -> &mut Simulation;
    /// Whether every stage has ended.
    fn is_complete(&self) -> bool;
    /// The current stage and the steps done in it.
    fn progress(&self) -> Progress;
    /// What the next step must compute.
    fn needs(&self) -> StepNeeds;
    /// The operations fired by the step just taken (`contacts`: its records, when
    /// [`StepNeeds::contacts`] asked for them): rows, samples, snapshots, stage changes.
    /// Returns whether a checkpoint is due.
    ///
    /// # Errors
    /// [`RunError`] when an operation fails (an unstable state, a file not written).
    fn after_step(
        &mut self,
        session: &mut Session<'_>,
        contacts: Option<&[ContactRecord]>,
    ) -> Result<bool, RunError>;
    /// Wall-clock seconds spent stepping, over all sessions (kept in the state).
    fn wall_seconds_mut(&mut self) -> &mut f64;
    /// Writes the set-up's outputs (time series, fields, figures) into `dir` and returns
    /// its summary, a JSON object.
    ///
    /// # Errors
    /// [`RunError::Io`] when a file cannot be written.
    fn write_outputs(&self, dir: &Path) -> Result<serde_json::Value, RunError>;
    /// The summary without writing anything (after a failure).
    fn summary(&self) -> serde_json::Value;
}

/// What a set-up's operations may ask of the driver during a step.
pub struct Session<'a> {
    /// The run directory.
    pub dir: &'a Path,
    /// Step of the last checkpoint on disk, if any.
    checkpointed: Option<u64>,
    /// Start of the wall-clock interval not yet added to the state.
    clock: Instant,
}

impl Session<'_> {
    /// Wall-clock seconds since the last lap (or the start), restarting the clock.
    pub fn lap(&mut self) -> f64 {
        let s = self.clock.elapsed().as_secs_f64();
        self.clock = Instant::now();
        s
    }

    /// An instability of `sim`'s current state as a run error, naming the last checkpoint.
    pub fn unstable(&self, sim: &Simulation, cause: Instability) -> RunError {
        RunError::Unstable {
            step: sim.step,
            time: sim.time,
            cause,
            checkpoint: self.checkpointed,
        }
    }

    /// `sim`'s sanity checks as a run error.
    ///
    /// # Errors
    /// [`RunError::Unstable`] when the state fails them.
    pub fn sane(&self, sim: &Simulation) -> Result<(), RunError> {
        sim.check_sanity()
            .map_err(|cause| self.unstable(sim, cause))
    }

    /// Writes `state` as a checkpoint file `name` of the run directory (e.g. the settled
    /// state a later run starts from).
    ///
    /// # Errors
    /// [`RunError`] when it cannot be written.
    pub fn save_state<T: Serialize>(&self, name: &str, state: &T) -> Result<(), RunError> {
        write_checkpoint(&self.dir.join(name), state)
    }
}

/// Takes the lock of the run directory `dir` (creating it if needed), without waiting:
/// [`RunError::Busy`] if another process holds it.
///
/// # Errors
/// [`RunError::Busy`], or [`RunError::Io`] when the directory or lock cannot be made.
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

/// The checkpoint file of a run directory.
pub const CHECKPOINT: &str = "checkpoint.bin";

/// A set-up's run in its directory: the state, and the lock held while it lives.
/// Dereferences to the state.
pub struct Driver<S> {
    state: S,
    /// Step of the last checkpoint written or read by this process.
    checkpointed: Option<u64>,
    /// The lock on the run directory.
    _lock: Arc<DirLock>,
}

impl<S: std::fmt::Debug> std::fmt::Debug for Driver<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Driver")
            .field("state", &self.state)
            .field("checkpointed", &self.checkpointed)
            .finish_non_exhaustive()
    }
}

impl<S> Deref for Driver<S> {
    type Target = S;
    fn deref(&self) -> &S {
        &self.state
    }
}

impl<S> DerefMut for Driver<S> {
    fn deref_mut(&mut self) -> &mut S {
        &mut self.state
    }
}

impl<S: SetUp> Driver<S> {
    /// Starts a run in `dir`: takes its lock, refuses a directory that holds a run unless
    /// `force`, marks it, builds the state with `build` (which may write the set-up's input
    /// files into the directory) and writes the first checkpoint. A failed start removes a
    /// directory it created, and records the failure in the summary of one that existed.
    ///
    /// # Errors
    /// [`RunError::Exists`], [`RunError::Busy`], or the error of `build` or the checkpoint.
    pub fn create(
        dir: &Path,
        force: bool,
        build: impl FnOnce(&mut Session<'_>) -> Result<S, RunError>,
    ) -> Result<Driver<S>, RunError> {
        let existed = dir.exists();
        Driver::create_locked(lock(dir)?, existed, dir, force, build)
    }

    /// [`Driver::create`] in a directory whose `lock` the caller holds; `existed` says
    /// whether the directory was there before.
    ///
    /// # Errors
    /// As [`Driver::create`].
    pub fn create_locked(
        lock: Arc<DirLock>,
        existed: bool,
        dir: &Path,
        force: bool,
        build: impl FnOnce(&mut Session<'_>) -> Result<S, RunError>,
    ) -> Result<Driver<S>, RunError> {
        if dir.join(CHECKPOINT).exists() && !force {
            return Err(RunError::Exists(dir.to_path_buf()));
        }
        // Marked before the preparation, so that a directory killed during it says what it
        // is.
        let marker = dir.join(made_by::FILE);
        made_by::mark(dir, S::MAKER).map_err(io_err("write", &marker))?;
        let mut session = Session {
            dir,
            checkpointed: None,
            clock: Instant::now(),
        };
        let state = match build(&mut session) {
            Ok(s) => s,
            Err(e) => {
                if existed {
                    // The error itself matters more than a summary that cannot be written.
                    let _ = write_failure_alone(dir, &e);
                } else {
                    drop(lock);
                    let _ = std::fs::remove_dir_all(dir);
                }
                return Err(e);
            }
        };
        let mut run = Driver {
            state,
            checkpointed: None,
            _lock: lock,
        };
        run.guard(dir, |run| run.checkpoint(dir))?;
        Ok(run)
    }

    /// Loads the checkpoint of the run directory `dir`, after taking the directory's lock
    /// (so that a checkpoint is never read while another process advances it).
    ///
    /// # Errors
    /// [`RunError::Checkpoint`] when there is none or it is unusable, [`RunError::Busy`].
    pub fn resume(dir: &Path) -> Result<Driver<S>, RunError> {
        let path = dir.join(CHECKPOINT);
        if !path.exists() {
            return Err(RunError::Checkpoint {
                path,
                reason: "no such file: this directory holds no rheodem run".into(),
            });
        }
        Driver::resume_locked(lock(dir)?, dir)
    }

    /// [`Driver::resume`] of a directory whose `lock` the caller holds.
    ///
    /// # Errors
    /// [`RunError::Checkpoint`] when the checkpoint is missing or unusable.
    pub fn resume_locked(lock: Arc<DirLock>, dir: &Path) -> Result<Driver<S>, RunError> {
        let state: S = read_checkpoint(&dir.join(CHECKPOINT))?;
        Ok(Driver {
            checkpointed: Some(state.simulation().step),
            state,
            _lock: lock,
        })
    }

    /// Whether every stage has ended.
    pub fn is_complete(&self) -> bool {
        self.state.is_complete()
    }

    /// The state, giving up the directory's lock.
    pub fn into_state(self) -> S {
        self.state
    }

    /// Runs every remaining stage, reporting progress after every step. A run already
    /// complete only rewrites its outputs (repairing a summary that a kill left saying
    /// "running"). On an error the summary says "failed", why and where.
    ///
    /// # Errors
    /// The first [`RunError`] of a step, an operation or an output.
    pub fn advance(
        &mut self,
        dir: &Path,
        mut progress: impl FnMut(Progress),
    ) -> Result<(), RunError> {
        self.advance_until(dir, u64::MAX, &mut progress)
    }

    /// Like [`Driver::advance`] but stops after step `stop` (counted from the start of
    /// the simulation; used to test resumption).
    ///
    /// # Errors
    /// As [`Driver::advance`].
    pub fn advance_until(
        &mut self,
        dir: &Path,
        stop: u64,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<(), RunError> {
        self.run_steps(dir, stop, false, progress)
    }

    /// Runs the current stage to its end, so that a caller can report between stages.
    ///
    /// # Errors
    /// As [`Driver::advance`].
    pub fn advance_stage(
        &mut self,
        dir: &Path,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<(), RunError> {
        self.run_steps(dir, u64::MAX, true, progress)
    }

    fn run_steps(
        &mut self,
        dir: &Path,
        stop: u64,
        one_stage: bool,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<(), RunError> {
        if self.state.is_complete() {
            return self.write_outputs(dir, Status::Completed);
        }
        self.guard(dir, |run| run.steps(dir, stop, one_stage, progress))
    }

    /// Runs `f`; if it fails, records the failure in the summary before passing it on.
    fn guard(
        &mut self,
        dir: &Path,
        f: impl FnOnce(&mut Driver<S>) -> Result<(), RunError>,
    ) -> Result<(), RunError> {
        let outcome = f(self);
        if let Err(e) = &outcome {
            // The error itself matters more than a summary that cannot be written.
            let mut summary = self.state.summary();
            let at = self.state.progress();
            summary["failed_at"] = serde_json::json!({
                "stage": at.stage,
                "time": self.state.simulation().time,
                "steps": self.state.simulation().step,
            });
            let _ = self.write_summary(dir, summary, Status::Failed, Some(e.to_string()));
        }
        outcome
    }

    fn steps(
        &mut self,
        dir: &Path,
        stop: u64,
        one_stage: bool,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<(), RunError> {
        let mut session = Session {
            dir,
            checkpointed: self.checkpointed,
            clock: Instant::now(),
        };
        let first = self.state.progress().stage;
        while !self.state.is_complete()
            && self.state.simulation().step < stop
            && !(one_stage && self.state.progress().stage != first)
        {
            let needs = self.state.needs();
            let sim = self.state.simulation_mut();
            let contacts = if needs.contacts {
                Some(sim.step_with::<ContactRecords>()?.0)
            } else {
                sim.step(needs.measure)?;
                None
            };
            if self.state.after_step(&mut session, contacts.as_deref())? {
                *self.state.wall_seconds_mut() += session.lap();
                // Never checkpoint a state that is not sane.
                session.sane(self.state.simulation())?;
                self.checkpoint(dir)?;
                session.checkpointed = self.checkpointed;
            }
            progress(self.state.progress());
        }
        *self.state.wall_seconds_mut() += session.lap();
        Ok(())
    }

    /// Writes the checkpoint, then the outputs and the summary.
    fn checkpoint(&mut self, dir: &Path) -> Result<(), RunError> {
        write_checkpoint(&dir.join(CHECKPOINT), &self.state)?;
        self.checkpointed = Some(self.state.simulation().step);
        let status = if self.state.is_complete() {
            Status::Completed
        } else {
            Status::Running
        };
        self.write_outputs(dir, status)
    }

    /// Writes the set-up's outputs and the summary of the state in memory.
    fn write_outputs(&self, dir: &Path, status: Status) -> Result<(), RunError> {
        let summary = self.state.write_outputs(dir)?;
        self.write_summary(dir, summary, status, None)
    }

    fn write_summary(
        &self,
        dir: &Path,
        mut summary: serde_json::Value,
        status: Status,
        error: Option<String>,
    ) -> Result<(), RunError> {
        summary["version"] = crate::VERSION.into();
        summary["commit"] = crate::COMMIT.into();
        summary["status"] = serde_json::to_value(status).unwrap_or_default();
        summary["last_checkpoint_step"] = self.checkpointed.into();
        summary["error"] = error.into();
        let path = dir.join("summary.json");
        let json = serde_json::to_string_pretty(&summary).unwrap_or_default();
        write_atomic(&path, json.as_bytes()).map_err(io_err("write", &path))
    }
}

/// The `summary.json` of the run directory `dir`, as the driver last wrote it.
///
/// # Errors
/// [`RunError::Io`] when it cannot be read or is not JSON.
pub fn read_summary(dir: &Path) -> Result<serde_json::Value, RunError> {
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(io_err("read", &path))?;
    serde_json::from_str(&text).map_err(|e| RunError::Io {
        operation: "parse",
        path: path.clone(),
        source: e.into(),
    })
}

/// Records a failure before any state existed: the summary already in `dir` (or a new
/// one) with `"status": "failed"`, the error and `"failed_at": "start"`.
fn write_failure_alone(dir: &Path, error: &RunError) -> Result<(), RunError> {
    let path = dir.join("summary.json");
    let mut summary = std::fs::read_to_string(&path)
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .filter(|v| v.is_object())
        .unwrap_or_else(|| {
            serde_json::json!({
                "program": "rheodem",
                "version": crate::VERSION,
                "commit": crate::COMMIT,
            })
        });
    summary["status"] = "failed".into();
    summary["error"] = error.to_string().into();
    summary["failed_at"] = "start".into();
    let text = serde_json::to_string_pretty(&summary).unwrap_or_default();
    write_atomic(&path, text.as_bytes()).map_err(io_err("write", &path))
}
