//! Infinite planar walls: fixed, infinitely heavy, with the contact law of their species.

use crate::contact::{ContactHistory, ContactTable, PairKinematics};
use crate::measure::ContactSums;
use crate::particles::Particles;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// An infinite fixed plane through `point` with unit `normal` pointing into the granular
/// region; spheres on that side touch it when closer than their radius.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlaneWall {
    /// A point on the plane (m).
    pub point: DVec3,
    /// Unit normal pointing towards the particles.
    pub normal: DVec3,
    /// Species of the wall material (selects the contact law with each particle species).
    pub species: u16,
    /// Contact history per particle id.
    history: Vec<ContactHistory>,
    /// Whether each particle id interacts with the wall.
    active: Vec<bool>,
}

impl PlaneWall {
    /// A wall for `particle_count` particles; `normal` is normalised here.
    pub fn new(point: DVec3, normal: DVec3, species: u16, particle_count: usize) -> PlaneWall {
        PlaneWall {
            point,
            normal: normal.normalize(),
            species,
            history: vec![ContactHistory::default(); particle_count],
            active: vec![false; particle_count],
        }
    }

    /// Adds the wall's forces and torques to the free particles, advancing contact history
    /// over `dt` (s); `index` names the wall in the contact sums.
    pub fn apply(
        &mut self,
        index: u32,
        particles: &mut Particles,
        laws: &ContactTable,
        dt: f64,
    ) -> ContactSums {
        let mut obs = ContactSums::default();
        for i in 0..particles.len() {
            if !particles.motion[i].is_free() {
                continue;
            }
            let id = particles.id[i] as usize;
            let a = particles.radius[i];
            let gap = (particles.position[i] - self.point).dot(self.normal);
            let overlap = a - gap;
            let law = laws.get(particles.species[i], self.species);
            if overlap <= -law.range() {
                if self.active[id] {
                    self.active[id] = false;
                    self.history[id] = ContactHistory::default();
                }
                continue;
            }
            let k = PairKinematics {
                normal: self.normal,
                overlap,
                radius_i: a,
                radius_j: f64::INFINITY,
                velocity: particles.velocity[i],
                omega_i: particles.angular_velocity[i],
                omega_j: DVec3::ZERO,
                reduced_mass: particles.mass[i],
            };
            let h = &mut self.history[id];
            let Some(f) = law.interact(&k, h, dt) else {
                self.active[id] = false;
                continue;
            };
            self.active[id] = true;
            particles.force[i] += f.force;
            particles.torque[i] += f.torque_i;
            let energy = law.elastic_energy(overlap, a, f64::INFINITY, h);
            obs.add_pair(
                &f,
                &k,
                energy,
                self.normal * gap,
                [particles.id[i], index],
                true,
            );
        }
        obs
    }
}
