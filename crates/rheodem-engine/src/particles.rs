//! Structure-of-arrays storage for polydisperse spheres.
//!
//! Every per-particle quantity lives in its own contiguous array, indexed by the particle's
//! current *slot*. Slots change when the neighbour list re-sorts particles by cell; the
//! permanent identity of a particle is its [`Particles::id`]. All quantities are SI.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// The part index of a particle that belongs to no wall part (a free particle).
pub const NO_PART: u16 = u16::MAX;

/// How a particle moves.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Motion {
    /// Integrated with Newton's equations (velocity Verlet).
    Free,
    /// Prescribed: never moves. Acts as an infinitely heavy wall particle.
    Fixed,
    /// Prescribed: rotates rigidly at `omega` (rad/s) about the axis through `center` along
    /// the unit vector `axis`. Acts as an infinitely heavy wall particle.
    Rotating {
        /// A point on the rotation axis (m).
        center: DVec3,
        /// Unit vector along the rotation axis.
        axis: DVec3,
        /// Angular velocity about `axis` (rad/s).
        omega: f64,
    },
}

impl Motion {
    /// Whether the particle is integrated (true) or has a prescribed motion (false).
    #[inline]
    pub fn is_free(&self) -> bool {
        matches!(self, Motion::Free)
    }
}

/// One sphere, used to add particles and to read them back.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sphere {
    /// Centre position (m).
    pub position: DVec3,
    /// Velocity (m/s).
    pub velocity: DVec3,
    /// Angular velocity (rad/s).
    pub angular_velocity: DVec3,
    /// Radius (m), positive.
    pub radius: f64,
    /// Index into the species table.
    pub species: u16,
    /// Free or prescribed motion.
    pub motion: Motion,
}

/// Structure-of-arrays particle store.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Particles {
    /// Permanent identity of the particle in each slot (0..len, a permutation).
    pub id: Vec<u32>,
    /// Centre positions (m).
    pub position: Vec<DVec3>,
    /// Velocities (m/s).
    pub velocity: Vec<DVec3>,
    /// Angular velocities (rad/s).
    pub angular_velocity: Vec<DVec3>,
    /// Total force from the last force evaluation (N).
    pub force: Vec<DVec3>,
    /// Total torque from the last force evaluation (N m).
    pub torque: Vec<DVec3>,
    /// Radii (m).
    pub radius: Vec<f64>,
    /// Masses (kg); finite also for prescribed particles (used for output only).
    pub mass: Vec<f64>,
    /// Inverse masses (1/kg); zero for prescribed particles, which count as infinitely heavy,
    /// and only for them (the integrator tells free particles by it).
    pub inv_mass: Vec<f64>,
    /// Inverse moments of inertia (1/(kg m²)), `1 / (2/5 m a²)`; zero for prescribed particles.
    pub inv_inertia: Vec<f64>,
    /// Species index of each particle.
    pub species: Vec<u16>,
    /// Motion kind of each particle.
    pub motion: Vec<Motion>,
    /// Wall part of each particle ([`NO_PART`] for particles of no part), see
    /// [`crate::observe::PartLoads`].
    #[serde(default)]
    pub part: Vec<u16>,
}

impl Particles {
    /// Number of particles.
    #[inline]
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// Whether every position, velocity and angular velocity is a finite number.
    pub fn is_finite(&self) -> bool {
        self.position
            .iter()
            .chain(&self.velocity)
            .chain(&self.angular_velocity)
            .all(|v| v.is_finite())
    }

    /// Whether the store is empty.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Appends a sphere of the given density (kg/m³); its id is the next free one.
    pub fn push(&mut self, s: Sphere, density: f64) {
        let mass = density * 4.0 / 3.0 * std::f64::consts::PI * s.radius.powi(3);
        let inertia = 0.4 * mass * s.radius * s.radius;
        let free = s.motion.is_free();
        self.id.push(self.len() as u32);
        self.position.push(s.position);
        self.velocity.push(s.velocity);
        self.angular_velocity.push(s.angular_velocity);
        self.force.push(DVec3::ZERO);
        self.torque.push(DVec3::ZERO);
        self.radius.push(s.radius);
        self.mass.push(mass);
        self.inv_mass.push(if free { 1.0 / mass } else { 0.0 });
        self.inv_inertia
            .push(if free { 1.0 / inertia } else { 0.0 });
        self.species.push(s.species);
        self.motion.push(s.motion);
        self.part.push(NO_PART);
    }

