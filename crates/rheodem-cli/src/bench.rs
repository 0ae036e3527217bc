//! `rheodem bench`: throughput on the standard problem (BENCHMARKS.md).

use crate::law_arg;
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
    /// The problem: `shear` (the standard problem) or `chute` (LAMMPS's chute benchmark,
    /// bench/in.chute; linear frictional law only).
    #[arg(long, default_value = "shear", value_parser = ["shear", "chute"])]
    pub problem: String,
    /// With `--problem chute`: prepare the state the benchmark times (the stack fallen for
    /// 30 000 steps), write it as a LAMMPS data file (atom_style sphere) to this path and
    /// exit.
    #[arg(long, value_name = "FILE")]
    pub write_lammps_data: Option<std::path::PathBuf>,
    /// With `--problem chute`: start from this LAMMPS data file (one written by
    /// `--write-lammps-data`) instead of preparing the state anew.
    #[arg(long, value_name = "FILE")]
    pub lammps_data: Option<std::path::PathBuf>,
    /// Verlet skin (model units; default: 0.2 for the standard problem as in its LAMMPS
    /// input, 0.1 for the chute as in LAMMPS's).
    #[arg(long)]
    pub skin: Option<f64>,
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
    /// The standard packing repeated this many times along each axis (2: 32 768 spheres),
    /// sheared at the same rate; the problem of benches/threads.sh.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=8))]
    pub replicate: u32,
    /// Run the members of each thread count's team one after another on one thread: the
    /// same split of the work and the same bits, without hand-overs or spin-waits (for
    /// counting a thread count's instructions under valgrind; no wall-clock meaning).
    #[arg(long)]
    pub members_in_turn: bool,
    /// Run the warm-up, write the simulation's state to this file and exit.
    #[arg(long, value_name = "FILE", conflicts_with = "load_state")]
    pub save_state: Option<std::path::PathBuf>,
    /// Start from a state written by `--save-state` (its problem, law and size) instead of
    /// building the problem.
    #[arg(long, value_name = "FILE")]
    pub load_state: Option<std::path::PathBuf>,
    /// Start from the simulation of a split-bottom checkpoint (a run directory's
    /// `checkpoint.bin` or `settled.bin`), stepped as it stands (grains, walls, their
    /// motion and law), instead of building the problem.
    #[arg(long, value_name = "FILE", conflicts_with = "load_state")]
    pub split_bottom_state: Option<std::path::PathBuf>,
}

/// The most threads `bench` takes: past the machine's CPUs only to count instructions
/// (with `--members-in-turn`) or to see oversubscription.
const MAX_BENCH_THREADS: usize = 1024;

