//! Willett's liquid bridge (Willett et al. 2000; Roy et al. 2016, Eqs. 10–15; docs/model.md
//! §2.5): no attraction on approach; a bridge forms at contact, pulls `−f_max` in contact
//! and `−f_max / (1 + 1.05 S̄ + 2.5 S̄²)`, `S̄ = S sqrt(r / V_b)`, on separation, and ruptures
//! past `S_c = (1 + θ/2) V_b^{1/3}`. Pair values use `r = 2 a_i a_j / (a_i + a_j)` and
//! `f_max = 2π r γ_s cos θ`.

use super::{
    AdhesiveLaw, Bounds, LawError, Parameter, Parameters, ResolvedLaw, Strength, bridge_radius,
    bridge_radius_lanes,
};
use crate::contact::lanes::Real;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Willett's liquid bridge.
///
/// A bridge pulls with `f_max = 2π r γ_s cos θ` in contact (`r` the harmonic-mean
/// radius), with `f_max / (1 + 1.05 S̄ + 2.5 S̄²)` at separation `S` (`S̄ = S sqrt(r/V_b)`),
/// and ruptures past `S_c = (1 + θ/2) V_b^{1/3}`; it forms only at contact:
///
/// ```
/// use rheodem_engine::contact::Adhesion;
/// use rheodem_engine::contact::adhesion::LiquidBridge;
/// use std::f64::consts::PI;
///
/// let (gamma, theta, volume) = (0.02, 20f64.to_radians(), 75e-12);
/// let bridge = Adhesion::LiquidBridge(LiquidBridge {
///     surface_tension: gamma,
///     contact_angle: theta,
///     volume,
/// });
/// let (a_i, a_j) = (1.1e-3, 0.6e-3);
/// let r = 2.0 * a_i * a_j / (a_i + a_j);
/// let f_max = 2.0 * PI * r * gamma * theta.cos();
/// assert!((bridge.contact_force(a_i, a_j) + f_max).abs() < 1e-15);
/// let s_c = (1.0 + theta / 2.0) * volume.cbrt();
/// assert!((bridge.range() - s_c).abs() < 1e-15);
/// let s = 0.5 * s_c;
/// let s_bar = s * (r / volume).sqrt();
/// let (f, alive) = bridge.separated_force(s, a_i, a_j, true);
/// assert!(alive && (f + f_max / (1.0 + 1.05 * s_bar + 2.5 * s_bar * s_bar)).abs() < 1e-15);
/// // No bridge on approach, none past rupture.
/// assert_eq!(bridge.separated_force(s, a_i, a_j, false), (0.0, false));
/// assert_eq!(bridge.separated_force(1.01 * s_c, a_i, a_j, true), (0.0, false));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LiquidBridge {
    /// Surface tension `γ_s` (N/m).
    pub surface_tension: f64,
    /// Contact angle `θ` (rad), in `[0, π/2)`.
    pub contact_angle: f64,
    /// Bridge volume `V_b` (m³).
    pub volume: f64,
}

/// [`LiquidBridge`] with its per-run constants computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolvedBridge {
    /// `2π γ_s cos θ` (N/m): `f_max` per unit pair radius `r`.
    pub force_per_radius: f64,
    /// Rupture distance `S_c = (1 + θ/2) V_b^{1/3}` (m).
    pub range: f64,
    /// `1 / V_b` (1/m³).
    pub inv_volume: f64,
}

/// The contact angle of the source papers (Shi et al. 2020, Roy et al. 2016), degrees.
pub const PAPERS_CONTACT_ANGLE_DEG: f64 = 20.0;

/// The surface tension of a liquid bridge's law (Willett's, Rabinovich's).
pub const SURFACE_TENSION: Parameter = Parameter {
    key: "surface_tension",
    unit: "N/m",
    meaning: "surface tension γ_s of the liquid",
    bounds: Bounds::Positive,
    default: None,
    note: "",
    instead_of: None,
};

/// The contact angle of a liquid bridge's law (Willett's, Rabinovich's), the papers' 20° by
/// default.
pub const CONTACT_ANGLE: Parameter = Parameter {
    key: "contact_angle_deg",
    unit: "degrees",
    meaning: "contact angle θ",
    bounds: Bounds::HalfOpen(0.0, 90.0),
    default: Some(PAPERS_CONTACT_ANGLE_DEG),
    note: ": a bridge with θ ≥ 90° does not attract",
    instead_of: None,
};

