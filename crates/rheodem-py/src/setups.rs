//! The registered set-ups, a scenario's run into its directory, and the fitted laws, run
//! from Python through the same driver as the command line.

use crate::errors::{RunError, from_json, run_error, scenario_error};
use crate::scenario::Scenario;
use crate::threads::pool;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyString};
use rheodem::run::Run;
use rheodem::scenario::invalid;
use rheodem::setups::registry::{SETUPS, SetUpInfo, find};
use rheodem::setups::runner::{Event, RunOptions};
use rheodem::setups::schema::{Field, Kind, Values};
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// How often the interpreter looks for Ctrl-C while a run goes on in another thread.
const SIGNAL_CHECK: Duration = Duration::from_millis(100);

/// The payload of the unwinding that stops a run on Ctrl-C.
struct Interrupted;

/// Runs `work` on a thread of `pool` with the interpreter lock released, looking for
/// Ctrl-C meanwhile. `work` gets a flag that turns true on Ctrl-C and should then stop
/// (through [`stop_if`]); the interrupt is raised once `work` has ended, however it ended
/// (a `work` that finished first has still done its job, but the caller asked to stop).
/// A panic of `work` other than that stop is passed on.
fn interruptible<T: Send>(
    py: Python<'_>,
    pool: &rayon::ThreadPool,
    work: impl FnOnce(&AtomicBool) -> T + Send,
) -> PyResult<T> {
    let stop = AtomicBool::new(false);
    let (sender, mut receiver) = std::sync::mpsc::channel();
    let mut interrupt = None;
    let outcome = std::thread::scope(|scope| {
        let stop = &stop;
        scope.spawn(move || {
            let outcome = catch_unwind(AssertUnwindSafe(|| pool.install(|| work(stop))));
            // The receiver lives until this thread is joined.
            let _ = sender.send(outcome);
        });
        loop {
            // A unique borrow is `Send` where the receiver is not `Sync`.
            let rx = &mut receiver;
            match py.detach(move || rx.recv_timeout(SIGNAL_CHECK)) {
                Ok(outcome) => return Some(outcome),
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                    if interrupt.is_none()
                        && let Err(e) = py.check_signals()
                    {
                        interrupt = Some(e);
                        stop.store(true, Ordering::Relaxed);
                    }
                }
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => return None,
            }
        }
    });
    match (outcome, interrupt) {
        (Some(Err(payload)), _) if !payload.is::<Interrupted>() => resume_unwind(payload),
        (_, Some(e)) => Err(e),
        (Some(Ok(value)), None) => Ok(value),
        _ => Err(RunError::new_err(
            "the run's thread ended without an outcome",
        )),
    }
}

/// Stops the run (unwinding to [`interruptible`]) once `stop` is set.
fn stop_if(stop: &AtomicBool) {
    if stop.load(Ordering::Relaxed) {
        resume_unwind(Box::new(Interrupted));
    }
}

/// A Python value for the field `f` as the set-up's spec takes it; an error names the key.
fn value_of(f: &Field, v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    let wrong = |what: &str| {
        scenario_error(invalid(
            f.key,
            v.repr().map_or_else(|_| "?".into(), |r| r.to_string()),
            format!("must be {what}"),
        ))
    };
    match f.kind {
        Kind::Switch => v
            .cast::<PyBool>()
            .map(|b| toml::Value::Boolean(b.is_true()))
            .map_err(|_| wrong("True or False")),
        Kind::Count if !v.is_instance_of::<PyBool>() && v.is_instance_of::<PyInt>() => v
            .extract::<i64>()
            .map(toml::Value::Integer)
            .map_err(|_| wrong("a whole number at most 2^63 - 1")),
        Kind::Count => Err(wrong("a whole number")),
        Kind::Number
            if !v.is_instance_of::<PyBool>()
                && (v.is_instance_of::<PyFloat>() || v.is_instance_of::<PyInt>()) =>
        {
            v.extract::<f64>()
                .map(toml::Value::Float)
                .map_err(|_| wrong("a number"))
        }
        Kind::Number => Err(wrong("a number")),
        Kind::Choice(_) | Kind::AdhesiveLaw => v
            .cast::<PyString>()
            .map(|s| toml::Value::String(s.to_string()))
            .map_err(|_| wrong("a name")),
    }
}

