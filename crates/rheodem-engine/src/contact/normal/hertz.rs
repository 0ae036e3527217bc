//! Hertz's elastic normal force between two spheres with Tsuji's dashpot (docs/model.md
//! §2.10): `f_n = (4/3) E* √(R* δ) δ + η_n dδ/dt` with `η_n = α(e) √(2 m_ij (4/3) E* √(R* δ))`.

use super::super::kernel::Touch;
use super::super::lanes::Real;
use super::super::parameters::{Bounds, LawError, Parameter, Parameters};
use super::{LinearNormal, NormalForce, NormalModel, NormalParts};
use serde::{Deserialize, Serialize};

/// The duration of an undamped Hertzian collision in units of
/// `(m_ij² / (R* E*² v))^{1/5}`: `2 √π Γ(7/5)/Γ(9/10) · (15/16)^{2/5}` (Johnson 1985, §11.4).
pub const HERTZ_TIME_FACTOR: f64 = 2.868_265_699_195_333;

/// The elastic constants of one material (SI units), from which a pair's effective moduli
/// are mixed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Young's modulus `E` (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio `ν`.
    pub poisson_ratio: f64,
}

impl Material {
    /// The effective Young's modulus `E*` (Pa) of a contact with `other`:
    /// `1/E* = (1 − ν_i²)/E_i + (1 − ν_j²)/E_j`.
    pub fn effective_modulus(&self, other: &Material) -> f64 {
        1.0 / ((1.0 - self.poisson_ratio.powi(2)) / self.youngs_modulus
            + (1.0 - other.poisson_ratio.powi(2)) / other.youngs_modulus)
    }

    /// The effective shear modulus `G*` (Pa) of a contact with `other`:
    /// `1/G* = 2(2 − ν_i)(1 + ν_i)/E_i + 2(2 − ν_j)(1 + ν_j)/E_j` (Mindlin's tangential
    /// stiffness is `8 G* a`).
    pub fn effective_shear_modulus(&self, other: &Material) -> f64 {
        let part = |m: &Material| {
            2.0 * (2.0 - m.poisson_ratio) * (1.0 + m.poisson_ratio) / m.youngs_modulus
        };
        1.0 / (part(self) + part(other))
    }
}

/// Parameters of the Hertz normal law of one species pair (SI units).
///
/// Two spheres of reduced radius `R* = a_i a_j/(a_i + a_j)` (a sphere on a plane: its own
/// radius) pressed together by `δ` touch over a circle of radius `a = √(R* δ)` and repel
/// with `(4/3) E* a δ`. The dashpot is Tsuji et al.'s (1992), `η_n = α √(m k_a)` with
/// `k_a = (4/3) E* a`, whose restitution does not depend on the impact speed; `α(e)` is
/// their polynomial fit. Their `m` is the mass of one of two equal spheres, `2 m_ij`: with
/// it the fit restitutes `e` to 0.1 % (tests/hertz_mindlin.rs); LAMMPS's `damping tsuji`
/// takes `m_ij` instead and restitutes more (0.928 for `e = 0.9`). The force is not
/// clipped: it turns slightly tensile at the end of a damped collision, as the linear
/// law's does.
///
/// An undamped collision of reduced mass `m_ij` at speed `v` lasts
/// `t_c = 2.868 (m_ij² / (R* E*² v))^{1/5}`:
///
/// ```
/// use rheodem_engine::contact::normal::hertz::{HertzNormal, HERTZ_TIME_FACTOR, Material};
/// use rheodem_engine::contact::NormalModel;
///
/// let glass = Material { youngs_modulus: 63.0e9, poisson_ratio: 0.22 };
/// let law = HertzNormal::between(&glass, &glass, 1.0, 0.5);
/// let (m_ij, r_ij) = (0.5 * 1.39e-5, 0.55e-3); // two 2.2 mm glass beads
/// let e_star = glass.youngs_modulus / (2.0 * (1.0 - 0.22 * 0.22));
/// let t_c = HERTZ_TIME_FACTOR * (m_ij * m_ij / (r_ij * e_star * e_star * 0.5)).powf(0.2);
/// assert!((law.contact_time(m_ij, r_ij).expect("elastic") / t_c - 1.0).abs() < 1e-12);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HertzNormal {
    /// Effective Young's modulus `E*` (Pa).
    pub effective_modulus: f64,
    /// Effective shear modulus `G*` (Pa), which a Mindlin sliding spring takes.
    pub effective_shear_modulus: f64,
    /// Restitution coefficient `e` of a binary collision, in (0, 1]; 1 is no dashpot.
    pub restitution: f64,
    /// The impact speed (m/s) at which the contact time that sets time steps is quoted.
    pub impact_speed: f64,
}

