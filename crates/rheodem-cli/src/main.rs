//! The `rheodem` command-line program: the subcommands and the helpers they share (worker
//! threads, memory limits). Each subcommand lives in a file of its own: `scenario_run.rs`
//! (`run`, `resume`, `check`), `bench.rs`, `shear.rs` (`sweep`, `compare`, `fit`, `db`),
//! `wet_study.rs`, `study.rs`, `cg.rs`, `predict.rs`, `contact.rs`, `setups.rs`. The
//! registered set-ups (`shear-box`, `split-bottom`, …) need no file: `setup_run.rs` builds
//! a subcommand for each from the registry, with the options `setup_args.rs` derives from
//! its parameters.

mod bench;
mod cg;
mod contact;
mod law_arg;
mod predict;
mod progress;
mod scenario_run;
mod setup_args;
mod setup_run;
mod setups;
mod shear;
mod study;
mod wet_study;

use anyhow::{Context, Result, bail};
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

/// Discrete-element simulator and rheology toolkit for cohesive granular materials.
#[derive(Parser)]
#[command(name = "rheodem", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scenario file into a run directory (without a file: the built-in default,
    /// examples/dense-packing.toml).
    Run(scenario_run::RunArgs),
    /// Continue a run from its last checkpoint.
    Resume(scenario_run::ResumeArgs),
    /// Coarse-grained fields of a run again, with its settings or others: a split-bottom run
    /// from its stored snapshots, a periodic-box run from its stored samples (fields.csv and
    /// fields.vti; docs/coarse-graining.md).
    Cg(cg::CgArgs),
    /// Run a list or grid of shear-box points (resumable), collecting one results table.
    Sweep {
        /// The sweep file (TOML); its `out` and `results` paths are relative to it.
        file: PathBuf,
        /// Points run at once (one thread each; default: all logical CPUs).
        #[arg(long, short)]
        jobs: Option<usize>,
        /// Less output.
        #[arg(long, short)]
        quiet: bool,
        /// Also store every finished point in this results database (SQLite, created if
        /// missing), under the sweep file's name.
        #[arg(long)]
        db: Option<PathBuf>,
    },
    /// Compare the finished points of a sweep directory with the laws fitted by Shi et al.
    /// 2020 (markdown table; docs/model.md §8–9).
    Compare {
        /// The sweep's output directory (or its results archive); with several, a point
        /// of a later directory replaces the point of the same name of an earlier one
        /// (e.g. a longer run of it).
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Also write the validation figures (SVG: φ and μ against Bo, I and p*, with the
        /// paper's laws) into this directory.
        #[arg(long)]
        figures: Option<PathBuf>,
    },
    /// The laws fitted by Shi et al. 2020 at one state point: φ, μ, Δφ and the regime of
    /// the (μ_p, Bo) phase diagram (docs/model.md §8).
    Predict(predict::PredictArgs),
    /// Fit the laws of Shi et al. 2020 to the finished points of a sweep directory, per μ_p
    /// and shear dynamics, in the layout of the paper's Tables 3, 5, 7 and 8 (markdown).
    Fit {
        /// The sweep's output directory (or its results archive); with several, a point
        /// of a later directory replaces the point of the same name of an earlier one.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
    },
    /// The wet split-bottom study of Roy et al. 2016 over finished split-bottom runs: c*
    /// against the rupture distance and the surface tension, torques, with the papers'
    /// coefficients (markdown) and figures.
    WetStudy {
        /// Run directories, or directories holding run directories.
        dirs: Vec<PathBuf>,
        /// Write the figures (PNG and SVG) into this directory.
        #[arg(long)]
        figures: Option<PathBuf>,
        /// The band friction μ held fixed for every run in the comparisons at one friction
        /// and in c_eq* from the torque (Eq. 27), ≥ 0; the papers hold 0.15 [default: the
        /// dry run's at the same Ω and g, else 0.15]
        #[arg(long)]
        mu: Option<f64>,
    },
    /// Studies: a sweep with a report and a quick variant (run here or submit to Slurm,
    /// status, collect, report).
    #[command(subcommand)]
    Study(study::StudyCommand),
    /// The results database (SQLite): import a sweep's points, export CSV, count.
    #[command(subcommand)]
    Db(shear::DbCommand),
    /// Contact-law tools: force–overlap curves, equivalent linear model.
    #[command(subcommand)]
    Contact(contact::ContactCommand),
    /// The registered set-ups, and each one's parameters (key, unit, meaning, allowed
    /// values, default) as a markdown table.
    Setups(setups::SetupsArgs),
    /// Check a scenario and print its resolved values, without running it (not even its
    /// preparation: the preparation's outcome is only known from `run`).
    Check(scenario_run::CheckArgs),
    /// Throughput on the standard problem (crates/rheodem/data/bench-packing.txt, see
    /// BENCHMARKS.md), in particle-steps per second.
    Bench(bench::BenchArgs),
}

