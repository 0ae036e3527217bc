//! `rheodem split-bottom`: the split-bottom ring shear cell (fill, settle, shear).

use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rheodem::io::atomic::write_atomic;
use rheodem::setups::split_bottom::{
    Cohesion, SplitBottomRun, SplitBottomSpec, Stage, TimeStepRule,
};
use std::path::{Path, PathBuf};

/// Arguments of `split-bottom`: every option overrides the same key of `--config`.
#[derive(Args)]
#[command(allow_negative_numbers = true)]
pub struct SplitBottomArgs {
    /// A TOML file with the cell's keys (those of a run's split-bottom.toml; docs/model.md §10);
    /// options override it.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Angular velocity Ω of the outer parts (rad/s).
    #[arg(long)]
    omega: Option<f64>,
    /// Gravity g (m/s²).
    #[arg(long)]
    gravity: Option<f64>,
    /// Adhesive law: dry, willett, linear.
    #[arg(long)]
    law: Option<String>,
    /// Surface tension γ_s of the Willett law (N/m).
    #[arg(long)]
    surface_tension: Option<f64>,
    /// Bridge volume V_b of the Willett law (nl = 1e-12 m³).
    #[arg(long)]
    volume_nl: Option<f64>,
    /// f_a^max of the linear irreversible law (N).
    #[arg(long)]
    max_force: Option<f64>,
    /// k_c of the linear irreversible law (N/m).
    #[arg(long)]
    adhesive_stiffness: Option<f64>,
    /// Particle friction μ_p.
    #[arg(long)]
    mu_p: Option<f64>,
    /// Shear duration (s).
    #[arg(long)]
    duration: Option<f64>,
    /// Start of the averaging window (s after the start of shear).
    #[arg(long)]
    average_from: Option<f64>,
    /// Factor on the cell's lengths (not the particles).
    #[arg(long)]
    scale: Option<f64>,
    /// Wedge angle Φ (degrees).
    #[arg(long)]
    wedge_deg: Option<f64>,
    /// Time-step rule: shortest (engine default) or mean-pair (the source papers' code).
    #[arg(long)]
    time_step: Option<String>,
    /// Random seed of the filling.
    #[arg(long)]
    seed: Option<u64>,
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
}

impl SplitBottomArgs {
    /// The spec: defaults, then the config file, then the options.
    fn spec(&self) -> Result<SplitBottomSpec> {
        let mut s = match &self.config {
            Some(path) => {
                let text = std::fs::read_to_string(path)
                    .with_context(|| format!("cannot read {}", path.display()))?;
                SplitBottomSpec::from_toml(&text)
                    .with_context(|| format!("in {}", path.display()))?
            }
            None => SplitBottomSpec::default(),
        };
        let set = |slot: &mut f64, v: Option<f64>| {
            if let Some(v) = v {
                *slot = v;
            }
        };
        set(&mut s.omega, self.omega);
        set(&mut s.gravity, self.gravity);
        set(&mut s.friction, self.mu_p);
        set(&mut s.duration, self.duration);
        set(&mut s.average_from, self.average_from);
        set(&mut s.scale, self.scale);
        set(&mut s.wedge_deg, self.wedge_deg);
        if let Some(seed) = self.seed {
            s.seed = seed;
        }
        if let Some(rule) = &self.time_step {
            s.time_step = match rule.as_str() {
                "shortest" => TimeStepRule::Shortest,
                "mean-pair" => TimeStepRule::MeanPair,
                other => anyhow::bail!("--time-step {other}: must be shortest or mean-pair"),
            };
        }
        let law = self.law.as_deref().unwrap_or(match s.cohesion {
            Cohesion::Dry => "dry",
            Cohesion::Willett { .. } => "willett",
            Cohesion::Linear { .. } => "linear",
        });
        s.cohesion = match law {
            "dry" => Cohesion::Dry,
            "willett" => {
                let (g0, v0, a0) = match s.cohesion {
                    Cohesion::Willett {
                        surface_tension,
                        volume,
                        contact_angle_deg,
                    } => (surface_tension, volume, contact_angle_deg),
                    _ => (0.020, 75e-12, 20.0),
                };
                Cohesion::Willett {
                    surface_tension: self.surface_tension.unwrap_or(g0),
                    volume: self.volume_nl.map_or(v0, |v| v * 1e-12),
                    contact_angle_deg: a0,
                }
            }
            "linear" => {
                let (f0, k0) = match s.cohesion {
                    Cohesion::Linear {
                        max_force,
                        stiffness,
                    } => (Some(max_force), Some(stiffness)),
                    _ => (None, None),
                };
                match (self.max_force.or(f0), self.adhesive_stiffness.or(k0)) {
                    (Some(max_force), Some(stiffness)) => Cohesion::Linear {
                        max_force,
                        stiffness,
                    },
                    _ => anyhow::bail!(
                        "--law linear needs --max-force and --adhesive-stiffness (or both in \
                         the config's cohesion table)"
                    ),
                }
            }
            other => anyhow::bail!("--law {other}: must be dry, willett or linear"),
        };
        Ok(s)
    }
}

/// Runs `rheodem split-bottom`.
pub fn run(args: SplitBottomArgs) -> Result<()> {
    let spec = args.spec()?;
    let (pool, _) = crate::pool(args.threads)?;
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| Path::new("runs").join("split-bottom"));
    let resumable = dir.join("checkpoint.bin").exists() && !args.force;
    let mut run = pool.install(|| -> Result<SplitBottomRun> {
        Ok(if resumable {
            let r = SplitBottomRun::resume(&dir)?;
            if r.spec != spec && args.from.is_none() {
                eprintln!(
                    "note: {} holds a run with other settings; resuming it as it was \
                     (use --force to start over)",
                    dir.display()
                );
            }
            r
        } else if let Some(from) = &args.from {
            SplitBottomRun::from_settled(spec, from, &dir, args.force)?
        } else {
            SplitBottomRun::start(spec, &dir, args.force)?
        })
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
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(1)
    };
    bar.set_style(
        ProgressStyle::with_template("{msg:7} {bar:40} {pos}/{len} steps  {per_sec}  ETA {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    pool.install(|| {
        run.advance(&dir, |stage, done, total| {
            if done % 64 == 0 || done == total {
                let name = match stage {
                    Stage::Settle => "settle",
                    _ => "shear",
                };
                if bar.message() != name {
                    bar.set_message(name);
                    bar.reset();
                }
                bar.set_length(total);
                bar.set_position(done);
            }
        })
    })?;
    bar.finish_and_clear();
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
/// them), their fits as markdown, the figures into `figures`.
pub fn wet_study(dirs: &[PathBuf], figures: Option<&Path>) -> Result<()> {
    use rheodem::setups::wet_study::{WetRun, wet_study};
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
    let study = wet_study(&runs).map_err(|e| anyhow::anyhow!("cannot draw the figures: {e}"))?;
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
