//! Observables of the particle system (docs/model.md §7): energies, stress tensor, coordination,
//! volume fraction, momenta.

use crate::contact::{PairForce, PairKinematics};
use crate::domain::Domain;
use crate::observe::{ContactObserver, ContactView, outer};
use crate::particles::Particles;
use crate::sanity::DeepestContact;
use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

/// Sums over contacts gathered by a force evaluation in measuring mode.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactSums {
    /// `Σ f_ij ⊗ l_ij` over interacting pairs (N m), `f_ij` the force on `i` and
    /// `l_ij = r_i − r_j` through periodic images; for a planar wall, `l` runs from the
    /// contact point's foot on the wall to the centre.
    pub stress_sum: DMat3,
    /// Elastic energy stored in the contacts (J).
    pub elastic_energy: f64,
    /// Contacts with overlap `δ > 0`.
    pub contacts: u64,
    /// Contacts whose sliding spring slipped.
    pub sliding: u64,
    /// Pairs apart (`δ ≤ 0`) that still attract (open bridges, or a reversible law's range).
    pub attracting_apart: u64,
    /// The deepest contact (largest overlap over the smaller radius).
    #[serde(default)]
    pub deepest: DeepestContact,
    /// Energy of the contact springs alone (J, ≥ 0): the repulsive part of
    /// `elastic_energy`, without the (negative) adhesive potential; equal to it without
    /// adhesion.
    #[serde(default)]
    pub spring_energy: f64,
}

impl Default for ContactSums {
    /// All sums zero (glam's `DMat3::default()` is the identity, hence no derive).
    fn default() -> Self {
        ContactSums {
            stress_sum: DMat3::ZERO,
            elastic_energy: 0.0,
            contacts: 0,
            sliding: 0,
            attracting_apart: 0,
            deepest: DeepestContact::default(),
            spring_energy: 0.0,
        }
    }
}

impl ContactSums {
    /// Adds another set of sums.
    pub fn add(&mut self, o: &ContactSums) {
        self.stress_sum += o.stress_sum;
        self.elastic_energy += o.elastic_energy;
        self.contacts += o.contacts;
        self.sliding += o.sliding;
        self.attracting_apart += o.attracting_apart;
        self.deepest.merge(&o.deepest);
        self.spring_energy += o.spring_energy;
    }

    /// Adds one interacting pair: force `pf` on `i`, kinematics `k`, stored energies
    /// `(elastic, springs)` (J; see the fields), branch vector `branch = r_i − r_j` (m) and
    /// the partners' ids (a particle id and a wall index if `wall`).
    #[inline]
    pub fn add_pair(
        &mut self,
        pf: &PairForce,
        k: &PairKinematics,
        energy: (f64, f64),
        branch: DVec3,
        pair: [u32; 2],
        wall: bool,
    ) {
        self.stress_sum += outer(pf.force, branch);
        self.elastic_energy += energy.0;
        self.spring_energy += energy.1;
        if k.overlap > 0.0 {
            self.contacts += 1;
            self.sliding += u64::from(pf.sliding);
            self.deepest.merge(&DeepestContact {
                ratio: k.overlap / k.radius_i.min(k.radius_j),
                overlap: k.overlap,
                pair,
                wall,
            });
        } else {
            self.attracting_apart += 1;
        }
    }
}

impl ContactObserver for ContactSums {
    #[inline]
    fn visit(&mut self, c: &ContactView<'_>) {
        let pair = [c.ids[0], c.ids[1]];
        let k = c.kinematics;
        let springs = c.spring_energy();
        let elastic = springs
            + c.kernel
                .adhesive_potential(k.overlap, k.radius_i, k.radius_j, c.history.bridge);
        self.add_pair(
            c.force,
            c.kinematics,
            (elastic, springs),
            c.branch,
            pair,
            c.wall.is_some(),
        );
    }
    fn merge(&mut self, other: Self) {
        self.add(&other);
    }
}

/// What the contacts of a measured step say: the part of [`Observables`] that comes from the
/// contact sums alone, without a walk over the neighbour list.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactSummary {
    /// Elastic energy stored in contacts (J).
    pub elastic_energy: f64,
    /// Energy of the contact springs alone (J), without the adhesive potential.
    pub spring_energy: f64,
    /// Contacts with `δ > 0` (particle pairs and wall contacts).
    pub contacts: u64,
    /// Fraction of contacts that slide.
    pub sliding_fraction: f64,
    /// Coordination number `Z = 2 N_c / N` over free particles.
    pub coordination: f64,
    /// Pairs apart that still attract (open liquid bridges, reversible range), per free
    /// particle.
    pub bridges_per_particle: f64,
}

