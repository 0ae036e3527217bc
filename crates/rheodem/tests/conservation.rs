//! Conservation laws and determinism of the time integration (docs/model.md §2–3).
//!
//! * **Energy.** Without damping and friction the only force is the linear spring
//!   `f = k_n δ n`, derived from the potential `½ k_n δ²` (continuous, with a continuous force,
//!   at `δ = 0`). Velocity Verlet is symplectic: while the set of touching pairs does not
//!   change, the total energy `Σ ½ m v² + Σ ½ I ω² + Σ ½ k_n δ²` fluctuates by `O((ω dt)²)`
//!   around a constant and does not drift. Each contact that opens or closes is a kink of the
//!   force, where the scheme makes a small energy error of random sign (zero mean; standard
//!   deviation 10⁻⁵ of the pair energy per binary collision at `t_c/100`), so a packing whose
//!   contacts keep changing shows a slow random walk of its energy that vanishes as `dt → 0`.
//!   The tests fit a straight line through the energy sampled every 100 steps over 10⁵ steps
//!   at `dt = t_c/100` and require `|slope| × run length` below 10⁻⁴ of the mean energy for a
//!   compressed packing with a persistent contact network, and below 5·10⁻⁴ (with a
//!   convergence check in `dt`) for a hot dense packing where contacts form and break all the
//!   time.
//! * **Linear momentum.** Every pair force is applied as `+f` on `i` and `−f` on `j`
//!   (normal, tangential, damping alike), periodic images carry no velocity shift, and there
//!   is no wall and no gravity: `Σ m v` is constant up to floating-point rounding, with
//!   friction and damping on.
//! * **Angular momentum.** About the origin, `Σ r × m v + Σ I ω`. The normal force acts along
//!   the branch vector; the tangential force `f_t` gives torques `−l_i n × f_t` and
//!   `−l_j n × f_t` with `l_i + l_j = a_i + a_j − δ = |r_i − r_j|`, which cancel the orbital
//!   term `(r_i − r_j) × f_t`; rolling and torsion torques come in `±` pairs. The kick changes
//!   `L` by `(Σ r × F + Σ T) dt/2 = 0` and the drift leaves `r × m v` unchanged (`v × v = 0`),
//!   so the discrete `L` of an isolated cluster is conserved to rounding, with friction,
//!   damping, rolling and torsion resistance on.
//! * **Determinism.** The force loop splits the half Verlet list into one chunk per thread
//!   and reduces the per-chunk buffers in chunk order, so a run is a pure function of its
//!   set-up and its thread count: repeating it gives bit-identical states.

mod common;

use common::*;
use glam::DVec3;
use rand::RngExt;
use rheodem::Simulation;
use rheodem::contact::{ContactLaw, Resistance};
use rheodem::measure::{angular_momentum, linear_momentum};
use rheodem::particles::Sphere;
use std::time::Instant;

/// Contact time of the lightest pair of two free spheres among `spheres` under `law`.
fn shortest_pair_contact_time(spheres: &[Sphere], law: &ContactLaw) -> f64 {
    let a_min = spheres
        .iter()
        .map(|s| s.radius)
        .fold(f64::INFINITY, f64::min);
    law.normal
        .contact_time(0.5 * mass(a_min), 0.5 * a_min)
        .expect("underdamped")
}

/// The frictional law with rolling and torsion resistance switched on as well
/// (`k_r = k_o = (2/7) k_n`, `γ_r = γ_o = (2/7) γ_n`, `μ_r = μ_o = mu_ro`).
fn full_law(e: f64, mu: f64, mu_ro: f64) -> ContactLaw {
    let mut law = frictional_law(e, mu);
    let resistance = Resistance {
        mu_static: mu_ro,
        mu_dynamic: mu_ro,
        ..*law.tangential.linear().expect("a linear sliding spring")
    };
    law.rolling = resistance.into();
    law.torsion = resistance.into();
    law
}

