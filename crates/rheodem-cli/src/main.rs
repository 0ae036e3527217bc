//! The `rheodem` command-line program: run a scenario, resume a run, benchmark the engine.

mod cg;
mod contact;
mod law_arg;
mod predict;
mod progress;
mod shear;
mod split_bottom;
mod study;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use rheodem::contact::LawKind;
use rheodem::io::made_by::{self, Maker};
use rheodem::run::Run;
use rheodem::scenario::Scenario;
use std::path::{Path, PathBuf};
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
    Run {
        /// The scenario (TOML); omitted: the built-in default.
        scenario: Option<PathBuf>,
        /// Run directory (default: `runs/<scenario name>`).
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Worker threads (default: all cores).
        #[arg(long, short)]
        threads: Option<usize>,
        /// Override the scenario's seed.
        #[arg(long)]
        seed: Option<u64>,
        /// Start over even if the directory already holds a run.
        #[arg(long)]
        force: bool,
        /// No progress bar; only the final line.
        #[arg(long, short)]
        quiet: bool,
        /// Refuse a scenario whose estimated memory exceeds this size (e.g. 8GiB, 500MB;
        /// default: the machine's physical memory).
        #[arg(long, value_name = "SIZE")]
        max_memory: Option<String>,
    },
    /// Continue a run from its last checkpoint.
    Resume {
        /// The run directory.
        dir: PathBuf,
        /// Worker threads (default: the count the run started with, for bit-identical results).
        #[arg(long, short)]
        threads: Option<usize>,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Stress-controlled simple shear box at given (μ_p, I, p*, Bo): steady-state φ, μ, Z, σ.
    ShearBox(shear::ShearBoxArgs),
    /// Split-bottom ring shear cell: fill, settle, shear; wall torque and the shear band.
    SplitBottom(split_bottom::SplitBottomArgs),
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
        /// The sweep's output directory (or its results archive).
        dir: PathBuf,
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
        /// The sweep's output directory (or its results archive).
        dir: PathBuf,
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
    /// Check a scenario and print its resolved values, without running it (not even its
    /// preparation: the preparation's outcome is only known from `run`).
    Check {
        /// The scenario (TOML).
        scenario: PathBuf,
        /// Worker threads the run would use, for the memory estimate (default: all cores).
        #[arg(long, short)]
        threads: Option<usize>,
        /// Refuse a scenario whose estimated memory exceeds this size (e.g. 8GiB, 500MB;
        /// default: the machine's physical memory).
        #[arg(long, value_name = "SIZE")]
        max_memory: Option<String>,
    },
    /// Throughput on the standard problem (crates/rheodem/data/bench-packing.txt, see
    /// BENCHMARKS.md), in particle-steps per second.
    Bench {
        /// Thread counts to measure (default: 1 and all cores).
        #[arg(long, short, value_delimiter = ',')]
        threads: Vec<usize>,
        /// Untimed warm-up steps.
        #[arg(long, default_value_t = 2000)]
        warmup: u64,
        /// Timed steps.
        #[arg(long, default_value_t = 3000)]
        steps: u64,
        /// Verlet skin (model units; the LAMMPS input uses 0.2).
        #[arg(long, default_value_t = rheodem::bench::DEFAULT_SKIN)]
        skin: f64,
        /// Also hold σ_yy at 185 (the LAMMPS steady pressure) by rescaling L_y.
        #[arg(long)]
        stress_control: bool,
        // The help text lists the registered laws.
        #[arg(long, value_delimiter = ',', value_parser = law_arg::law_kind,
              help = law_arg::law_help("Adhesive laws to measure at the bench strength \
                  (f_a^max = 185 for the mean pair, rupture at 0.225 d; default: none, \
                  reversible, liquid_bridge)"))]
        cohesion: Vec<LawKind>,
    },
}

/// The scenario `rheodem run` uses when given none.
const DEFAULT_SCENARIO: &str = include_str!("../../../examples/dense-packing.toml");

