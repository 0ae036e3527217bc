//! `rheodem.Simulation`: a simulation stepped from Python, its state as NumPy views, its
//! contacts as a table, custom measurements on a trigger, checkpoints.

use crate::contacts;
use crate::errors::{RunError, from_json, run_error, scenario_error};
use crate::scenario::Scenario;
use crate::threads::pool;
use crate::views::{Field, Lent, view};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use pyo3::{PyTraverseError, PyVisit};
use rheodem::run::{ScenarioState, read_checkpoint, write_checkpoint};
use rheodem::scenario::Resolved;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Longest stretch of steps between two looks at Ctrl-C (and other signals).
const SIGNAL_CHECK: Duration = Duration::from_millis(50);

/// When a measurement attached to a simulation fires.
#[derive(Clone, Copy, Debug)]
enum Trigger {
    /// At every step that is a multiple of this count.
    Every(u64),
    /// At the first step at or after each multiple of a period.
    Period {
        /// The period (s).
        dt: f64,
        /// The multiple of the period at which it fires next, always after the current
        /// time.
        next: u64,
    },
}

impl Trigger {
    /// A period trigger whose next multiple comes after `time`.
    fn period(dt: f64, time: f64) -> Trigger {
        let mut next = (time / dt).floor().max(0.0) as u64;
        while next as f64 * dt <= time {
            next += 1;
        }
        Trigger::Period { dt, next }
    }

    /// The next step at which it fires after `step`, or the time (s) from which it fires.
    fn next(&self, step: u64) -> (u64, f64) {
        match *self {
            Trigger::Every(n) => (
                (step / n).saturating_add(1).saturating_mul(n),
                f64::INFINITY,
            ),
            Trigger::Period { dt, next } => (u64::MAX, next as f64 * dt),
        }
    }

    /// Whether it fires at `step`, `time`; a period moves on to its next multiple after
    /// `time`.
    fn fires(&mut self, step: u64, time: f64) -> bool {
        match *self {
            Trigger::Every(n) => step.is_multiple_of(n),
            Trigger::Period { dt, next } => {
                if time < next as f64 * dt {
                    return false;
                }
                *self = Trigger::period(dt, time);
                true
            }
        }
    }
}

/// A measurement attached to a simulation.
struct Action {
    id: u64,
    callable: Py<PyAny>,
    trigger: Trigger,
}

/// What a Python checkpoint holds.
#[derive(Serialize)]
struct SavedRef<'a> {
    threads: usize,
    resolved: &'a Option<Resolved>,
    simulation: &'a rheodem::Simulation,
}

/// [`SavedRef`] read back.
#[derive(Deserialize)]
struct Saved {
    threads: usize,
    resolved: Option<Resolved>,
    simulation: rheodem::Simulation,
}

/// A DEM simulation driven from Python.
///
/// Made from a Scenario (`Simulation(scenario, threads=None)`), from a checkpoint
/// (`Simulation.load`) or from a command-line run directory (`Simulation.from_run`). Its
/// particle arrays are read-only NumPy views without copies (the rule of their lifetime is
/// in docs/python.md); it runs with the interpreter lock released and stops cleanly on
/// Ctrl-C between steps. Results are bit-identical for a given thread count.
#[pyclass(module = "rheodem._rheodem")]
pub struct Simulation {
    sim: rheodem::Simulation,
    threads: usize,
    pool: rayon::ThreadPool,
    /// The scenario's derived values (its last step among them), `None` for a state built
    /// without a scenario.
    resolved: Option<Resolved>,
    lent: Lent,
    actions: Vec<Action>,
    next_action: u64,
    /// Whether an attached measurement is running (the simulation is then read-only);
    /// shared so that it is set and cleared without borrowing the simulation.
    in_action: Arc<AtomicBool>,
}

/// Clears the flag of a running measurement when the measurements are done, however they
/// end.
struct Acting(Arc<AtomicBool>);

impl Acting {
    fn start(flag: &Arc<AtomicBool>) -> Acting {
        flag.store(true, Ordering::Relaxed);
        Acting(flag.clone())
    }
}

impl Drop for Acting {
    fn drop(&mut self) {
        self.0.store(false, Ordering::Relaxed);
    }
}

/// The error of a simulation used by another thread while it runs or is read.
fn busy(e: impl std::fmt::Display) -> PyErr {
    RunError::new_err(format!(
        "the simulation is in use by another thread (it is running or being read): {e}"
    ))
}

impl Simulation {
    fn assemble(
        sim: rheodem::Simulation,
        threads: usize,
        pool: rayon::ThreadPool,
        resolved: Option<Resolved>,
    ) -> Simulation {
        Simulation {
            sim,
            threads,
            pool,
            resolved,
            lent: Lent::default(),
            actions: Vec::new(),
            next_action: 0,
            in_action: Arc::new(AtomicBool::new(false)),
        }
    }

