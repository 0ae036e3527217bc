//! Helpers shared by the physics tests.
#![allow(dead_code)]

use glam::DVec3;
use rheodem::contact::{ContactLaw, ContactTable, Damping, NormalLaw, Resistance};
use rheodem::domain::Domain;
use rheodem::particles::{Motion, Particles, Sphere};
use rheodem::walls::PlaneWall;
use rheodem::Simulation;

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
        normal: NormalLaw {
            stiffness: KN,
            damping: if e < 1.0 {
                Damping::from_restitution(e, KN)
            } else {
                Damping::NONE
            },
        },
        tangential: Resistance::NONE,
        rolling: Resistance::NONE,
        torsion: Resistance::NONE,
    }
}

/// The paper's frictional law: `k_t = 2/7 k_n`, `γ_t = 2/7 γ_n`, `μ_s = μ_d = mu`.
pub fn frictional_law(e: f64, mu: f64) -> ContactLaw {
    let mut law = normal_law(e);
    law.tangential = Resistance {
        stiffness: 2.0 / 7.0 * KN,
        damping: law.normal.damping.scaled(2.0 / 7.0),
        mu_static: mu,
        mu_dynamic: mu,
    };
    law
}

/// A large non-periodic box.
pub fn open_box(half: f64) -> Domain {
    Domain {
        lo: DVec3::splat(-half),
        hi: DVec3::splat(half),
        periodic: [false; 3],
    }
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
        .map(|(point, normal)| PlaneWall::new(point, normal, 0, p.len()))
        .collect();
    let max_r = spheres.iter().map(|s| s.radius).fold(0.0, f64::max);
    Simulation::new(p, domain, ContactTable::uniform(1, law), walls, gravity, dt, 0.2 * max_r, 0.0)
        .expect("valid test set-up")
}

/// Slot of the particle with permanent id `id`.
pub fn slot(sim: &Simulation, id: u32) -> usize {
    sim.particles.slot_of()[id as usize] as usize
}
