//! Reversible linear ("dry", van der Waals type) adhesion (Shi et al. 2020, Eq. 3;
//! docs/model.md §2.4): `−f_max` in contact, `−f_max + k_c S` at separation `S` up to
//! `δ_a = f_max / k_c`, the same on approach and separation.

use super::parameters::{self, LINEAR_LAW_PARAMETERS};
use super::{AdhesiveLaw, LawError, Parameter, Parameters, ResolvedLaw, Strength};
use crate::contact::lanes::Real;
use serde::{Deserialize, Serialize};

/// Reversible linear adhesion.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reversible {
    /// Maximum adhesive force `f_a^max` (N).
    pub max_force: f64,
    /// Adhesive stiffness `k_c^a` (N/m).
    pub stiffness: f64,
}

impl AdhesiveLaw for Reversible {
    const NAME: &'static str = "reversible";
    const ALIASES: &'static [&'static str] = &[];
    const SUMMARY: &'static str =
        "Reversible linear adhesion, -f_max + k_c S up to S = f_max/k_c (Shi et al. 2020, Eq. 3).";
    const PARAMETERS: &'static [Parameter] = LINEAR_LAW_PARAMETERS;
    const FORMS_BRIDGES: bool = false;
    type Resolved = Reversible;

    fn from_parameters(p: &Parameters<'_>) -> Result<Reversible, LawError> {
        let (max_force, stiffness) = parameters::linear_law(p)?;
        Ok(Reversible {
            max_force,
            stiffness,
        })
    }

    /// `f_max` of the mean pair with `k_c^a = k_n` (Shi et al. 2020).
    fn at_strength(s: &Strength) -> Vec<(&'static str, f64)> {
        vec![
            ("max_force", s.max_force),
            ("stiffness", s.normal_stiffness),
        ]
    }

    fn resolve(&self) -> Reversible {
        *self
    }
}

impl ResolvedLaw for Reversible {
    #[inline(always)]
    fn range(&self) -> f64 {
        self.max_force / self.stiffness
    }

    #[inline(always)]
    fn max_force(&self, _a_i: f64, _a_j: f64) -> f64 {
        self.max_force
    }

    #[inline(always)]
    fn contact_force_lanes<R: Real, const WALL: bool>(&self, _a_i: R, _a_j: R) -> R {
        R::splat(-self.max_force)
    }

    #[inline(always)]
    fn separated_force_lanes<R: Real, const WALL: bool>(
        &self,
        s: R,
        _a_i: R,
        _a_j: R,
        _bridge: R::Mask,
    ) -> (R, R::Mask) {
        let zero = R::splat(0.0);
        let f = R::splat(self.stiffness) * s - R::splat(self.max_force);
        (R::select(f.lt(zero), f, zero), R::all(false))
    }

    fn separation_energy(&self, s: f64, _a_i: f64, _a_j: f64) -> f64 {
        let range = self.range();
        -0.5 * self.stiffness * (range - s) * (range - s)
    }
}

#[cfg(test)]
mod tests {
    use crate::contact::Adhesion;

    const A: f64 = 1.1e-3;

    #[test]
    fn reversible_potential_is_continuous_and_zero_at_range() {
        let r = Adhesion::Reversible(super::Reversible {
            max_force: 2.0,
            stiffness: 4.0,
        });
        assert_eq!(r.range(), 0.5);
        assert_eq!(r.potential(-0.5, A, A, false), 0.0);
        assert!((r.potential(0.0, A, A, false) - (-0.5 * 2.0 * 0.5)).abs() < 1e-15);
        assert!((r.potential(-1e-12, A, A, false) - r.potential(0.0, A, A, false)).abs() < 1e-11);
    }

    #[test]
    fn the_force_is_the_same_on_approach_and_separation() {
        let r = Adhesion::Reversible(super::Reversible {
            max_force: 2.0,
            stiffness: 4.0,
        });
        for s in [0.0, 0.1, 0.25, 0.49] {
            let expected = 4.0 * s - 2.0;
            assert_eq!(r.separated_force(s, A, A, false), (expected, false));
            assert_eq!(r.separated_force(s, A, A, true), (expected, false));
        }
        assert_eq!(r.separated_force(0.6, A, A, false), (0.0, false));
    }
}
