//! Rabinovich's liquid bridge (Rabinovich et al. 2005; docs/model.md §2.11): the capillary
//! force of a bridge of fixed volume between two spheres, with the filling-angle term,
//! formed at contact and ruptured past Lian et al.'s distance `S_c = (1 + θ/2) V_b^{1/3}`.

use super::willett::{CONTACT_ANGLE, SURFACE_TENSION};
use super::{
    AdhesiveLaw, Bounds, LawError, Parameter, Parameters, ResolvedLaw, Strength, bridge_radius,
    bridge_radius_lanes,
};
use crate::contact::lanes::Real;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Rabinovich's liquid bridge of volume `V_b` between two spheres of pair radius
/// `r = 2 a_i a_j/(a_i + a_j)` (a sphere on a plane: `2 a_i`) at separation `S`:
///
/// ```text
/// d_sp = (S/2) (√(1 + 2 V_b/(π r S²)) − 1)      immersion height
/// α    = √(2 d_sp / r)                           half-filling angle
/// f    = −2π r γ_s cos θ / (1 + S/(2 d_sp)) − 2π r γ_s sin α sin(θ + α)
/// ```
///
/// In contact the force is its value at `S = 0`, where `α₀ = (2 V_b/(π r³))^{1/4}`; the
/// second (filling-angle) term adds `sin α₀ sin(θ + α₀)/cos θ` to Willett's `2π r γ_s cos θ`
/// (32 % for 75 nl between 2.2 mm grains at θ = 20°). A bridge forms at contact and
/// ruptures past `S_c = (1 + θ/2) V_b^{1/3}` (Lian et al. 1993):
///
/// ```
/// use rheodem_engine::contact::Adhesion;
/// use rheodem_engine::contact::adhesion::Rabinovich;
/// use std::f64::consts::PI;
///
/// let (gamma, theta, volume) = (0.02, 20f64.to_radians(), 75e-12);
/// let bridge = Adhesion::Rabinovich(Rabinovich { surface_tension: gamma, contact_angle: theta, volume });
/// let r: f64 = 1.1e-3; // two 2.2 mm grains
/// let alpha = (2.0 * volume / (PI * r.powi(3))).powf(0.25);
/// let at_contact = 2.0 * PI * r * gamma * (theta.cos() + alpha.sin() * (theta + alpha).sin());
/// assert!((bridge.contact_force(1.1e-3, 1.1e-3) + at_contact).abs() < 1e-15);
/// assert!((bridge.range() - (1.0 + theta / 2.0) * volume.cbrt()).abs() < 1e-15);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Rabinovich {
    /// Surface tension `γ_s` (N/m).
    pub surface_tension: f64,
    /// Contact angle `θ` (rad), in `[0, π/2)`.
    pub contact_angle: f64,
    /// Bridge volume `V_b` (m³), positive.
    pub volume: f64,
}

/// [`Rabinovich`] with its per-run constants computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolvedRabinovich {
    /// `2π γ_s` (N/m).
    two_pi_gamma: f64,
    /// Contact angle `θ` (rad).
    theta: f64,
    /// `cos θ`.
    cos_theta: f64,
    /// `2 V_b/π` (m³): `2 V_b/(π r)` is the `q` of the immersion height.
    q_times_r: f64,
    /// Rupture distance `S_c` (m).
    range: f64,
}

