//! The errors of a run, and I/O errors that name what was attempted and where.

use crate::neighbor::NeighborError;
use crate::sanity::Instability;
use crate::scenario::ScenarioError;
use std::path::{Path, PathBuf};

/// Errors of a run.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scenario is invalid.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// A coarse-graining setting or a snapshot file is unusable.
    #[error(transparent)]
    Fields(#[from] crate::cg::CgError),
    /// A file could not be written or read.
    #[error("cannot {operation} {}: {source}", path.display())]
    Io {
        /// What was attempted ("write", "read", "create the directory", …).
        operation: &'static str,
        /// The file.
        path: PathBuf,
        /// The cause (the operating system's reason).
        source: std::io::Error,
    },
    /// The checkpoint is unreadable, damaged or from another version.
    #[error("{}: not a usable checkpoint: {reason}", path.display())]
    Checkpoint {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// The run directory already holds a run.
    #[error(
        "{} already holds a run: resume it with `rheodem resume {}`, or pass --force to start over",
        .0.display(), .0.display()
    )]
    Exists(PathBuf),
    /// Another process is running in the run directory.
    #[error(
        "{} is being run by another process (it holds {}/.lock); wait for it to finish",
        .0.display(), .0.display()
    )]
    Busy(PathBuf),
    /// The run directory holds a run of another scenario than the one asked for.
    #[error(
        "{} holds a run of different parameters than this point (changed since it started?): \
         remove the directory to start the point over",
        .0.display()
    )]
    Mismatch(PathBuf),
    /// The run directory holds a run of the same set-up with other settings.
    #[error(
        "{} holds a run with other settings ({}): give the same settings to resume it, \
         pass --force to replace it, or choose another directory",
        dir.display(), changes.join("; ")
    )]
    Changed {
        /// The run directory.
        dir: PathBuf,
        /// Each changed setting, as `key: old → new`.
        changes: Vec<String>,
    },
    /// The run directory was made by another command (the message says which, and how to
    /// continue it).
    #[error("{0}")]
    OtherCommand(String),
    /// The state stopped being a meaningful DEM state.
    #[error(
        "the simulation became unstable at step {step} (t = {time:e} s): {cause}. {}. Usual \
         causes: a time step too large for the stiffest contact (`run.dt`), overlapping or \
         coincident initial positions, or velocities or a prescribed motion far beyond what \
         the contacts can resolve",
        match checkpoint {
            Some(k) => format!("The last checkpoint (step {k}) predates it and is kept"),
            None => "No checkpoint was written before it".to_string(),
        }
    )]
    Unstable {
        /// Step at which the state was found unstable.
        step: u64,
        /// Simulated time of that step (s).
        time: f64,
        /// What is wrong, with the particles concerned.
        cause: Instability,
        /// Step of the last checkpoint on disk, if any.
        checkpoint: Option<u64>,
    },
    /// The neighbour search failed (box too small).
    #[error(transparent)]
    Neighbor(#[from] NeighborError),
}

/// An I/O error naming `operation` and `path`.
pub fn io_err<'a>(
    operation: &'static str,
    path: &'a Path,
) -> impl FnOnce(std::io::Error) -> RunError + 'a {
    move |source| RunError::Io {
        operation,
        path: path.to_path_buf(),
        source,
    }
}
