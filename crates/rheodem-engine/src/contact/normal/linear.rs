//! Linear visco-elastic normal force (docs/model.md §2.2): `f_n = k_n δ + γ_n dδ/dt`.

use super::super::damping::Damping;
use super::super::kernel::Touch;
use super::super::lanes::Real;
use super::super::parameters::{Bounds, LawError, Parameter, Parameters};
use super::{NormalForce, NormalModel, NormalParts};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Parameters of the linear visco-elastic normal force.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LinearNormal {
    /// Normal stiffness `k_n` (N/m).
    pub stiffness: f64,
    /// Normal damping `γ_n` (kg/s) as a function of the reduced mass.
    pub damping: Damping,
}

impl LinearNormal {
    /// Repulsive (elastic + viscous) normal force `k_n δ + γ_n δ̇` (N) for overlap `δ` (m),
    /// overlap rate `δ̇` (m/s) and damping coefficient `gamma_n` (kg/s). Not clipped: it turns
    /// slightly tensile at the end of a damped contact.
    ///
    /// With the damping of a restitution coefficient `e`, `γ_n = −2 ln e sqrt(m_ij k_n /
    /// (π² + ln² e))`, a binary collision of reduced mass `m_ij` lasts
    /// `t_c = π / sqrt(k_n/m_ij − (γ_n / 2 m_ij)²)` and restitutes `e`:
    ///
    /// ```
    /// use rheodem_engine::contact::{Damping, LinearNormal};
    /// use std::f64::consts::PI;
    ///
    /// let (k_n, e, m_ij) = (100.0, 0.8, 5.0e-6);
    /// let law = LinearNormal { stiffness: k_n, damping: Damping::from_restitution(e, k_n) };
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

/// The keys of the dashpot every normal law takes (at most one of them; none means no
/// damping).
pub const DASHPOT_PARAMETERS: [Parameter; 3] = [
    Parameter {
        key: "restitution",
        unit: "",
        meaning: "restitution coefficient e of a binary collision, the same for every pair (sets γ_n)",
        bounds: Bounds::LeftOpen(0.0, 1.0),
        default: None,
        note: "",
        instead_of: None,
    },
    Parameter {
        key: "damping",
        unit: "kg/s",
        meaning: "fixed dashpot γ_n",
        bounds: Bounds::NonNegative,
        default: None,
        note: "",
        instead_of: Some("restitution"),
    },
    Parameter {
        key: "damping_per_mass",
        unit: "1/s",
        meaning: "mass-proportional dashpot γ_n = γ̂ m_ij",
        bounds: Bounds::NonNegative,
        default: None,
        note: "",
        instead_of: Some("restitution"),
    },
];

/// The stiffness key of the linear law.
const STIFFNESS: Parameter = Parameter {
    key: "stiffness",
    unit: "N/m",
    meaning: "normal stiffness k_n",
    bounds: Bounds::Positive,
    default: None,
    note: "",
    instead_of: None,
};

/// The dashpot given by the keys of [`DASHPOT_PARAMETERS`] for a spring of stiffness `k`
/// (N/m): at most one of them, none meaning no damping.
pub fn dashpot(p: &Parameters<'_>, k: f64) -> Result<Damping, LawError> {
    let restitution = p.get("restitution")?;
    let fixed = p.get("damping")?;
    let per_mass = p.get("damping_per_mass")?;
    let given: Vec<&str> = [
        ("restitution", restitution.is_some()),
        ("damping", fixed.is_some()),
        ("damping_per_mass", per_mass.is_some()),
    ]
    .iter()
    .filter(|g| g.1)
    .map(|g| g.0)
    .collect();
    if given.len() > 1 {
        return Err(LawError {
            key: String::new(),
            value: given.join(" and "),
            reason: "give at most one of restitution, damping, damping_per_mass".into(),
        });
    }
    Ok(match (restitution, fixed, per_mass) {
        (Some(e), _, _) if e < 1.0 => Damping::from_restitution(e, k),
        (_, Some(g), _) => Damping {
            fixed: g,
            ..Damping::NONE
        },
        (_, _, Some(g)) => Damping {
            per_mass: g,
            ..Damping::NONE
        },
        _ => Damping::NONE,
    })
}

impl NormalModel for LinearNormal {
    const NAME: &'static str = "linear";
    const PARAMETERS: &'static [Parameter] = &[
        STIFFNESS,
        DASHPOT_PARAMETERS[0],
        DASHPOT_PARAMETERS[1],
        DASHPOT_PARAMETERS[2],
    ];

    fn from_parameters(p: &Parameters<'_>) -> Result<LinearNormal, LawError> {
        p.check_keys()?;
        let stiffness = p.require("stiffness")?;
        Ok(LinearNormal {
            stiffness,
            damping: dashpot(p, stiffness)?,
        })
    }

    fn reference(&self) -> Option<LinearNormal> {
        Some(*self)
    }

    const ALIASES: &'static [&'static str] = &["hooke"];
    const SUMMARY: &'static str = "Linear spring and dashpot, k_n δ + γ_n dδ/dt (Cundall & Strack 1979; Shi et al. 2020, Eq. 1).";
    type Resolved = LinearNormal;

    fn resolve(&self) -> LinearNormal {
        *self
    }

    fn max_stiffness(&self, _r_ij: f64) -> f64 {
        self.stiffness
    }

    fn contact_time(&self, m_ij: f64, _r_ij: f64) -> Option<f64> {
        LinearNormal::contact_time(self, m_ij)
    }

    fn restitution(&self, m_ij: f64) -> Option<f64> {
        LinearNormal::restitution(self, m_ij)
    }

    fn damping_scaled(&self, factor: f64) -> LinearNormal {
        LinearNormal {
            damping: self.damping.scaled(factor),
            ..*self
        }
    }
}

impl NormalForce for LinearNormal {
    #[inline(always)]
    fn force_lanes<R: Real, const WALL: bool>(
        &self,
        k: &Touch<R>,
        overlap_rate: R,
        _state: &mut R,
    ) -> NormalParts<R> {
        let gamma_n = self.damping.in_lanes(k.reduced_mass);
        NormalParts {
            repulsive: R::splat(self.stiffness) * k.overlap + gamma_n * overlap_rate,
            adhesive: None,
        }
    }

    fn energy(&self, overlap: f64, _a_i: f64, _a_j: f64, _state: f64) -> f64 {
        0.5 * (self.stiffness * overlap * overlap)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn restitution_damping_round_trips_for_any_mass() {
        for &e in &[0.3, 0.5, 0.8, 0.95, 0.999] {
            let law = LinearNormal {
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
        let law = LinearNormal {
            stiffness: 4.0,
            damping: Damping::NONE,
        };
        let t = law.contact_time(1.0).expect("underdamped");
        assert!((t - PI / 2.0).abs() < 1e-15);
    }

    #[test]
    fn overdamped_has_no_contact_time() {
        let law = LinearNormal {
            stiffness: 1.0,
            damping: Damping {
                fixed: 10.0,
                ..Damping::NONE
            },
        };
        assert!(law.contact_time(1.0).is_none());
    }
}
