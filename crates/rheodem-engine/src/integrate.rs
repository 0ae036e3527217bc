//! Velocity Verlet with rotation, and prescribed motion of wall particles.
//!
//! One step of length `dt` is `kick(dt/2)`, `drift(dt)` (one pass, [`kick_drift`]), force
//! evaluation, `kick(dt/2)`.
//! Spheres need no orientation for their dynamics, so only angular velocities are integrated.

use crate::particles::{Motion, Particles};
use crate::team::Team;
use glam::{DQuat, DVec3};

/// Fewest particles per team member in the loops over particles: such a loop costs
/// nanoseconds per particle, handing a piece to another thread a fraction of a
/// microsecond (see [`crate::team`]).
pub(crate) const PARTICLES_PER_TASK: usize = 512;

/// Half-step velocity update `v += F/m · h`, `ω += T/I · h` (free particles only: prescribed
/// ones have zero inverse mass and inertia), shared among the members of `team`.
pub fn kick(p: &mut Particles, h: f64, team: &Team) {
    let len = team.piece_len(p.len(), PARTICLES_PER_TASK);
    let mut pieces: Vec<_> = p
        .velocity
        .chunks_mut(len)
        .zip(p.angular_velocity.chunks_mut(len))
        .zip(p.force.chunks(len).zip(p.torque.chunks(len)))
        .zip(p.inv_mass.chunks(len).zip(p.inv_inertia.chunks(len)))
        .collect();
    team.for_each(&mut pieces, |(((v, w), (f, t)), (im, ii))| {
        // Zipped, so that no access is bounds-checked.
        let rates = f.iter().zip(t.iter()).zip(im.iter().zip(ii.iter()));
        for ((v, w), ((f, t), (im, ii))) in v.iter_mut().zip(w.iter_mut()).zip(rates) {
            kick_one(v, w, *f, *t, *im, *ii, h);
        }
    });
}

#[inline(always)]
fn kick_one(v: &mut DVec3, w: &mut DVec3, f: DVec3, t: DVec3, im: f64, ii: f64, h: f64) {
    *v += f * (im * h);
    *w += t * (ii * h);
}

/// Position update over `dt` (s): free particles move with their velocity; prescribed ones
/// follow their motion law (a rigid rotation sets position, velocity and angular velocity).
pub fn drift(p: &mut Particles, dt: f64, team: &Team) {
    let len = team.piece_len(p.len(), PARTICLES_PER_TASK);
    let mut pieces: Vec<_> = p
        .position
        .chunks_mut(len)
        .zip(p.velocity.chunks_mut(len))
        .zip(p.angular_velocity.chunks_mut(len))
        .zip(p.motion.chunks(len))
        .collect();
    team.for_each(&mut pieces, |(((r, v), w), motion)| {
        let state = r.iter_mut().zip(v.iter_mut()).zip(w.iter_mut());
        let mut turn = LastTurn::default();
        for (((r, v), w), motion) in state.zip(motion.iter()) {
            drift_one(r, v, w, motion, dt, &mut turn);
        }
    });
}

/// [`kick`] over `h` (s) followed by [`drift`] over `dt` (s), in one pass over the
/// particles (the same numbers as the two calls).
pub fn kick_drift(p: &mut Particles, h: f64, dt: f64, team: &Team) {
    let len = team.piece_len(p.len(), PARTICLES_PER_TASK);
    let mut pieces: Vec<_> = p
        .position
        .chunks_mut(len)
        .zip(p.velocity.chunks_mut(len))
        .zip(p.angular_velocity.chunks_mut(len))
        .zip(p.motion.chunks(len))
        .zip(p.force.chunks(len).zip(p.torque.chunks(len)))
        .zip(p.inv_mass.chunks(len).zip(p.inv_inertia.chunks(len)))
        .collect();
    team.for_each(
        &mut pieces,
        |(((((r, v), w), motion), (f, t)), (im, ii))| {
            // Zipped, so that no access is bounds-checked.
            let state = r.iter_mut().zip(v.iter_mut()).zip(w.iter_mut());
            let rates = f.iter().zip(t.iter()).zip(im.iter().zip(ii.iter()));
            let mut turn = LastTurn::default();
            for (((r, v), w), (motion, ((f, t), (im, ii)))) in state.zip(motion.iter().zip(rates)) {
                kick_one(v, w, *f, *t, *im, *ii, h);
                // A particle with a mass is free (prescribed ones are infinitely heavy), so
                // its motion record (64 bytes) need not be read.
                if *im != 0.0 {
                    debug_assert!(motion.is_free(), "a prescribed particle has a finite mass");
                    *r += *v * dt;
                } else {
                    drift_one(r, v, w, motion, dt, &mut turn);
                }
            }
        },
    );
}

