//! Input and output: packings, atomic file writes, time series, VTK snapshots.

pub mod atomic;
pub mod packing;
pub mod timeseries;
pub mod vtk;