impl AdhesiveLaw for LiquidBridge {
    const NAME: &'static str = "liquid_bridge";
    const ALIASES: &'static [&'static str] = &["willett"];
    const SUMMARY: &'static str = "Willett's capillary bridge: formed at contact, \
        -2 pi r gamma cos(theta) / (1 + 1.05 S + 2.5 S^2) apart, ruptured at \
        (1 + theta/2) V^(1/3) (Roy et al. 2016, Eqs. 10-15).";
    const PARAMETERS: &'static [Parameter] = &[
        SURFACE_TENSION,
        CONTACT_ANGLE,
        Parameter {
            key: "volume",
            unit: "m³",
            meaning: "bridge volume V_b",
            bounds: Bounds::NonNegative,
            default: None,
            note: "; 0 is the contact-only limit (attraction while touching, none apart)",
            instead_of: None,
        },
    ];
    const FORMS_BRIDGES: bool = true;
    type Resolved = ResolvedBridge;

    fn from_parameters(p: &Parameters<'_>) -> Result<LiquidBridge, LawError> {
        p.check_keys()?;
        Ok(LiquidBridge {
            surface_tension: p.require("surface_tension")?,
            contact_angle: p.require("contact_angle_deg")?.to_radians(),
            volume: p.require("volume")?,
        })
    }

    /// The papers' `θ = 20°`; `γ_s` such that the mean pair (`r = d_p/2`) pulls with
    /// `f_max`; `V_b` such that it ruptures at the rupture distance.
    fn at_strength(s: &Strength) -> Vec<(&'static str, f64)> {
        let theta = PAPERS_CONTACT_ANGLE_DEG.to_radians();
        vec![
            (
                "surface_tension",
                s.max_force / (2.0 * PI * 0.5 * s.mean_diameter * theta.cos()),
            ),
            ("contact_angle_deg", PAPERS_CONTACT_ANGLE_DEG),
            ("volume", (s.rupture_distance / (1.0 + 0.5 * theta)).powi(3)),
        ]
    }

    fn resolve(&self) -> ResolvedBridge {
        ResolvedBridge {
            force_per_radius: 2.0 * PI * self.surface_tension * self.contact_angle.cos(),
            range: (1.0 + 0.5 * self.contact_angle) * self.volume.cbrt(),
            // `V_b = 0` is the contact-only limit: no range, so the only separation at
            // which the law is evaluated apart is `S = 0`, where `S̄ = 0`.
            inv_volume: if self.volume > 0.0 {
                1.0 / self.volume
            } else {
                0.0
            },
        }
    }
}

impl ResolvedLaw for ResolvedBridge {
    #[inline(always)]
    fn range(&self) -> f64 {
        self.range
    }

    #[inline(always)]
    fn max_force(&self, a_i: f64, a_j: f64) -> f64 {
        self.force_per_radius * bridge_radius(a_i, a_j)
    }

    #[inline(always)]
    fn contact_force_lanes<R: Real, const WALL: bool>(&self, a_i: R, a_j: R) -> R {
        let r = bridge_radius_lanes::<R, WALL>(a_i, a_j);
        -(R::splat(self.force_per_radius) * r)
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
        let r = bridge_radius_lanes::<R, WALL>(a_i, a_j);
        let s_bar = s * (r * R::splat(self.inv_volume)).sqrt();
        let f = -(R::splat(self.force_per_radius) * r) * willett_factor(s_bar);
        (R::select(alive, f, R::splat(0.0)), alive)
    }

    fn separation_energy(&self, s: f64, a_i: f64, a_j: f64) -> f64 {
        // f_a = −f_max / (1 + 1.05 S̄ + 2.5 S̄²), S̄ = S √(r / V_b).
        let scale = (bridge_radius(a_i, a_j) * self.inv_volume).sqrt();
        -self.max_force(a_i, a_j) / scale * willett_integral(s * scale, (self.range - s) * scale)
    }
}

/// Willett's force factor `1 / (1 + 1.05 S̄ + 2.5 S̄²)` at scaled separation `S̄`.
#[inline(always)]
pub fn willett_factor<R: Real>(s_bar: R) -> R {
    let one = R::splat(1.0);
    one / (one + s_bar * (R::splat(1.05) + R::splat(2.5) * s_bar))
}

/// `∫_y^{y+l} dt / (1 + 1.05 t + 2.5 t²)` for `y, l ≥ 0`, in closed form (the quadratic has
/// no real root): `(2/q) [atan u(y + l) − atan u(y)]` with `u(t) = (2ct + b)/q`,
/// `q² = 4c − b²`, taken as one arctangent, `atan((u(y + l) − u(y))/(1 + u(y + l) u(y)))`
/// (both `u` are positive), whose numerator `2cl/q` loses no digits to a difference when
/// the interval is short.
fn willett_integral(y: f64, l: f64) -> f64 {
    let (b, c): (f64, f64) = (1.05, 2.5);
    let q = (4.0 * c - b * b).sqrt();
    let (u_x, u_y) = ((2.0 * c * (y + l) + b) / q, (2.0 * c * y + b) / q);
    2.0 / q * (2.0 * c * l / q / (1.0 + u_x * u_y)).atan()
}

