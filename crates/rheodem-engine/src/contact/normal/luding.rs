//! Luding's elasto-plastic adhesive normal law (Luding 2008, Granular Matter 10, 235,
//! Eqs. 6–8; docs/model.md §2.9): a hysteretic spring whose unloading stiffness grows with
//! the largest overlap the contact has reached, and an adhesive branch in tension. The
//! largest overlap `δ_max` is the law's per-contact state.

use super::super::adhesion::{bridge_radius, bridge_radius_lanes};
use super::super::damping::Damping;
use super::super::kernel::Touch;
use super::super::lanes::Real;
use super::super::parameters::{Bounds, LawError, Parameter, Parameters};
use super::linear::{DASHPOT_PARAMETERS, dashpot};
use super::{LinearNormal, NormalForce, NormalModel, NormalParts};
use serde::{Deserialize, Serialize};

/// Parameters of Luding's elasto-plastic adhesive normal law (SI units).
///
/// A contact loads along `k_1 δ` and unloads or reloads along `k_2 (δ − δ_0)`, where
/// `δ_0 = (1 − k_1/k_2) δ_max` is the plastic overlap and the unloading stiffness
/// `k_2 = k_1 + (k_p − k_1) δ_max/δ_max^p` grows from `k_1` to `k_p`, reached at
/// `δ_max^p = k_p/(k_p − k_1) φ_f r` with `r = 2 a_i a_j/(a_i + a_j)` (`2 a_i` on a wall);
/// `δ_max` is held at `δ_max^p` beyond it, so that the contact then follows the `k_p` line
/// both ways. In tension the force is bounded by the adhesive branch `−k_c δ`: a contact
/// unloaded past it follows `−k_c δ` and moves `δ_max` to `(k_2 + k_c)/(k_2 − k_1) δ`, so
/// that reloading leaves the branch along `k_2` through the current point. The dashpot
/// `γ_n δ̇` is added; the force acts until `δ = 0`, where the contact ends and `δ_max` is
/// forgotten.
///
/// Loaded to `δ_max = 0.01` (below `δ_max^p = 0.02`) and unloaded, a contact with
/// `k_1 = 1`, `k_p = 5`, `k_c = 0.5` unloads along `k_2 = 3` and leaves the adhesive branch
/// at the pull-off force `−k_c (k_2 − k_1)/(k_2 + k_c) δ_max`:
///
/// ```
/// use rheodem_engine::contact::{Damping, LudingNormal, NormalModel};
///
/// let law = LudingNormal {
///     stiffness: 1.0,
///     max_stiffness: 5.0,
///     adhesive_stiffness: 0.5,
///     plasticity_depth: 0.008,
///     damping: Damping::NONE,
/// };
/// // r = 2 a_i a_j/(a_i + a_j) = 2 for two spheres of radius 2.
/// let (a, d_max) = (2.0, 0.01);
/// let mut state = 0.0;
/// assert!((law.force(d_max, a, a, &mut state) - d_max).abs() < 1e-15); // k_1 δ
/// assert_eq!(state, d_max);
/// let (k2, kc) = (3.0, 0.5);
/// let d_min = (k2 - 1.0) / (k2 + kc) * d_max;
/// let pull_off = law.force(d_min, a, a, &mut state);
/// assert!((pull_off + kc * d_min).abs() < 1e-15);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LudingNormal {
    /// Loading stiffness `k_1` (N/m).
    pub stiffness: f64,
    /// Largest unloading stiffness `k_p` (N/m), above `k_1`.
    pub max_stiffness: f64,
    /// Adhesive stiffness `k_c` (N/m) of the tensile branch, ≥ 0.
    pub adhesive_stiffness: f64,
    /// Plasticity depth `φ_f`: the largest plastic overlap over `2 a_i a_j/(a_i + a_j)`.
    pub plasticity_depth: f64,
    /// Normal damping `γ_n` (kg/s) as a function of the reduced mass.
    pub damping: Damping,
}

impl LudingNormal {
    /// The hysteretic force `f_hys` (N, without the dashpot) of a pair of radii `a_i`, `a_j`
    /// (m) at overlap `δ > 0` (m), advancing the contact's largest overlap `state` (m).
    pub fn force(&self, overlap: f64, a_i: f64, a_j: f64, state: &mut f64) -> f64 {
        let f = if a_j.is_finite() {
            self.hysteretic::<f64, false>(overlap, a_i, a_j, state)
        } else {
            self.hysteretic::<f64, true>(overlap, a_i, a_j, state)
        };
        f.0 + f.1
    }