/// Measures the standard problem for each law and thread count.
pub fn run(args: BenchArgs) -> Result<()> {
    let BenchArgs {
        threads,
        warmup,
        steps,
        problem,
        write_lammps_data,
        lammps_data,
        skin,
        stress_control,
        cohesion,
        normal,
        replicate,
        members_in_turn,
        save_state,
        load_state,
        split_bottom_state,
    } = args;
    if let Some(&n) = threads.iter().find(|&&n| n == 0 || n > MAX_BENCH_THREADS) {
        bail!("--threads {n}: must lie in [1, {MAX_BENCH_THREADS}]");
    }
    rheodem::team::set_members_in_turn(members_in_turn);
    let chute = problem == "chute";
    let skin = skin.unwrap_or(if chute {
        rheodem::bench::chute::SKIN
    } else {
        rheodem::bench::DEFAULT_SKIN
    });
    if !(skin.is_finite() && skin > 0.0) {
        bail!("--skin = {skin}: must be a positive number");
    }
    let all = std::thread::available_parallelism().map_or(1, |n| n.get());
    let counts = if threads.is_empty() {
        if all > 1 { vec![1, all] } else { vec![1] }
    } else {
        threads
    };
    if chute {
        if replicate != 1
            || save_state.is_some()
            || load_state.is_some()
            || split_bottom_state.is_some()
        {
            bail!(
                "--replicate, --save-state and --load-state are for the standard problem \
                 (--problem shear)"
            );
        }
        if stress_control || !cohesion.is_empty() || normal != NormalKind::Linear {
            bail!(
                "--problem chute runs LAMMPS's chute law only (Hooke with tangential history): \
                 leave out --stress-control, --cohesion and --normal"
            );
        }
        return match write_lammps_data {
            Some(path) => write_chute(counts[0], &path),
            None => run_chute(
                &counts,
                warmup,
                steps,
                skin,
                lammps_data.as_deref(),
                members_in_turn,
            ),
        };
    }
    if write_lammps_data.is_some() || lammps_data.is_some() {
        bail!(
            "--write-lammps-data and --lammps-data are for --problem chute (the standard \
             problem's data file comes from benches/peers/lammps_data.py)"
        );
    }
    if let Some((flag, path)) =
        load_state
            .as_ref()
            .map(|p| ("--load-state", p))
            .or(split_bottom_state
                .as_ref()
                .map(|p| ("--split-bottom-state", p)))
    {
        if replicate != 1
            || stress_control
            || !cohesion.is_empty()
            || normal != NormalKind::Linear
            || save_state.is_some()
        {
            bail!(
                "{flag} {}: the state holds its problem, law and size; leave out \
                 --replicate, --stress-control, --cohesion, --normal and --save-state",
                path.display()
            );
        }
        use rheodem::driver::checkpoint::read_checkpoint;
        let sim: rheodem::Simulation = if split_bottom_state.is_some() {
            read_checkpoint::<rheodem::setups::split_bottom::SplitBottomState>(path)
                .map(|state| state.simulation)
        } else {
            read_checkpoint(path)
        }
        .map_err(|e| anyhow::anyhow!("{flag} {}: {e}", path.display()))?;
        println!(
            "state {}: {} particles at step {}",
            path.display(),
            sim.particles.len(),
            sim.step
        );
        for &n in &counts {
            let (pool, n) = bench_pool(n, members_in_turn)?;
            let mut sim = sim.clone();
            let r = pool.install(|| rheodem::bench::run_timed(&mut sim, warmup, steps));
            print_report("state", n, &r);
        }
        return Ok(());
    }
    let variants = if cohesion.is_empty() {
        vec![LawKind::None, LawKind::Reversible, LawKind::LiquidBridge]
    } else {
        cohesion
    };
    if save_state.is_some() && (variants.len() > 1 || counts.len() > 1) {
        bail!("--save-state writes one state: give one --cohesion and one --threads");
    }
    println!("standard problem: {}", rheodem::bench::DESCRIPTION);
    if replicate > 1 {
        println!("repeated {replicate} times along each axis");
    }
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
            let (pool, n) = bench_pool(n, members_in_turn)?;
            let mut sim = rheodem::bench::standard_problem_replicated(
                normal,
                1.0,
                cohesion,
                skin,
                replicate as usize,
            );
            if stress_control {
                rheodem::bench::add_stress_control(&mut sim, 185.0);
            }
            if let Some(path) = &save_state {
                pool.install(|| rheodem::bench::run_timed(&mut sim, warmup, 0));
                rheodem::driver::checkpoint::write_checkpoint(path, &sim)
                    .map_err(|e| anyhow::anyhow!("--save-state {}: {e}", path.display()))?;
                println!(
                    "wrote {} ({} particles at step {})",
                    path.display(),
                    sim.particles.len(),
                    sim.step
                );
                return Ok(());
            }
            let r = pool.install(|| rheodem::bench::run_timed(&mut sim, warmup, steps));
            print_report(&name, n, &r);
        }
    }
    Ok(())
}

/// A pool of `n` threads for the bench (checked against [`MAX_BENCH_THREADS`] already),
/// with a warning past the machine's CPUs unless the members run in turn.
fn bench_pool(n: usize, members_in_turn: bool) -> Result<(rayon::ThreadPool, usize)> {
    let cpus = crate::cpus();
    if n > cpus && !members_in_turn {
        eprintln!("warning: --threads {n} exceeds the {cpus} logical CPUs of this machine");
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map_err(|e| anyhow::anyhow!("cannot start a pool of {n} threads: {e}"))?;
    Ok((pool, n))
}

/// Prepares the chute's state on `threads` threads and writes it as a LAMMPS data file.
fn write_chute(threads: usize, path: &std::path::Path) -> Result<()> {
    use rheodem::bench::chute;
    let (pool, _) = bench_pool(threads, false)?;
    let sim = pool.install(chute::chute_problem);
    std::fs::write(path, chute::lammps_data(&sim))
        .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?;
    println!(
        "wrote {} ({} atoms, {} steps after the stack)",
        path.display(),
        sim.particles.len(),
        sim.step
    );
    Ok(())
}

/// LAMMPS's chute benchmark on each thread count, from the data file `data` or prepared
/// anew.
fn run_chute(
    counts: &[usize],
    warmup: u64,
    steps: u64,
    skin: f64,
    data: Option<&std::path::Path>,
    members_in_turn: bool,
) -> Result<()> {
    use rheodem::bench::chute;
    let text = match data {
        Some(path) => Some((
            path.display().to_string(),
            std::fs::read_to_string(path)
                .map_err(|e| anyhow::anyhow!("cannot read {}: {e}", path.display()))?,
        )),
        None => None,
    };
    println!("chute problem: {}", chute::DESCRIPTION);
    for &n in counts {
        let (pool, n) = bench_pool(n, members_in_turn)?;
        let r = pool.install(|| -> Result<_> {
            let mut sim = match &text {
                Some((shown, t)) => chute::from_lammps_data(t)
                    .map_err(|e| anyhow::anyhow!("--lammps-data {shown}: {e}"))?,
                None => chute::chute_problem(),
            };
            sim.neighbors.skin = skin;
            Ok(rheodem::bench::run_timed(&mut sim, warmup, steps))
        })?;
        print_report("chute", n, &r);
    }
    Ok(())
}

/// The timing of one run and its throughput line (read by benches/peers/run.sh).
fn print_report(name: &str, n: usize, r: &rheodem::bench::BenchReport) {
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