    /// Appends a sphere as [`Particles::push`] does, as a member of wall part `part`.
    pub fn push_in_part(&mut self, s: Sphere, density: f64, part: u16) {
        self.push(s, density);
        if let Some(p) = self.part.last_mut() {
            *p = part;
        }
    }

    /// Turns the particle in slot `i` into a wall particle of `part` with the prescribed
    /// `motion` (infinitely heavy from now on; velocity and spin follow the motion from the
    /// next drift, and are zeroed here).
    pub fn prescribe(&mut self, i: usize, motion: Motion, part: u16) {
        self.motion[i] = motion;
        self.part[i] = part;
        self.inv_mass[i] = 0.0;
        self.inv_inertia[i] = 0.0;
        self.velocity[i] = DVec3::ZERO;
        self.angular_velocity[i] = DVec3::ZERO;
    }

    /// Reads back the sphere in slot `i`.
    pub fn sphere(&self, i: usize) -> Sphere {
        Sphere {
            position: self.position[i],
            velocity: self.velocity[i],
            angular_velocity: self.angular_velocity[i],
            radius: self.radius[i],
            species: self.species[i],
            motion: self.motion[i],
        }
    }

    /// Slot of each id: `slot_of()[id] = slot`.
    pub fn slot_of(&self) -> Vec<u32> {
        let mut slot = vec![0u32; self.len()];
        for (s, &id) in self.id.iter().enumerate() {
            slot[id as usize] = s as u32;
        }
        slot
    }

    /// Reorders every array so that new slot `k` holds the particle of old slot `order[k]`.
    pub fn permute(&mut self, order: &[u32]) {
        fn apply<T: Copy>(v: &mut Vec<T>, order: &[u32]) {
            let out: Vec<T> = order.iter().map(|&o| v[o as usize]).collect();
            *v = out;
        }
        apply(&mut self.id, order);
        apply(&mut self.position, order);
        apply(&mut self.velocity, order);
        apply(&mut self.angular_velocity, order);
        apply(&mut self.force, order);
        apply(&mut self.torque, order);
        apply(&mut self.radius, order);
        apply(&mut self.mass, order);
        apply(&mut self.inv_mass, order);
        apply(&mut self.inv_inertia, order);
        apply(&mut self.species, order);
        apply(&mut self.motion, order);
        apply(&mut self.part, order);
    }

    /// Total volume of the free particles (m³).
    pub fn free_volume(&self) -> f64 {
        (0..self.len())
            .filter(|&i| self.motion[i].is_free())
            .map(|i| 4.0 / 3.0 * std::f64::consts::PI * self.radius[i].powi(3))
            .sum()
    }

    /// Number of free (integrated) particles.
    pub fn free_count(&self) -> usize {
        self.motion.iter().filter(|m| m.is_free()).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(x: f64) -> Sphere {
        Sphere {
            position: DVec3::new(x, 0.0, 0.0),
            velocity: DVec3::ZERO,
            angular_velocity: DVec3::ZERO,
            radius: 0.5,
            species: 0,
            motion: Motion::Free,
        }
    }

    #[test]
    fn permute_keeps_identity_with_data() {
        let mut p = Particles::default();
        for k in 0..4 {
            p.push(sphere(k as f64), 1000.0);
        }
        p.permute(&[2, 0, 3, 1]);
        assert_eq!(p.id, vec![2, 0, 3, 1]);
        for s in 0..4 {
            assert_eq!(p.position[s].x, p.id[s] as f64);
        }
        let slot = p.slot_of();
        assert_eq!(slot[2], 0);
        assert_eq!(slot[1], 3);
    }

    #[test]
    fn prescribed_particles_are_infinitely_heavy() {
        let mut p = Particles::default();
        let mut s = sphere(0.0);
        s.motion = Motion::Fixed;
        p.push(s, 1000.0);
        assert_eq!(p.inv_mass[0], 0.0);
        assert_eq!(p.inv_inertia[0], 0.0);
        assert!(p.mass[0] > 0.0);
    }
}