/// One row of the time series.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Observables {
    /// Simulated time (s).
    pub time: f64,
    /// Step number.
    pub step: u64,
    /// Translational kinetic energy of the free particles, `½ Σ m v²` (J).
    pub kinetic_translational: f64,
    /// Rotational kinetic energy of the free particles, `½ Σ I ω²` (J).
    pub kinetic_rotational: f64,
    /// Elastic energy stored in contacts (J).
    pub elastic_energy: f64,
    /// Contacts with `δ > 0` (particle pairs and wall contacts).
    pub contacts: u64,
    /// Fraction of contacts that slide.
    pub sliding_fraction: f64,
    /// Coordination number `Z = 2 N_c / N` over free particles.
    pub coordination: f64,
    /// Coordination number without rattlers (particles with fewer than 2 particle contacts).
    #[serde(default)]
    pub coordination_without_rattlers: f64,
    /// Pairs apart that still attract (open liquid bridges, reversible range), per free
    /// particle.
    pub bridges_per_particle: f64,
    /// Volume fraction of the free particles in the box.
    pub volume_fraction: f64,
    /// Box edge lengths (m).
    pub box_size: [f64; 3],
    /// Granular temperature `T_g = (1/3N) Σ |v − u(r)|²` (m²/s²), `u` the mean flow.
    pub granular_temperature: f64,
    /// Stress tensor `σ = (Σ m v'⊗v' + Σ f⊗l) / V` (Pa), compression positive, row-major.
    pub stress: [[f64; 3]; 3],
}

impl Observables {
    /// Mean stress `tr σ / 3` (Pa).
    pub fn mean_stress(&self) -> f64 {
        (self.stress[0][0] + self.stress[1][1] + self.stress[2][2]) / 3.0
    }

    /// Total energy: kinetic plus elastic (J).
    pub fn total_energy(&self) -> f64 {
        self.kinetic_translational + self.kinetic_rotational + self.elastic_energy
    }

    /// Whether the energies, the stress and the box are finite numbers: `false` once a
    /// simulation has blown up (a NaN or infinite position or velocity reaches all three).
    pub fn is_finite(&self) -> bool {
        self.total_energy().is_finite()
            && self.stress.iter().flatten().all(|s| s.is_finite())
            && self.box_size.iter().all(|l| l.is_finite())
    }
}

/// Kinetic energies `(½ Σ m v², ½ Σ I ω²)` of the free particles (J), `v` the velocity in
/// the lab ([`Domain::lab_velocity`]).
pub fn kinetic_energies(p: &Particles, domain: &Domain) -> (f64, f64) {
    let mut trans = 0.0;
    let mut rot = 0.0;
    for i in 0..p.len() {
        if p.motion[i].is_free() {
            let v = domain.lab_velocity(p.position[i], p.velocity[i]);
            trans += 0.5 * p.mass[i] * v.length_squared();
            rot += 0.5 / p.inv_inertia[i] * p.angular_velocity[i].length_squared();
        }
    }
    (trans, rot)
}

/// Kinetic stress sum `Σ m v' ⊗ v'` over free particles (kg m²/s²), `v'` the velocity
/// relative to the domain's mean flow ([`Domain::peculiar_velocity`]).
pub fn kinetic_stress_sum(p: &Particles, domain: &Domain) -> DMat3 {
    let mut s = DMat3::ZERO;
    for i in 0..p.len() {
        if p.motion[i].is_free() {
            let v = domain.peculiar_velocity(p.position[i], p.velocity[i]);
            s += outer(v * p.mass[i], v);
        }
    }
    s
}

/// Granular temperature `(1/3N) Σ |v_i − u(r_i)|²` over the free particles (m²/s²).
pub fn granular_temperature(p: &Particles, domain: &Domain) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for i in 0..p.len() {
        if p.motion[i].is_free() {
            sum += domain
                .peculiar_velocity(p.position[i], p.velocity[i])
                .length_squared();
            n += 1;
        }
    }
    if n > 0 { sum / (3.0 * n as f64) } else { 0.0 }
}

/// Total linear momentum of the free particles (kg m/s).
pub fn linear_momentum(p: &Particles) -> DVec3 {
    (0..p.len())
        .filter(|&i| p.motion[i].is_free())
        .map(|i| p.velocity[i] * p.mass[i])
        .sum()
}

/// Total angular momentum of the free particles about the origin, orbital plus spin
/// (kg m²/s).
pub fn angular_momentum(p: &Particles) -> DVec3 {
    (0..p.len())
        .filter(|&i| p.motion[i].is_free())
        .map(|i| {
            p.position[i].cross(p.velocity[i] * p.mass[i])
                + p.angular_velocity[i] / p.inv_inertia[i]
        })
        .sum()
}

/// Converts a glam matrix into a row-major array.
pub fn to_rows(m: DMat3) -> [[f64; 3]; 3] {
    std::array::from_fn(|r| std::array::from_fn(|c| m.col(c)[r]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outer_product_rows_and_columns() {
        let m = to_rows(outer(DVec3::new(1.0, 2.0, 3.0), DVec3::new(4.0, 5.0, 6.0)));
        assert_eq!(m[0], [4.0, 5.0, 6.0]);
        assert_eq!(m[2], [12.0, 15.0, 18.0]);
    }
}
