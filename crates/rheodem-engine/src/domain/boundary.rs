//! The interface every boundary implements, and the list of boundaries a [`Domain`] may
//! hold.
//!
//! A boundary answers, for the box `[lo, hi]` it closes ([`Frame`]): the mean flow it
//! imposes (its velocity and gradient, whether the particles are dragged with it, whether
//! contacts measure against it), its own motion over a step, the transform of every image
//! code, the rotated images the neighbour search must query, how a particle that left is
//! mapped back, and the region's volume. Each method has the plain periodic box's answer
//! as its default, so a boundary states only where it differs.
//!
//! Adding a boundary: a file in `domain/` with its state and its `impl Boundary`, and its
//! line in the registry ([`super::registry`]).
//!
//! [`Domain`]: super::Domain

use super::dynamics::ShearDynamics;
use super::image::{IMAGE_COUNT, ImageTransform, image_offsets};
use glam::{DMat3, DVec3};

/// The box a boundary closes: its corners (m) and which axes are periodic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Lower corner (m).
    pub lo: DVec3,
    /// Upper corner (m).
    pub hi: DVec3,
    /// Which of `x`, `y`, `z` are periodic.
    pub periodic: [bool; 3],
}

impl Frame {
    /// Edge lengths (m).
    pub fn lengths(&self) -> DVec3 {
        self.hi - self.lo
    }
}

/// What every boundary answers; the defaults are the periodic box's (translated images, no
/// mean flow, the box's volume).
pub trait Boundary {
    /// Velocity of the mean flow (m/s) at `r` in `frame`.
    #[inline]
    fn mean_flow(&self, _frame: &Frame, _r: DVec3) -> DVec3 {
        DVec3::ZERO
    }

    /// The mean flow's velocity gradient `L_ab = ∂v_a/∂r_b` (1/s).
    fn velocity_gradient(&self) -> DMat3 {
        DMat3::ZERO
    }

    /// How the particles move with the mean flow ([`ShearDynamics::Lab`] without one).
    #[inline]
    fn dynamics(&self) -> ShearDynamics {
        ShearDynamics::Lab
    }

    /// The gradient `L` (1/s) that contacts subtract, as `L b`, from a pair's relative
    /// velocity across the branch `b`, where contacts measure against the mean flow.
    fn contact_velocity_gradient(&self) -> Option<DMat3> {
        None
    }

    /// Under affine drag, moves every free particle by the mean flow over `dt` (s).
    fn drag(
        &self,
        _frame: &Frame,
        _positions: &mut [DVec3],
        _free: impl Fn(usize) -> bool,
        _dt: f64,
    ) {
    }

    /// Advances the boundary's own motion over `dt` (s) in a box of edges `lengths` (m);
    /// returns the increment of the box's deformation gradient, if it deforms.
    fn advance(&mut self, _dt: f64, _lengths: DVec3) -> Option<DMat3> {
        None
    }

    /// Follows an affine rescaling of the box by `scale` along each axis.
    fn rescale(&mut self, _scale: DVec3) {}

    /// How often the image codes have changed meaning (each change forces a rebuild).
    fn image_epoch(&self) -> u64 {
        0
    }

    /// Volume of the region (m³).
    fn volume(&self, frame: &Frame) -> f64 {
        let l = frame.lengths();
        l.x * l.y * l.z
    }

    /// The image codes the neighbour search must try besides the translations of the
    /// periodic axes, with the map of a query position.
    fn rotated_images(&self) -> Vec<(u8, DMat3)> {
        Vec::new()
    }

    /// The turns (multiples of a rotation) that image `code` stands for.
    #[inline]
    fn image_turns(&self, _code: u8) -> i32 {
        0
    }

    /// How many turns the position `r` lies outside the region (rotating boundaries).
    fn turns(&self, _r: DVec3) -> i32 {
        0
    }

    /// The current transformation of every image code: translations by the box's edges.
    fn image_transforms(&self, frame: &Frame) -> [ImageTransform; IMAGE_COUNT] {
        translations(frame.lengths(), 0.0, 0.0)
    }

    /// Maps a particle back into the region and returns the map applied; along periodic
    /// axes the position is translated.
    fn wrap(
        &self,
        frame: &Frame,
        position: &mut DVec3,
        _velocity: &mut DVec3,
        _spin: &mut DVec3,
    ) -> ImageTransform {
        let before = *position;
        wrap_periodic_axes(frame, [false; 3], position);
        ImageTransform {
            shift: *position - before,
            ..ImageTransform::IDENTITY
        }
    }
}

/// The images of a box of edges `l` (m) whose images across `y` are shifted by `shift`
/// (m) along `x` and move `velocity_jump` (m/s) faster along `x`.
pub fn translations(l: DVec3, shift: f64, velocity_jump: f64) -> [ImageTransform; IMAGE_COUNT] {
    std::array::from_fn(|code| {
        let c = image_offsets(code as u8);
        let (cx, cy, cz) = (c[0] as f64, c[1] as f64, c[2] as f64);
        ImageTransform {
            rotation: None,
            shift: DVec3::new(cx * l.x + cy * shift, cy * l.y, cz * l.z),
            velocity_shift: DVec3::new(cy * velocity_jump, 0.0, 0.0),
        }
    })
}

/// Translates `position` back into `frame` along each periodic axis not in `skip`
/// (an axis another rule wraps, such as the Lees-Edwards `y`).
pub fn wrap_periodic_axes(frame: &Frame, skip: [bool; 3], position: &mut DVec3) {
    let l = frame.lengths();
    for axis in 0..3 {
        if frame.periodic[axis] && !skip[axis] {
            let x = position[axis];
            if x < frame.lo[axis] || x >= frame.hi[axis] {
                let k = ((x - frame.lo[axis]) / l[axis]).floor();
                let mut w = x - k * l[axis];
                if w >= frame.hi[axis] {
                    w -= l[axis];
                }
                if w < frame.lo[axis] {
                    w = frame.lo[axis];
                }
                position[axis] = w;
            }
        }
    }
}
