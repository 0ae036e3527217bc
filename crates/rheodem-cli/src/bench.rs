//! `rheodem bench`: throughput on the standard problem (BENCHMARKS.md).

use crate::{law_arg, pool};
use anyhow::{Result, bail};
use clap::Args;
use rheodem::contact::{LawKind, NormalKind};

/// Arguments of `rheodem bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// Thread counts to measure (default: 1 and all cores).
    #[arg(long, short, value_delimiter = ',')]
    pub threads: Vec<usize>,
    /// Untimed warm-up steps.
    #[arg(long, default_value_t = 2000)]
    pub warmup: u64,
    /// Timed steps.
    #[arg(long, default_value_t = 3000)]
    pub steps: u64,
    /// Verlet skin (model units; the LAMMPS input uses 0.2).
    #[arg(long, default_value_t = rheodem::bench::DEFAULT_SKIN)]
    pub skin: f64,
    /// Also hold σ_yy at 185 (the LAMMPS steady pressure) by rescaling L_y.
    #[arg(long)]
    pub stress_control: bool,
    // The help text lists the registered laws.
    #[arg(long, value_delimiter = ',', value_parser = law_arg::law_kind,
          help = law_arg::law_help("Adhesive laws to measure at the bench strength \
              (f_a^max = 185 for the mean pair, rupture at 0.225 d; default: none, \
              reversible, liquid_bridge)"))]
    pub cohesion: Vec<LawKind>,
    /// Normal law of the problem: linear (the standard problem), hertz (Hertz with
    /// Mindlin's sliding spring) or luding (plastic, no adhesive branch); the laws'
    /// parameters are in docs/model.md and BENCHMARKS.md.
    #[arg(long, default_value = "linear", value_parser = NormalKind::from_name)]
    pub normal: NormalKind,
}

/// Measures the standard problem for each law and thread count.
pub fn run(args: BenchArgs) -> Result<()> {
    let BenchArgs {
        threads,
        warmup,
        steps,
        skin,
        stress_control,
        cohesion,
        normal,
    } = args;
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
        let law = match cohesion {
            LawKind::None => "frictional",
            law => law.name(),
        };
        let name = match normal {
            NormalKind::Linear => law.to_string(),
            other => format!("{other}, {law}"),
        };
        for &n in &counts {
            let (pool, n) = pool(Some(n))?;
            let r = pool.install(|| {
                let mut sim = rheodem::bench::standard_problem_with(normal, 1.0, cohesion, skin);
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