/// Runs an undamped, frictionless packing for `steps` steps at `dt = t_c / per_contact` (of
/// the lightest pair), sampling the total energy every `every` steps with a measuring step.
/// Returns `(relative drift, relative RMS fluctuation, mean Z)`: the drift is the slope of the
/// least-squares line through the samples times the sampled time span, over the mean energy.
#[allow(clippy::too_many_arguments)]
fn energy_run(
    cells: usize,
    phi: f64,
    w: f64,
    v_rms: f64,
    seed: u64,
    per_contact: f64,
    steps: u64,
    every: u64,
    label: &str,
) -> (f64, f64, f64) {
    let law = normal_law(1.0);
    let (spheres, domain) = fcc_packing(cells, phi, w, v_rms, 0.0, seed);
    let dt = shortest_pair_contact_time(&spheres, &law) / per_contact;
    let mut sim = simulation(&spheres, law, domain, vec![], DVec3::ZERO, dt);
    let clock = Instant::now();
    let (drift, rms, z) = energy_drift(&mut sim, steps, every);
    let elapsed = clock.elapsed();
    eprintln!(
        "energy [{label}]: {} particles, φ = {phi}, w = {w}, {steps} steps at t_c/{per_contact} \
         ({:.0} t_c) in {:.1} s, {} rebuilds, mean Z = {:.2}: relative drift = {drift:.3e}, \
         relative RMS fluctuation = {rms:.3e}",
        sim.particles.len(),
        steps as f64 / per_contact,
        elapsed.as_secs_f64(),
        sim.neighbors.builds,
        z,
    );
    (drift, rms, z)
}

/// Total energy of an undamped, frictionless, compressed periodic packing: no drift over 10⁵
/// steps at `t_c/100`.
///
/// 256 spheres (`w = 1.05`) on an FCC lattice at nominal `φ = 0.78` (soft spheres: every
/// lattice neighbour overlaps by up to ~5 %), with random velocities (σ = 0.05 m/s per
/// component): an elastic solid with `Z ≈ 11.4`, whose contacts are mostly persistent but
/// open and close now and then. 10⁵ steps ≈ 10³ `t_c`, energy sampled every 100 steps.
/// Measured over six seeds: |drift| ≤ 1.8·10⁻⁵, RMS 2–6·10⁻⁶. Criterion: 10⁻⁴.
#[test]
fn energy_is_conserved_in_compressed_packing() {
    let (drift, _, z) = energy_run(4, 0.78, 1.05, 0.05, 11, 100.0, 100_000, 100, "compressed");
    assert!(z > 10.0, "not a dense contact network: Z = {z:.2}");
    assert!(
        drift.abs() < 1e-4,
        "energy drift {drift:.3e} of the mean energy"
    );
}

/// Total energy of an undamped, frictionless, hot dense packing where contacts form and break
/// all the time.
///
/// 256 spheres (`w = 1.2`) at `φ = 0.6`, random velocities σ = 0.1 m/s: `Z ≈ 1.5`, about 2·10⁵
/// contact events in 10³ `t_c`. Each event is a kink of the force (`k_n δ` starts and stops),
/// where Verlet makes an `O(dt²)` energy error of random sign (binary collisions at `t_c/100`:
/// standard deviation 10⁻⁵ of the pair energy, mean zero). The total energy therefore
/// performs a random walk: measured relative "drift" over 10³ `t_c` at `t_c/100` is
/// ±(0.1–1.5)·10⁻⁴ depending on the realisation (7 seeds), falling as `dt²–dt³` (≈3·10⁻⁶ at
/// `t_c/400`), independent of the Verlet skin (50 to 1600 rebuilds) and decreasing as
/// `1/√N` with system size (108 → 864 spheres): integration error, not a missed contact.
/// At `t_c/100` the test bounds the drift by 5·10⁻⁴ (~5σ) and checks the convergence: over
/// 250 `t_c`, the RMS fluctuation at `t_c/400` must be below 1/8 of that at `t_c/100` (second
/// order would give 1/16).
#[test]
fn energy_is_conserved_with_contacts_forming_and_breaking() {
    let (drift, rms_100, z) = energy_run(4, 0.6, 1.2, 0.1, 11, 100.0, 100_000, 100, "hot, t_c/100");
    assert!(z > 1.0, "not dense: Z = {z:.2}");
    assert!(
        drift.abs() < 5e-4,
        "energy drift {drift:.3e} of the mean energy"
    );
    let (_, rms_100_short, _) =
        energy_run(4, 0.6, 1.2, 0.1, 12, 100.0, 25_000, 100, "hot, t_c/100");
    let (_, rms_400_short, _) =
        energy_run(4, 0.6, 1.2, 0.1, 12, 400.0, 100_000, 400, "hot, t_c/400");
    eprintln!(
        "energy: RMS fluctuation over 250 t_c: {rms_100_short:.3e} at t_c/100, {rms_400_short:.3e} at t_c/400 \
         (ratio {:.1}); over 1000 t_c at t_c/100: {rms_100:.3e}",
        rms_100_short / rms_400_short
    );
    assert!(
        rms_400_short < rms_100_short / 8.0,
        "energy error does not converge with dt"
    );
}