/// The turn of a rigid rotation over one step, kept for the next particle: the wall
/// particles of a part share one motion, and the quaternion costs a sine and a cosine.
#[derive(Default)]
struct LastTurn(Option<(DVec3, f64, DQuat)>);

impl LastTurn {
    /// The rotation by `angle` (rad) about the unit vector `axis`.
    #[inline]
    fn get(&mut self, axis: DVec3, angle: f64) -> DQuat {
        match self.0 {
            Some((a, t, q)) if a == axis && t == angle => q,
            _ => {
                let q = DQuat::from_axis_angle(axis, angle);
                self.0 = Some((axis, angle, q));
                q
            }
        }
    }
}

#[inline(always)]
fn drift_one(
    r: &mut DVec3,
    v: &mut DVec3,
    w: &mut DVec3,
    motion: &Motion,
    dt: f64,
    turn: &mut LastTurn,
) {
    match *motion {
        Motion::Free => *r += *v * dt,
        Motion::Fixed => {
            *v = DVec3::ZERO;
            *w = DVec3::ZERO;
        }
        Motion::Rotating {
            center,
            axis,
            omega,
        } => {
            let q = turn.get(axis, omega * dt);
            *r = center + q * (*r - center);
            *w = axis * omega;
            *v = w.cross(*r - center);
        }
    }
}

/// Adds gravity `m g` (N) to the force of every free particle.
pub fn add_gravity(p: &mut Particles, g: DVec3, team: &Team) {
    if g == DVec3::ZERO {
        return;
    }
    let len = team.piece_len(p.len(), PARTICLES_PER_TASK);
    let mut pieces: Vec<_> = p
        .force
        .chunks_mut(len)
        .zip(p.mass.chunks(len).zip(p.inv_mass.chunks(len)))
        .collect();
    team.for_each(&mut pieces, |(f, (m, im))| {
        for ((f, m), im) in f.iter_mut().zip(m.iter()).zip(im.iter()) {
            // Free particles are those with a finite mass (see `kick_drift`).
            if *im != 0.0 {
                *f += g * *m;
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particles::Sphere;

    #[test]
    fn wall_particles_of_different_rotations_each_follow_their_own() {
        // Neighbours in memory with the same motion share one quaternion per step; one of
        // another speed or axis between them must not take it.
        let motions = [
            (DVec3::Z, 0.7),
            (DVec3::Z, 0.7),
            (DVec3::X, 0.7),
            (DVec3::Z, -0.3),
        ];
        let mut p = Particles::default();
        for (k, &(axis, omega)) in motions.iter().cycle().take(8).enumerate() {
            let motion = Motion::Rotating {
                center: DVec3::ZERO,
                axis,
                omega,
            };
            let position = DVec3::new(1.0 + k as f64, 0.5, 0.25);
            p.push(
                Sphere {
                    position,
                    velocity: DVec3::ZERO,
                    angular_velocity: DVec3::ZERO,
                    radius: 0.1,
                    species: 0,
                    motion,
                },
                1.0,
            );
        }
        let start = p.position.clone();
        let dt = 1e-3;
        for _ in 0..500 {
            kick_drift(&mut p, 0.5 * dt, dt, &Team::new(1));
        }
        for (k, &(axis, omega)) in motions.iter().cycle().take(8).enumerate() {
            let expected = DQuat::from_axis_angle(axis, omega * 0.5) * start[k];
            assert!(
                (p.position[k] - expected).length() < 1e-12,
                "particle {k}: {} against {expected}",
                p.position[k]
            );
        }
    }

    #[test]
    fn rotating_particle_follows_the_rigid_rotation() {
        let mut p = Particles::default();
        let center = DVec3::new(1.0, 2.0, 0.0);
        let omega = 0.7;
        p.push(
            Sphere {
                position: center + DVec3::new(3.0, 0.0, 5.0),
                velocity: DVec3::ZERO,
                angular_velocity: DVec3::ZERO,
                radius: 0.1,
                species: 0,
                motion: Motion::Rotating {
                    center,
                    axis: DVec3::Z,
                    omega,
                },
            },
            1.0,
        );
        let dt = 1e-3;
        for _ in 0..1000 {
            drift(&mut p, dt, &Team::new(1));
        }
        // After t = 1: angle 0.7 rad about z through `center`; height unchanged.
        let expected = center + DVec3::new(3.0 * omega.cos(), 3.0 * omega.sin(), 5.0);
        assert!((p.position[0] - expected).length() < 1e-12);
        let v = DVec3::Z.cross(p.position[0] - center) * omega;
        assert!((p.velocity[0] - v).length() < 1e-15);
        assert_eq!(p.angular_velocity[0], DVec3::Z * omega);
        // Kicks never move a prescribed particle.
        p.force[0] = DVec3::ONE;
        kick(&mut p, 1.0, &Team::new(2));
        assert!((p.velocity[0] - v).length() < 1e-15);
    }
}