#[cfg(test)]
mod tests {
    use super::LiquidBridge;
    use crate::contact::Adhesion;
    use std::f64::consts::PI;

    const A: f64 = 1.1e-3;

    fn bridge() -> Adhesion {
        Adhesion::LiquidBridge(LiquidBridge {
            surface_tension: 0.02,
            contact_angle: 20f64.to_radians(),
            volume: 75e-12,
        })
    }

    #[test]
    fn rupture_distance_matches_seed_correction() {
        // 75 nl, θ = 20°: S_c = 0.495 mm, not the "4.95 nm" of Shi et al. 2020, Table 1
        // (docs/model.md §2.5).
        assert!((bridge().range() - 0.4953e-3).abs() < 1e-7);
    }

    #[test]
    fn willett_energy_matches_simpson_quadrature() {
        let b = bridge();
        let (a_i, a_j) = (A, 0.7 * A);
        let n = 20000;
        let h = b.range() / n as f64;
        let f = |s: f64| b.separated_force(s, a_i, a_j, true).0;
        let mut sum = f(0.0) + f(b.range());
        for k in 1..n {
            sum += f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
        }
        let quad = sum * h / 3.0;
        let closed = b.separation_energy(0.0, a_i, a_j);
        assert!(
            ((quad - closed) / closed).abs() < 1e-10,
            "{quad} vs {closed}"
        );
        // From part of the way, down to a sliver before rupture (Simpson's rule on the
        // remaining interval; its error scales as h⁴, far below the tolerance).
        for from in [0.3, 0.9, 0.999] {
            let s0 = from * b.range();
            let h = (b.range() - s0) / n as f64;
            let mut sum = f(s0) + f(b.range());
            for k in 1..n {
                sum += f(s0 + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
            }
            let quad = sum * h / 3.0;
            let closed = b.separation_energy(s0, a_i, a_j);
            assert!(
                ((quad - closed) / closed).abs() < 1e-10,
                "from {from} of the range: {quad} vs {closed}"
            );
        }
    }

    /// `V_b = 0`: Willett's contact-only limit (Roy et al. 2016, Sect. 3.1, the finite
    /// cohesion `c*₀` of a vanishing bridge): `−f_max` while touching, nothing once apart,
    /// and the limit of the law as `V_b → 0` at every separation.
    #[test]
    fn willett_zero_volume_attracts_only_in_contact() {
        let at_volume = |volume| {
            Adhesion::LiquidBridge(LiquidBridge {
                surface_tension: 0.02,
                contact_angle: 20f64.to_radians(),
                volume,
            })
        };
        let zero = at_volume(0.0);
        let (a_i, a_j) = (A, 0.7 * A);
        let r = 2.0 * a_i * a_j / (a_i + a_j);
        let f_max = 2.0 * PI * 0.02 * 20f64.to_radians().cos() * r;
        assert_eq!(zero.range(), 0.0);
        assert!((zero.contact_force(a_i, a_j) + f_max).abs() < 1e-15 * f_max);
        // At contact the bridge pulls with f_max; any gap breaks it.
        let (f0, alive0) = zero.separated_force(0.0, a_i, a_j, true);
        assert!(alive0 && (f0 + f_max).abs() < 1e-15 * f_max, "{f0}");
        for s in [1e-12, 1e-6, 1e-3] {
            assert_eq!(zero.separated_force(s, a_i, a_j, true), (0.0, false));
        }
        // Energy: −f_max δ in contact, zero apart.
        assert_eq!(zero.potential(-1e-6, a_i, a_j, true), 0.0);
        let delta = 1e-5;
        assert!((zero.potential(delta, a_i, a_j, true) + f_max * delta).abs() < 1e-18);
        // The limit: a tiny volume's force at a fixed gap vanishes, its contact force not.
        let tiny = at_volume(1e-30);
        assert_eq!(tiny.separated_force(1e-6, a_i, a_j, true).0, 0.0);
        assert_eq!(tiny.contact_force(a_i, a_j), zero.contact_force(a_i, a_j));
    }

    #[test]
    fn at_strength_gives_the_mean_pair_its_force_and_range() {
        use crate::contact::adhesion::{LawKind, LawSpec, Strength};
        let s = Strength {
            max_force: 1.3e-4,
            rupture_distance: 0.225 * 2.2e-3,
            normal_stiffness: 100.0,
            mean_diameter: 2.2e-3,
        };
        let law = LawSpec::new(LawKind::LiquidBridge, LawKind::LiquidBridge.at_strength(&s))
            .build()
            .expect("valid");
        let a = 1.1e-3;
        assert!((law.max_force(a, a) - s.max_force).abs() < 1e-15 * s.max_force);
        assert!((law.range() - s.rupture_distance).abs() < 1e-15);
    }
}
