//! The registry of boundaries: the one place that lists them. [`BoundaryKind`] is what a
//! [`super::Domain`] holds, and each of its methods hands the question to the boundary
//! it holds, statically dispatched so that every call inlines.

use super::boundary::{Boundary, Frame};
use super::dynamics::ShearDynamics;
use super::image::{IMAGE_COUNT, ImageTransform};
use super::lees_edwards::LeesEdwards;
use super::periodic::Periodic;
use super::wedge::Wedge;
use glam::{DMat3, DVec3};

/// The boundary a domain holds: one variant per boundary module.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum BoundaryKind {
    /// The box with its periodic axes alone ([`super::periodic`]).
    #[default]
    Periodic,
    /// Lees-Edwards shear ([`super::lees_edwards`]).
    LeesEdwards(LeesEdwards),
    /// The angular-periodic wedge ([`super::wedge`]).
    Wedge(Wedge),
}

/// `each_boundary!(kind, b => expr)`: `expr` with `b` bound to the boundary `kind` holds.
/// A new boundary adds its variant above and its arm here and in `each_boundary_mut!`.
macro_rules! each_boundary {
    ($kind:expr, $b:ident => $e:expr) => {
        match $kind {
            BoundaryKind::Periodic => {
                let $b = &Periodic;
                $e
            }
            BoundaryKind::LeesEdwards($b) => $e,
            BoundaryKind::Wedge($b) => $e,
        }
    };
}

/// `each_boundary_mut!(kind, b => expr)`: as `each_boundary!`, with `b` mutable.
macro_rules! each_boundary_mut {
    ($kind:expr, $b:ident => $e:expr) => {
        match $kind {
            BoundaryKind::Periodic => {
                let $b = &mut Periodic;
                $e
            }
            BoundaryKind::LeesEdwards($b) => $e,
            BoundaryKind::Wedge($b) => $e,
        }
    };
}

impl BoundaryKind {
    /// See [`Boundary::mean_flow`].
    #[inline]
    pub fn mean_flow(&self, frame: &Frame, r: DVec3) -> DVec3 {
        each_boundary!(self, b => Boundary::mean_flow(b, frame, r))
    }

    /// See [`Boundary::velocity_gradient`].
    pub fn velocity_gradient(&self) -> DMat3 {
        each_boundary!(self, b => Boundary::velocity_gradient(b))
    }

    /// See [`Boundary::dynamics`].
    #[inline]
    pub fn dynamics(&self) -> ShearDynamics {
        each_boundary!(self, b => Boundary::dynamics(b))
    }

    /// See [`Boundary::contact_velocity_gradient`].
    pub fn contact_velocity_gradient(&self) -> Option<DMat3> {
        each_boundary!(self, b => Boundary::contact_velocity_gradient(b))
    }

    /// See [`Boundary::drag`].
    pub fn drag(
        &self,
        frame: &Frame,
        positions: &mut [DVec3],
        free: impl Fn(usize) -> bool,
        dt: f64,
    ) {
        each_boundary!(self, b => Boundary::drag(b, frame, positions, free, dt))
    }

    /// See [`Boundary::advance`].
    pub fn advance(&mut self, dt: f64, lengths: DVec3) -> Option<DMat3> {
        each_boundary_mut!(self, b => Boundary::advance(b, dt, lengths))
    }

    /// See [`Boundary::rescale`].
    pub fn rescale(&mut self, scale: DVec3) {
        each_boundary_mut!(self, b => Boundary::rescale(b, scale))
    }

    /// See [`Boundary::image_epoch`].
    pub fn image_epoch(&self) -> u64 {
        each_boundary!(self, b => Boundary::image_epoch(b))
    }

    /// See [`Boundary::volume`].
    pub fn volume(&self, frame: &Frame) -> f64 {
        each_boundary!(self, b => Boundary::volume(b, frame))
    }

    /// See [`Boundary::rotated_images`].
    pub fn rotated_images(&self) -> Vec<(u8, DMat3)> {
        each_boundary!(self, b => Boundary::rotated_images(b))
    }

    /// See [`Boundary::image_turns`].
    #[inline]
    pub fn image_turns(&self, code: u8) -> i32 {
        each_boundary!(self, b => Boundary::image_turns(b, code))
    }

    /// See [`Boundary::turns`].
    pub fn turns(&self, r: DVec3) -> i32 {
        each_boundary!(self, b => Boundary::turns(b, r))
    }

    /// See [`Boundary::image_transforms`].
    pub fn image_transforms(&self, frame: &Frame) -> [ImageTransform; IMAGE_COUNT] {
        each_boundary!(self, b => Boundary::image_transforms(b, frame))
    }

    /// See [`Boundary::wrap`].
    pub fn wrap(
        &self,
        frame: &Frame,
        position: &mut DVec3,
        velocity: &mut DVec3,
        spin: &mut DVec3,
    ) -> ImageTransform {
        each_boundary!(self, b => Boundary::wrap(b, frame, position, velocity, spin))
    }
}