/// Tsuji et al.'s (1992) damping factor `α(e)` of the Hertzian dashpot
/// `η_n = α √(2 m_ij k_a)`: the sixth-order polynomial fit of the restitution of the
/// damped Hertzian oscillator (as LAMMPS's `damping tsuji` writes it); zero at `e = 1`.
pub fn tsuji_alpha(e: f64) -> f64 {
    if e >= 1.0 {
        return 0.0;
    }
    let c = [1.2728, -4.2783, 11.087, -22.348, 27.467, -18.022, 4.8218];
    c.iter().rev().fold(0.0, |acc, &ck| acc * e + ck)
}

impl HertzNormal {
    /// The law of a contact between `a` and `b` with restitution `e` (0 < e ≤ 1) and
    /// contact times quoted at `impact_speed` (m/s).
    pub fn between(a: &Material, b: &Material, restitution: f64, impact_speed: f64) -> HertzNormal {
        HertzNormal {
            effective_modulus: a.effective_modulus(b),
            effective_shear_modulus: a.effective_shear_modulus(b),
            restitution,
            impact_speed,
        }
    }

    /// The material of `youngs_modulus` and `poisson_ratio` in `p`, checked.
    pub fn material(p: &Parameters<'_>) -> Result<Material, LawError> {
        Ok(Material {
            youngs_modulus: p.require("youngs_modulus")?,
            poisson_ratio: p.require("poisson_ratio")?,
        })
    }

    /// The elastic force `(4/3) E* √(R* δ) δ` (N) at overlap `δ ≥ 0` (m) of a pair of
    /// reduced radius `R*` (m).
    pub fn elastic_force(&self, overlap: f64, r_ij: f64) -> f64 {
        4.0 / 3.0 * self.effective_modulus * (r_ij * overlap).sqrt() * overlap
    }
}

/// [`HertzNormal`] with its constants: `(4/3) E*` and the dashpot factor `√2 α(e)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolvedHertz {
    /// `(4/3) E*` (Pa).
    modulus: f64,
    /// `√2 α(e)`: `η_n = √2 α √(m_ij k_a)`.
    alpha: f64,
}

/// The reduced radius `R* = a_i a_j/(a_i + a_j)` (m) in lanes; `a_i` against a wall.
#[inline(always)]
pub fn reduced_radius_lanes<R: Real, const WALL: bool>(a_i: R, a_j: R) -> R {
    if WALL { a_i } else { a_i * a_j / (a_i + a_j) }
}

impl NormalModel for HertzNormal {
    const NAME: &'static str = "hertz";
    const ALIASES: &'static [&'static str] = &["hertz_material", "hertz_tsuji"];
    const SUMMARY: &'static str = "Hertz's elastic force (4/3) E* √(R* δ) δ with Tsuji's dashpot for a restitution e (Hertz 1882; Tsuji et al. 1992).";
    const PARAMETERS: &'static [Parameter] = &[
        Parameter {
            key: "youngs_modulus",
            unit: "Pa",
            meaning: "Young's modulus E of the material (omit to take each species' own)",
            bounds: Bounds::Positive,
            default: None,
            note: "",
            instead_of: None,
        },
        Parameter {
            key: "poisson_ratio",
            unit: "",
            meaning: "Poisson's ratio ν of the material (omit to take each species' own)",
            bounds: Bounds::LeftOpen(-1.0, 0.5),
            default: None,
            note: "",
            instead_of: None,
        },
        Parameter {
            key: "restitution",
            unit: "",
            meaning: "restitution coefficient e of a binary collision (1: no dashpot)",
            bounds: Bounds::LeftOpen(0.0, 1.0),
            default: Some(1.0),
            note: "",
            instead_of: None,
        },
        Parameter {
            key: "impact_speed",
            unit: "m/s",
            meaning: "impact speed at which the contact time that sets the time step is quoted",
            bounds: Bounds::Positive,
            default: Some(1.0),
            note: "",
            instead_of: None,
        },
    ];
    type Resolved = ResolvedHertz;

    /// The law of one material against itself (`youngs_modulus` and `poisson_ratio`
    /// required here; a scenario fills them from the species of each pair where omitted).
    fn from_parameters(p: &Parameters<'_>) -> Result<HertzNormal, LawError> {
        p.check_keys()?;
        let material = HertzNormal::material(p)?;
        Ok(HertzNormal::between(
            &material,
            &material,
            p.require("restitution")?,
            p.require("impact_speed")?,
        ))
    }

    /// None: Hertz's stiffness grows with the overlap, so springs beside it give their
    /// own (a Mindlin spring takes `G*` from it).
    fn reference(&self) -> Option<LinearNormal> {
        None
    }

    fn resolve(&self) -> ResolvedHertz {
        ResolvedHertz {
            modulus: 4.0 / 3.0 * self.effective_modulus,
            alpha: std::f64::consts::SQRT_2 * tsuji_alpha(self.restitution),
        }
    }

    /// The secant stiffness `f/δ = (4/3) E* √(R* δ)` at an overlap of 1 % of `R*`.
    fn max_stiffness(&self, r_ij: f64) -> f64 {
        4.0 / 3.0 * self.effective_modulus * 0.1 * r_ij
    }

    /// The undamped collision time `2.868 (m_ij²/(R* E*² v))^{1/5}` at the law's impact
    /// speed `v` (a damped one lasts slightly longer).
    fn contact_time(&self, m_ij: f64, r_ij: f64) -> Option<f64> {
        let e = self.effective_modulus;
        Some(HERTZ_TIME_FACTOR * (m_ij * m_ij / (r_ij * e * e * self.impact_speed)).powf(0.2))
    }

    /// The restitution `e` the dashpot is set for, the same at every mass and speed.
    fn restitution(&self, _m_ij: f64) -> Option<f64> {
        Some(self.restitution)
    }

    /// The law with `α` scaled by `factor`, expressed as the restitution that gives it
    /// (`e = 0.1` at most damping the fit covers).
    fn damping_scaled(&self, factor: f64) -> HertzNormal {
        let target = tsuji_alpha(self.restitution) * factor;
        // α(e) falls monotonically on (0.1, 1]: bisect for the e that gives `target`.
        let (mut lo, mut hi) = (0.1, 1.0);
        if target >= tsuji_alpha(lo) {
            hi = lo;
        }
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if tsuji_alpha(mid) > target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        HertzNormal {
            restitution: hi,
            ..*self
        }
    }
}