fn main() -> ExitCode {
    // The derived subcommands, and one per registered set-up after `run` and `resume`.
    let matches = setup_run::with_set_ups(Cli::command(), 2).get_matches();
    let set_up = matches
        .subcommand()
        .and_then(|(name, m)| Some((rheodem::setups::registry::find(name).ok()?, m)));
    let outcome = match set_up {
        Some((info, m)) => setup_run::run(info, m),
        None => Cli::from_arg_matches(&matches)
            .map_err(|e| e.exit())
            .and_then(dispatch),
    };
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", error_chain(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes, joined by `: `, leaving out a cause whose text an earlier
/// message already holds (an error that quotes its source would print it twice).
fn error_chain(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if out.contains(&text) {
            continue;
        }
        if !out.is_empty() {
            out.push_str(": ");
        }
        out.push_str(&text);
    }
    out
}

/// Oversubscription allowed beyond the logical CPUs (to resume, bit for bit, a run
/// started on a larger machine); more only slows a run down.
const MAX_THREADS_PER_CPU: usize = 4;

/// Logical CPUs this process may use.
fn cpus() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Checks a worker count given as `flag`: at least 1, at most
/// [`MAX_THREADS_PER_CPU`] × the logical CPUs; warns above the CPU count.
pub(crate) fn worker_count(flag: &str, n: usize) -> Result<usize> {
    let (cpus, max) = (cpus(), MAX_THREADS_PER_CPU * cpus());
    if n == 0 || n > max {
        bail!(
            "{flag} {n}: must lie in [1, {max}] ({MAX_THREADS_PER_CPU} × the {cpus} logical CPUs of this machine)"
        );
    }
    if n > cpus {
        eprintln!(
            "warning: {flag} {n} exceeds the {cpus} logical CPUs of this machine; the run will be slower"
        );
    }
    Ok(n)
}

/// Runs `work(k, pool)` for every `k` in `0..n`, `jobs` at a time on worker threads, each
/// with its own one-thread rayon pool (so that every point runs as on one core); returns
/// the errors of pools that could not be built.
pub(crate) fn for_each_point(
    n: usize,
    jobs: usize,
    work: impl Fn(usize, &rayon::ThreadPool) + Sync,
) -> Vec<String> {
    let next = std::sync::atomic::AtomicUsize::new(0);
    let errors = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..jobs.min(n) {
            scope.spawn(|| {
                let pool = match rayon::ThreadPoolBuilder::new().num_threads(1).build() {
                    Ok(p) => p,
                    Err(e) => {
                        errors.lock().map(|mut v| v.push(e.to_string())).ok();
                        return;
                    }
                };
                loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                    if k >= n {
                        break;
                    }
                    work(k, &pool);
                }
            });
        }
    });
    errors.into_inner().unwrap_or_default()
}

/// The memory limit of a run (bytes): `--max-memory` if given, else the machine's physical
/// memory (none where the system does not say).
pub(crate) fn memory_limit(max_memory: Option<&str>) -> Result<Option<u64>> {
    match max_memory {
        Some(text) => rheodem::memory::parse_size(text)
            .map(Some)
            .map_err(|e| anyhow::anyhow!("--max-memory {e}")),
        None => Ok(rheodem::memory::physical_memory()),
    }
}

/// A thread pool of `threads` workers (default: all logical CPUs), checked as `--threads`.
pub(crate) fn pool(threads: Option<usize>) -> Result<(rayon::ThreadPool, usize)> {
    let n = worker_count("--threads", threads.unwrap_or_else(cpus))?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .context("cannot start the thread pool")?;
    Ok((pool, n))
}

fn dispatch(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Cg(args) => cg::run(args),
        Command::Run(args) => scenario_run::run(args),
        Command::Resume(args) => scenario_run::resume(args),
        Command::Contact(cmd) => contact::run(cmd),
        Command::Predict(args) => predict::run(&args),
        Command::Fit { dirs } => shear::fit(&dirs),
        Command::WetStudy { dirs, figures, mu } => wet_study::run(&dirs, figures.as_deref(), mu),
        Command::Sweep {
            file,
            jobs,
            quiet,
            db,
        } => shear::sweep(&file, jobs, quiet, db.as_deref()),
        Command::Db(cmd) => shear::db(cmd),
        Command::Study(cmd) => study::study(cmd),
        Command::Compare { dirs, figures } => shear::compare(&dirs, figures.as_deref()),
        Command::Check(args) => scenario_run::check(args),
        Command::Setups(args) => setups::run(&args),
        Command::Bench(args) => bench::run(args),
    }
}
