//! Coarse-graining: continuum fields from particles and contacts (docs/coarse-graining.md).
//!
//! A field `q(X)` is a sum over particles (or over contacts, spread along their segments)
//! weighted by a kernel `ψ(X − r_i)` of a width about a particle diameter ([`kernel`]),
//! evaluated on a grid of points ([`grid`]): Cartesian, slabs, or the axisymmetric `(r, z)`
//! half-plane, where the kernel is averaged around the ring about the `z` axis so that a
//! wedge with periodic faces gives the fields of the full ring exactly. The kernel-weighted
//! sums are accumulated over snapshots ([`sums`]), from records of particles and contacts
//! ([`snapshot`]) that a run produces as it goes or stores in its snapshot files, and the
//! fields are derived from their time average ([`fields`]).
//!
//! All quantities in SI units.

pub mod fields;
pub mod grid;
pub mod kernel;
pub mod mercury;
pub mod output;
pub mod periodic;
pub mod shear_band;
pub mod snapshot;
pub mod sums;

pub use fields::{FieldPoint, Material, fields};
pub use grid::Grid;
pub use kernel::{Kernel, KernelShape};
pub use snapshot::{ContactRecord, ContactRecords, ParticleRecord, Snapshot, images_for};
pub use sums::{CgSums, PointSums};

/// Errors of the coarse-graining.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CgError {
    /// A setting or an input is out of range; the message names it.
    #[error("coarse-graining: {0}")]
    Invalid(String),
}
