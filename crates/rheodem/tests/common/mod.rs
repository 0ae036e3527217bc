//! Helpers shared by the physics tests.
#![allow(dead_code)]

use glam::DVec3;
use rheodem::Simulation;
use rheodem::contact::{
    Adhesion, ContactLaw, ContactTable, Damping, LinearNormal, Resistance, Spring,
};
use rheodem::domain::Domain;
use rheodem::particles::{Motion, Particles, Sphere};
use rheodem::walls::Wall;

/// Density used by the tests (kg/m³).
pub const RHO: f64 = 2000.0;
/// Normal stiffness used by the tests (N/m).
pub const KN: f64 = 100.0;

/// A free sphere.
pub fn sphere(position: DVec3, velocity: DVec3, radius: f64) -> Sphere {
    Sphere {
        position,
        velocity,
        angular_velocity: DVec3::ZERO,
        radius,
        species: 0,
        motion: Motion::Free,
    }
}

/// Frictionless linear law with restitution `e` (or undamped when `e == 1`).
pub fn normal_law(e: f64) -> ContactLaw {
    ContactLaw {
        normal: LinearNormal {
            stiffness: KN,
            damping: if e < 1.0 {
                Damping::from_restitution(e, KN)
            } else {
                Damping::NONE
            },
        }
        .into(),
        tangential: Spring::NONE,
        rolling: Spring::NONE,
        torsion: Spring::NONE,
        adhesion: Adhesion::None,
    }
}

/// The paper's frictional law: `k_t = 2/7 k_n`, `γ_t = 2/7 γ_n`, `μ_s = μ_d = mu`.
pub fn frictional_law(e: f64, mu: f64) -> ContactLaw {
    let mut law = normal_law(e);
    law.tangential = Resistance {
        stiffness: 2.0 / 7.0 * KN,
        damping: law
            .normal
            .linear()
            .expect("a linear normal law")
            .damping
            .scaled(2.0 / 7.0),
        mu_static: mu,
        mu_dynamic: mu,
    }
    .into();
    law
}

/// A large non-periodic box.
pub fn open_box(half: f64) -> Domain {
    Domain::new(DVec3::splat(-half), DVec3::splat(half), [false; 3])
}

/// Builds a simulation of the given spheres with one law for everything.
pub fn simulation(
    spheres: &[Sphere],
    law: ContactLaw,
    domain: Domain,
    walls: Vec<(DVec3, DVec3)>,
    gravity: DVec3,
    dt: f64,
) -> Simulation {
    let mut p = Particles::default();
    for s in spheres {
        p.push(*s, RHO);
    }
    let walls = walls
        .into_iter()
        .map(|(point, normal)| Wall::plane(point, normal, 0))
        .collect();
    let max_r = spheres.iter().map(|s| s.radius).fold(0.0, f64::max);
    Simulation::new(
        p,
        domain,
        ContactTable::uniform(1, law),
        walls,
        gravity,
        dt,
        0.2 * max_r,
    )
    .expect("valid test set-up")
}

/// Slot of the particle with permanent id `id`.
pub fn slot(sim: &Simulation, id: u32) -> usize {
    sim.particles.slot_of()[id as usize] as usize
}

// ---------------------------------------------------------------------------------------
// Helpers of the friction and conservation tests.
// ---------------------------------------------------------------------------------------

use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Radius of the reference test sphere (m): `d_p = 2.2 mm`, as in the paper.
pub const A_REF: f64 = 1.1e-3;

/// Mass (kg) of a free sphere of radius `a` (m) at the test density.
pub fn mass(a: f64) -> f64 {
    RHO * 4.0 / 3.0 * std::f64::consts::PI * a.powi(3)
}

/// A deterministic random generator for test set-ups.
pub fn rng(seed: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(seed)
}

/// A vector with components uniform in `[-s, s]`.
pub fn random_vec(rng: &mut Xoshiro256PlusPlus, s: f64) -> DVec3 {
    DVec3::new(
        rng.random_range(-s..s),
        rng.random_range(-s..s),
        rng.random_range(-s..s),
    )
}

