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
use crate::cg::{self, ContactRecord, periodic::BoxFields};
use crate::io::atomic::write_atomic;
use crate::io::made_by::Maker;
use crate::io::{timeseries, vtk};
use crate::measure::Observables;
use crate::sanity::Instability;
use crate::scenario::{Resolved, Scenario, build};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::Arc;

use crate::driver::{Driver, Every, Session, SetUp, StepNeeds};
pub use crate::driver::{
    Progress, RunError, Status, io_err, lock, read_checkpoint, write_checkpoint,
};
use crate::io::lock::DirLock;

pub mod samples;

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

/// A scenario's run (`rheodem run`, a shear-box point): everything its checkpoint holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ScenarioState {
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
}

/// A scenario's run in its directory, on the staged run driver.
pub type Run = Driver<ScenarioState>;

/// The JSON summary of a scenario's run (the driver adds the status, version, commit,
/// last checkpoint and error).
#[derive(Serialize)]
struct Summary<'a> {
    program: &'static str,
    seed: u64,
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

impl Driver<ScenarioState> {
    /// Builds the scenario (relative paths from `base_dir`) and creates the run directory
    /// `dir`, refusing one that already holds a run unless `force` (which also removes the
    /// old run's snapshots). The directory stays locked against other processes while the
    /// returned run lives.
    ///
    /// # Errors
    /// [`RunError`] for an invalid scenario, a directory that holds a run or is busy, or
    /// a file not written.
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
    ///
    /// # Errors
    /// As [`Run::start`].
    pub fn start_locked(
        lock: Arc<DirLock>,
        existed: bool,
        scenario: Scenario,
        base_dir: &Path,
        dir: &Path,
        threads: usize,
        force: bool,
    ) -> Result<Run, RunError> {
        Driver::create_locked(lock, existed, dir, force, |session| {
            ScenarioState::prepare(scenario, base_dir, threads, session)
        })
    }
}

impl ScenarioState {
    /// The built scenario in the run directory: its input files written, the old run's
    /// snapshots and samples removed, the first time-series row recorded.
    fn prepare(
        scenario: Scenario,
        base_dir: &Path,
        threads: usize,
        session: &mut Session<'_>,
    ) -> Result<ScenarioState, RunError> {
        let dir = session.dir;
        let built = build(&scenario, base_dir)?;
        let snapshots = dir.join("snapshots");
        remove_snapshots(&snapshots)?;
        samples::remove_all(dir)?;
        std::fs::create_dir_all(&snapshots).map_err(io_err("create the directory", &snapshots))?;
        let steps = built.resolved.steps;
        let plan = OutputPlan {
            steps,
            timeseries_every: Every::spread(steps, scenario.output.timeseries_rows).0,
            snapshot_every: Every::spread(steps, scenario.output.snapshots).0,
            checkpoint_every: Every::spread(steps, scenario.output.checkpoints).0,
        };
        // Checked by `build`.
        let fields = scenario.fields.as_ref().map(BoxFields::new).transpose()?;
        let mut state = ScenarioState {
            scenario,
            resolved: built.resolved,
            plan,
            threads,
            simulation: built.simulation,
            rows: Vec::new(),
            snapshots: Vec::new(),
            wall_seconds: 0.0,
            fields,
        };
        let header = format!(
            "# rheodem {} (commit {}) — scenario as run, every default written out; seed {}\n",
            crate::VERSION,
            crate::COMMIT,
            state.scenario.seed
        );
        let path = dir.join("scenario.toml");
        write_atomic(&path, (header + &state.scenario.to_toml()).as_bytes())
            .map_err(io_err("write", &path))?;
        let path = dir.join("resolved.json");
        let json = serde_json::to_string_pretty(&state.resolved).unwrap_or_default();
        write_atomic(&path, json.as_bytes()).map_err(io_err("write", &path))?;
        state.record(session)?;
        Ok(state)
    }

    /// Appends a time-series row for the current (measured) state, and a snapshot if due.
    fn record(&mut self, session: &Session<'_>) -> Result<(), RunError> {
        session.sane(&self.simulation)?;
        let row = self.simulation.observables();
        if !row.is_finite() {
            return Err(session.unstable(&self.simulation, Instability::NonFiniteMeasurement));
        }
        self.rows.push(row);
        if Every(self.plan.snapshot_every).fires(self.simulation.step) {
            self.snapshot(session.dir)?;
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

    /// Whether the step after the current one writes a time-series row.
    fn row_due(&self, step: u64) -> bool {
        Every(self.plan.timeseries_every).fires(step) || step == self.plan.steps
    }
}

impl SetUp for ScenarioState {
    const MAKER: Maker = Maker::Run;

    fn simulation(&self) -> &Simulation {
        &self.simulation
    }

    fn simulation_mut(&mut self) -> &mut Simulation {
        &mut self.simulation
    }

    fn is_complete(&self) -> bool {
        self.simulation.step >= self.plan.steps
    }

    fn progress(&self) -> Progress {
        Progress {
            stage: "run",
            done: self.simulation.step,
            total: self.plan.steps,
        }
    }

    fn needs(&self) -> StepNeeds {
        let row = self.row_due(self.simulation.step + 1);
        let end = self.simulation.time + self.simulation.dt;
        StepNeeds {
            measure: row,
            contacts: row && self.fields.as_ref().is_some_and(|f| f.wants(end)),
        }
    }

    fn after_step(
        &mut self,
        session: &mut Session<'_>,
        contacts: Option<&[ContactRecord]>,
    ) -> Result<bool, RunError> {
        let step = self.simulation.step;
        if let (Some(contacts), Some(fields)) = (contacts, self.fields.as_mut()) {
            let view = cg::periodic::LabView::of(&self.simulation);
            if fields.spec.records {
                samples::write(session.dir, &view, contacts)?;
            }
            fields.add(&view, contacts)?;
        }
        if self.row_due(step) {
            self.record(session)?;
        } else if Every(self.plan.snapshot_every).fires(step) {
            self.snapshot(session.dir)?;
        }
        Ok(Every(self.plan.checkpoint_every).fires(step) || step == self.plan.steps)
    }

    fn wall_seconds_mut(&mut self) -> &mut f64 {
        &mut self.wall_seconds
    }

    fn write_outputs(&self, dir: &Path) -> Result<serde_json::Value, RunError> {
        let path = dir.join("timeseries.csv");
        write_atomic(&path, timeseries::to_csv(&self.rows).as_bytes())
            .map_err(io_err("write", &path))?;
        let path = dir.join("snapshots.pvd");
        write_atomic(&path, vtk::collection_pvd(&self.snapshots).as_bytes())
            .map_err(io_err("write", &path))?;
        if let Some(fields) = &self.fields {
            write_fields(fields, dir)?;
        }
        Ok(self.summary())
    }

    fn summary(&self) -> serde_json::Value {
        let done = self.simulation.step;
        let summary = Summary {
            program: "rheodem",
            seed: self.scenario.seed,
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
        serde_json::to_value(&summary).unwrap_or_default()
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
