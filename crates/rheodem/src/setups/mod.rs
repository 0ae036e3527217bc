//! Builders of the standard set-ups.

pub mod archive;
pub mod chute;
pub mod cohesion_figures;
pub mod compare;
pub mod law_fits;
pub mod law_options;
pub mod phase_diagram;
pub mod point_result;
pub mod regimes;
pub mod registry;
pub mod results_db;
pub mod runner;
pub mod schema;
pub mod shear_box;
mod shear_box_run;
pub mod slurm;
pub mod split_bottom;
/// The split-bottom cell's fields, under their former path.
pub use split_bottom::fields as split_bottom_fields;
pub mod split_bottom_study;
pub mod studied;
pub mod study;
pub mod sweep;
pub mod wet_study;