fn main() -> ExitCode {
    match run(Cli::parse()) {
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

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::SplitBottom(args) => split_bottom::run(args),
        Command::Cg(args) => cg::run(args),
        Command::Run {
            scenario,
            out,
            threads,
            seed,
            force,
            quiet,
            max_memory,
        } => {
            let limit = memory_limit(max_memory.as_deref())?;
            let (mut sc, name, base) = match &scenario {
                Some(path) => (
                    Scenario::from_file(path)?,
                    path.file_stem()
                        .map_or("run".into(), |s| s.to_string_lossy().into_owned()),
                    path.parent().unwrap_or(Path::new(".")).to_path_buf(),
                ),
                None => (
                    Scenario::from_toml(DEFAULT_SCENARIO)?,
                    "default".to_string(),
                    PathBuf::from("."),
                ),
            };
            if let Some(s) = seed {
                sc.seed = s;
            }
            let dir = out.unwrap_or_else(|| Path::new("runs").join(&name));
            if !force {
                made_by::expect(&dir, Maker::Run).map_err(|e| anyhow::anyhow!("{e}"))?;
            }
            let shown = scenario
                .as_ref()
                .map_or("the built-in default scenario".to_string(), |p| {
                    p.display().to_string()
                });
            let (pool, n) = pool(threads)?;
            let (particles, bytes) =
                rheodem::scenario::size::memory_estimate(&sc, &base, n, limit)?;
            if !quiet {
                eprintln!(
                    "preparing {shown} ({particles} particles, about {} of memory) …",
                    rheodem::memory::Bytes(bytes)
                );
            }
            let mut r = pool.install(|| Run::start(sc, &base, &dir, n, force))?;
            for w in &r.resolved.warnings {
                eprintln!("warning: {w}");
            }
            if !quiet {
                eprintln!(
                    "{} free + {} wall particles, dt = {:.4e} s (t_c/{:.1}), {} steps, {} threads → {}",
                    r.resolved.free_particles,
                    r.resolved.wall_particles,
                    r.resolved.dt,
                    r.resolved.contact_time / r.resolved.dt,
                    r.plan.steps,
                    n,
                    dir.display()
                );
            }
            advance(&pool, &mut r, &dir, quiet)
        }
        Command::Resume {
            dir,
            threads,
            quiet,
        } => {
            match made_by::read(&dir) {
                Some(Maker::Run) | None if dir.join("checkpoint.bin").exists() => {}
                Some(Maker::Run) => bail!(
                    "{} holds a `rheodem run` that stopped before its first checkpoint (during \
                     its preparation, say): start it again with `rheodem run SCENARIO --out {} \
                     --force`",
                    dir.display(),
                    dir.display()
                ),
                Some(other) => bail!(
                    "{} holds a `rheodem {}` run, which `resume` does not continue: {}",
                    dir.display(),
                    other.name(),
                    other.how_to_continue(&dir)
                ),
                None => bail!(
                    "{} holds no rheodem run (no checkpoint.bin){}",
                    dir.display(),
                    if dir.exists() {
                        ""
                    } else {
                        ": no such directory"
                    }
                ),
            }
            let mut r = Run::resume(&dir)?;
            if threads.is_none() && r.threads > MAX_THREADS_PER_CPU * cpus() {
                bail!(
                    "{} started with {} threads, more than this machine allows ({} × {} CPUs): \
                     pass --threads N (the result then differs in the last bits from an \
                     uninterrupted run)",
                    dir.display(),
                    r.threads,
                    MAX_THREADS_PER_CPU,
                    cpus()
                );
            }
            let (pool, n) = pool(threads.or(Some(r.threads)))?;
            if n != r.threads && !quiet {
                eprintln!(
                    "note: the run started with {} threads; with {n} it will not be bit-identical",
                    r.threads
                );
            }
            r.threads = n;
            if r.is_complete() {
                // Rewrites the outputs of the final checkpoint (a kill may have come
                // between the checkpoint and the summary).
                r.advance(&dir, |_, _| {})?;
                println!(
                    "{} is already complete ({} steps)",
                    dir.display(),
                    r.plan.steps
                );
                return Ok(());
            }
            if !quiet {
                eprintln!(
                    "resuming {} at step {} of {}",
                    dir.display(),
                    r.simulation.step,
                    r.plan.steps
                );
            }
            advance(&pool, &mut r, &dir, quiet)
        }
        Command::Contact(cmd) => contact::run(cmd),
        Command::Predict(args) => predict::run(&args),
        Command::Fit { dir } => shear::fit(&dir),
        Command::WetStudy { dirs, figures, mu } => {
            split_bottom::wet_study(&dirs, figures.as_deref(), mu)
        }
        Command::ShearBox(args) => shear::shear_box(args),
        Command::Sweep {
            file,
            jobs,
            quiet,
            db,
        } => shear::sweep(&file, jobs, quiet, db.as_deref()),
        Command::Db(cmd) => shear::db(cmd),
        Command::Study(cmd) => study::study(cmd),
        Command::Compare { dir, figures } => shear::compare(&dir, figures.as_deref()),
        Command::Check {
            scenario,
            threads,
            max_memory,
        } => {
            let limit = memory_limit(max_memory.as_deref())?;
            let threads = worker_count("--threads", threads.unwrap_or_else(cpus))?;
            let sc = Scenario::from_file(&scenario)?;
            let base = scenario.parent().unwrap_or(Path::new("."));
            let (particles, bytes) =
                rheodem::scenario::size::memory_estimate(&sc, base, threads, limit)?;
            eprintln!(
                "note: {particles} particles, an estimated {} of memory on {threads} threads{}",
                rheodem::memory::Bytes(bytes),
                limit.map_or(String::new(), |l| format!(
                    " (limit {})",
                    rheodem::memory::Bytes(l)
                ))
            );
            let checked = rheodem::scenario::check(&sc, base)?;
            for w in &checked.resolved.warnings {
                eprintln!("warning: {w}");
            }
            if let Some(p) = &checked.preparation {
                eprintln!("note: not run by `check`: the preparation ({p})");
            }
            println!("{}", serde_json::to_string_pretty(&checked.resolved)?);
            Ok(())
        }
        Command::Bench {
            threads,
            warmup,
            steps,
            skin,
            stress_control,
            cohesion,
        } => {
            if !(skin.is_finite() && skin > 0.0) {
                bail!("--skin = {skin}: must be a positive number");
            }
            let all = std::thread::available_parallelism().map_or(1, |n| n.get());
            let counts = if threads.is_empty() {
                if all > 1 { vec![1, all] } else { vec![1] }
            } else {
                threads
            };
            let variants = if cohesion.is_empty() {
                vec![LawKind::None, LawKind::Reversible, LawKind::LiquidBridge]
            } else {
                cohesion
            };
            println!("standard problem: {}", rheodem::bench::DESCRIPTION);
            for cohesion in variants {
                let name = match cohesion {
                    LawKind::None => "frictional",
                    law => law.name(),
                };
                for &n in &counts {
                    let (pool, n) = pool(Some(n))?;
                    let r = pool.install(|| {
                        let mut sim = rheodem::bench::standard_problem(1.0, cohesion, skin);
                        if stress_control {
                            rheodem::bench::add_stress_control(&mut sim, 185.0);
                        }
                        rheodem::bench::run_timed(&mut sim, warmup, steps)
                    });
                    let total = r.loop_time.as_secs_f64();
                    let pct = |d: std::time::Duration| 100.0 * d.as_secs_f64() / total;
                    println!(
                        "{name}, threads {n}: {} particles × {} steps in {:.3} s — neighbours {:.1} % (rebuilds {:.1} %: {}, {:.1} pairs/particle), forces {:.1} %, integration {:.1} %; P = {:.1}, Z = {:.2}",
                        r.particles,
                        r.steps,
                        total,
                        pct(r.neighbor_time),
                        pct(r.rebuild_time),
                        r.rebuilds,
                        r.pairs_per_particle,
                        pct(r.force_time),
                        pct(r.integrate_time),
                        r.pressure,
                        r.coordination
                    );
                    println!(
                        "throughput: {:.0} particle-steps/s ({:.2} M, {name}, threads {n})",
                        r.particle_steps_per_second(),
                        r.particle_steps_per_second() / 1e6
                    );
                }
            }
            Ok(())
        }
    }
}

fn advance(pool: &rayon::ThreadPool, r: &mut Run, dir: &Path, quiet: bool) -> Result<()> {
    let report = progress::Progress::new(quiet, r.simulation.particles.len());
    pool.install(|| {
        r.advance(dir, |done, total| {
            if done.is_multiple_of(64) || done == total {
                report.update("run", done, total);
            }
        })
    })?;
    report.finish();
    let last = r.rows.last();
    println!(
        "done: {} steps, t = {:.6e} s, {:.1} s wall{}; outputs in {}",
        r.simulation.step,
        r.simulation.time,
        r.wall_seconds,
        last.map_or(String::new(), |o| format!(
            ", φ = {:.4}, Z = {:.3}, P = {:.4e} Pa",
            o.volume_fraction,
            o.coordination,
            o.mean_stress()
        )),
        dir.display()
    );
    Ok(())
}
