//! Input and output: packings, atomic file writes, directory locks, time series, VTK
//! snapshots, large tables formatted in parallel.

pub mod atomic;
pub mod lock;
pub mod made_by;
pub mod packing;
pub mod text;
pub mod timeseries;
pub mod vtk;