/// The values of `params` by field key of `info`; an unknown key is refused with the
/// known ones, and None leaves a parameter at its default.
fn values_of(info: &SetUpInfo, params: Option<&Bound<'_, PyDict>>) -> PyResult<Values> {
    let mut values = Values::new();
    let Some(params) = params else {
        return Ok(values);
    };
    for (k, v) in params.iter() {
        let key: String = k.extract()?;
        let Some(f) = info.fields.iter().find(|f| f.key == key) else {
            let known: Vec<&str> = info.fields.iter().map(|f| f.key).collect();
            return Err(scenario_error(invalid(
                key,
                v.repr().map_or_else(|_| "?".into(), |r| r.to_string()),
                format!(
                    "is no parameter of {}; it takes {}",
                    info.name,
                    known.join(", ")
                ),
            )));
        };
        if v.is_none() {
            continue;
        }
        values.push((f.key, value_of(f, &v)?));
    }
    // In the order of the fields, as the command line gives them.
    values.sort_by_key(|(k, _)| info.fields.iter().position(|f| f.key == *k));
    Ok(values)
}

/// Runs the registered set-up `name` with `params` (its keys, as `rheodem setups NAME`
/// lists them) into the run directory `out`, as its subcommand does: an unfinished run of
/// the same settings resumes, one of other settings is refused unless `force`. Returns
/// `(summary, report, warnings)`: the summary as a dict (the run directory's
/// `summary.json` or point result), the report in words as the command line prints it. Ctrl-C stops it at the next step; it then resumes
/// from its last checkpoint.
#[pyfunction]
#[pyo3(signature = (name, out, params = None, threads = None, force = false, from_run = None, config = None, max_memory = None))]
#[allow(clippy::too_many_arguments)]
pub fn run_setup<'py>(
    py: Python<'py>,
    name: &str,
    out: PathBuf,
    params: Option<&Bound<'_, PyDict>>,
    threads: Option<usize>,
    force: bool,
    from_run: Option<PathBuf>,
    config: Option<PathBuf>,
    max_memory: Option<u64>,
) -> PyResult<(Bound<'py, PyAny>, String, Vec<String>)> {
    let info = find(name).map_err(|e| scenario_error(invalid("setup", name, e)))?;
    let base = match &config {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| RunError::new_err(format!("cannot read {}: {e}", path.display())))?;
            toml::from_str::<toml::Table>(&text).map_err(|e| {
                scenario_error(rheodem::scenario::ScenarioError::Parse(format!(
                    "{} is not valid TOML: {e}",
                    path.display()
                )))
            })?
        }
        None => toml::Table::new(),
    };
    let values = values_of(info, params)?;
    (info.accepts)(base.clone(), &values).map_err(scenario_error)?;
    if from_run.is_some() && info.from.is_none() {
        return Err(run_error(rheodem::setups::runner::no_start_from(
            info.name,
            from_run.as_deref().unwrap_or(Path::new("")),
        )));
    }
    let (pool, threads) = pool(threads, None)?;
    let options = RunOptions {
        dir: &out,
        threads,
        force,
        from: from_run.as_deref(),
        max_memory: if info.estimates_memory {
            max_memory.or_else(rheodem::memory::physical_memory)
        } else {
            None
        },
    };
    let finished = interruptible(py, &pool, |stop| {
        let mut warnings = Vec::new();
        let mut events = |e: Event<'_>| match e {
            Event::Progress(_) => stop_if(stop),
            Event::Warning(w) => warnings.push(w.to_string()),
            Event::Particles(_) | Event::Note(_) => {}
        };
        (info.run)(base, &values, &options, &mut events).map(|f| (f, warnings))
    })?;
    let (finished, mut warnings) = finished.map_err(run_error)?;
    warnings.extend(finished.warnings);
    let summary = serde_json::to_string(&finished.summary).unwrap_or_default();
    Ok((from_json(py, &summary)?, finished.report, warnings))
}

