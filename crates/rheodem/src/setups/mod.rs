//! Builders of the standard set-ups.

pub mod compare;
pub mod shear_box;
pub mod split_bottom;
pub mod sweep;