impl AdhesiveLaw for Rabinovich {
    const NAME: &'static str = "rabinovich";
    const ALIASES: &'static [&'static str] = &["rabinovich_bridge"];
    const SUMMARY: &'static str = "Rabinovich's capillary bridge of fixed volume with its filling-angle term: formed at contact, ruptured at (1 + theta/2) V^(1/3) (Rabinovich et al. 2005; Lian et al. 1993).";
    const PARAMETERS: &'static [Parameter] = &[
        SURFACE_TENSION,
        CONTACT_ANGLE,
        Parameter {
            key: "volume",
            unit: "m³",
            meaning: "bridge volume V_b",
            bounds: Bounds::Positive,
            default: None,
            note: " (the contact-only limit is liquid_bridge's, volume = 0)",
            instead_of: None,
        },
    ];
    const FORMS_BRIDGES: bool = true;
    type Resolved = ResolvedRabinovich;

    fn from_parameters(p: &Parameters<'_>) -> Result<Rabinovich, LawError> {
        p.check_keys()?;
        Ok(Rabinovich {
            surface_tension: p.require("surface_tension")?,
            contact_angle: p.require("contact_angle_deg")?.to_radians(),
            volume: p.require("volume")?,
        })
    }

    /// `θ = 20°`; `V_b` such that the bridge ruptures at the rupture distance, and `γ_s`
    /// such that the mean pair (`r = d_p/2`) pulls with `f_max` in contact.
    fn at_strength(s: &Strength) -> Vec<(&'static str, f64)> {
        let theta = 20f64.to_radians();
        let volume = (s.rupture_distance / (1.0 + 0.5 * theta)).powi(3);
        let unit = Rabinovich {
            surface_tension: 1.0,
            contact_angle: theta,
            volume,
        }
        .resolve();
        let a = 0.5 * s.mean_diameter;
        vec![
            ("surface_tension", s.max_force / unit.max_force(a, a)),
            ("contact_angle_deg", 20.0),
            ("volume", volume),
        ]
    }

    fn resolve(&self) -> ResolvedRabinovich {
        ResolvedRabinovich {
            two_pi_gamma: 2.0 * PI * self.surface_tension,
            theta: self.contact_angle,
            cos_theta: self.contact_angle.cos(),
            q_times_r: 2.0 * self.volume / PI,
            range: (1.0 + 0.5 * self.contact_angle) * self.volume.cbrt(),
        }
    }
}

impl ResolvedRabinovich {
    /// The force (N, ≤ 0) at separation `s ≥ 0` (m) for pair radius `r` (m), in lanes.
    #[inline(always)]
    fn force<R: Real>(&self, s: R, r: R) -> R {
        let q = R::splat(self.q_times_r) / r;
        // d_sp = (√(S² + q) − S)/2, written without the difference of near-equal terms.
        let d_sp = q / (R::splat(2.0) * ((s * s + q).sqrt() + s));
        let alpha = (R::splat(2.0) * d_sp / r).sqrt();
        let (sin_a, cos_a) = alpha.sin_cos();
        let (sin_t, cos_t) = (R::splat(self.theta.sin()), R::splat(self.cos_theta));
        let scale = R::splat(self.two_pi_gamma) * r;
        let meniscus = R::splat(self.cos_theta) / (R::splat(1.0) + s / (R::splat(2.0) * d_sp));
        // sin(θ + α) = sin θ cos α + cos θ sin α.
        let filling = sin_a * (sin_t * cos_a + cos_t * sin_a);
        -(scale * (meniscus + filling))
    }
}

/// Gauss–Legendre nodes and weights on [−1, 1], eight points.
const GAUSS_8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_2, 0.101_228_536_290_376_26),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_65, 0.362_683_783_378_362),
    (0.183_434_642_495_65, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (0.960_289_856_497_536_2, 0.101_228_536_290_376_26),
];

/// Panels of the separation energy's quadrature.
const PANELS: usize = 16;

impl ResolvedLaw for ResolvedRabinovich {
    #[inline(always)]
    fn range(&self) -> f64 {
        self.range
    }

    /// `|f(0)| = 2π r γ_s (cos θ + sin α₀ sin(θ + α₀))`.
    fn max_force(&self, a_i: f64, a_j: f64) -> f64 {
        -self.force(0.0, bridge_radius(a_i, a_j))
    }

    #[inline(always)]
    fn contact_force_lanes<R: Real, const WALL: bool>(&self, a_i: R, a_j: R) -> R {
        self.force(R::splat(0.0), bridge_radius_lanes::<R, WALL>(a_i, a_j))
    }

