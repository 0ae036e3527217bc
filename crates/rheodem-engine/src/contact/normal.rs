//! Linear visco-elastic normal force (docs/model.md §2.2): `f_n = k_n δ + γ_n dδ/dt`.

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

/// Parameters of the linear visco-elastic normal force.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct NormalLaw {
    /// Normal stiffness `k_n` (N/m).
    pub stiffness: f64,
    /// Normal damping `γ_n` (kg/s) as a function of the reduced mass.
    pub damping: Damping,
}

impl NormalLaw {
    /// Repulsive (elastic + viscous) normal force `k_n δ + γ_n δ̇` (N) for overlap `δ` (m),
    /// overlap rate `δ̇` (m/s) and damping coefficient `gamma_n` (kg/s). Not clipped: it turns
    /// slightly tensile at the end of a damped contact.
    ///
    /// With the damping of a restitution coefficient `e`, `γ_n = −2 ln e sqrt(m_ij k_n /
    /// (π² + ln² e))`, a binary collision of reduced mass `m_ij` lasts
    /// `t_c = π / sqrt(k_n/m_ij − (γ_n / 2 m_ij)²)` and restitutes `e`:
    ///
    /// ```
    /// use rheodem_engine::contact::{Damping, NormalLaw};
    /// use std::f64::consts::PI;
    ///
    /// let (k_n, e, m_ij) = (100.0, 0.8, 5.0e-6);
    /// let law = NormalLaw { stiffness: k_n, damping: Damping::from_restitution(e, k_n) };
    /// let gamma_n = law.damping.coefficient(m_ij);
    /// let ln_e: f64 = e.ln();
    /// assert!((gamma_n / (-2.0 * ln_e * (m_ij * k_n / (PI * PI + ln_e * ln_e)).sqrt()) - 1.0).abs() < 1e-12);
    /// // 10 µm of overlap closing at 0.1 m/s: elastic 1 mN plus the dashpot.
    /// let f = law.force(1.0e-5, 0.1, gamma_n);
    /// assert!((f - (1.0e-3 + 0.1 * gamma_n)).abs() < 1e-15);
    /// let t_c = law.contact_time(m_ij).expect("underdamped");
    /// let w2 = k_n / m_ij - (gamma_n / (2.0 * m_ij)).powi(2);
    /// assert!((t_c - PI / w2.sqrt()).abs() < 1e-12 * t_c);
    /// assert!((law.restitution(m_ij).expect("underdamped") - e).abs() < 1e-12);
    /// ```
    #[inline]
    pub fn force(&self, overlap: f64, overlap_rate: f64, gamma_n: f64) -> f64 {
        self.stiffness * overlap + gamma_n * overlap_rate
    }

    /// Contact duration `t_c = π / sqrt(k_n/m_ij − (γ_n/(2 m_ij))²)` (s) of a binary
    /// collision with reduced mass `m_ij` (kg), or `None` when the contact is overdamped.
    pub fn contact_time(&self, m_ij: f64) -> Option<f64> {
        let g = self.damping.coefficient(m_ij) / (2.0 * m_ij);
        let w2 = self.stiffness / m_ij - g * g;
        (w2 > 0.0).then(|| PI / w2.sqrt())
    }

    /// Restitution coefficient `e = exp(−γ_n t_c / (2 m_ij))` of a binary collision with
    /// reduced mass `m_ij` (kg), or `None` when overdamped.
    pub fn restitution(&self, m_ij: f64) -> Option<f64> {
        let t_c = self.contact_time(m_ij)?;
        Some((-self.damping.coefficient(m_ij) * t_c / (2.0 * m_ij)).exp())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn restitution_damping_round_trips_for_any_mass() {
        for &e in &[0.3, 0.5, 0.8, 0.95, 0.999] {
            let law = NormalLaw {
                stiffness: 100.0,
                damping: Damping::from_restitution(e, 100.0),
            };
            for &m in &[1e-6, 1e-3, 1.0] {
                let got = law.restitution(m).expect("underdamped");
                assert!((got - e).abs() < 1e-12, "e={e} m={m} got={got}");
            }
        }
    }

    #[test]
    fn undamped_contact_time_is_half_period() {
        let law = NormalLaw {
            stiffness: 4.0,
            damping: Damping::NONE,
        };
        let t = law.contact_time(1.0).expect("underdamped");
        assert!((t - PI / 2.0).abs() < 1e-15);
    }

    #[test]
    fn overdamped_has_no_contact_time() {
        let law = NormalLaw {
            stiffness: 1.0,
            damping: Damping {
                fixed: 10.0,
                ..Damping::NONE
            },
        };
        assert!(law.contact_time(1.0).is_none());
    }
}
