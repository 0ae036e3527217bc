//! The linear spring–dashpot–Coulomb resistance with history (docs/model.md §2.3), used
//! for sliding friction, rolling resistance and torsion resistance.

use super::super::damping::Damping;
use super::super::kernel::Touch;
use super::super::lanes::{Real, V3};
use super::{SpringModel, coulomb_cap};
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Parameters of one spring–dashpot–Coulomb resistance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Resistance {
    /// Spring stiffness (N/m).
    pub stiffness: f64,
    /// Dashpot coefficient (kg/s) as a function of the reduced mass.
    pub damping: Damping,
    /// Static Coulomb coefficient: the spring slips when `|f| > μ_s f_rep`.
    pub mu_static: f64,
    /// Dynamic Coulomb coefficient: a slipping contact carries `μ_d f_rep`.
    pub mu_dynamic: f64,
}

impl Resistance {
    /// A resistance that never acts.
    pub const NONE: Resistance = Resistance {
        stiffness: 0.0,
        damping: Damping::NONE,
        mu_static: 0.0,
        mu_dynamic: 0.0,
    };

    /// Whether this resistance can ever produce a force: it needs a spring or a dashpot
    /// and a non-zero Coulomb limit.
    #[inline]
    pub fn is_active(&self) -> bool {
        // The Coulomb limit first: one comparison settles the usual inactive case.
        self.mu_static > 0.0 && (self.stiffness > 0.0 || !self.damping.is_zero())
    }

    /// Advances a spring `xi` (m) that lives in the tangent plane of a contact with unit
    /// normal `n` (sliding and rolling), driven by the relative velocity `v` (m/s, in the
    /// tangent plane) over `dt` (s); returns the force (N) and whether the contact slips.
    ///
    /// The spring is first rotated into the current tangent plane keeping its length, then
    /// stretched by `v dt`. `gamma` is the dashpot coefficient of this pair (kg/s) and
    /// `f_rep ≥ 0` the repulsive normal force (N) that sets the Coulomb limits.
    #[inline]
    pub fn update_in_plane(
        &self,
        xi: &mut DVec3,
        n: DVec3,
        v: DVec3,
        gamma: f64,
        f_rep: f64,
        dt: f64,
    ) -> (DVec3, bool) {
        let mut x = V3::from_glam(*xi);
        let (f, slip) = self.in_plane(&mut x, V3::from_glam(n), V3::from_glam(v), gamma, f_rep, dt);
        *xi = x.to_glam();
        (f.to_glam(), slip)
    }

    /// Like [`Resistance::update_in_plane`] for a spring that lives along the normal `n`
    /// (torsion): the spring is first turned onto the current normal keeping its length and
    /// sense, then stretched by `v dt` (`v` along `n`).
    #[inline]
    pub fn update_along_normal(
        &self,
        xi: &mut DVec3,
        n: DVec3,
        v: DVec3,
        gamma: f64,
        f_rep: f64,
        dt: f64,
    ) -> (DVec3, bool) {
        let mut x = V3::from_glam(*xi);
        let (f, slip) =
            self.along_normal(&mut x, V3::from_glam(n), V3::from_glam(v), gamma, f_rep, dt);
        *xi = x.to_glam();
        (f.to_glam(), slip)
    }

    /// [`Resistance::update_in_plane`] in lanes.
    #[inline(always)]
    pub fn in_plane<R: Real>(
        &self,
        xi: &mut V3<R>,
        n: V3<R>,
        v: V3<R>,
        gamma: R,
        f_rep: R,
        dt: f64,
    ) -> (V3<R>, R::Mask) {
        rotate_into_plane(xi, n);
        self.stretch_and_cap(xi, v, gamma, f_rep, dt)
    }

    /// [`Resistance::update_along_normal`] in lanes.
    #[inline(always)]
    pub fn along_normal<R: Real>(
        &self,
        xi: &mut V3<R>,
        n: V3<R>,
        v: V3<R>,
        gamma: R,
        f_rep: R,
        dt: f64,
    ) -> (V3<R>, R::Mask) {
        let len = xi.dot(*xi).sqrt();
        let zero = R::splat(0.0);
        *xi = V3::select(n.dot(*xi).lt(zero), n.scale(-len), n.scale(len));
        self.stretch_and_cap(xi, v, gamma, f_rep, dt)
    }

    /// Stretches the spring by `v dt`, forms the trial force `−k ξ − γ v` and caps it at
    /// `μ_s f_rep`: a slipping contact carries `μ_d f_rep` along the trial direction and its
    /// spring is reset to match, `ξ = −(f + γ v)/k`.
    #[inline(always)]
    fn stretch_and_cap<R: Real>(
        &self,
        xi: &mut V3<R>,
        v: V3<R>,
        gamma: R,
        f_rep: R,
        dt: f64,
    ) -> (V3<R>, R::Mask) {
        *xi = *xi + v.scale(R::splat(dt));
        let trial = xi.scale(R::splat(-self.stiffness)) - v.scale(gamma);
        let (capped, slip) = coulomb_cap(trial, self.mu_static, self.mu_dynamic, f_rep);
        let reset = if self.stiffness > 0.0 {
            (capped + v.scale(gamma)).scale(R::splat(-1.0 / self.stiffness))
        } else {
            V3::zero()
        };
        *xi = V3::select(slip, reset, *xi);
        (V3::select(slip, capped, trial), slip)
    }
}

