//! LAMMPS's own granular benchmark, chute flow (`bench/in.chute` of the LAMMPS
//! distribution), as both codes run it side by side (`PROBLEM=chute` of
//! `benches/peers/run.sh`, input `benches/peers/lammps-in.chute`).
//!
//! Reduced units (`d = 1`, density 1, `g = 1`): 32 000 monodisperse spheres above a frozen
//! rough base of 800, periodic along `x` and `y`, open along `z` (LAMMPS's `boundary p p
//! fs`), gravity 1 tilted by 26° (`fix gravity 1.0 chute 26.0`), the Hookean law with
//! tangential history `k_n = 2·10⁵`, `k_t = 2/7 k_n`, mass-proportional normal damping
//! `γ_n = 50` (per unit reduced mass), no tangential damping, `μ = 0.5`
//! (`pair_style gran/hooke/history 200000.0 NULL 50.0 NULL 0.5 0`), base–base pairs
//! excluded, skin 0.1, `dt = 10⁻⁴`.
//!
//! LAMMPS's own input reads a flowing state from its data file. Here the layer is built as
//! a loose simple-cubic stack, 40 × 20 columns of 40 spheres 1.025 apart in the plane and
//! 1.05 apart in height (positions jittered by ±0.01), on a base of one sphere per column
//! lowered by up to 0.3, and falls for [`PREPARE_STEPS`] steps into contact; that state is
//! what both codes time: `rheodem bench --problem chute --write-lammps-data FILE` writes it
//! as a LAMMPS data file once, and LAMMPS and `rheodem bench --problem chute --lammps-data
//! FILE` ([`from_lammps_data`]) both start from that file.

use crate::Simulation;
use crate::contact::{ContactLaw, ContactTable, Damping, LinearNormal, Resistance, Spring};
use crate::domain::Domain;
use crate::generate::Rng;
use crate::particles::{Motion, Particles, Sphere};
use glam::DVec3;
use rand::{RngExt, SeedableRng};
use std::fmt::Write;

/// One-line description of the problem as run here.
pub const DESCRIPTION: &str = "LAMMPS's chute benchmark (bench/in.chute): 32000 spheres on a \
frozen rough base of 800, periodic x and y, gravity 1 at 26 degrees, Hooke + tangential \
history k_n = 2e5, gamma_n = 50 per unit mass, mu = 0.5, dt = 1e-4, skin 0.1";

/// Columns of the stack along `x` and `y`.
pub const COLUMNS: [usize; 2] = [40, 20];
/// Spheres per column (the free spheres: 32 000 in all).
pub const LAYERS: usize = 40;
/// Spacing of the columns (diameters).
pub const SPACING: f64 = 1.025;
/// Spacing of the layers (diameters).
pub const LAYER_SPACING: f64 = 1.05;
/// Inclination of gravity (degrees).
pub const ANGLE_DEG: f64 = 26.0;
/// Time step (reduced units).
pub const DT: f64 = 1e-4;
/// Verlet skin (diameters).
pub const SKIN: f64 = 0.1;
/// Steps the stack falls before the state both codes time: 3 time units, in which its top
/// layer has fallen onto the layers below and the compacted layer starts to flow.
pub const PREPARE_STEPS: u64 = 30_000;
/// Density of the spheres (reduced units).
pub const DENSITY: f64 = 1.0;
/// Lower and upper ends of the box along `z` (LAMMPS shrink-wraps beyond them).
pub const Z_RANGE: [f64; 2] = [-1.0, 45.0];

/// The contact law of every pair: `gran/hooke/history 200000.0 NULL 50.0 NULL 0.5 0`.
pub fn law() -> ContactLaw {
    let k = 2e5;
    ContactLaw {
        normal: LinearNormal {
            stiffness: k,
            damping: Damping {
                per_mass: 50.0,
                ..Damping::NONE
            },
        }
        .into(),
        tangential: Resistance {
            stiffness: 2.0 / 7.0 * k,
            damping: Damping::NONE,
            mu_static: 0.5,
            mu_dynamic: 0.5,
        }
        .into(),
        rolling: Spring::NONE,
        torsion: Spring::NONE,
        adhesion: Default::default(),
    }
}

