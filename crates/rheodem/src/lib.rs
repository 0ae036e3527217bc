//! # rheodem
//!
//! A discrete-element (DEM) engine for polydisperse soft spheres with linear visco-elastic
//! frictional contacts, and the rheology tools built on it. All quantities are SI unless a
//! doc comment says otherwise.

pub mod contact;
pub mod domain;
pub mod forces;
pub mod integrate;
pub mod measure;
pub mod neighbor;
pub mod particles;
pub mod simulation;
pub mod timestep;
pub mod walls;

pub use simulation::Simulation;
