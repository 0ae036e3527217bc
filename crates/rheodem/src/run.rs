//! A run on disk: its directory, outputs, checkpoints and resumption.
//!
//! A run directory holds
//! - `scenario.toml`: the scenario with every default written out, headed by the program
//!   version and seed;
//! - `resolved.json`: the derived values (time step, contact time, particle counts, radius
//!   distribution, preparation outcome, version, seed);
//! - `timeseries.csv`: one row of observables every `T/timeseries_rows`;
//! - `snapshots/*.vtp` and `snapshots.pvd`: particle snapshots for ParaView;
//! - `checkpoint.bin`: the complete state at the last checkpoint;
//! - `summary.json`: status, progress, final observables.
//!
//! Every file is written atomically (see [`crate::io::atomic`]).

use crate::Simulation;
use crate::io::atomic::write_atomic;
use crate::io::{timeseries, vtk};
use crate::measure::Observables;
use crate::neighbor::NeighborError;
use crate::scenario::{Resolved, Scenario, ScenarioError, build};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Errors of a run.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scenario is invalid.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// A file could not be written or read.
    #[error("{path}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The checkpoint is unreadable or from another version.
    #[error("{path}: not a usable checkpoint: {reason}")]
    Checkpoint {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// The run directory already holds a run.
    #[error(
        "{0} already holds a run: resume it with `rheodem resume {0}`, or pass --force to start over"
    )]
    Exists(PathBuf),
    /// The run directory holds a run of another scenario than the one asked for.
    #[error(
        "{0} holds a run of different parameters than this point (changed since it started?): \
         remove the directory to start the point over"
    )]
    Mismatch(PathBuf),
    /// The state stopped being finite numbers.
    #[error(
        "the simulation blew up at step {step} (t = {time:e} s): non-finite energy or stress; \
         the last checkpoint before it is kept. Usual causes: a time step too large for the \
         stiffest contact (`run.dt`), or a prescribed motion or force far beyond the contact \
         stiffness"
    )]
    Diverged {
        /// Step of the first non-finite row.
        step: u64,
        /// Simulated time of that row (s).
        time: f64,
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
}

/// Header of checkpoint files. The body is MessagePack with named fields, so a checkpoint
/// stays readable when later versions add fields (with defaults) to the state.
const CHECKPOINT_MAGIC: &[u8; 8] = b"RHEODEM2";

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> RunError + '_ {
    move |source| RunError::Io {
        path: path.to_path_buf(),
        source,
    }
}

impl Run {
    /// Builds the scenario (relative paths from `base_dir`) and creates the run directory
    /// `dir`, refusing one that already holds a run unless `force`.
    pub fn start(
        scenario: Scenario,
        base_dir: &Path,
        dir: &Path,
        threads: usize,
        force: bool,
    ) -> Result<Run, RunError> {
        if dir.join("checkpoint.bin").exists() && !force {
            return Err(RunError::Exists(dir.to_path_buf()));
        }
        let built = build(&scenario, base_dir)?;
        std::fs::create_dir_all(dir.join("snapshots")).map_err(io_err(dir))?;
        let steps = built.resolved.steps;
        let plan = OutputPlan {
            steps,
            timeseries_every: OutputPlan::every(steps, scenario.output.timeseries_rows),
            snapshot_every: OutputPlan::every(steps, scenario.output.snapshots),
            checkpoint_every: OutputPlan::every(steps, scenario.output.checkpoints),
        };
        let mut run = Run {
            scenario,
            resolved: built.resolved,
            plan,
            threads,
            simulation: built.simulation,
            rows: Vec::new(),
            snapshots: Vec::new(),
            wall_seconds: 0.0,
        };
        let header = format!(
            "# rheodem {} (commit {}) — scenario as run, every default written out; seed {}\n",
            crate::VERSION,
            crate::COMMIT,
            run.scenario.seed
        );
        let path = dir.join("scenario.toml");
        write_atomic(&path, (header + &run.scenario.to_toml()).as_bytes())
            .map_err(io_err(&path))?;
        let path = dir.join("resolved.json");
        let json = serde_json::to_string_pretty(&run.resolved).unwrap_or_default();
        write_atomic(&path, json.as_bytes()).map_err(io_err(&path))?;
        run.record(dir)?;
        run.checkpoint(dir, Status::Running)?;
        Ok(run)
    }

