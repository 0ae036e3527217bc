//! Mindlin's tangential spring of a Hertzian contact (docs/model.md §2.10): stiffness
//! `8 G* a` with the contact radius `a = √(R* δ)`, the stored displacement rescaled by
//! `a/a_prev` when the contact shrinks, a dashpot and a Coulomb limit.

use super::super::kernel::Touch;
use super::super::lanes::{Real, V3};
use super::linear::rotate_into_plane;
use super::{SpringModel, coulomb_cap};
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Parameters of Mindlin's sliding spring (SI units), beside Hertz's normal law.
///
/// The spring `ξ` (m) is the tangential displacement of the contact since it formed; the
/// force is `f = −k_t ξ − γ_t v_t` with `k_t = 8 G* a`. When the contact radius shrinks
/// (`a < a_prev`, unloading) the displacement is first scaled by `a/a_prev`, so that the
/// force falls as `a²` rather than `a` (Mindlin & Deresiewicz's unloading, in the
/// rescaled form of LAMMPS's `tangential mindlin_rescale`); the radius at the last step is
/// the contact's state. The force is capped at `μ_s f_rep`: a slipping contact carries
/// `μ_d f_rep` and its spring is reset to match, as for the linear spring.
///
/// At fixed overlap the force is the closed form `min(8 G* a |ξ|, μ f_rep)`:
///
/// ```
/// use glam::DVec3;
/// use rheodem_engine::contact::spring::Mindlin;
///
/// let law = Mindlin { effective_shear_modulus: 1.0e9, dashpot: 0.0, mu_static: 0.5, mu_dynamic: 0.5 };
/// let (r_ij, overlap): (f64, f64) = (1.0e-3, 1.0e-6);
/// let a = (r_ij * overlap).sqrt();
/// let mut xi = DVec3::ZERO;
/// let mut a_prev = 0.0;
/// // 0.1 µm of sliding in one step, well below the Coulomb limit of 1 N.
/// let f = law.slide(&mut xi, &mut a_prev, DVec3::Z, DVec3::X * 1.0e-6, r_ij, overlap, 1.0e-6, 1.0, 0.1);
/// assert!((f.x + 8.0e9 * a * 1.0e-7).abs() < 1e-9);
/// assert_eq!(a_prev, a);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mindlin {
    /// Effective shear modulus `G*` (Pa) of the pair (from its Hertz normal law).
    pub effective_shear_modulus: f64,
    /// Dashpot factor (Pa^½): `γ_t = dashpot · √(m_ij a)` (kg/s); a fraction `x_t` of
    /// Tsuji's normal dashpot is `x_t √2 α(e) √((4/3) E*)`.
    pub dashpot: f64,
    /// Static Coulomb coefficient: the spring slips when `|f| > μ_s f_rep`.
    pub mu_static: f64,
    /// Dynamic Coulomb coefficient: a slipping contact carries `μ_d f_rep`.
    pub mu_dynamic: f64,
}

impl Mindlin {
    /// Advances the spring `xi` (m) of a contact of reduced radius `r_ij` (m) at overlap
    /// `δ` (m) with unit normal `n`, sliding at `v` (m/s, in the tangent plane) over `dt`
    /// (s), with reduced mass `m_ij` (kg) and repulsive normal force `f_rep` (N); `a_prev`
    /// is the contact radius at the last step (m; zero at the first touch), updated.
    /// Returns the force (N).
    #[allow(clippy::too_many_arguments)]
    pub fn slide(
        &self,
        xi: &mut DVec3,
        a_prev: &mut f64,
        n: DVec3,
        v: DVec3,
        r_ij: f64,
        overlap: f64,
        m_ij: f64,
        f_rep: f64,
        dt: f64,
    ) -> DVec3 {
        let mut x = V3::from_glam(*xi);
        let a = (r_ij * overlap).sqrt();
        let (f, _) = self.update(
            &mut x,
            a_prev,
            V3::from_glam(n),
            V3::from_glam(v),
            a,
            m_ij,
            f_rep,
            dt,
        );
        *xi = x.to_glam();
        f.to_glam()
    }