/// Total linear momentum of a frictional, damped periodic packing is conserved to rounding.
///
/// 108 spheres at `φ = 0.6` with random velocities and spins, `e = 0.8`, `μ = 0.5`, rolling and
/// torsion resistance on, 500 steps at `t_c/50`. Tolerance 10⁻¹² of `Σ m|v|`: each step adds
/// rounding of order 10⁻¹⁶ of the largest impulses, a few per cent of `m|v|` per step.
#[test]
fn linear_momentum_is_conserved_in_periodic_box() {
    let law = full_law(0.8, 0.5, 0.1);
    let (spheres, domain) = fcc_packing(3, 0.6, 1.2, 0.1, 0.1 / A_REF, 5);
    let dt = shortest_pair_contact_time(&spheres, &law) / 50.0;
    let mut sim = simulation(&spheres, law, domain, vec![], DVec3::ZERO, dt);
    let p0 = linear_momentum(&sim.particles);
    let scale: f64 = (0..sim.particles.len())
        .map(|i| sim.particles.mass[i] * sim.particles.velocity[i].length())
        .sum();
    let (mut worst, mut contacts, mut sliding) = (0.0f64, 0u64, 0.0f64);
    for _ in 0..500 {
        sim.step(true).expect("step");
        let dp = (linear_momentum(&sim.particles) - p0).length() / scale;
        worst = worst.max(dp);
        let obs = sim.observables();
        contacts += obs.contacts;
        sliding += obs.sliding_fraction * obs.contacts as f64;
    }
    let ke: f64 = (0..sim.particles.len())
        .map(|i| 0.5 * sim.particles.mass[i] * sim.particles.velocity[i].length_squared())
        .sum();
    eprintln!(
        "linear momentum: {} particles, 500 steps, {:.1} contacts/step ({:.0} sliding), {} rebuilds, \
         |P0|/Σm|v| = {:.3e}, max |ΔP|/Σm|v| = {worst:.3e}, final KE {ke:.3e} J",
        sim.particles.len(),
        contacts as f64 / 500.0,
        sliding,
        sim.neighbors.builds,
        p0.length() / scale,
    );
    assert!(contacts > 500 * 50, "too few contacts: {contacts}");
    assert!(sliding > 0.0, "no contact ever slid");
    assert!(
        sim.neighbors.has_images(),
        "no pair across the periodic boundary"
    );
    assert!(
        worst < 1e-12,
        "linear momentum changed by {worst:.3e} of Σ m|v|"
    );
}

