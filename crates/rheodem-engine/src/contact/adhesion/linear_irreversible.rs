//! Irreversible linear adhesion (Roy et al. 2016, Eqs. 16–17; docs/model.md §2.6): a bridge
//! forms at contact, pulls `−f_max` while touching and `−(f_max − k_c S)` on separation, and
//! ruptures past `S_c = f_max / k_c`; no attraction on approach.

use super::parameters::{self, LINEAR_LAW_PARAMETERS};
use super::{AdhesiveLaw, LawError, Parameter, Parameters, ResolvedLaw, Strength};
use crate::contact::lanes::Real;
use serde::{Deserialize, Serialize};

/// Irreversible linear adhesion.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LinearIrreversible {
    /// Maximum adhesive force `f_a^max` (N).
    pub max_force: f64,
    /// Adhesive stiffness `k_c` (N/m) of the separation branch.
    pub stiffness: f64,
}

/// [`LinearIrreversible`] with its rupture distance `S_c` (m) computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolvedLinear {
    /// `f_max` (N).
    pub max_force: f64,
    /// `k_c` (N/m).
    pub stiffness: f64,
    /// `S_c` (m).
    pub range: f64,
}

impl AdhesiveLaw for LinearIrreversible {
    const NAME: &'static str = "linear_irreversible";
    const ALIASES: &'static [&'static str] = &["linear"];
    const SUMMARY: &'static str = "Irreversible linear adhesion: a bridge formed at contact, \
        -(f_max - k_c S) apart, ruptured at S_c = f_max/k_c (Roy et al. 2016, Eqs. 16-17).";
    const PARAMETERS: &'static [Parameter] = LINEAR_LAW_PARAMETERS;
    const FORMS_BRIDGES: bool = true;
    type Resolved = ResolvedLinear;

    fn from_parameters(p: &Parameters<'_>) -> Result<LinearIrreversible, LawError> {
        let (max_force, stiffness) = parameters::linear_law(p)?;
        Ok(LinearIrreversible {
            max_force,
            stiffness,
        })
    }

    /// `f_max` of the mean pair, rupture at the set-up's rupture distance.
    fn at_strength(s: &Strength) -> Vec<(&'static str, f64)> {
        vec![("max_force", s.max_force), ("range", s.rupture_distance)]
    }

    fn resolve(&self) -> ResolvedLinear {
        ResolvedLinear {
            max_force: self.max_force,
            stiffness: self.stiffness,
            range: self.max_force / self.stiffness,
        }
    }
}

impl ResolvedLaw for ResolvedLinear {
    #[inline(always)]
    fn range(&self) -> f64 {
        self.range
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
        bridge: R::Mask,
    ) -> (R, R::Mask) {
        let alive = R::both(bridge, s.le(R::splat(self.range)));
        let f = R::splat(self.stiffness) * s - R::splat(self.max_force);
        (R::select(alive, f, R::splat(0.0)), alive)
    }

    fn separation_energy(&self, s: f64, _a_i: f64, _a_j: f64) -> f64 {
        -0.5 * self.stiffness * (self.range - s) * (self.range - s)
    }
}

#[cfg(test)]
mod tests {
    use crate::contact::Adhesion;

    const A: f64 = 1.1e-3;

    #[test]
    fn only_a_live_bridge_pulls_and_it_breaks_past_the_rupture_distance() {
        let law = Adhesion::LinearIrreversible(super::LinearIrreversible {
            max_force: 2.0,
            stiffness: 4.0,
        });
        assert_eq!(law.range(), 0.5);
        assert_eq!(law.contact_force(A, A), -2.0);
        assert_eq!(law.separated_force(0.25, A, A, true), (-1.0, true));
        assert_eq!(law.separated_force(0.25, A, A, false), (0.0, false));
        assert_eq!(law.separated_force(0.5, A, A, true), (0.0, true));
        assert_eq!(law.separated_force(0.51, A, A, true), (0.0, false));
        // The energy of the triangle under the separation branch, and none without a bridge.
        assert!((law.potential(0.0, A, A, true) + 0.5 * 2.0 * 0.5).abs() < 1e-15);
        assert_eq!(law.potential(-0.1, A, A, false), 0.0);
    }
}