    /// Loads the checkpoint of the run directory `dir`.
    pub fn resume(dir: &Path) -> Result<Run, RunError> {
        let path = dir.join("checkpoint.bin");
        let bytes = std::fs::read(&path).map_err(io_err(&path))?;
        let bad = |reason: String| RunError::Checkpoint {
            path: path.clone(),
            reason,
        };
        let body = bytes
            .strip_prefix(CHECKPOINT_MAGIC.as_slice())
            .ok_or_else(|| bad("missing rheodem checkpoint header".into()))?;
        let (version, state): (String, Run) =
            rmp_serde::from_slice(body).map_err(|e| bad(e.to_string()))?;
        if version != crate::VERSION {
            return Err(bad(format!(
                "written by rheodem {version}, this is {}",
                crate::VERSION
            )));
        }
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

    /// Like [`Run::advance`] but stops after step `stop` (used to test resumption).
    pub fn advance_until(
        &mut self,
        dir: &Path,
        stop: u64,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<(), RunError> {
        let stop = stop.min(self.plan.steps);
        let mut clock = Instant::now();
        while self.simulation.step < stop {
            let next = self.simulation.step + 1;
            let row = OutputPlan::due(self.plan.timeseries_every, next) || next == self.plan.steps;
            self.simulation.step(row)?;
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
                if !self.simulation.particles.is_finite() {
                    return Err(RunError::Diverged {
                        step: next,
                        time: self.simulation.time,
                    });
                }
                self.checkpoint(dir, status)?;
            }
            progress(next, self.plan.steps);
        }
        self.wall_seconds += clock.elapsed().as_secs_f64();
        Ok(())
    }

    /// Appends a time-series row for the current (measured) state, and a snapshot if due.
    fn record(&mut self, dir: &Path) -> Result<(), RunError> {
        let row = self.simulation.observables();
        if !row.is_finite() {
            return Err(RunError::Diverged {
                step: row.step,
                time: row.time,
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
            vtk::particles_vtp(&self.simulation.particles).as_bytes(),
        )
        .map_err(io_err(&path))?;
        self.snapshots.push((self.simulation.time, name));
        Ok(())
    }

    /// Writes the time series, snapshot collection, summary and checkpoint.
    fn checkpoint(&self, dir: &Path, status: Status) -> Result<(), RunError> {
        let path = dir.join("timeseries.csv");
        write_atomic(&path, timeseries::to_csv(&self.rows).as_bytes()).map_err(io_err(&path))?;
        let path = dir.join("snapshots.pvd");
        write_atomic(&path, vtk::collection_pvd(&self.snapshots).as_bytes())
            .map_err(io_err(&path))?;
        let path = dir.join("checkpoint.bin");
        let mut bytes = CHECKPOINT_MAGIC.to_vec();
        let body = rmp_serde::to_vec_named(&(crate::VERSION.to_string(), self)).map_err(|e| {
            RunError::Checkpoint {
                path: path.clone(),
                reason: e.to_string(),
            }
        })?;
        bytes.extend_from_slice(&body);
        write_atomic(&path, &bytes).map_err(io_err(&path))?;
        self.write_summary(dir, status)
    }

    fn write_summary(&self, dir: &Path, status: Status) -> Result<(), RunError> {
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
        };
        let path = dir.join("summary.json");
        let json = serde_json::to_string_pretty(&summary).unwrap_or_default();
        write_atomic(&path, json.as_bytes()).map_err(io_err(&path))
    }
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
