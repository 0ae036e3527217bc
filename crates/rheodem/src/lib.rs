//! # rheodem
//!
//! A discrete-element (DEM) engine for polydisperse soft spheres with linear visco-elastic
//! frictional contacts, and the rheology tools built on it. All quantities are SI unless a
//! doc comment says otherwise.

pub mod analysis;
pub mod bench;
pub mod contact;
pub mod domain;
pub mod forces;
pub mod generate;
pub mod integrate;
pub mod io;
pub mod measure;
pub mod neighbor;
pub mod particles;
pub mod plot;
pub mod rheology;
pub mod run;
pub mod sanity;
pub mod scenario;
pub mod setups;
pub mod simulation;
pub mod stress_control;
pub mod timestep;
pub mod walls;

pub use simulation::Simulation;

/// Version of the program, recorded in every output; checkpoints resume only under the
/// same version.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// Git commit the program was built from (`+dirty` with uncommitted changes), recorded in
/// every output for provenance.
pub const COMMIT: &str = env!("RHEODEM_COMMIT");
