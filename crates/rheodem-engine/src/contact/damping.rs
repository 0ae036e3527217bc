//! Dashpot coefficients that may depend on a pair's reduced mass, shared by the normal law
//! and the springs (docs/model.md §2.2–2.3).

use super::lanes::Real;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// A damping coefficient that may depend on the pair's reduced mass `m_ij` (kg):
/// `γ(m_ij) = fixed + per_mass · m_ij + per_sqrt_mass · sqrt(m_ij)` (kg/s).
///
/// The three common parametrisations map onto it: a fixed `γ` (`fixed`), LAMMPS-style
/// mass-proportional damping `γ = γ̂ m_ij` (`per_mass`), and a constant restitution
/// coefficient `e` (`per_sqrt_mass`, see [`Damping::from_restitution`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Damping {
    /// Constant part (kg/s).
    pub fixed: f64,
    /// Part proportional to the reduced mass (1/s).
    pub per_mass: f64,
    /// Part proportional to the square root of the reduced mass (kg^½/s).
    pub per_sqrt_mass: f64,
}

impl Damping {
    /// No damping.
    pub const NONE: Damping = Damping {
        fixed: 0.0,
        per_mass: 0.0,
        per_sqrt_mass: 0.0,
    };

    /// Damping giving the restitution coefficient `e` (0 < e ≤ 1) for every pair of a
    /// linear spring of stiffness `k_n` (N/m): `γ_n = −2 ln e sqrt(m_ij k_n / (π² + ln² e))`.
    pub fn from_restitution(e: f64, k_n: f64) -> Damping {
        let ln_e = e.ln();
        Damping {
            per_sqrt_mass: -2.0 * ln_e * (k_n / (PI * PI + ln_e * ln_e)).sqrt(),
            ..Damping::NONE
        }
    }

    /// The coefficient scaled by `factor` (e.g. `γ_t = (2/7) γ_n`).
    pub fn scaled(&self, factor: f64) -> Damping {
        Damping {
            fixed: self.fixed * factor,
            per_mass: self.per_mass * factor,
            per_sqrt_mass: self.per_sqrt_mass * factor,
        }
    }

    /// Whether the coefficient is zero for every mass.
    pub fn is_zero(&self) -> bool {
        self.fixed == 0.0 && self.per_mass == 0.0 && self.per_sqrt_mass == 0.0
    }

    /// The coefficient for reduced mass `m_ij` (kg/s).
    #[inline]
    pub fn coefficient(&self, m_ij: f64) -> f64 {
        self.in_lanes(m_ij)
    }

    /// [`Damping::coefficient`] in lanes.
    #[inline(always)]
    pub fn in_lanes<R: Real>(&self, m_ij: R) -> R {
        let g = R::splat(self.fixed) + R::splat(self.per_mass) * m_ij;
        if self.per_sqrt_mass != 0.0 {
            g + R::splat(self.per_sqrt_mass) * m_ij.sqrt()
        } else {
            g
        }
    }
}
