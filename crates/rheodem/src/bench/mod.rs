//! The throughput problems of `BENCHMARKS.md`: the standard problem (4096 polydisperse
//! spheres at `φ = 0.62`, Hooke + tangential history, `μ = 0.5`, `dt = 3.2·10⁻⁴`, model
//! units), and LAMMPS's own granular benchmark, chute flow ([`chute`]).
//!
//! As in the LAMMPS input, the standard packing starts from the affine profile `v_x = γ̇ y` and is
//! sheared at `γ̇ = 1` through Lees-Edwards boundaries (shear `x`, gradient `y`).

pub mod chute;

use crate::Simulation;
pub use crate::contact::standard::{BENCH_STRENGTH, bench_adhesion, bench_law, bench_law_with};
use crate::contact::{ContactLaw, ContactTable, LawKind, NormalKind};
use crate::domain::Domain;
use crate::io::packing::parse_packing;
use crate::particles::{Motion, Particles, Sphere};
use glam::DVec3;
use std::time::{Duration, Instant};

/// One-line description of the problem as run here.
pub const DESCRIPTION: &str = "standard packing (crates/rheodem/data/bench-packing.txt), \
4096 spheres, phi = 0.62, Hooke + tangential history, mu = 0.5, dt = 3.2e-4, Lees-Edwards shear \
at rate 1 from the affine profile v_x = y";

/// The standard packing, `data/bench-packing.txt`, shipped with the crate: first line
/// `# L <edge> N <count> phi <φ>`, then `diameter x y z` per sphere (density 1).
/// `benches/peers/lammps_data.py` turns the same file into LAMMPS's data file.
pub const PACKING: &str = include_str!("../../data/bench-packing.txt");

/// Verlet skin of the standard problem (model units), as in the LAMMPS input.
pub const DEFAULT_SKIN: f64 = 0.2;

/// Builds the standard problem sheared at `shear_rate` (model units) with the given
/// adhesive law at the bench strength ([`BENCH_STRENGTH`]) and Verlet skin (model units).
pub fn standard_problem(shear_rate: f64, cohesion: LawKind, skin: f64) -> Simulation {
    standard_problem_with(NormalKind::Linear, shear_rate, cohesion, skin)
}

/// [`standard_problem`] with the normal law `normal` of [`bench_law_with`].
pub fn standard_problem_with(
    normal: NormalKind,
    shear_rate: f64,
    cohesion: LawKind,
    skin: f64,
) -> Simulation {
    standard_problem_replicated(normal, shear_rate, cohesion, skin, 1)
}

/// [`standard_problem_with`] on the standard packing repeated `copies` times along each
/// axis (`copies³ × 4096` spheres in a box `copies` times as wide), sheared at the same
/// rate from the affine profile across the whole box: the larger problem of the thread
/// scaling measurements (`copies = 2`: 32 768 spheres).
///
/// # Panics
/// If `copies` is zero.
pub fn standard_problem_replicated(
    normal: NormalKind,
    shear_rate: f64,
    cohesion: LawKind,
    skin: f64,
    copies: usize,
) -> Simulation {
    assert!(copies > 0, "the packing is repeated at least once");
    let packing = parse_packing(PACKING).expect("the shipped packing is valid");
    let edge = packing
        .box_edge
        .expect("the shipped packing has a box edge");
    let mut particles = Particles::default();
    for (a, b, c) in
        (0..copies).flat_map(|a| (0..copies).flat_map(move |b| (0..copies).map(move |c| (a, b, c))))
    {
        let shift = edge * DVec3::new(a as f64, b as f64, c as f64);
        for (d, r) in &packing.spheres {
            let r = *r + shift;
            particles.push(
                Sphere {
                    position: r,
                    velocity: DVec3::new(shear_rate * r.y, 0.0, 0.0),
                    angular_velocity: DVec3::ZERO,
                    radius: 0.5 * d,
                    species: 0,
                    motion: Motion::Free,
                },
                1.0,
            );
        }
    }
    let domain = Domain::new(DVec3::ZERO, DVec3::splat(copies as f64 * edge), [true; 3])
        .with_lees_edwards(shear_rate);
    Simulation::new(
        particles,
        domain,
        ContactTable::uniform(
            1,
            ContactLaw {
                adhesion: bench_adhesion(cohesion),
                ..bench_law_with(normal)
            },
        ),
        Vec::new(),
        DVec3::ZERO,
        3.2e-4,
        skin,
    )
    .expect("the standard problem's box is large enough")
}

