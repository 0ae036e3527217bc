//! The split-bottom ring shear cell (docs/model.md §10): an angular-periodic wedge of an
//! annulus between a fixed inner and a rotating outer cylinder, whose bottom is split at
//! `R_s` (inside fixed, outside rotating with the outer cylinder), filled with grains to a
//! free surface under gravity.
//!
//! A run passes through stages, each ending in a checkpoint:
//! 1. **fill** — `N` spheres are placed at random without overlap in a mould slightly
//!    larger than the cell (smooth cylinders at `R_i − d_p/2`, `R_o + d_p/2`, a smooth floor
//!    at `z = −d_p/2`), loosely, up to about twice the filling height;
//! 2. **settle** — they fall under gravity with the damping multiplied by
//!    `settle_damping` until the translational kinetic energy is below
//!    `settle_kinetic_ratio` times the energy of the contact springs (the repulsive elastic
//!    energy, without the negative adhesive potential of a cohesive law, so that the test
//!    means "at rest" under any law); then the layer of particles touching each mould wall is frozen into
//!    the rough walls: inner cylinder and inner bottom (`r < R_s`) fixed, outer cylinder and
//!    outer bottom rotating. The smooth mould walls stay as backstops. The state is saved as
//!    `settled.bin`, from which any number of shear runs can start (`from_settled`);
//! 3. **shear** — the rotating parts turn at `Ω`; the wall torques, kinetic energy, contacts
//!    and surface height are recorded, and the azimuthal velocity profile is averaged in
//!    three horizontal slabs over the averaging window and fitted with an error function.
//!
//! The run goes through the staged run driver ([`crate::driver`]), which owns its
//! directory, lock, checkpoints, resumption and summary; this module supplies the stages.
//! Its files: `open` (resume, refuse or start a run in a directory), `runner` (the
//! cell as an experiment any front end runs by name), `spec` (the keys, their
//! checks, the geometry and the filling), `schema` (the
//! parameters, declared once, and how given values become a spec), `state` (the
//! checkpointed state and the cell's measurements), `stages` (fill, settle, shear and the
//! operations of each step), `outputs` (time series, profiles, figures, summary) and
//! `fields` (the coarse-grained fields and the shear band's rheology).

pub mod fields;
mod open;
mod outputs;
mod runner;
mod schema;
pub(crate) mod spec;
mod stages;
mod state;

pub use open::{MemoryLimit, Opened};
pub use spec::{Geometry, Groups, SplitBottomSpec, TimeStepRule};
pub use stages::SplitBottomRun;
pub use state::{PARTS, Row, SLABS, SettleReport, ShearResults, SlabFit, SplitBottomState, Stage};