    /// [`Mindlin::slide`] in lanes, at contact radius `a` (m).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn update<R: Real>(
        &self,
        xi: &mut V3<R>,
        a_prev: &mut R,
        n: V3<R>,
        v: V3<R>,
        a: R,
        m_ij: R,
        f_rep: R,
        dt: f64,
    ) -> (V3<R>, R::Mask) {
        // Unloading: the displacement shrinks with the contact radius.
        let shrinks = a.lt(*a_prev);
        *xi = V3::select(shrinks, xi.scale(a / *a_prev), *xi);
        *a_prev = a;
        rotate_into_plane(xi, n);
        self.stretch_and_cap(xi, v, a, m_ij, f_rep, dt)
    }

    /// Stretches the spring by `v dt`, forms the trial force `−8 G* a ξ − γ_t v` and caps
    /// it at `μ_s f_rep`; a slipping contact carries `μ_d f_rep` along the trial direction
    /// and its spring is reset to match.
    #[inline(always)]
    fn stretch_and_cap<R: Real>(
        &self,
        xi: &mut V3<R>,
        v: V3<R>,
        a: R,
        m_ij: R,
        f_rep: R,
        dt: f64,
    ) -> (V3<R>, R::Mask) {
        *xi = *xi + v.scale(R::splat(dt));
        let k_t = R::splat(8.0 * self.effective_shear_modulus) * a;
        let gamma = if self.dashpot != 0.0 {
            R::splat(self.dashpot) * (m_ij * a).sqrt()
        } else {
            R::splat(0.0)
        };
        let trial = xi.scale(-k_t) - v.scale(gamma);
        let (capped, slip) = coulomb_cap(trial, self.mu_static, self.mu_dynamic, f_rep);
        // A touching contact has a > 0, so k_t > 0.
        let reset = (capped + v.scale(gamma)).scale(-(R::splat(1.0) / k_t));
        *xi = V3::select(slip, reset, *xi);
        (V3::select(slip, capped, trial), slip)
    }

    /// The contact radius `a = √(R* δ)` (m) of a touching pair in lanes; against a wall
    /// (`radius_j = ∞`) `R*` is the sphere's radius.
    #[inline(always)]
    fn contact_radius<R: Real>(k: &Touch<R>) -> R {
        let one = R::splat(1.0);
        let r = one / (one / k.radius_i + one / k.radius_j);
        (r * k.overlap).sqrt()
    }
}

impl SpringModel for Mindlin {
    const NAME: &'static str = "mindlin";
    const ALIASES: &'static [&'static str] = &["mindlin_rescale"];
    const SUMMARY: &'static str = "Mindlin's tangential spring 8 G* √(R* δ) beside Hertz, rescaled as the contact shrinks, capped by a Coulomb limit (Mindlin 1949; Mindlin & Deresiewicz 1953).";
    const KEEPS_STATE: bool = true;

    #[inline(always)]
    fn is_active(&self) -> bool {
        self.mu_static > 0.0 && self.effective_shear_modulus > 0.0
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
        state: &mut R,
    ) -> (V3<R>, R::Mask) {
        let a = Mindlin::contact_radius(k);
        self.update(xi, state, n, v, a, k.reduced_mass, f_rep, dt)
    }

    /// Scenarios refuse Mindlin for torsion; as a torsion spring it would act along the
    /// normal with the same stiffness and no rescaling.
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
        let len = xi.dot(*xi).sqrt();
        *xi = V3::select(n.dot(*xi).lt(R::splat(0.0)), n.scale(-len), n.scale(len));
        let a = Mindlin::contact_radius(k);
        self.stretch_and_cap(xi, v, a, k.reduced_mass, f_rep, dt)
    }

    /// `½ (8 G* a) |ξ|²`, the spring's energy at the current stiffness.
    fn energy(&self, xi: DVec3, overlap: f64, a_i: f64, a_j: f64) -> f64 {
        let r = 1.0 / (1.0 / a_i + 1.0 / a_j);
        0.5 * 8.0
            * self.effective_shear_modulus
            * (r * overlap.max(0.0)).sqrt()
            * xi.length_squared()
    }

    /// The same law with its dashpot scaled by `factor`.
    fn damping_scaled(&self, factor: f64) -> Mindlin {
        Mindlin {
            dashpot: self.dashpot * factor,
            ..*self
        }
    }
}