    /// Whether the state is the end of a step rather than freshly assembled: it has taken
    /// steps, or its scenario's preparation has (which then sets the clock back to zero).
    fn ends_a_step(&self) -> bool {
        self.sim.step > 0
            || self
                .resolved
                .as_ref()
                .is_some_and(|r| r.preparation.is_some())
    }

    fn writable(&self) -> PyResult<()> {
        if self.in_action.load(Ordering::Relaxed) {
            return Err(RunError::new_err(
                "a measurement attached to a simulation reads its state; it cannot step it",
            ));
        }
        Ok(())
    }

    /// Steps until step `stop`, a time mark or a look at the signals is due, in the pool.
    fn advance(&mut self, stop: u64, mark: f64) -> Result<(), rheodem::neighbor::NeighborError> {
        let (sim, pool) = (&mut self.sim, &self.pool);
        pool.install(|| {
            let start = Instant::now();
            while sim.step < stop && sim.time < mark {
                sim.step(false)?;
                if start.elapsed() > SIGNAL_CHECK {
                    break;
                }
            }
            Ok(())
        })
    }

    /// The next step and time at which an attached measurement fires.
    fn next_stop(&self) -> (u64, f64) {
        self.actions
            .iter()
            .map(|a| a.trigger.next(self.sim.step))
            .fold((u64::MAX, f64::INFINITY), |(s, t), (s2, t2)| {
                (s.min(s2), t.min(t2))
            })
    }

    fn array<'py>(slf: &Bound<'py, Self>, field: Field) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        let owner = slf.clone().into_any().unbind();
        let mut me = slf.try_borrow_mut().map_err(busy)?;
        let me = &mut *me;
        view(py, &me.sim.particles, &mut me.lent, field, owner)
    }
}

#[pymethods]
impl Simulation {
    /// Builds `scenario` (its particles placed and prepared as the scenario says) to run
    /// on `threads` worker threads (default: all logical CPUs).
    #[new]
    #[pyo3(signature = (scenario, threads = None))]
    fn new(py: Python<'_>, scenario: &Scenario, threads: Option<usize>) -> PyResult<Simulation> {
        let (pool, threads) = pool(threads, None)?;
        let (inner, base) = (&scenario.inner, &scenario.base_dir);
        let built = py
            .detach(|| pool.install(|| rheodem::scenario::build(inner, base)))
            .map_err(scenario_error)?;
        Ok(Simulation::assemble(
            built.simulation,
            threads,
            pool,
            Some(built.resolved),
        ))
    }

    /// Loads a checkpoint written by `checkpoint`; the run continues bit-identically with
    /// the thread count it was written with (the default) and may be given another.
    #[staticmethod]
    #[pyo3(signature = (path, threads = None))]
    fn load(path: PathBuf, threads: Option<usize>) -> PyResult<Simulation> {
        let saved: Saved = read_checkpoint(&path).map_err(run_error)?;
        let (pool, threads) = pool(threads, Some(saved.threads))?;
        Ok(Simulation::assemble(
            saved.simulation,
            threads,
            pool,
            saved.resolved,
        ))
    }

    /// The state at the last checkpoint of a run directory of `rheodem run` (or
    /// `rheodem.run_scenario`), with the run's thread count unless `threads` is given.
    #[staticmethod]
    #[pyo3(signature = (directory, threads = None))]
    fn from_run(directory: PathBuf, threads: Option<usize>) -> PyResult<Simulation> {
        let state = rheodem::run::Run::resume(&directory)
            .map_err(run_error)?
            .into_state();
        let ScenarioState {
            resolved,
            threads: ran_with,
            simulation,
            ..
        } = state;
        let (pool, threads) = pool(threads, Some(ran_with))?;
        Ok(Simulation::assemble(
            simulation,
            threads,
            pool,
            Some(resolved),
        ))
    }

    /// The standard throughput problem of BENCHMARKS.md (4096 spheres at φ = 0.62 sheared
    /// through Lees-Edwards boundaries, model units), with the adhesive law `cohesion`
    /// (a registered name; default none) at the bench strength, as `rheodem bench` runs it.
    #[staticmethod]
    #[pyo3(signature = (cohesion = "none", threads = None))]
    fn standard_problem(
        py: Python<'_>,
        cohesion: &str,
        threads: Option<usize>,
    ) -> PyResult<Simulation> {
        let law = rheodem::contact::LawKind::from_name(cohesion).map_err(|e| {
            scenario_error(rheodem::scenario::invalid("cohesion", cohesion, e.reason))
        })?;
        let (pool, threads) = pool(threads, None)?;
        let sim = py.detach(|| {
            pool.install(|| {
                rheodem::bench::standard_problem(1.0, law, rheodem::bench::DEFAULT_SKIN)
            })
        });
        Ok(Simulation::assemble(sim, threads, pool, None))
    }

