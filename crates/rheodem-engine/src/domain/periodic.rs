//! The box with periodic axes and no other boundary: images translated by the box's
//! edges, particles that leave along a periodic axis re-entering on the other side.

use super::boundary::Boundary;

/// The periodic box: every answer of [`Boundary`] is its default.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Periodic;

impl Boundary for Periodic {}
