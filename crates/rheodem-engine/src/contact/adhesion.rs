//! Adhesive (cohesive) normal forces, added to the repulsive normal force (docs/model.md
//! §2.4–2.6).
//!
//! Forces are positive when repulsive, so every adhesive force here is ≤ 0. The separation
//! of two surfaces is `S = −δ` (m). Three laws:
//! - [`Adhesion::Reversible`]: dry, van der Waals type; `−f_max` in contact, rising linearly
//!   to zero at `S = δ_a = f_max / k_c`, the same on approach and separation.
//! - [`Adhesion::LiquidBridge`]: wet, Willett's capillary force. No attraction on approach;
//!   a bridge forms at contact, pulls `−f_max` in contact and
//!   `−f_max / (1 + 1.05 S̄ + 2.5 S̄²)`, `S̄ = S sqrt(r / V_b)`, on separation, and ruptures
//!   past `S_c = (1 + θ/2) V_b^{1/3}`. Pair values use `r = 2 a_i a_j / (a_i + a_j)` and
//!   `f_max = 2π r γ_s cos θ`.
//! - [`Adhesion::LinearIrreversible`]: the bridge's loading path with a linear separation
//!   branch `−(f_max − k_c S)`, rupture at `S_c = f_max / k_c`.

use super::lanes::Real;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// An adhesive law.
///
/// A Willett bridge pulls with `f_max = 2π r γ_s cos θ` in contact (`r` the harmonic-mean
/// radius), with `f_max / (1 + 1.05 S̄ + 2.5 S̄²)` at separation `S` (`S̄ = S sqrt(r/V_b)`),
/// and ruptures past `S_c = (1 + θ/2) V_b^{1/3}`; it forms only at contact:
///
/// ```
/// use rheodem_engine::contact::Adhesion;
/// use std::f64::consts::PI;
///
/// let (gamma, theta, volume) = (0.02, 20f64.to_radians(), 75e-12);
/// let bridge = Adhesion::LiquidBridge { surface_tension: gamma, contact_angle: theta, volume };
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
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum Adhesion {
    /// No adhesion.
    #[default]
    None,
    /// Reversible linear adhesion (Shi et al. 2020, Eq. 3).
    Reversible {
        /// Maximum adhesive force `f_a^max` (N).
        max_force: f64,
        /// Adhesive stiffness `k_c^a` (N/m).
        stiffness: f64,
    },
    /// Irreversible Willett liquid bridge (Roy et al. 2016, Eqs. 10–15).
    LiquidBridge {
        /// Surface tension `γ_s` (N/m).
        surface_tension: f64,
        /// Contact angle `θ` (rad), in `[0, π/2)`.
        contact_angle: f64,
        /// Bridge volume `V_b` (m³).
        volume: f64,
    },
    /// Irreversible linear adhesion (Roy et al. 2016, Eqs. 16–17).
    LinearIrreversible {
        /// Maximum adhesive force `f_a^max` (N).
        max_force: f64,
        /// Adhesive stiffness `k_c` (N/m) of the separation branch.
        stiffness: f64,
    },
}