/// The stack on its base, at rest, before it falls.
pub fn stack() -> Simulation {
    let mut rng = Rng::seed_from_u64(1);
    let mut jitter = |a: f64| a * (2.0 * rng.random::<f64>() - 1.0);
    let mut particles = Particles::default();
    let mut add = |r: DVec3, motion: Motion| {
        particles.push(
            Sphere {
                position: r,
                velocity: DVec3::ZERO,
                angular_velocity: DVec3::ZERO,
                radius: 0.5,
                species: 0,
                motion,
            },
            DENSITY,
        );
    };
    let [nx, ny] = COLUMNS;
    for i in 0..nx {
        for j in 0..ny {
            let (x, y) = ((i as f64 + 0.5) * SPACING, (j as f64 + 0.5) * SPACING);
            let lowered = 0.15 * (jitter(1.0) + 1.0);
            add(
                DVec3::new(x + jitter(0.01), y + jitter(0.01), -lowered),
                Motion::Fixed,
            );
            for k in 0..LAYERS {
                let z = (k as f64 + 1.0) * LAYER_SPACING;
                add(
                    DVec3::new(x + jitter(0.01), y + jitter(0.01), z + jitter(0.01)),
                    Motion::Free,
                );
            }
        }
    }
    assemble(
        particles,
        [Z_RANGE[0], Z_RANGE[1]],
        [nx as f64 * SPACING, ny as f64 * SPACING],
    )
    .expect("the chute's box holds three cells along x and y")
}

/// The chute of `particles` in the box `[0, L_x) × [0, L_y) × [z_lo, z_hi]`, periodic along
/// `x` and `y`, with the law, gravity, time step and skin of the problem.
fn assemble(
    particles: Particles,
    z: [f64; 2],
    lengths: [f64; 2],
) -> Result<Simulation, crate::neighbor::NeighborError> {
    let domain = Domain::new(
        DVec3::new(0.0, 0.0, z[0]),
        DVec3::new(lengths[0], lengths[1], z[1]),
        [true, true, false],
    );
    let theta = ANGLE_DEG.to_radians();
    Simulation::new(
        particles,
        domain,
        ContactTable::uniform(1, law()),
        Vec::new(),
        DVec3::new(theta.sin(), 0.0, -theta.cos()),
        DT,
        SKIN,
    )
}

/// The state both codes time: the stack after it has fallen for [`PREPARE_STEPS`] steps.
pub fn chute_problem() -> Simulation {
    let mut sim = stack();
    for _ in 0..PREPARE_STEPS {
        sim.step(false).expect("the chute stays valid");
    }
    sim
}

/// `sim` as a LAMMPS data file for `atom_style sphere` (the box, then `Atoms` as `id type
/// diameter density x y z` and `Velocities` as `id vx vy vz ωx ωy ωz`, by particle id,
/// type 2 for the frozen base, density [`DENSITY`]), positions wrapped into the periodic box, every number in
/// Rust's shortest round-trip form.
pub fn lammps_data(sim: &Simulation) -> String {
    let p = &sim.particles;
    let (lo, hi) = (sim.domain.lo, sim.domain.hi);
    let l = hi - lo;
    let mut s = format!(
        "LAMMPS data file: {DESCRIPTION}; written by rheodem {} after {} steps\n\n{} atoms\n2 atom \
         types\n\n{} {} xlo xhi\n{} {} ylo yhi\n{} {} zlo zhi\n\nAtoms # sphere\n\n",
        crate::VERSION,
        sim.step,
        p.len(),
        lo.x,
        hi.x,
        lo.y,
        hi.y,
        lo.z,
        hi.z
    );
    let slots = p.slot_of();
    for (id, &k) in slots.iter().enumerate() {
        let k = k as usize;
        let r = p.position[k];
        let wrap = |x: f64, a: usize| lo[a] + (x - lo[a]).rem_euclid(l[a]);
        let kind = if p.motion[k].is_free() { 1 } else { 2 };
        let _ = writeln!(
            s,
            "{} {kind} {} {DENSITY} {} {} {}",
            id + 1,
            2.0 * p.radius[k],
            wrap(r.x, 0),
            wrap(r.y, 1),
            r.z
        );
    }
    s.push_str("\nVelocities\n\n");
    for (id, &k) in slots.iter().enumerate() {
        let (v, w) = (p.velocity[k as usize], p.angular_velocity[k as usize]);
        let _ = writeln!(
            s,
            "{} {} {} {} {} {} {}",
            id + 1,
            v.x,
            v.y,
            v.z,
            w.x,
            w.y,
            w.z
        );
    }
    s
}