impl SpringModel for Resistance {
    const NAME: &'static str = "linear";
    const ALIASES: &'static [&'static str] = &["coulomb"];
    const SUMMARY: &'static str = "Linear spring and dashpot capped by a Coulomb limit, -k ξ - γ v with |f| ≤ μ f_n (Cundall & Strack 1979; Luding 2008).";

    #[inline(always)]
    fn is_active(&self) -> bool {
        Resistance::is_active(self)
    }

    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn in_plane_lanes<R: Real>(
        &self,
        xi: &mut V3<R>,
        n: V3<R>,
        v: V3<R>,
        k: &Touch<R>,
        f_rep: R,
        dt: f64,
        _state: &mut R,
    ) -> (V3<R>, R::Mask) {
        let gamma = self.damping.in_lanes(k.reduced_mass);
        self.in_plane(xi, n, v, gamma, f_rep, dt)
    }

    #[inline(always)]
    fn along_normal_lanes<R: Real>(
        &self,
        xi: &mut V3<R>,
        n: V3<R>,
        v: V3<R>,
        k: &Touch<R>,
        f_rep: R,
        dt: f64,
    ) -> (V3<R>, R::Mask) {
        let gamma = self.damping.in_lanes(k.reduced_mass);
        self.along_normal(xi, n, v, gamma, f_rep, dt)
    }

    fn energy(&self, xi: DVec3, _overlap: f64, _a_i: f64, _a_j: f64) -> f64 {
        0.5 * (self.stiffness * xi.length_squared())
    }

    fn damping_scaled(&self, factor: f64) -> Resistance {
        Resistance {
            damping: self.damping.scaled(factor),
            ..*self
        }
    }
}

/// Removes the normal component of `xi` and restores its length.
///
/// With `c = n·ξ` and `x = c²/|ξ|²` the rescaling factor is `(1 − x)^{-1/2}`. Between two
/// steps the normal turns by a tiny angle, so `x` is tiny and the series
/// `1 + x/2 + 3x²/8` (relative error below `x³`, i.e. 1e-12 for `x < 1e-4`) replaces a
/// square root and a division on the hot path.
#[inline(always)]
pub(super) fn rotate_into_plane<R: Real>(xi: &mut V3<R>, n: V3<R>) {
    let len2 = xi.dot(*xi);
    let c = n.dot(*xi);
    let t = *xi - n.scale(c);
    let x = c * c / len2;
    let one = R::splat(1.0);
    let series = t.scale(one + x * (R::splat(0.5) + R::splat(0.375) * x));
    let exact = t.scale((one / (one - x)).sqrt());
    let rotated = V3::select(
        x.lt(R::splat(1e-4)),
        series,
        V3::select(x.lt(one), exact, V3::zero()),
    );
    *xi = V3::select(len2.eq(R::splat(0.0)), *xi, rotated);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn friction(mu: f64) -> Resistance {
        Resistance {
            stiffness: 10.0,
            damping: Damping::NONE,
            mu_static: mu,
            mu_dynamic: mu,
        }
    }

    #[test]
    fn spring_follows_hooke_below_the_limit() {
        let mut xi = DVec3::ZERO;
        let (f, slip) = friction(1.0).update_in_plane(&mut xi, DVec3::Z, DVec3::X, 0.0, 100.0, 0.1);
        assert!(!slip);
        assert_eq!(xi, DVec3::new(0.1, 0.0, 0.0));
        assert_eq!(f, DVec3::new(-1.0, 0.0, 0.0));
    }

    #[test]
    fn slip_caps_force_and_resets_spring() {
        let mut xi = DVec3::new(1.0, 0.0, 0.0);
        let (f, slip) = friction(0.5).update_in_plane(&mut xi, DVec3::Z, DVec3::X, 0.0, 2.0, 0.1);
        assert!(slip);
        assert!((f.length() - 1.0).abs() < 1e-15);
        assert!((-10.0 * xi - f).length() < 1e-15);
    }

    #[test]
    fn rotation_keeps_spring_length_in_new_plane() {
        let mut xi = V3::new(3.0, 0.0, 4.0);
        rotate_into_plane(&mut xi, V3::new(0.0, 0.0, 1.0));
        assert!((xi.to_glam() - DVec3::new(5.0, 0.0, 0.0)).length() < 1e-14);
        // A spring of zero length stays zero (no 0/0).
        let mut zero = V3::zero();
        rotate_into_plane(&mut zero, V3::new(0.0, 0.0, 1.0));
        assert_eq!(zero, V3::zero());
    }
}

#[cfg(test)]
mod torsion_tests {
    use super::*;

    #[test]
    fn normal_spring_follows_the_normal() {
        let r = Resistance {
            stiffness: 1.0,
            damping: Damping::NONE,
            mu_static: 10.0,
            mu_dynamic: 10.0,
        };
        // A spring pointing against a new normal keeps its length and its sense.
        let mut xi = DVec3::new(-1.2, 1.6, 0.0);
        let (f, slip) = r.update_along_normal(&mut xi, DVec3::X, DVec3::ZERO, 0.0, 1.0, 0.1);
        assert!(!slip);
        assert!((xi - DVec3::new(-2.0, 0.0, 0.0)).length() < 1e-15);
        assert_eq!(f, -xi);
    }
}
