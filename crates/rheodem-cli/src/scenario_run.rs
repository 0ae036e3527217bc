//! `rheodem run`, `resume` and `check`: a scenario file into a run directory, a run
//! continued from its last checkpoint, a scenario checked without running it.

use crate::progress;
use crate::{MAX_THREADS_PER_CPU, cpus, memory_limit, pool, worker_count};
use anyhow::{Result, bail};
use clap::Args;
use rheodem::io::made_by::{self, Maker};
use rheodem::run::Run;
use rheodem::scenario::Scenario;
use std::path::{Path, PathBuf};

/// The scenario `rheodem run` uses when given none.
const DEFAULT_SCENARIO: &str = include_str!("../../../examples/dense-packing.toml");

/// Arguments of `rheodem run`.
#[derive(Args)]
pub struct RunArgs {
    /// The scenario (TOML); omitted: the built-in default.
    pub scenario: Option<PathBuf>,
    /// Run directory (default: `runs/<scenario name>`).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long, short)]
    pub threads: Option<usize>,
    /// Override the scenario's seed.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Start over even if the directory already holds a run.
    #[arg(long)]
    pub force: bool,
    /// No progress bar; only the final line.
    #[arg(long, short)]
    pub quiet: bool,
    /// Refuse a scenario whose estimated memory exceeds this size (e.g. 8GiB, 500MB;
    /// default: the machine's physical memory).
    #[arg(long, value_name = "SIZE")]
    pub max_memory: Option<String>,
}

/// Arguments of `rheodem resume`.
#[derive(Args)]
pub struct ResumeArgs {
    /// The run directory.
    pub dir: PathBuf,
    /// Worker threads (default: the count the run started with, for bit-identical results).
    #[arg(long, short)]
    pub threads: Option<usize>,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Arguments of `rheodem check`.
#[derive(Args)]
pub struct CheckArgs {
    /// The scenario (TOML).
    pub scenario: PathBuf,
    /// Worker threads the run would use, for the memory estimate (default: all cores).
    #[arg(long, short)]
    pub threads: Option<usize>,
    /// Refuse a scenario whose estimated memory exceeds this size (e.g. 8GiB, 500MB;
    /// default: the machine's physical memory).
    #[arg(long, value_name = "SIZE")]
    pub max_memory: Option<String>,
}

/// Runs a scenario (or the built-in default) into its run directory.
pub fn run(args: RunArgs) -> Result<()> {
    let RunArgs {
        scenario,
        out,
        threads,
        seed,
        force,
        quiet,
        max_memory,
    } = args;
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
    let (particles, bytes) = rheodem::scenario::size::memory_estimate(&sc, &base, n, limit)?;
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

/// Continues a run from its last checkpoint.
pub fn resume(args: ResumeArgs) -> Result<()> {
    let ResumeArgs {
        dir,
        threads,
        quiet,
    } = args;
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
        r.advance(&dir, |_| {})?;
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

/// Checks a scenario and prints its resolved values, without running it.
pub fn check(args: CheckArgs) -> Result<()> {
    let CheckArgs {
        scenario,
        threads,
        max_memory,
    } = args;
    let limit = memory_limit(max_memory.as_deref())?;
    let threads = worker_count("--threads", threads.unwrap_or_else(cpus))?;
    let sc = Scenario::from_file(&scenario)?;
    let base = scenario.parent().unwrap_or(Path::new("."));
    let (particles, bytes) = rheodem::scenario::size::memory_estimate(&sc, base, threads, limit)?;
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

/// Steps a started or resumed run to its end with a progress bar, then prints its last line.
fn advance(pool: &rayon::ThreadPool, r: &mut Run, dir: &Path, quiet: bool) -> Result<()> {
    let report = progress::Progress::new(quiet, r.simulation.particles.len());
    pool.install(|| {
        r.advance(dir, |p| {
            if p.done.is_multiple_of(64) || p.done == p.total {
                report.update(p.stage, p.done, p.total);
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