/// Tangential part of the relative velocity of the two surfaces at the contact point of
/// spheres `i` and `j`: `v_c = (v_i − v_j) − (l_i ω_i + l_j ω_j) × n`, `n` the unit normal
/// from `j` to `i` and `l` the lever arms (the radii when the spheres just touch), with the
/// normal component removed. This is the `v_t` of docs/model.md §2.1.
pub fn contact_slip(v_rel: DVec3, w_i: DVec3, w_j: DVec3, l_i: f64, l_j: f64, n: DVec3) -> DVec3 {
    let v_c = v_rel - (l_i * w_i + l_j * w_j).cross(n);
    v_c - n * n.dot(v_c)
}

/// A triply periodic, polydisperse packing on a face-centred cubic lattice:
/// `4 cells³` free spheres with radii uniform in `[r, w r]` (mean diameter `2 A_REF`),
/// assigned to lattice sites at random, the box edge set so that the volume fraction is
/// `phi`. Velocity components are uniform with standard deviation `v_rms` and zero total
/// momentum is *not* enforced; angular velocity components are uniform with standard
/// deviation `spin` (rad/s). At `w = 1.2`, `phi ≈ 0.575` is the density where the largest
/// spheres just touch their nearest lattice neighbours; above it the larger pairs start
/// out overlapping, which gives a dense set-up with many contacts from the first step.
pub fn fcc_packing(
    cells: usize,
    phi: f64,
    w: f64,
    v_rms: f64,
    spin: f64,
    seed: u64,
) -> (Vec<Sphere>, Domain) {
    let mut rng = rng(seed);
    let n = 4 * cells * cells * cells;
    let raw: Vec<f64> = (0..n).map(|_| rng.random_range(1.0..w)).collect();
    let mean = raw.iter().sum::<f64>() / n as f64;
    let radii: Vec<f64> = raw.iter().map(|r| r * A_REF / mean).collect();
    let volume: f64 = radii
        .iter()
        .map(|a| 4.0 / 3.0 * std::f64::consts::PI * a.powi(3))
        .sum();
    let edge = (volume / phi).cbrt();
    let s = edge / cells as f64;
    // Uniform in [-√3 σ, √3 σ] has standard deviation σ.
    let (v_amp, w_amp) = (3f64.sqrt() * v_rms, 3f64.sqrt() * spin);
    let basis = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(0.5, 0.5, 0.0),
        DVec3::new(0.5, 0.0, 0.5),
        DVec3::new(0.0, 0.5, 0.5),
    ];
    let mut spheres = Vec::with_capacity(n);
    for i in 0..cells {
        for j in 0..cells {
            for k in 0..cells {
                for b in &basis {
                    let cell = DVec3::new(i as f64, j as f64, k as f64);
                    let position = (cell + *b + DVec3::splat(0.25)) * s;
                    let mut sph =
                        sphere(position, random_vec(&mut rng, v_amp), radii[spheres.len()]);
                    sph.angular_velocity = if spin > 0.0 {
                        random_vec(&mut rng, w_amp)
                    } else {
                        DVec3::ZERO
                    };
                    spheres.push(sph);
                }
            }
        }
    }
    let domain = Domain::new(DVec3::ZERO, DVec3::splat(edge), [true; 3]);
    (spheres, domain)
}

/// Least-squares straight line through `(x, y)`: returns `(intercept, slope)`.
pub fn linear_fit(x: &[f64], y: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    let slope = sxy / sxx;
    (my - slope * mx, slope)
}

/// Runs `sim` for `steps` steps on one thread (the same realisation of the integration
/// error on every machine), sampling the total energy every `every` steps with a measuring
/// step. Returns `(relative drift, relative RMS fluctuation, mean Z)`: the drift is the
/// slope of the least-squares line through the samples times the sampled time span, over
/// the mean energy.
pub fn energy_drift(sim: &mut Simulation, steps: u64, every: u64) -> (f64, f64, f64) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("thread pool");
    let (t, energy, z) = pool.install(|| {
        let (mut t, mut energy, mut z) = (Vec::new(), Vec::new(), 0.0);
        for k in 1..=steps {
            let measure = k % every == 0;
            sim.step(measure).expect("step");
            if measure {
                let obs = sim.observables();
                t.push(sim.time);
                energy.push(obs.total_energy());
                z += obs.coordination;
            }
        }
        (t, energy, z)
    });
    let n = energy.len() as f64;
    let mean = energy.iter().sum::<f64>() / n;
    let (_, slope) = linear_fit(&t, &energy);
    let drift = slope * (t[t.len() - 1] - t[0]) / mean;
    let rms = (energy.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / n).sqrt() / mean;
    (drift, rms, z / n)
}