/// A clump of touching spheres near the origin, imploding with random velocities and spins.
fn clump(count: usize, seed: u64) -> Vec<Sphere> {
    let mut rng = rng(seed);
    // FCC sites with nearest-neighbour distance 2.06 A_REF (the largest diameter), nearest to
    // the origin first.
    let mut sites = Vec::new();
    let s = 2.06 * A_REF * 2f64.sqrt();
    let basis = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(0.5, 0.5, 0.0),
        DVec3::new(0.5, 0.0, 0.5),
        DVec3::new(0.0, 0.5, 0.5),
    ];
    for i in -3..=3 {
        for j in -3..=3 {
            for k in -3..=3 {
                for b in &basis {
                    // Shifted off the lattice origin so that the clump is not symmetric.
                    let r =
                        (DVec3::new(i as f64, j as f64, k as f64) + *b + DVec3::new(0.1, 0.2, 0.3))
                            * s;
                    sites.push(r);
                }
            }
        }
    }
    sites.sort_by(|a, b| a.length().total_cmp(&b.length()));
    sites.truncate(count);
    let r_max = sites.iter().map(|r| r.length()).fold(0.0, f64::max);
    sites
        .into_iter()
        .map(|r| {
            // Radii within ±3 % of A_REF: lattice neighbours start at most 6 % of a apart.
            let a = A_REF * rng.random_range(0.97..1.03);
            // Inward at up to 0.05 m/s, plus random parts, so that the clump collides with
            // itself for hundreds of steps.
            let v = -0.05 * r / r_max + random_vec(&mut rng, 0.01);
            let mut sph = sphere(r, v, a);
            sph.angular_velocity = random_vec(&mut rng, 0.05 / A_REF);
            sph
        })
        .collect()
}

/// Angular momentum (orbital + spin, about the origin) of an isolated clump is conserved to
/// rounding with friction, damping, rolling and torsion resistance on.
///
/// 40 spheres, `e = 0.5`, `μ = 0.5`, `μ_r = μ_o = 0.05`, open box, no walls, no gravity,
/// 400 steps at `t_c/50`. Tolerance 10⁻¹² of `Σ |r × m v| + |I ω|` (rounding of the pair
/// torques is ~10⁻¹⁶ of each term per step).
#[test]
fn angular_momentum_is_conserved_for_isolated_clump() {
    let law = full_law(0.5, 0.5, 0.05);
    let spheres = clump(40, 3);
    let dt = shortest_pair_contact_time(&spheres, &law) / 50.0;
    let mut sim = simulation(&spheres, law, open_box(0.02), vec![], DVec3::ZERO, dt);
    let p = &sim.particles;
    let l0 = angular_momentum(p);
    let scale: f64 = (0..p.len())
        .map(|i| {
            p.position[i].cross(p.velocity[i] * p.mass[i]).length()
                + (p.angular_velocity[i] / p.inv_inertia[i]).length()
        })
        .sum();
    let spin0: DVec3 = (0..p.len())
        .map(|i| p.angular_velocity[i] / p.inv_inertia[i])
        .sum();
    let (mut worst, mut contacts, mut sliding) = (0.0f64, 0u64, 0.0f64);
    // Largest rolling and torsion spring seen (m): the resistances must have acted.
    let (mut rolling, mut torsion) = (0.0f64, 0.0f64);
    // The clump closes its gaps in ~80 steps, collides for ~300 and then disperses.
    let steps = 400;
    for _ in 0..steps {
        sim.step(true).expect("step");
        let dl = (angular_momentum(&sim.particles) - l0).length() / scale;
        worst = worst.max(dl);
        let obs = sim.observables();
        contacts += obs.contacts;
        sliding += obs.sliding_fraction * obs.contacts as f64;
        let pairs = sim.neighbors.slices();
        for h in pairs.history.iter() {
            rolling = rolling.max(h.rolling.length());
            torsion = torsion.max(h.torsion.length());
        }
    }
    let p = &sim.particles;
    let spin1: DVec3 = (0..p.len())
        .map(|i| p.angular_velocity[i] / p.inv_inertia[i])
        .sum();
    eprintln!(
        "angular momentum: {} particles, {steps} steps, {:.1} contacts/step ({:.0} sliding), \
         largest rolling/torsion spring {rolling:.2e}/{torsion:.2e} m, |L0|/scale = {:.3e}, \
         spin part moved by {:.3e} of scale, max |ΔL|/scale = {worst:.3e}",
        p.len(),
        contacts as f64 / steps as f64,
        sliding,
        l0.length() / scale,
        (spin1 - spin0).length() / scale,
    );
    assert!(contacts > steps * 10, "too few contacts: {contacts}");
    assert!(sliding > 0.0, "no contact ever slid");
    assert!(
        rolling > 0.0 && torsion > 0.0,
        "rolling or torsion resistance never acted"
    );
    // The exchange between orbital and spin parts must be real for the test to mean something.
    assert!(
        (spin1 - spin0).length() > 1e-3 * scale,
        "no torque exchange"
    );
    assert!(
        worst < 1e-12,
        "angular momentum changed by {worst:.3e} of the scale"
    );
}