/// The chute problem in the state of a LAMMPS data file written by [`lammps_data`] (or any
/// `atom_style sphere` data file of the same box: type 2 frozen, the rest free; velocities
/// and spins from its `Velocities` section where it has one).
///
/// # Errors
/// A message naming the line that is not a number, an atom without a position, or a box
/// that is missing or too small.
pub fn from_lammps_data(text: &str) -> Result<Simulation, String> {
    let mut bounds = [[f64::NAN; 2]; 3];
    let mut atoms: Vec<(u64, Sphere, f64)> = Vec::new();
    let mut velocities = std::collections::HashMap::new();
    let mut section = "";
    for (n, line) in text.lines().enumerate().skip(1) {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        let numbers = |k: usize| -> Result<Vec<f64>, String> {
            words
                .iter()
                .take(k)
                .map(|w| w.parse::<f64>())
                .collect::<Result<Vec<f64>, _>>()
                .ok()
                .filter(|v| v.len() == k)
                .ok_or_else(|| format!("line {}: `{line}` needs {k} numbers", n + 1))
        };
        match words.as_slice() {
            ["Atoms"] => section = "atoms",
            ["Velocities"] => section = "velocities",
            [_, _, axis, _] if axis.ends_with("lo") => {
                let a = ["xlo", "ylo", "zlo"]
                    .iter()
                    .position(|x| x == axis)
                    .ok_or_else(|| format!("line {}: unknown bounds `{line}`", n + 1))?;
                let v = numbers(2)?;
                bounds[a] = [v[0], v[1]];
            }
            _ if section == "atoms" => {
                let v = numbers(7)?;
                let sphere = Sphere {
                    position: DVec3::new(v[4], v[5], v[6]),
                    velocity: DVec3::ZERO,
                    angular_velocity: DVec3::ZERO,
                    radius: 0.5 * v[2],
                    species: 0,
                    motion: if v[1] == 2.0 {
                        Motion::Fixed
                    } else {
                        Motion::Free
                    },
                };
                atoms.push((v[0] as u64, sphere, v[3]));
            }
            _ if section == "velocities" => {
                let v = numbers(7)?;
                velocities.insert(
                    v[0] as u64,
                    (DVec3::new(v[1], v[2], v[3]), DVec3::new(v[4], v[5], v[6])),
                );
            }
            _ => {}
        }
    }
    if bounds.iter().flatten().any(|b| !b.is_finite()) {
        return Err("the data file lacks its box (xlo xhi, ylo yhi, zlo zhi)".into());
    }
    if atoms.is_empty() {
        return Err("the data file has no Atoms".into());
    }
    atoms.sort_by_key(|a| a.0);
    let mut particles = Particles::default();
    for (id, mut sphere, density) in atoms {
        if let (Some((v, w)), true) = (velocities.get(&id), sphere.motion.is_free()) {
            sphere.velocity = *v;
            sphere.angular_velocity = *w;
        }
        particles.push(sphere, density);
    }
    if bounds[0][0] != 0.0 || bounds[1][0] != 0.0 {
        return Err("the box must start at x = 0 and y = 0 (xlo, ylo)".into());
    }
    assemble(particles, bounds[2], [bounds[0][1], bounds[1][1]]).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stack: 32 000 free spheres and 800 frozen ones, none overlapping, all inside the
    /// box; the data file lists each once, base as type 2, in id order.
    #[test]
    fn the_stack_is_lammps_chute_and_its_data_file_lists_it() {
        let sim = stack();
        let p = &sim.particles;
        assert_eq!(p.len(), 32_800);
        assert_eq!(p.free_count(), 32_000);
        assert!(!sim.neighbors.is_empty());
        let data = lammps_data(&sim);
        assert!(data.contains("\n32800 atoms\n2 atom types\n"));
        let atoms: Vec<&str> = data
            .split("Atoms # sphere\n\n")
            .nth(1)
            .and_then(|t| t.split("\nVelocities").next())
            .expect("an Atoms section")
            .lines()
            .collect();
        assert_eq!(atoms.len(), 32_800);
        assert_eq!(
            atoms
                .iter()
                .filter(|l| l.split(' ').nth(1) == Some("2"))
                .count(),
            800
        );
        for (k, line) in atoms.iter().enumerate() {
            let f: Vec<f64> = line
                .split(' ')
                .map(|x| x.parse().expect("a number"))
                .collect();
            assert_eq!(f[0] as usize, k + 1);
            assert_eq!((f[2], f[3]), (1.0, 1.0));
            assert!((0.0..41.0).contains(&f[4]) && (0.0..20.5).contains(&f[5]));
            assert!((Z_RANGE[0]..Z_RANGE[1]).contains(&f[6]));
        }
        // The data file reads back as the same spheres.
        let back = from_lammps_data(&data).expect("its own data file");
        assert_eq!(back.particles.len(), 32_800);
        assert_eq!(back.particles.free_count(), 32_000);
        let (a, b) = (sim.particles.slot_of(), back.particles.slot_of());
        for id in [0, 1, 4_000, 32_799] {
            let (r, q) = (
                sim.particles.position[a[id] as usize],
                back.particles.position[b[id] as usize],
            );
            assert!(
                (r - q).length() < 1e-12 || (r.z - q.z).abs() < 1e-12,
                "{r} {q}"
            );
        }
        assert!(from_lammps_data("x\n\n1 atoms\n").is_err());
        // No two spheres touch in the stack (the closest are 1.005 apart).
        let mut sim = sim;
        sim.compute_forces(true);
        assert_eq!(sim.contact_summary().contacts, 0);
    }
}