    /// Writes the complete state to `path` (atomically); `Simulation.load` continues it.
    fn checkpoint(&self, path: PathBuf) -> PyResult<()> {
        let saved = SavedRef {
            threads: self.threads,
            resolved: &self.resolved,
            simulation: &self.sim,
        };
        write_checkpoint(&path, &saved).map_err(run_error)
    }

    /// Advances `steps` steps, or by `duration` seconds (rounded up to whole steps), or,
    /// with neither, to the end of the scenario's `run.duration`. Attached measurements
    /// fire at their steps. Ctrl-C stops it between steps (raising KeyboardInterrupt with
    /// the state at the last complete step).
    #[pyo3(signature = (steps = None, duration = None))]
    fn run(slf: &Bound<'_, Self>, steps: Option<u64>, duration: Option<f64>) -> PyResult<()> {
        let py = slf.py();
        let target = {
            let me = slf.try_borrow().map_err(busy)?;
            me.writable()?;
            let now = me.sim.step;
            match (steps, duration) {
                (Some(n), None) => now.saturating_add(n),
                (None, Some(d)) if d.is_finite() && d >= 0.0 => {
                    now.saturating_add((d / me.sim.dt - 1e-9).ceil().max(0.0) as u64)
                }
                (None, Some(d)) => {
                    return Err(PyValueError::new_err(format!(
                        "duration = {d}: must be zero or a positive number of seconds"
                    )));
                }
                (None, None) => me.end_step().max(now),
                (Some(_), Some(_)) => {
                    return Err(PyValueError::new_err("give steps or duration, not both"));
                }
            }
        };
        loop {
            let (fired, flag) = {
                let mut me = slf.try_borrow_mut().map_err(busy)?;
                if me.sim.step >= target {
                    break;
                }
                let (stop, mark) = me.next_stop();
                let me = &mut *me;
                me.lent.release(&mut me.sim.particles);
                py.detach(|| me.advance(stop.min(target), mark))
                    .map_err(|e| RunError::new_err(e.to_string()))?;
                let (step, time) = (me.sim.step, me.sim.time);
                let mut fired = Vec::new();
                for a in &mut me.actions {
                    if a.trigger.fires(step, time) {
                        fired.push(a.callable.clone_ref(py));
                    }
                }
                (fired, me.in_action.clone())
            };
            // The measurements of the step first, so that Ctrl-C loses none.
            if !fired.is_empty() {
                let _acting = Acting::start(&flag);
                for f in &fired {
                    f.call1(py, (slf,))?;
                }
            }
            py.check_signals()?;
        }
        let me = slf.try_borrow().map_err(busy)?;
        me.sim
            .check_sanity()
            .map_err(|cause| RunError::new_err(format!("at step {}: {cause}", me.sim.step)))
    }

    /// Advances one step (`run(steps=1)`).
    fn step(slf: &Bound<'_, Self>) -> PyResult<()> {
        Simulation::run(slf, Some(1), None)
    }

    /// Calls `callback(simulation)` every `every` steps (at steps that are multiples of
    /// it) or at the first step at or after each multiple of `dt` seconds; returns a
    /// handle for `detach`. The callback reads the state (views, `contacts()`,
    /// `observables()`); stepping the simulation from it raises RunError. A simulation
    /// without attached measurements pays nothing for the feature.
    #[pyo3(signature = (callback, every = None, dt = None))]
    fn attach(
        &mut self,
        callback: Py<PyAny>,
        every: Option<u64>,
        dt: Option<f64>,
    ) -> PyResult<u64> {
        let trigger = match (every, dt) {
            (Some(0), None) => {
                return Err(PyValueError::new_err(
                    "every = 0: must be a positive number of steps",
                ));
            }
            (Some(n), None) => Trigger::Every(n),
            (None, Some(p)) if p.is_finite() && p > 0.0 => Trigger::period(p, self.sim.time),
            (None, Some(p)) => {
                return Err(PyValueError::new_err(format!(
                    "dt = {p}: must be a positive number of seconds"
                )));
            }
            _ => {
                return Err(PyValueError::new_err(
                    "give exactly one trigger: every (steps) or dt (seconds)",
                ));
            }
        };
        self.next_action += 1;
        self.actions.push(Action {
            id: self.next_action,
            callable: callback,
            trigger,
        });
        Ok(self.next_action)
    }

    /// Removes the measurement of `handle` (from `attach`); raises ValueError for an
    /// unknown handle.
    fn detach(&mut self, handle: u64) -> PyResult<()> {
        let before = self.actions.len();
        self.actions.retain(|a| a.id != handle);
        if self.actions.len() == before {
            return Err(PyValueError::new_err(format!(
                "no measurement attached with handle {handle}"
            )));
        }
        Ok(())
    }