/// Bit pattern of the state of every particle, ordered by permanent id.
fn fingerprint(sim: &Simulation) -> Vec<[u64; 9]> {
    let p = &sim.particles;
    let slot = p.slot_of();
    (0..p.len())
        .map(|id| {
            let i = slot[id] as usize;
            let (r, v, w) = (p.position[i], p.velocity[i], p.angular_velocity[i]);
            [r.x, r.y, r.z, v.x, v.y, v.z, w.x, w.y, w.z].map(f64::to_bits)
        })
        .collect()
}

/// A frictional, damped periodic packing with rolling and torsion resistance, stepped 600
/// times at `t_c/50` (several neighbour-list rebuilds and re-sorts).
fn determinism_run() -> (Vec<[u64; 9]>, u64) {
    let law = full_law(0.8, 0.5, 0.1);
    let (spheres, domain) = fcc_packing(3, 0.6, 1.2, 0.2, 0.2 / A_REF, 17);
    let dt = shortest_pair_contact_time(&spheres, &law) / 50.0;
    let mut sim = simulation(&spheres, law, domain, vec![], DVec3::ZERO, dt);
    for k in 0..600 {
        sim.step(k % 7 == 0).expect("step");
    }
    (fingerprint(&sim), sim.neighbors.builds)
}

/// The same set-up stepped twice gives bit-identical states, in the default pool and in
/// pools of 1 and 3 threads (3 chunks on fewer cores exercises the ordered reduction under
/// work stealing). Whether different thread counts agree is reported, not required.
#[test]
fn runs_are_bit_identical_for_a_given_thread_count() {
    let (first, builds) = determinism_run();
    let (second, _) = determinism_run();
    assert!(
        builds > 3,
        "only {builds} neighbour builds: the test would not exercise re-sorting"
    );
    assert!(first == second, "two runs in the default pool differ");

    let mut by_threads = Vec::new();
    for threads in [1usize, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        let (a, _) = pool.install(determinism_run);
        let (b, _) = pool.install(determinism_run);
        assert!(a == b, "two runs with {threads} threads differ");
        by_threads.push((threads, a));
    }
    for (threads, state) in &by_threads {
        eprintln!(
            "determinism: {builds} rebuilds; {threads} thread(s) vs default pool ({} threads): {}",
            rayon::current_num_threads(),
            if *state == first {
                "bit-identical"
            } else {
                "differ (allowed)"
            }
        );
    }
}

/// Cloning a simulation mid-run (a checkpoint) and stepping both copies gives bit-identical
/// states: everything a step depends on lives in `Simulation`.
#[test]
fn clone_continues_bit_identically() {
    let law = full_law(0.8, 0.5, 0.1);
    let (spheres, domain) = fcc_packing(3, 0.6, 1.2, 0.2, 0.2 / A_REF, 23);
    let dt = shortest_pair_contact_time(&spheres, &law) / 50.0;
    let mut sim = simulation(&spheres, law, domain, vec![], DVec3::ZERO, dt);
    for _ in 0..150 {
        sim.step(false).expect("step");
    }
    let mut copy = sim.clone();
    for _ in 0..300 {
        sim.step(false).expect("step");
        copy.step(false).expect("step");
    }
    assert!(
        fingerprint(&sim) == fingerprint(&copy),
        "the clone diverged"
    );
}
