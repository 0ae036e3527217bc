//! Lees-Edwards boundaries (docs/model.md §4.3–4.5): shear along `x`, gradient along `y`;
//! the images across `y` are shifted along `x` and, in the lab frame, move faster along `x`.

use super::boundary::{Boundary, Frame, translations, wrap_periodic_axes};
pub use super::dynamics::ShearDynamics;
use super::image::{IMAGE_COUNT, ImageTransform};
use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

/// Lees-Edwards boundaries (docs/model.md §4.3–4.5): shear along `x`, gradient along `y`.
/// The image across `y = L_y` is shifted by `shift` in `x`; in the lab frame it also moves
/// `γ̇ L_y` faster in `x`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LeesEdwards {
    /// Shear rate `γ̇` (1/s).
    pub shear_rate: f64,
    /// Accumulated shift `s = ∫ γ̇ L_y dt`, kept in `[−L_x/2, L_x/2)` (m).
    pub shift: f64,
    /// How often `shift` has been brought back into its range (each time the image codes
    /// of the neighbour list change meaning, so the list must be rebuilt).
    pub wraps: u64,
    /// The dynamics of the sheared particles (default the lab frame). Also read from the
    /// boolean `peculiar_contacts` of older checkpoints.
    #[serde(default, alias = "peculiar_contacts")]
    pub dynamics: ShearDynamics,
}

impl LeesEdwards {
    /// Shear at `shear_rate` (1/s) in the lab frame, shift zero.
    pub fn new(shear_rate: f64) -> LeesEdwards {
        LeesEdwards {
            shear_rate,
            shift: 0.0,
            wraps: 0,
            dynamics: ShearDynamics::Lab,
        }
    }

    /// The velocity jump (m/s) along `x` of the images across `y` for a box of height
    /// `l_y` (m): `γ̇ L_y`, none under affine drag (stored velocities then exclude the mean
    /// flow).
    #[inline]
    pub fn velocity_jump(&self, l_y: f64) -> f64 {
        if self.dynamics == ShearDynamics::AffineDrag {
            0.0
        } else {
            self.shear_rate * l_y
        }
    }

    /// Velocity of the mean flow (m/s) at the height `height` (m) above the box's lower
    /// face: `γ̇ height x̂`.
    #[inline]
    pub fn mean_flow(&self, height: f64) -> DVec3 {
        DVec3::new(self.shear_rate * height, 0.0, 0.0)
    }

    /// The mean flow's velocity gradient (1/s), `L_ab = ∂v_a/∂r_b`: `γ̇` in `L_xy`, zero
    /// elsewhere, so that `L b` is the mean flow's difference across a branch `b`.
    pub fn velocity_gradient(&self) -> DMat3 {
        DMat3::from_cols(
            DVec3::ZERO,
            DVec3::new(self.shear_rate, 0.0, 0.0),
            DVec3::ZERO,
        )
    }

    /// Advances the shift over `dt` (s) in a box of edges `l` (m), `s += γ̇ L_y dt`, brought
    /// back into `[−L_x/2, L_x/2)` (counted in `wraps`); returns the strain `γ̇ dt`.
    pub fn advance(&mut self, dt: f64, l: DVec3) -> f64 {
        let strain = self.shear_rate * dt;
        self.shift += strain * l.y;
        if self.shift >= 0.5 * l.x || self.shift < -0.5 * l.x {
            self.shift -= l.x * (self.shift / l.x).round();
            if self.shift >= 0.5 * l.x {
                self.shift -= l.x;
            }
            self.wraps += 1;
        }
        strain
    }

    /// Maps a particle that crossed `y = lo_y` or `y = hi_y` (m; height `l_y`) back: `y`
    /// by `∓L_y`, `x` by `∓s` and `v_x` by `∓` the [velocity jump](Self::velocity_jump).
    pub fn wrap_y(
        &self,
        position: &mut DVec3,
        velocity: &mut DVec3,
        lo_y: f64,
        hi_y: f64,
        l_y: f64,
    ) {
        let jump = self.velocity_jump(l_y);
        let mut k = ((position.y - lo_y) / l_y).floor();
        // One more crossing where rounding left y on the boundary.
        for _ in 0..3 {
            if k != 0.0 {
                position.y -= k * l_y;
                position.x -= k * self.shift;
                velocity.x -= k * jump;
            }
            k = if position.y >= hi_y {
                1.0
            } else if position.y < lo_y {
                -1.0
            } else {
                break;
            };
        }
    }

    /// Under affine drag, moves every free particle by the mean flow over `dt` (s),
    /// `x += γ̇ (y − lo_y) dt`; does nothing under the other dynamics.
    pub fn drag(&self, positions: &mut [DVec3], free: impl Fn(usize) -> bool, dt: f64, lo_y: f64) {
        if self.dynamics != ShearDynamics::AffineDrag {
            return;
        }
        let rate = self.shear_rate * dt;
        for (i, r) in positions.iter_mut().enumerate() {
            if free(i) {
                r.x += rate * (r.y - lo_y);
            }
        }
    }
}

impl Boundary for LeesEdwards {
    #[inline]
    fn mean_flow(&self, frame: &Frame, r: DVec3) -> DVec3 {
        LeesEdwards::mean_flow(self, r.y - frame.lo.y)
    }

    fn velocity_gradient(&self) -> DMat3 {
        LeesEdwards::velocity_gradient(self)
    }

    #[inline]
    fn dynamics(&self) -> ShearDynamics {
        self.dynamics
    }

    fn contact_velocity_gradient(&self) -> Option<DMat3> {
        (self.dynamics == ShearDynamics::PeculiarContacts)
            .then(|| LeesEdwards::velocity_gradient(self))
    }

    fn drag(&self, frame: &Frame, positions: &mut [DVec3], free: impl Fn(usize) -> bool, dt: f64) {
        LeesEdwards::drag(self, positions, free, dt, frame.lo.y);
    }

    fn advance(&mut self, dt: f64, lengths: DVec3) -> Option<DMat3> {
        let strain = LeesEdwards::advance(self, dt, lengths);
        let mut shear = DMat3::IDENTITY;
        shear.y_axis.x = strain;
        Some(shear)
    }

    fn rescale(&mut self, scale: DVec3) {
        self.shift *= scale.x;
    }

    fn image_epoch(&self) -> u64 {
        self.wraps
    }

    /// The images across `y` are shifted by `c_y s` in `x` and, unless the particles are
    /// dragged affinely (their velocities then exclude the mean flow), move `c_y γ̇ L_y`
    /// faster in `x`.
    fn image_transforms(&self, frame: &Frame) -> [ImageTransform; IMAGE_COUNT] {
        let l = frame.lengths();
        translations(l, self.shift, self.velocity_jump(l.y))
    }

    /// Crossing `y` also shifts `x` by `∓s` and, with full stored velocities, `v_x` by
    /// `∓γ̇ L_y`; the other periodic axes are translated.
    fn wrap(
        &self,
        frame: &Frame,
        position: &mut DVec3,
        velocity: &mut DVec3,
        _spin: &mut DVec3,
    ) -> ImageTransform {
        let before = *position;
        let l = frame.lengths();
        self.wrap_y(position, velocity, frame.lo.y, frame.hi.y, l.y);
        wrap_periodic_axes(frame, [false, true, false], position);
        ImageTransform {
            shift: *position - before,
            ..ImageTransform::IDENTITY
        }
    }
}