impl NormalForce for ResolvedHertz {
    #[inline(always)]
    fn force_lanes<R: Real, const WALL: bool>(
        &self,
        k: &Touch<R>,
        overlap_rate: R,
        _state: &mut R,
    ) -> NormalParts<R> {
        let r = reduced_radius_lanes::<R, WALL>(k.radius_i, k.radius_j);
        // k_a = (4/3) E* a with a = √(R* δ).
        let stiffness = R::splat(self.modulus) * (r * k.overlap).sqrt();
        let elastic = stiffness * k.overlap;
        let repulsive = if self.alpha != 0.0 {
            elastic + R::splat(self.alpha) * (k.reduced_mass * stiffness).sqrt() * overlap_rate
        } else {
            elastic
        };
        NormalParts {
            repulsive,
            adhesive: None,
        }
    }

    /// `(8/15) E* √R* δ^{5/2}`.
    fn energy(&self, overlap: f64, a_i: f64, a_j: f64, _state: f64) -> f64 {
        let r = if a_j.is_finite() {
            a_i * a_j / (a_i + a_j)
        } else {
            a_i
        };
        0.4 * self.modulus * (r * overlap).sqrt() * overlap * overlap
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GLASS: Material = Material {
        youngs_modulus: 63.0e9,
        poisson_ratio: 0.22,
    };

    #[test]
    fn like_materials_mix_to_the_textbook_moduli() {
        let e = GLASS.youngs_modulus;
        let nu = GLASS.poisson_ratio;
        assert!(
            (GLASS.effective_modulus(&GLASS) / (e / (2.0 * (1.0 - nu * nu))) - 1.0).abs() < 1e-14
        );
        let g = e / (2.0 * (1.0 + nu));
        let expected = g / (2.0 * (2.0 - nu));
        assert!((GLASS.effective_shear_modulus(&GLASS) / expected - 1.0).abs() < 1e-14);
    }

    #[test]
    fn the_energy_is_the_work_of_the_elastic_force() {
        let law = HertzNormal::between(&GLASS, &GLASS, 1.0, 1.0);
        let resolved = law.resolve();
        let (a, d, h) = (1.1e-3, 2.0e-6, 1.0e-12);
        let de =
            (resolved.energy(d + h, a, a, 0.0) - resolved.energy(d - h, a, a, 0.0)) / (2.0 * h);
        assert!((de / law.elastic_force(d, 0.5 * a) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn the_fit_gives_no_damping_at_full_restitution_and_falls_with_it() {
        assert_eq!(tsuji_alpha(1.0), 0.0);
        let mut last = f64::INFINITY;
        for k in 1..100 {
            let a = tsuji_alpha(0.1 + 0.009 * k as f64);
            assert!(a < last && a > 0.0);
            last = a;
        }
        // Scaling the dashpot finds the restitution whose α is the scaled one.
        let law = HertzNormal::between(&GLASS, &GLASS, 0.7, 1.0);
        let half = law.damping_scaled(0.5);
        assert!((tsuji_alpha(half.restitution) / (0.5 * tsuji_alpha(0.7)) - 1.0).abs() < 1e-9);
    }
}