/// Puts the standard problem under `σ_yy` control at `target` (model units), with the
/// contact modulus `k_n / d = 10⁴` and a relaxation time of 40 `t_k` (`t_k = 0.01`).
pub fn add_stress_control(sim: &mut Simulation, target: f64) {
    sim.set_stress_control(crate::stress_control::StressControl {
        target,
        modulus: 1.0e4,
        time: 0.4,
        max_strain_per_step: 1e-4,
    });
}

/// Timing of a benchmark run.
#[derive(Clone, Debug)]
pub struct BenchReport {
    /// Threads used.
    pub threads: usize,
    /// Particles.
    pub particles: usize,
    /// Timed steps.
    pub steps: u64,
    /// Wall time of the timed loop.
    pub loop_time: Duration,
    /// Time in neighbour-list checks and rebuilds.
    pub neighbor_time: Duration,
    /// Of [`BenchReport::neighbor_time`], the time in rebuilds.
    pub rebuild_time: Duration,
    /// Time in force evaluation.
    pub force_time: Duration,
    /// Time in the integrator (kicks and drift).
    pub integrate_time: Duration,
    /// Neighbour-list rebuilds in the timed loop.
    pub rebuilds: u64,
    /// Mean stress at the end (model units).
    pub pressure: f64,
    /// Coordination number at the end.
    pub coordination: f64,
    /// Neighbour-list pairs per particle at the end.
    pub pairs_per_particle: f64,
}

impl BenchReport {
    /// Throughput in particle-steps per second.
    pub fn particle_steps_per_second(&self) -> f64 {
        self.particles as f64 * self.steps as f64 / self.loop_time.as_secs_f64()
    }
}

/// Runs `warmup` untimed steps and `steps` timed steps of `sim` in the current rayon pool,
/// timing the phases of each step.
pub fn run_timed(sim: &mut Simulation, warmup: u64, steps: u64) -> BenchReport {
    for _ in 0..warmup {
        sim.step(false).expect("bench box stays valid");
    }
    let builds0 = sim.neighbors.builds;
    let (mut t_nb, mut t_f, mut t_int) = (Duration::ZERO, Duration::ZERO, Duration::ZERO);
    let mut t_build = Duration::ZERO;
    let start = Instant::now();
    for k in 0..steps {
        let measure = k + 1 == steps;
        let t0 = Instant::now();
        sim.begin_step();
        let t1 = Instant::now();
        if sim.list_is_stale() {
            let tb = Instant::now();
            sim.rebuild_neighbors().expect("bench box stays valid");
            t_build += tb.elapsed();
        }
        let t2 = Instant::now();
        sim.compute_forces(measure);
        let t3 = Instant::now();
        sim.end_step();
        let t4 = Instant::now();
        t_int += (t1 - t0) + (t4 - t3);
        t_nb += t2 - t1;
        t_f += t3 - t2;
    }
    let loop_time = start.elapsed();
    let obs = sim.observables();
    BenchReport {
        threads: rayon::current_num_threads(),
        particles: sim.particles.len(),
        steps,
        loop_time,
        neighbor_time: t_nb,
        rebuild_time: t_build,
        force_time: t_f,
        integrate_time: t_int,
        rebuilds: sim.neighbors.builds - builds0,
        pressure: obs.mean_stress(),
        coordination: obs.coordination,
        pairs_per_particle: sim.neighbors.len() as f64 / sim.particles.len() as f64,
    }
}
