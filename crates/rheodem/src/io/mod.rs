//! Input and output: packings, atomic file writes, directory locks, time series, VTK
//! snapshots.

pub mod atomic;
pub mod lock;
pub mod packing;
pub mod timeseries;
pub mod vtk;
