//! Normal-stress control of a Lees-Edwards box (docs/model.md §5): `L_y` dilates or compacts so
//! that the measured `σ_yy` (kinetic + contact) holds its target.
//!
//! Control law, proportional on the strain rate:
//! `L̇_y / L_y = (σ_yy − σ_0) / (M τ)`, with `M = k_n / d_p` the contact modulus (Pa) and `τ`
//! the relaxation time (s). Linearised around the steady state, the box relaxes with time
//! constant `τ · (M / K)`, `K = −L_y ∂σ_yy/∂L_y` the packing's stiffness (of the order of
//! `M` times the coordination number), so `τ` of tens of `t_k = sqrt(ρ d³/k_n)` — longer
//! than the sound-crossing time of the box, about 16 `t_k` for 4096 particles — gives a
//! smooth approach without the oscillation an integral law shows. The `y` coordinates and
//! the `y` velocities are rescaled affinely with the box.

use crate::domain::Domain;
use crate::particles::Particles;
use serde::{Deserialize, Serialize};

/// Proportional control of `σ_yy` through `L_y`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StressControl {
    /// Target `σ_yy` (Pa), compression positive.
    pub target: f64,
    /// Contact modulus `M = k_n / d_p` (Pa).
    pub modulus: f64,
    /// Relaxation time `τ` (s).
    pub time: f64,
    /// Largest strain per step, a safeguard against violent starts (default 1e-4).
    pub max_strain_per_step: f64,
}

impl StressControl {
    /// Strain rate of `L_y` (1/s) for a measured `σ_yy` (Pa).
    pub fn strain_rate(&self, sigma_yy: f64) -> f64 {
        (sigma_yy - self.target) / (self.modulus * self.time)
    }

    /// Rescales the box and the particles along `y` for one step `dt` (s) given the measured
    /// `σ_yy` (Pa); returns the strain applied.
    pub fn apply(
        &self,
        sigma_yy: f64,
        dt: f64,
        domain: &mut Domain,
        particles: &mut Particles,
    ) -> f64 {
        let cap = self.max_strain_per_step;
        let strain = (self.strain_rate(sigma_yy) * dt).clamp(-cap, cap);
        domain.scale_y(
            1.0 + strain,
            &mut particles.position,
            &mut particles.velocity,
        );
        strain
    }
}
