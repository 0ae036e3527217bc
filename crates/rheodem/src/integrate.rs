//! Velocity Verlet with rotation, and prescribed motion of wall particles.
//!
//! One step of length `dt` is `kick(dt/2)`, `drift(dt)`, force evaluation, `kick(dt/2)`.
//! Spheres need no orientation for their dynamics, so only angular velocities are integrated.

use crate::particles::{Motion, Particles};
use glam::{DQuat, DVec3};
use rayon::prelude::*;

/// Minimum particles per rayon task in the element-wise loops.
const MIN_LEN: usize = 2048;

/// Half-step velocity update `v += F/m · h`, `ω += T/I · h` (free particles only: prescribed
/// ones have zero inverse mass and inertia).
pub fn kick(p: &mut Particles, h: f64) {
    p.velocity
        .par_iter_mut()
        .zip(p.angular_velocity.par_iter_mut())
        .zip(p.force.par_iter().zip(&p.torque))
        .zip(p.inv_mass.par_iter().zip(&p.inv_inertia))
        .with_min_len(MIN_LEN)
        .for_each(|(((v, w), (f, t)), (im, ii))| {
            *v += *f * (im * h);
            *w += *t * (ii * h);
        });
}

/// Position update over `dt` (s): free particles move with their velocity; prescribed ones
/// follow their motion law (a rigid rotation sets position, velocity and angular velocity).
pub fn drift(p: &mut Particles, dt: f64) {
    p.position
        .par_iter_mut()
        .zip(p.velocity.par_iter_mut())
        .zip(p.angular_velocity.par_iter_mut())
        .zip(p.motion.par_iter())
        .with_min_len(MIN_LEN)
        .for_each(|(((r, v), w), motion)| match *motion {
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
                let q = DQuat::from_axis_angle(axis, omega * dt);
                *r = center + q * (*r - center);
                *w = axis * omega;
                *v = w.cross(*r - center);
            }
        });
}

/// Adds gravity `m g` (N) to the force of every free particle.
pub fn add_gravity(p: &mut Particles, g: DVec3) {
    if g == DVec3::ZERO {
        return;
    }
    p.force
        .par_iter_mut()
        .zip(p.mass.par_iter().zip(&p.motion))
        .with_min_len(MIN_LEN)
        .for_each(|(f, (m, motion))| {
            if motion.is_free() {
                *f += g * *m;
            }
        });
}