    /// `f_hys` split as the reference of the Coulomb limits, `f_hys + k_c δ`, and the
    /// adhesive part `−k_c δ` (N), in lanes, advancing `δ_max` in `state`.
    #[inline(always)]
    fn hysteretic<R: Real, const WALL: bool>(
        &self,
        overlap: R,
        a_i: R,
        a_j: R,
        state: &mut R,
    ) -> (R, R) {
        let k1 = R::splat(self.stiffness);
        let kc = R::splat(self.adhesive_stiffness);
        let r = bridge_radius_lanes::<R, WALL>(a_i, a_j);
        let plastic_limit = R::splat(self.plastic_limit_factor()) * r;
        let grown = R::select(overlap.gt(*state), overlap, *state);
        let d_max = R::select(grown.gt(plastic_limit), plastic_limit, grown);
        let k2 = k1 + R::splat(self.max_stiffness - self.stiffness) * d_max / plastic_limit;
        let d0 = (R::splat(1.0) - k1 / k2) * d_max;
        let on_k2 = k2 * (overlap - d0);
        let adhesive = -(kc * overlap);
        let tension = on_k2.lt(adhesive);
        let f = R::select(tension, adhesive, on_k2);
        *state = R::select(tension, (k2 + kc) / (k2 - k1) * overlap, d_max);
        (f - adhesive, adhesive)
    }

    /// `δ_max^p / r = k_p φ_f/(k_p − k_1)`.
    fn plastic_limit_factor(&self) -> f64 {
        self.max_stiffness / (self.max_stiffness - self.stiffness) * self.plasticity_depth
    }
}

impl NormalModel for LudingNormal {
    const NAME: &'static str = "luding";
    const PARAMETERS: &'static [Parameter] = &[
        Parameter {
            key: "stiffness",
            unit: "N/m",
            meaning: "loading stiffness k_1",
            bounds: Bounds::Positive,
            default: None,
            note: "",
            instead_of: None,
        },
        Parameter {
            key: "max_stiffness",
            unit: "N/m",
            meaning: "largest unloading stiffness k_p, above k_1",
            bounds: Bounds::Positive,
            default: None,
            note: "",
            instead_of: None,
        },
        Parameter {
            key: "adhesive_stiffness",
            unit: "N/m",
            meaning: "adhesive stiffness k_c of the tensile branch",
            bounds: Bounds::NonNegative,
            default: Some(0.0),
            note: "",
            instead_of: None,
        },
        Parameter {
            key: "plasticity_depth",
            unit: "",
            meaning: "plasticity depth φ_f: the largest plastic overlap over 2 a_i a_j/(a_i + a_j)",
            bounds: Bounds::LeftOpen(0.0, 1.0),
            default: None,
            note: "",
            instead_of: None,
        },
        DASHPOT_PARAMETERS[0],
        DASHPOT_PARAMETERS[1],
        DASHPOT_PARAMETERS[2],
    ];

    /// The law from its keys; a `restitution` sets the dashpot of the loading line `k_1`.
    fn from_parameters(p: &Parameters<'_>) -> Result<LudingNormal, LawError> {
        p.check_keys()?;
        let k1 = p.require("stiffness")?;
        let kp = p.require("max_stiffness")?;
        if kp <= k1 {
            return Err(LawError {
                key: "max_stiffness".into(),
                value: kp.to_string(),
                reason: format!("must lie above `stiffness` = {k1} N/m (k_p > k_1)"),
            });
        }
        Ok(LudingNormal {
            stiffness: k1,
            max_stiffness: kp,
            adhesive_stiffness: p.require("adhesive_stiffness")?,
            plasticity_depth: p.require("plasticity_depth")?,
            damping: dashpot(p, k1)?,
        })
    }

    /// The loading line `k_1` with the law's dashpot.
    fn reference(&self) -> Option<LinearNormal> {
        Some(self.loading())
    }

    const ALIASES: &'static [&'static str] = &["elasto_plastic", "linear_plastic"];
    const SUMMARY: &'static str = "Elasto-plastic adhesive spring: loading k_1, unloading k_2(δ_max) up to k_p, tension -k_c δ, plus γ_n dδ/dt (Luding 2008, Eqs. 6-8).";
    type Resolved = LudingNormal;

    fn resolve(&self) -> LudingNormal {
        *self
    }

    /// `k_p`, the stiffest line a contact follows.
    fn max_stiffness(&self, _r_ij: f64) -> f64 {
        self.max_stiffness
    }

    /// The contact time of the `k_p` line (the shortest a branch gives).
    fn contact_time(&self, m_ij: f64, _r_ij: f64) -> Option<f64> {
        self.stiffest().contact_time(m_ij)
    }

    /// The restitution of the loading line `k_1` with the law's dashpot, as a scenario's
    /// `restitution` sets it (an elastic bound: a plastic collision restitutes less).
    fn restitution(&self, m_ij: f64) -> Option<f64> {
        self.loading().restitution(m_ij)
    }

    fn damping_scaled(&self, factor: f64) -> LudingNormal {
        LudingNormal {
            damping: self.damping.scaled(factor),
            ..*self
        }
    }
}