    /// Simulated time (s).
    #[getter]
    fn time(&self) -> f64 {
        self.sim.time
    }

    /// Steps taken since the start of the simulation.
    #[getter]
    fn step_count(&self) -> u64 {
        self.sim.step
    }

    /// The scenario's last step (its run duration in steps); 0 when unknown.
    #[getter]
    fn end_step(&self) -> u64 {
        self.resolved.as_ref().map_or(0, |r| r.steps)
    }

    /// Time step (s).
    #[getter]
    fn dt(&self) -> f64 {
        self.sim.dt
    }

    /// Worker threads of the force loop.
    #[getter]
    fn threads(&self) -> usize {
        self.threads
    }

    /// Number of particles (free and wall).
    fn __len__(&self) -> usize {
        self.sim.particles.len()
    }

    /// The box's lower and upper corners (m), each a 3-tuple.
    #[getter]
    fn box_bounds(&self) -> ([f64; 3], [f64; 3]) {
        let d = &self.sim.domain;
        (d.lo.to_array(), d.hi.to_array())
    }

    /// Names of the wall parts, indexed by `parts`.
    #[getter]
    fn part_names(&self) -> Vec<String> {
        self.sim.parts.clone()
    }

    /// The derived values of the scenario (time step, contact time, particle counts,
    /// radius distribution, version, seed) as a dict; None for a state without them.
    #[getter]
    fn resolved<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.resolved
            .as_ref()
            .map(|r| from_json(py, &serde_json::to_string(r).unwrap_or_default()))
            .transpose()
    }

    /// Centre positions (m), (N, 3) float64, read-only view.
    #[getter]
    fn positions<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Simulation::array(slf, Field::Position)
    }

    /// Velocities (m/s), (N, 3) float64, read-only view.
    #[getter]
    fn velocities<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Simulation::array(slf, Field::Velocity)
    }

    /// Angular velocities (rad/s), (N, 3) float64, read-only view.
    #[getter]
    fn angular_velocities<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Simulation::array(slf, Field::AngularVelocity)
    }

    /// Total force of the last evaluation (N), (N, 3) float64, read-only view.
    #[getter]
    fn forces<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Simulation::array(slf, Field::Force)
    }

    /// Total torque of the last evaluation (N m), (N, 3) float64, read-only view.
    #[getter]
    fn torques<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Simulation::array(slf, Field::Torque)
    }

    /// Radii (m), (N,) float64, read-only view.
    #[getter]
    fn radii<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Simulation::array(slf, Field::Radius)
    }

    /// Masses (kg), (N,) float64, read-only view.
    #[getter]
    fn masses<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Simulation::array(slf, Field::Mass)
    }

    /// Permanent particle ids of the rows, (N,) uint32, read-only view (the row order
    /// changes at every neighbour-list rebuild; the ids do not).
    #[getter]
    fn ids<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Simulation::array(slf, Field::Id)
    }

    /// Wall part of each particle (an index into `part_names`; 65535 for none), (N,)
    /// uint16, read-only view.
    #[getter]
    fn parts<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Simulation::array(slf, Field::Part)
    }

    /// Species index of each particle, (N,) uint16, read-only view.
    #[getter]
    fn species<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Simulation::array(slf, Field::Species)
    }

    /// The contacts of the current state as a dict of NumPy arrays (a computed copy; the
    /// columns are in docs/python.md).
    fn contacts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (sim, pool) = (&self.sim, &self.pool);
        let ends = self.ends_a_step();
        let table = py.detach(|| pool.install(|| contacts::evaluate(sim, ends)));
        table.into_dict(py)
    }

    /// The observables of the current state (stress tensor, kinetic and elastic energies,
    /// coordination, …, SI units; the contact parts evaluated as for `contacts()`) as a
    /// dict.
    fn observables<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let (sim, pool) = (&self.sim, &self.pool);
        let ends = self.ends_a_step();
        let o = py.detach(|| pool.install(|| contacts::observables(sim, ends)));
        from_json(py, &serde_json::to_string(&o).unwrap_or_default())
    }

    /// The attached callables, for Python's cycle collector.
    fn __traverse__(&self, visit: PyVisit<'_>) -> Result<(), PyTraverseError> {
        for a in &self.actions {
            visit.call(&a.callable)?;
        }
        Ok(())
    }

    /// Drops the attached callables (Python's cycle collector breaking a cycle).
    fn __clear__(&mut self) {
        self.actions.clear();
    }

    fn __repr__(&self) -> String {
        format!(
            "Simulation({} particles, step {}, t = {:e} s, dt = {:e} s, {} threads)",
            self.sim.particles.len(),
            self.sim.step,
            self.sim.time,
            self.sim.dt,
            self.threads
        )
    }
}
