//! `rheodem split-bottom`: the split-bottom ring shear cell (fill, settle, shear).

use crate::progress::Progress;
use crate::setup_args::Parameters;
use anyhow::{Context, Result, bail};
use clap::Args;
use rheodem::io::atomic::write_atomic;
use rheodem::setups::split_bottom::{MemoryLimit, SplitBottomRun, SplitBottomSpec, Stage};
use std::path::{Path, PathBuf};

/// Arguments of `split-bottom`: the cell's parameters (every option overrides the same key
/// of `--config`) and how to run it.
#[derive(Args)]
#[command(allow_negative_numbers = true)]
pub struct SplitBottomArgs {
    /// A TOML file with the cell's keys (those of a run's split-bottom.toml; docs/model.md §10);
    /// options override it.
    #[arg(long)]
    config: Option<PathBuf>,
    #[command(flatten)]
    parameters: Parameters<SplitBottomSpec>,
    /// Start shearing from the settled state of this earlier split-bottom run directory.
    #[arg(long)]
    from: Option<PathBuf>,
    /// Run directory (default: runs/split-bottom).
    #[arg(long, short)]
    out: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long, short)]
    threads: Option<usize>,
    /// Start over even if the directory holds a run (otherwise an unfinished run resumes).
    #[arg(long)]
    force: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
    /// Refuse a cell whose estimated memory exceeds this size (e.g. 8GiB, 500MB; default:
    /// the machine's physical memory).
    #[arg(long, value_name = "SIZE")]
    max_memory: Option<String>,
}

/// Runs `rheodem split-bottom`.
pub fn run(args: SplitBottomArgs) -> Result<()> {
    let spec = args.parameters.spec(args.config.as_deref())?;
    let limit = crate::memory_limit(args.max_memory.as_deref())?;
    let (pool, threads) = crate::pool(args.threads)?;
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| Path::new("runs").join("split-bottom"));
    let memory = MemoryLimit {
        threads,
        bytes: limit,
    };
    let quiet = args.quiet;
    let (mut run, _) = pool.install(|| {
        SplitBottomRun::open(
            spec,
            &dir,
            args.from.as_deref(),
            args.force,
            memory,
            |particles, bytes| {
                if !quiet {
                    eprintln!(
                        "split-bottom: about {particles} particles, an estimated {} of memory",
                        rheodem::memory::Bytes(bytes)
                    );
                }
            },
        )
    })?;
    if !args.quiet {
        eprintln!(
            "split-bottom: {} particles ({} free before settling), dt = {:.3e} s, outputs in {}",
            run.simulation.particles.len(),
            run.simulation.particles.free_count(),
            run.simulation.dt,
            dir.display()
        );
    }
    let report = Progress::new(args.quiet, run.simulation.particles.len());
    let mut progress = |p: rheodem::driver::Progress| {
        if p.done.is_multiple_of(64) || p.done == p.total {
            report.update(p.stage, p.done, p.total);
        }
    };
    // Stage by stage (a finished run only rewrites its outputs), with a warning when
    // settling ended on its time limit.
    loop {
        let stage = run.stage;
        pool.install(|| run.advance_stage(&dir, &mut progress))?;
        if stage == Stage::Settle
            && let Some(notice) = run.settled.as_ref().and_then(|r| r.limit_notice(&run.spec))
        {
            report.note(&format!("warning: {notice}"));
        }
        if run.stage == Stage::Done {
            break;
        }
    }
    report.finish();
    let res = run.results();
    let fmt = |e: &Option<rheodem::analysis::Estimate>| {
        e.map_or("n/a".to_string(), |e| {
            format!("{:.4e} ± {:.1e}", e.mean, e.error)
        })
    };
    println!(
        "done: t = {:.3} s, {:.0} s wall; net torque (full ring) {} N m; balance {} N m",
        run.simulation.time,
        run.wall_seconds,
        fmt(&res.net_torque),
        fmt(&res.balance)
    );
    for b in &res.band {
        match &b.fit {
            Ok(f) => println!(
                "  {:7} slab z ∈ [{:.4}, {:.4}] m: R_c = {:.4e} ± {:.1e} m, W = {:.3e} ± {:.1e} m",
                b.slab, b.z[0], b.z[1], f.centre, f.centre_err, f.width, f.width_err
            ),
            Err(e) => println!("  {:7} slab: no fit ({e})", b.slab),
        }
    }
    println!("outputs in {}", dir.display());
    Ok(())
}

/// Runs `wet-study`: the runs found in `dirs` (each a run directory, or a directory of
/// them), their fits as markdown (at the band friction `mu` where one is held fixed), the
/// figures into `figures`.
pub fn wet_study(dirs: &[PathBuf], figures: Option<&Path>, mu: Option<f64>) -> Result<()> {
    use rheodem::setups::wet_study::{WetRun, wet_study};
    if let Some(mu) = mu
        && !(mu.is_finite() && mu >= 0.0)
    {
        bail!("--mu {mu}: the band friction must be a finite number ≥ 0");
    }
    let mut runs = Vec::new();
    let mut left_out = Vec::new();
    for dir in dirs {
        let candidates: Vec<PathBuf> = if dir.join("summary.json").exists() {
            vec![dir.clone()]
        } else {
            let mut subs: Vec<PathBuf> = std::fs::read_dir(dir)
                .with_context(|| format!("cannot read {}", dir.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.join("summary.json").exists())
                .collect();
            subs.sort();
            subs
        };
        for c in candidates {
            match WetRun::read(&c) {
                Ok(r) => runs.push(r),
                Err(e) => left_out.push(e),
            }
        }
    }
    if runs.is_empty() {
        bail!(
            "no finished split-bottom run with band rheology in {}{}",
            dirs.iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
            if left_out.is_empty() {
                String::new()
            } else {
                format!(" ({})", left_out.join("; "))
            }
        );
    }
    let study =
        wet_study(&runs, mu).map_err(|e| anyhow::anyhow!("cannot draw the figures: {e}"))?;
    print!("{}", study.markdown);
    if !left_out.is_empty() {
        println!("\nLeft out:\n- {}", left_out.join("\n- "));
    }
    if let Some(out) = figures {
        std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
        for f in &study.figures {
            for (ext, bytes) in [("svg", f.svg.as_bytes()), ("png", f.png.as_slice())] {
                let file = out.join(format!("{}.{ext}", f.name));
                write_atomic(&file, bytes)
                    .with_context(|| format!("cannot write {}", file.display()))?;
            }
        }
        eprintln!("{} figures in {}", study.figures.len(), out.display());
    }
    Ok(())
}
