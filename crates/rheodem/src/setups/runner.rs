//! Running a registered set-up into a run directory, the same way from every front end.
//!
//! A set-up that implements [`Experiment`] (besides its [`SetUpSchema`]) is run from its
//! checked spec: the directory is opened (an unfinished run of the same settings resumes,
//! one of other settings is refused unless `force`, naming each changed key where the
//! directory records its settings), every stage
//! runs to its end, and the outcome comes back as the run's summary (the JSON object of
//! its `summary.json` or result file), a short report in words and its warnings. The
//! command line builds one subcommand per registered set-up on this, and a library caller
//! runs a set-up by name through [`super::registry`]. The caller runs it inside the
//! thread pool of [`RunOptions::threads`] workers.

use super::schema::SetUpSchema;
use crate::driver::Progress;
use crate::run::RunError;
use crate::scenario::invalid;
use std::path::Path;

/// How to run a set-up: the options every set-up takes.
#[derive(Clone, Copy, Debug)]
pub struct RunOptions<'a> {
    /// The run directory.
    pub dir: &'a Path,
    /// Worker threads of the pool the run is called in (recorded in the outputs, and
    /// counted in the memory estimate).
    pub threads: usize,
    /// Start over even if the directory holds a run of other settings (otherwise the
    /// same settings resume and others are refused).
    pub force: bool,
    /// An earlier run directory to start from, for a set-up that can
    /// ([`Experiment::FROM`]).
    pub from: Option<&'a Path>,
    /// Refuse a run whose estimated peak memory exceeds this many bytes (`None`: no
    /// limit), for a set-up that estimates it ([`Experiment::ESTIMATES_MEMORY`]).
    pub max_memory: Option<u64>,
}

/// What a run tells its caller while it goes.
#[derive(Clone, Copy, Debug)]
pub enum Event<'a> {
    /// The run has this many particles (sent once it is built or resumed, before its
    /// first step; for rates in particle-steps per second).
    Particles(usize),
    /// Something worth a line before or between stages: the resolved values, a size
    /// estimate, where the outputs go.
    Note(&'a str),
    /// A warning about the run (a stage that ended at its time limit).
    Warning(&'a str),
    /// Steps done in the current stage.
    Progress(Progress),
}

/// A finished run.
#[derive(Clone, Debug)]
pub struct Finished {
    /// Its summary: the JSON object the run directory holds (`summary.json` or the
    /// point's result file), with the resolved parameters, version, seed and results.
    pub summary: serde_json::Value,
    /// Its results in a few lines of words, as the command line prints them.
    pub report: String,
    /// Warnings about the results (not steady, too few rows to average).
    pub warnings: Vec<String>,
}

/// A set-up that runs into a run directory.
pub trait Experiment: SetUpSchema {
    /// What [`RunOptions::from`] means for this set-up (the option's help), or `None`
    /// where the set-up cannot start from another run.
    const FROM: Option<&'static str>;
    /// Whether the set-up estimates a new run's peak memory before building it, and
    /// refuses one above [`RunOptions::max_memory`] (others ignore the limit).
    const ESTIMATES_MEMORY: bool;

    /// Runs the checked spec `self` into `options.dir` to its end (resuming or refusing
    /// as the module says), telling `events` how it goes.
    ///
    /// # Errors
    /// [`RunError`] for a directory of other settings or made by another command, a
    /// start from a run where the set-up has none, a run beyond the memory limit, an
    /// unstable state, or a file not read or written.
    fn run(
        self,
        options: &RunOptions<'_>,
        events: &mut dyn FnMut(Event<'_>),
    ) -> Result<Finished, RunError>;
}

/// The refusal of [`RunOptions::from`] by the set-up `name`, which cannot start from
/// another run.
pub fn no_start_from(name: &str, from: &Path) -> RunError {
    invalid(
        "from",
        from.display(),
        format!("{name} cannot start from another run: leave it out"),
    )
    .into()
}
