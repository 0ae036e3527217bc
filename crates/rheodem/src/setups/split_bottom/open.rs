//! Opening a split-bottom run directory for a spec: the unfinished (or finished) run of the
//! same settings is resumed, one of other settings is refused naming each changed key, and
//! otherwise a new run starts, from scratch or from a settled state, once its memory has
//! been checked. Every front end (the command line, a library call) opens runs this
//! way.

use super::spec::SplitBottomSpec;
use super::stages::SplitBottomRun;
use super::state::SplitBottomState;
use crate::driver::Driver;
use crate::io::made_by::{self, Maker};
use crate::run::RunError;
use crate::setups::schema::spec_changes;
use std::path::Path;

/// How [`Driver::open`] found its directory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Opened {
    /// A run of the same settings, resumed from its last checkpoint.
    Resumed,
    /// A new run.
    Started,
}

/// The memory a new run may take: the worker threads it will run on and the most bytes
/// its estimated peak may reach (`None`: no limit).
#[derive(Clone, Copy, Debug)]
pub struct MemoryLimit {
    /// Worker threads.
    pub threads: usize,
    /// Largest estimated peak (bytes).
    pub bytes: Option<u64>,
}

impl Driver<SplitBottomState> {
    /// Opens `dir` for `spec` (and `from`, the settled run to shear from): resumes the run
    /// there if it has the same settings, refuses one of other settings, starts a new one
    /// otherwise (with `force`, always). Before a new run is built (filling a large cell
    /// takes minutes), its particle count and estimated peak memory are checked against
    /// `memory` and handed to `starting`.
    ///
    /// # Errors
    /// [`RunError`] for a directory made by another command, a run of other settings
    /// (each changed key named), an invalid spec, a cell beyond the memory limit, or a
    /// file not read or written.
    pub fn open(
        spec: SplitBottomSpec,
        dir: &Path,
        from: Option<&Path>,
        force: bool,
        memory: MemoryLimit,
        starting: impl FnOnce(usize, u64),
    ) -> Result<(SplitBottomRun, Opened), RunError> {
        if !force {
            made_by::expect(dir, Maker::SplitBottom).map_err(RunError::OtherCommand)?;
            if dir.join("checkpoint.bin").exists() {
                let run = SplitBottomRun::resume(dir)?;
                let asked = from.map(|p| p.display().to_string());
                let mut changes = spec_changes(&run.spec, &spec);
                if run.from != asked {
                    changes.push(format!(
                        "from: {} → {}",
                        run.from.as_deref().unwrap_or("(none)"),
                        asked.as_deref().unwrap_or("(none)")
                    ));
                }
                if !changes.is_empty() {
                    return Err(RunError::Changed {
                        dir: dir.to_path_buf(),
                        changes,
                    });
                }
                return Ok((run, Opened::Resumed));
            }
        }
        let (particles, bytes) = spec.memory_estimate(memory.threads, memory.bytes)?;
        starting(particles, bytes);
        let run = match from {
            Some(settled) => SplitBottomRun::from_settled(spec, settled, dir, force)?,
            None => SplitBottomRun::start(spec, dir, force)?,
        };
        Ok((run, Opened::Started))
    }
}