/// Every registered set-up with its parameters (key, kind, unit, meaning, allowed range,
/// whether required, default) as a list of dicts.
#[pyfunction]
pub fn setups(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    let list: Vec<serde_json::Value> = SETUPS
        .iter()
        .map(|s| {
            let defaults = (s.defaults)();
            let fields: Vec<serde_json::Value> = s
                .fields
                .iter()
                .map(|f| {
                    let default = f
                        .spec_key()
                        .and_then(|k| defaults.get(k))
                        .and_then(|v| serde_json::to_value(v).ok());
                    serde_json::json!({
                        "key": f.key,
                        "kind": match f.kind {
                            Kind::Number => "number",
                            Kind::Count => "count",
                            Kind::Switch => "switch",
                            Kind::Choice(_) => "choice",
                            Kind::AdhesiveLaw => "adhesive law",
                        },
                        "choices": f.choices(),
                        "unit": f.unit,
                        "meaning": f.meaning,
                        "allowed": f.range.short(),
                        "required": f.required,
                        "default": default,
                    })
                })
                .collect();
            serde_json::json!({
                "name": s.name,
                "summary": s.summary,
                "starts_from_run": s.from.is_some(),
                "parameters": fields,
            })
        })
        .collect();
    from_json(py, &serde_json::to_string(&list).unwrap_or_default())
}

/// Runs a scenario into the run directory `out`, as `rheodem run` does (refusing a
/// directory that holds a run unless `force`), or, with `resume`, continues the run in
/// `out` from its last checkpoint as `rheodem resume` does. Returns the summary as a JSON
/// dict. Ctrl-C stops it at the next step; it then resumes from its last checkpoint.
#[pyfunction]
#[pyo3(signature = (scenario, out, threads = None, force = false, resume = false))]
pub fn run_scenario<'py>(
    py: Python<'py>,
    scenario: Option<&Scenario>,
    out: PathBuf,
    threads: Option<usize>,
    force: bool,
    resume: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let mut run = if resume {
        Run::resume(&out).map_err(run_error)?
    } else {
        let Some(sc) = scenario else {
            return Err(PyValueError::new_err(
                "give a scenario, or resume=True to continue the run in `out`",
            ));
        };
        let (pool, n) = pool(threads, None)?;
        let (inner, base) = (sc.inner.clone(), sc.base_dir.clone());
        let out = &out;
        interruptible(py, &pool, move |_| Run::start(inner, &base, out, n, force))?
            .map_err(run_error)?
    };
    // A resumed run keeps its thread count unless told otherwise (bit-identical results).
    let (pool, _) = pool(threads, Some(run.threads))?;
    let out_dir = &out;
    interruptible(py, &pool, |stop| run.advance(out_dir, |_| stop_if(stop)))?.map_err(run_error)?;
    let summary = std::fs::read_to_string(out.join("summary.json")).map_err(|e| {
        RunError::new_err(format!("cannot read the summary in {}: {e}", out.display()))
    })?;
    from_json(py, &summary)
}

/// The fitted laws of Shi et al. 2020 at a state point (friction `mu_p`, inertial number
/// `inertial`, softness `softness`, Bond number `bond`), as a dict: each predicted
/// quantity with its value and the equation it comes from, the regime, notes.
#[pyfunction]
#[pyo3(signature = (mu_p, inertial, softness, bond = 0.0))]
pub fn predict(
    py: Python<'_>,
    mu_p: f64,
    inertial: f64,
    softness: f64,
    bond: f64,
) -> PyResult<Bound<'_, PyAny>> {
    let p = rheodem::rheology::predict::predict(mu_p, inertial, softness, bond)
        .map_err(|e| scenario_error(rheodem::scenario::ScenarioError::Parse(e)))?;
    from_json(py, &serde_json::to_string(&p).unwrap_or_default())
}