    #[inline(always)]
    fn separated_force_lanes<R: Real, const WALL: bool>(
        &self,
        s: R,
        a_i: R,
        a_j: R,
        bridge: R::Mask,
    ) -> (R, R::Mask) {
        let alive = R::both(bridge, s.le(R::splat(self.range)));
        let f = self.force(s, bridge_radius_lanes::<R, WALL>(a_i, a_j));
        (R::select(alive, f, R::splat(0.0)), alive)
    }

    /// `∫_s^{S_c} f dS` by composite eight-point Gauss–Legendre quadrature over 16 panels
    /// (the force is smooth on `[0, S_c]`: relative error below 10⁻¹²).
    fn separation_energy(&self, s: f64, a_i: f64, a_j: f64) -> f64 {
        let r = bridge_radius(a_i, a_j);
        let h = (self.range - s) / PANELS as f64;
        let mut sum = 0.0;
        for p in 0..PANELS {
            let mid = s + (p as f64 + 0.5) * h;
            for (x, w) in GAUSS_8 {
                sum += w * self.force(mid + 0.5 * h * x, r);
            }
        }
        0.5 * h * sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::Adhesion;

    fn bridge(volume: f64) -> Adhesion {
        Adhesion::Rabinovich(Rabinovich {
            surface_tension: 0.02,
            contact_angle: 20f64.to_radians(),
            volume,
        })
    }

    /// The paper's equations evaluated as written, without rheodem's rearrangements.
    fn paper(s: f64, r: f64, gamma: f64, theta: f64, v: f64) -> f64 {
        let d_sp = s / 2.0 * (-1.0 + (1.0 + 2.0 * v / (PI * r * s * s)).sqrt());
        let alpha = (s / r * (-1.0 + (1.0 + 2.0 * v / (PI * r * s * s)).sqrt())).sqrt();
        -2.0 * PI * r * gamma * theta.cos() / (1.0 + s / (2.0 * d_sp))
            - 2.0 * PI * gamma * r * alpha.sin() * (theta + alpha).sin()
    }

    #[test]
    fn the_force_is_the_papers_from_contact_to_rupture() {
        let theta = 20f64.to_radians();
        for volume in [4.2e-12, 75e-12, 200e-12] {
            let b = bridge(volume);
            let (a_i, a_j) = (1.1e-3, 0.8e-3);
            let r = 2.0 * a_i * a_j / (a_i + a_j);
            for k in 1..=100 {
                let s = b.range() * k as f64 / 100.0;
                let (f, alive) = b.separated_force(s, a_i, a_j, true);
                let expected = paper(s, r, 0.02, theta, volume);
                assert!(alive);
                // The paper's form loses digits to √(1 + x) − 1 at small S: 1e-9 bounds it.
                assert!(
                    (f / expected - 1.0).abs() < 1e-9,
                    "V = {volume}, S = {s}: {f} vs {expected}"
                );
            }
            // The contact value is the limit S → 0 of the paper's form.
            let near = paper(1e-9 * b.range(), r, 0.02, theta, volume);
            assert!((b.contact_force(a_i, a_j) / near - 1.0).abs() < 1e-6);
            assert_eq!(
                b.separated_force(1.0001 * b.range(), a_i, a_j, true),
                (0.0, false)
            );
            assert_eq!(
                b.separated_force(0.5 * b.range(), a_i, a_j, false),
                (0.0, false)
            );
        }
    }

    #[test]
    fn the_separation_energy_is_the_integral_of_the_force() {
        let b = bridge(75e-12);
        let (a_i, a_j) = (1.1e-3, 0.7e-3);
        for from in [0.0, 0.3, 0.9] {
            let s0 = from * b.range();
            let n = 20_000;
            let h = (b.range() - s0) / n as f64;
            let f = |s: f64| b.separated_force(s, a_i, a_j, true).0;
            let mut sum = f(s0) + f(b.range());
            for k in 1..n {
                sum += f(s0 + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
            }
            let simpson = sum * h / 3.0;
            let closed = b.separation_energy(s0, a_i, a_j);
            assert!(
                (closed / simpson - 1.0).abs() < 1e-10,
                "from {from}: {closed} vs {simpson}"
            );
        }
    }
}