impl LudingNormal {
    /// The loading line `k_1` with this law's dashpot.
    fn loading(&self) -> LinearNormal {
        LinearNormal {
            stiffness: self.stiffness,
            damping: self.damping,
        }
    }

    /// The linear law along the `k_p` line with this law's dashpot.
    fn stiffest(&self) -> LinearNormal {
        LinearNormal {
            stiffness: self.max_stiffness,
            damping: self.damping,
        }
    }
}

impl NormalForce for LudingNormal {
    const KEEPS_STATE: bool = true;

    #[inline(always)]
    fn force_lanes<R: Real, const WALL: bool>(
        &self,
        k: &Touch<R>,
        overlap_rate: R,
        state: &mut R,
    ) -> NormalParts<R> {
        let gamma_n = self.damping.in_lanes(k.reduced_mass);
        let (reference, adhesive) =
            self.hysteretic::<R, WALL>(k.overlap, k.radius_i, k.radius_j, state);
        NormalParts {
            repulsive: reference + gamma_n * overlap_rate,
            adhesive: Some(adhesive),
        }
    }

    /// The work (J) the spring returns when the contact unloads from `δ` to separation at
    /// fixed `δ_max`: along the `k_2` line down to the adhesive branch at
    /// `δ_min = k_2 δ_0/(k_2 + k_c)`, then along `−k_c δ` (negative when tension dominates).
    fn energy(&self, overlap: f64, a_i: f64, a_j: f64, state: f64) -> f64 {
        let r = bridge_radius(a_i, a_j);
        let limit = self.plastic_limit_factor() * r;
        let d_max = state.min(limit);
        let kc = self.adhesive_stiffness;
        let k2 = self.stiffness + (self.max_stiffness - self.stiffness) * d_max / limit;
        let d0 = (1.0 - self.stiffness / k2) * d_max;
        let d_min = k2 * d0 / (k2 + kc);
        if overlap <= d_min {
            -0.5 * kc * overlap * overlap
        } else {
            0.5 * k2 * ((overlap - d0).powi(2) - (d_min - d0).powi(2)) - 0.5 * kc * d_min * d_min
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAW: LudingNormal = LudingNormal {
        stiffness: 1.0e3,
        max_stiffness: 5.0e3,
        adhesive_stiffness: 500.0,
        plasticity_depth: 0.05,
        damping: Damping::NONE,
    };
    /// Radius of two equal spheres: `r = 2 a_i a_j/(a_i + a_j) = a`.
    const A: f64 = 1.0e-3;

    /// `δ_max^p = k_p/(k_p − k_1) φ_f r`.
    fn plastic_limit() -> f64 {
        5.0 / 4.0 * 0.05 * A
    }

    /// Drives the overlap through `path` in `n` steps per leg; returns `(δ, f_hys)` pairs.
    fn drive(law: &LudingNormal, path: &[f64], n: usize) -> Vec<(f64, f64)> {
        let mut state = 0.0;
        let mut out = Vec::new();
        for leg in path.windows(2) {
            for s in 1..=n {
                let d = leg[0] + (leg[1] - leg[0]) * s as f64 / n as f64;
                if d > 0.0 {
                    out.push((d, law.force(d, A, A, &mut state)));
                } else {
                    state = 0.0;
                }
            }
        }
        out
    }

    #[test]
    fn a_cycle_follows_the_closed_form_branches() {
        let d_max = 0.4 * plastic_limit();
        let k1 = LAW.stiffness;
        let k2 = k1 + (LAW.max_stiffness - k1) * d_max / plastic_limit();
        let kc = LAW.adhesive_stiffness;
        let d0 = (1.0 - k1 / k2) * d_max;
        let d_min = (k2 - k1) / (k2 + kc) * d_max;
        let path = drive(&LAW, &[0.0, d_max, 0.7 * d_max, d_max, 1e-9], 4000);
        for (i, &(d, f)) in path.iter().enumerate() {
            let expected = if i < 4000 {
                k1 * d // virgin loading
            } else if i < 12000 || d > d_min {
                k2 * (d - d0) // unloading and reloading on the k2 line
            } else {
                -kc * d // the adhesive branch
            };
            assert!(
                (f - expected).abs() < 1e-9 * k1 * d_max,
                "step {i}: δ = {d}, f = {f}, expected {expected}"
            );
        }
        // The pull-off force: the most negative force of the cycle.
        let f_min = path.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        let expected = -kc * (k2 - k1) / (k2 + kc) * d_max;
        assert!(
            (f_min / expected - 1.0).abs() < 1e-3,
            "{f_min} vs {expected}"
        );
    }

    #[test]
    fn the_work_of_a_cycle_is_the_closed_form_dissipation() {
        for &(kc, d_max) in &[(0.0, 0.5), (500.0, 0.5), (500.0, 0.99), (2.0e3, 0.2)] {
            let law = LudingNormal {
                adhesive_stiffness: kc,
                ..LAW
            };
            let d_max = d_max * plastic_limit();
            let k1 = law.stiffness;
            let k2 = k1 + (law.max_stiffness - k1) * d_max / plastic_limit();
            // Loaded to δ_max and unloaded to separation: the areas of two triangles.
            let expected = 0.5 * d_max * d_max * (k2 - k1) * (k1 + kc) / (k2 + kc);
            let path = drive(&law, &[0.0, d_max, 0.0], 20_000);
            // Work done on the contact, ∮ f dδ, by the trapezoidal rule.
            let mut work = 0.0;
            let mut last = (0.0, 0.0);
            for &(d, f) in &path {
                work += 0.5 * (f + last.1) * (d - last.0);
                last = (d, f);
            }
            work += 0.5 * last.1 * (0.0 - last.0);
            assert!(
                (work / expected - 1.0).abs() < 1e-3,
                "k_c = {kc}: work {work} vs {expected}"
            );
        }
    }

    #[test]
    fn beyond_the_plastic_limit_the_stiffest_line_is_elastic() {
        let limit = plastic_limit();
        let d0 = LAW.plasticity_depth * A; // φ_f r: the largest plastic overlap
        let path = drive(&LAW, &[0.0, 2.0 * limit, 1.5 * limit, 2.0 * limit], 2000);
        for &(d, f) in &path[2000..] {
            assert!((f - LAW.max_stiffness * (d - d0)).abs() < 1e-9 * LAW.max_stiffness * limit);
        }
        // Loading past the limit follows the k_p line too.
        let (d, f) = path[1999];
        assert!((f - LAW.max_stiffness * (d - d0)).abs() < 1e-9 * LAW.max_stiffness * limit);
    }

    #[test]
    fn the_energy_is_the_work_the_spring_returns() {
        // At fixed δ_max, dE/dδ is the force on either branch, and E is continuous where
        // the unloading line meets the adhesive branch.
        let state = 0.6 * plastic_limit();
        let k1 = LAW.stiffness;
        let k2 = k1 + (LAW.max_stiffness - k1) * state / plastic_limit();
        let d_min = (k2 - k1) / (k2 + LAW.adhesive_stiffness) * state;
        let h = 1e-7 * plastic_limit();
        for d in [0.3 * d_min, 1.5 * d_min, 0.5 * state] {
            let f = LAW.force(d, A, A, &mut state.clone());
            let de = LAW.energy(d + h, A, A, state) - LAW.energy(d - h, A, A, state);
            assert!((de / (2.0 * h) - f).abs() < 1e-6 * f.abs(), "δ = {d}");
        }
        let jump = LAW.energy(d_min * (1.0 + 1e-12), A, A, state)
            - LAW.energy(d_min * (1.0 - 1e-12), A, A, state);
        assert!(jump.abs() < 1e-9 * LAW.adhesive_stiffness * d_min * d_min);
    }
}