/// The radius `r = 2 a_i a_j / (a_i + a_j)` (m) of a pair (twice the reduced radius); for a
/// planar wall (`a_j = ∞`) it is `2 a_i`.
#[inline]
pub fn bridge_radius(a_i: f64, a_j: f64) -> f64 {
    if a_j.is_finite() {
        2.0 * a_i * a_j / (a_i + a_j)
    } else {
        2.0 * a_i
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

impl Adhesion {
    /// Whether the law has any adhesion.
    pub fn is_none(&self) -> bool {
        matches!(self, Adhesion::None)
    }

    /// Whether the law needs a bridge formed at contact (irreversible laws).
    #[inline]
    pub fn needs_bridge(&self) -> bool {
        matches!(
            self,
            Adhesion::LiquidBridge { .. } | Adhesion::LinearIrreversible { .. }
        )
    }

    /// Range of the attraction beyond contact (m): `δ_a` or `S_c`; zero without adhesion.
    pub fn range(&self) -> f64 {
        match *self {
            Adhesion::None => 0.0,
            Adhesion::Reversible {
                max_force,
                stiffness,
            }
            | Adhesion::LinearIrreversible {
                max_force,
                stiffness,
            } => max_force / stiffness,
            Adhesion::LiquidBridge {
                contact_angle,
                volume,
                ..
            } => (1.0 + 0.5 * contact_angle) * volume.cbrt(),
        }
    }

    /// Maximum adhesive force `f_a^max` (N) of a pair of radii `a_i`, `a_j` (m).
    pub fn max_force(&self, a_i: f64, a_j: f64) -> f64 {
        self.resolve().max_force(a_i, a_j)
    }

    /// Adhesive force (N, ≤ 0) of a pair in contact (`δ ≥ 0`): `−f_a^max` for every law.
    pub fn contact_force(&self, a_i: f64, a_j: f64) -> f64 {
        -self.max_force(a_i, a_j)
    }

    /// Adhesive force (N, ≤ 0) of a pair separated by `s > 0` (m), and whether the
    /// bridge survives. `bridge` says whether an irreversible law's bridge exists.
    pub fn separated_force(&self, s: f64, a_i: f64, a_j: f64, bridge: bool) -> (f64, bool) {
        self.resolve().separated_force(s, a_i, a_j, bridge)
    }

    /// The law with its per-run constants computed (`2π γ_s cos θ`, the range, `1/V_b`),
    /// as the pair loop uses it.
    pub fn resolve(&self) -> ResolvedAdhesion {
        let range = self.range();
        match *self {
            Adhesion::None => ResolvedAdhesion::None,
            Adhesion::Reversible {
                max_force,
                stiffness,
            } => ResolvedAdhesion::Reversible {
                max_force,
                stiffness,
            },
            Adhesion::LinearIrreversible {
                max_force,
                stiffness,
            } => ResolvedAdhesion::LinearIrreversible {
                max_force,
                stiffness,
                range,
            },
            Adhesion::LiquidBridge {
                surface_tension,
                contact_angle,
                volume,
            } => ResolvedAdhesion::LiquidBridge {
                force_per_radius: 2.0 * PI * surface_tension * contact_angle.cos(),
                range,
                // `V_b = 0` is the contact-only limit: no range, so the only separation at
                // which the law is evaluated apart is `S = 0`, where `S̄ = 0`.
                inv_volume: if volume > 0.0 { 1.0 / volume } else { 0.0 },
            },
        }
    }

    /// Work (J) the attraction still does before the pair is free, from separation `s ≥ 0`
    /// (m) with a live bridge: `∫_s^{range} f_a dS` (≤ 0). It is the adhesive potential
    /// energy of a pair at `s` relative to separated particles.
    pub fn separation_energy(&self, s: f64, a_i: f64, a_j: f64) -> f64 {
        self.resolve().separation_energy(s, a_i, a_j)
    }

    /// Adhesive potential energy (J) of a pair at overlap `δ` (m): the separation energy from
    /// contact plus `−f_max δ` inside the contact; zero for a pair without a bridge under an
    /// irreversible law.
    pub fn potential(&self, overlap: f64, a_i: f64, a_j: f64, bridge: bool) -> f64 {
        self.resolve().potential(overlap, a_i, a_j, bridge)
    }
}

/// An [`Adhesion`] law with its per-run constants computed (see [`Adhesion::resolve`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ResolvedAdhesion {
    /// No adhesion.
    None,
    /// Reversible: `−f_max + k_c S` up to `S = f_max / k_c`.
    Reversible {
        /// `f_max` (N).
        max_force: f64,
        /// `k_c` (N/m).
        stiffness: f64,
    },
    /// Willett's bridge: `f_max = 2π r γ_s cos θ`, rupture at `S_c`.
    LiquidBridge {
        /// `2π γ_s cos θ` (N/m): `f_max` per unit pair radius `r`.
        force_per_radius: f64,
        /// Rupture distance `S_c = (1 + θ/2) V_b^{1/3}` (m).
        range: f64,
        /// `1 / V_b` (1/m³).
        inv_volume: f64,
    },
    /// The linear irreversible law: `−f_max + k_c S` up to rupture at `S_c = f_max / k_c`.
    LinearIrreversible {
        /// `f_max` (N).
        max_force: f64,
        /// `k_c` (N/m).
        stiffness: f64,
        /// `S_c` (m).
        range: f64,
    },
}

impl ResolvedAdhesion {
    /// Whether there is no adhesion.
    #[inline(always)]
    pub fn is_none(&self) -> bool {
        matches!(self, ResolvedAdhesion::None)
    }

    /// Whether a bridge forms at contact (irreversible laws).
    #[inline(always)]
    pub fn needs_bridge(&self) -> bool {
        matches!(
            self,
            ResolvedAdhesion::LiquidBridge { .. } | ResolvedAdhesion::LinearIrreversible { .. }
        )
    }

    /// Range of the attraction beyond contact (m).
    #[inline(always)]
    pub fn range(&self) -> f64 {
        match *self {
            ResolvedAdhesion::None => 0.0,
            ResolvedAdhesion::Reversible {
                max_force,
                stiffness,
            } => max_force / stiffness,
            ResolvedAdhesion::LiquidBridge { range, .. }
            | ResolvedAdhesion::LinearIrreversible { range, .. } => range,
        }
    }

    /// `f_a^max` (N) of a pair of radii `a_i`, `a_j` (m).
    #[inline(always)]
    pub fn max_force(&self, a_i: f64, a_j: f64) -> f64 {
        match *self {
            ResolvedAdhesion::None => 0.0,
            ResolvedAdhesion::Reversible { max_force, .. }
            | ResolvedAdhesion::LinearIrreversible { max_force, .. } => max_force,
            ResolvedAdhesion::LiquidBridge {
                force_per_radius, ..
            } => force_per_radius * bridge_radius(a_i, a_j),
        }
    }

    /// [`Adhesion::separation_energy`] (J) with the constants resolved.
    pub fn separation_energy(&self, s: f64, a_i: f64, a_j: f64) -> f64 {
        let range = self.range();
        if s >= range {
            return 0.0;
        }
        match *self {
            ResolvedAdhesion::None => 0.0,
            ResolvedAdhesion::Reversible { stiffness, .. }
            | ResolvedAdhesion::LinearIrreversible { stiffness, .. } => {
                -0.5 * stiffness * (range - s) * (range - s)
            }
            ResolvedAdhesion::LiquidBridge { inv_volume, .. } => {
                // f_a = −f_max / (1 + 1.05 S̄ + 2.5 S̄²), S̄ = S √(r / V_b).
                let scale = (bridge_radius(a_i, a_j) * inv_volume).sqrt();
                -self.max_force(a_i, a_j) / scale * willett_integral(s * scale, (range - s) * scale)
            }
        }
    }

    /// [`Adhesion::potential`] (J) with the constants resolved.
    pub fn potential(&self, overlap: f64, a_i: f64, a_j: f64, bridge: bool) -> f64 {
        if self.is_none() || (self.needs_bridge() && !bridge) {
            return 0.0;
        }
        if overlap >= 0.0 {
            self.separation_energy(0.0, a_i, a_j) - self.max_force(a_i, a_j) * overlap
        } else {
            self.separation_energy(-overlap, a_i, a_j)
        }
    }

    /// Adhesive force (N, ≤ 0) in contact: `−f_a^max`.
    #[inline(always)]
    pub fn contact_force(&self, a_i: f64, a_j: f64) -> f64 {
        -self.max_force(a_i, a_j)
    }

    /// [`ResolvedAdhesion::contact_force`] in lanes, for two spheres or (`WALL`) a sphere
    /// on a wall (`a_j` unused).
    #[inline(always)]
    pub fn contact_force_lanes<R: Real, const WALL: bool>(&self, a_i: R, a_j: R) -> R {
        match *self {
            ResolvedAdhesion::None => R::splat(0.0),
            ResolvedAdhesion::Reversible { max_force, .. }
            | ResolvedAdhesion::LinearIrreversible { max_force, .. } => R::splat(-max_force),
            ResolvedAdhesion::LiquidBridge {
                force_per_radius, ..
            } => {
                let two = R::splat(2.0);
                let r = if WALL {
                    two * a_i
                } else {
                    two * a_i * a_j / (a_i + a_j)
                };
                -(R::splat(force_per_radius) * r)
            }
        }
    }

    /// Adhesive force (N, ≤ 0) at separation `s > 0` (m), and whether the bridge survives;
    /// `bridge` says whether an irreversible law's bridge exists.
    #[inline(always)]
    pub fn separated_force(&self, s: f64, a_i: f64, a_j: f64, bridge: bool) -> (f64, bool) {
        if a_j.is_finite() {
            self.separated_force_lanes::<f64, false>(s, a_i, a_j, bridge)
        } else {
            self.separated_force_lanes::<f64, true>(s, a_i, a_j, bridge)
        }
    }

    /// [`ResolvedAdhesion::separated_force`] in lanes, for two spheres or (`WALL`) a
    /// sphere on a wall (`a_j` unused).
    #[inline(always)]
    pub fn separated_force_lanes<R: Real, const WALL: bool>(
        &self,
        s: R,
        a_i: R,
        a_j: R,
        bridge: R::Mask,
    ) -> (R, R::Mask) {
        let zero = R::splat(0.0);
        match *self {
            ResolvedAdhesion::None => (zero, R::all(false)),
            ResolvedAdhesion::Reversible {
                max_force,
                stiffness,
            } => {
                let f = R::splat(stiffness) * s - R::splat(max_force);
                (R::select(f.lt(zero), f, zero), R::all(false))
            }
            ResolvedAdhesion::LinearIrreversible {
                max_force,
                stiffness,
                range,
            } => {
                let alive = R::both(bridge, s.le(R::splat(range)));
                let f = R::splat(stiffness) * s - R::splat(max_force);
                (R::select(alive, f, zero), alive)
            }
            ResolvedAdhesion::LiquidBridge {
                force_per_radius,
                range,
                inv_volume,
            } => {
                let alive = R::both(bridge, s.le(R::splat(range)));
                let two = R::splat(2.0);
                let r = if WALL {
                    two * a_i
                } else {
                    two * a_i * a_j / (a_i + a_j)
                };
                let s_bar = s * (r * R::splat(inv_volume)).sqrt();
                let f = -(R::splat(force_per_radius) * r) * willett_factor(s_bar);
                (R::select(alive, f, zero), alive)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: f64 = 1.1e-3;

    fn bridge() -> Adhesion {
        Adhesion::LiquidBridge {
            surface_tension: 0.02,
            contact_angle: 20f64.to_radians(),
            volume: 75e-12,
        }
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
        let zero = Adhesion::LiquidBridge {
            surface_tension: 0.02,
            contact_angle: 20f64.to_radians(),
            volume: 0.0,
        };
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
        let tiny = Adhesion::LiquidBridge {
            surface_tension: 0.02,
            contact_angle: 20f64.to_radians(),
            volume: 1e-30,
        };
        assert_eq!(tiny.separated_force(1e-6, a_i, a_j, true).0, 0.0);
        assert_eq!(tiny.contact_force(a_i, a_j), zero.contact_force(a_i, a_j));
    }

    #[test]
    fn reversible_potential_is_continuous_and_zero_at_range() {
        let r = Adhesion::Reversible {
            max_force: 2.0,
            stiffness: 4.0,
        };
        assert_eq!(r.range(), 0.5);
        assert_eq!(r.potential(-0.5, A, A, false), 0.0);
        assert!((r.potential(0.0, A, A, false) - (-0.5 * 2.0 * 0.5)).abs() < 1e-15);
        assert!((r.potential(-1e-12, A, A, false) - r.potential(0.0, A, A, false)).abs() < 1e-11);
    }
}
