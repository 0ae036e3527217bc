//! The split-bottom cell as an [`Experiment`]: the run directory opened by
//! [`SplitBottomRun::open`], then every stage run to its end, with a warning where settling
//! ended at its time limit; and in studies ([`Studied`]): its points named by their
//! controls, its result file `summary.json`, its report with the relations of Roy et al.
//! 2016.

use super::open::MemoryLimit;
use super::spec::SplitBottomSpec;
use super::stages::SplitBottomRun;
use super::state::Stage;
use crate::analysis::Estimate;
use crate::run::RunError;
use crate::scenario::ScenarioError;
use crate::setups::results_db::ResultsDb;
use crate::setups::runner::{Event, Experiment, Finished, RunOptions};
use crate::setups::split_bottom_study as study_points;
use crate::setups::studied::Studied;
use crate::setups::study::{Report, StudySpec};
use crate::setups::sweep::{PointStatus, SweepSpec};
use std::fmt::Write;
use std::path::{Path, PathBuf};

impl Experiment for SplitBottomSpec {
    const FROM: Option<&'static str> = Some(
        "Start shearing from the settled state of this earlier split-bottom run directory \
         (same cell and particles).",
    );

    const ESTIMATES_MEMORY: bool = true;

    fn run(
        self,
        options: &RunOptions<'_>,
        events: &mut dyn FnMut(Event<'_>),
    ) -> Result<Finished, RunError> {
        let dir = options.dir;
        let memory = MemoryLimit {
            threads: options.threads,
            bytes: options.max_memory,
        };
        let (mut run, _) = SplitBottomRun::open(
            self,
            dir,
            options.from,
            options.force,
            memory,
            |n, bytes| {
                events(Event::Note(&format!(
                    "split-bottom: about {n} particles, an estimated {} of memory",
                    crate::memory::Bytes(bytes)
                )));
            },
        )?;
        events(Event::Note(&format!(
            "split-bottom: {} particles ({} free before settling), dt = {:.3e} s, outputs in {}",
            run.simulation.particles.len(),
            run.simulation.particles.free_count(),
            run.simulation.dt,
            dir.display()
        )));
        events(Event::Particles(run.simulation.particles.len()));
        // Stage by stage (a finished run only rewrites its outputs), with a warning when
        // settling ended on its time limit.
        loop {
            let stage = run.stage;
            run.advance_stage(dir, &mut |p| events(Event::Progress(p)))?;
            if stage == Stage::Settle
                && let Some(notice) = run.settled.as_ref().and_then(|r| r.limit_notice(&run.spec))
            {
                events(Event::Warning(&notice));
            }
            if run.stage == Stage::Done {
                break;
            }
        }
        let summary = crate::driver::read_summary(dir)?;
        Ok(Finished {
            summary,
            report: report(&run, dir),
            warnings: Vec::new(),
        })
    }
}

/// The finished run in words: time, wall time, net torque and balance, the band per slab.
fn report(run: &SplitBottomRun, dir: &Path) -> String {
    let res = run.results();
    let show = |e: &Option<Estimate>| {
        e.map_or("n/a".to_string(), |e| {
            format!("{:.4e} ± {:.1e}", e.mean, e.error)
        })
    };
    let mut text = String::new();
    let _ = writeln!(
        text,
        "done: t = {:.3} s, {:.0} s wall; net torque (full ring) {} N m; balance {} N m",
        run.simulation.time,
        run.wall_seconds,
        show(&res.net_torque),
        show(&res.balance)
    );
    for b in &res.band {
        let _ = match &b.fit {
            Ok(f) => writeln!(
                text,
                "  {:7} slab z ∈ [{:.4}, {:.4}] m: R_c = {:.4e} ± {:.1e} m, W = {:.3e} ± {:.1e} m",
                b.slab, b.z[0], b.z[1], f.centre, f.centre_err, f.width, f.width_err
            ),
            Err(e) => writeln!(text, "  {:7} slab: no fit ({e})", b.slab),
        };
    }
    let _ = writeln!(text, "outputs in {}", dir.display());
    text
}

impl Studied for SplitBottomSpec {
    fn points(variant: &SweepSpec) -> Result<Vec<(String, Self)>, ScenarioError> {
        study_points::expand(&variant.base, &variant.grid, &variant.point)
    }

    fn status(&self, name: &str, dir: &Path, archive: Option<&Path>) -> PointStatus<PathBuf> {
        match archive.and_then(|a| study_points::archived(a, name, self)) {
            Some(file) => PointStatus::Finished(file),
            None => study_points::point_status(dir, self),
        }
    }

    fn archive(archive: &Path, name: &str, result: &Path) -> Result<(), String> {
        study_points::archive_point(archive, name, result).map_err(|e| e.to_string())
    }

    fn store(db: &mut ResultsDb, study: &str, name: &str, result: &Path) -> Result<(), String> {
        db.insert_cell(study, name, result)
            .map_err(|e| e.to_string())
    }

    fn report(
        study: &StudySpec,
        variant: &str,
        total: usize,
        finished: &[(String, PathBuf)],
    ) -> Result<Report, String> {
        crate::setups::study::split_bottom_report(study, variant, total, finished)
    }

    fn outcome(name: &str, result: &Path) -> String {
        match crate::setups::wet_study::WetRun::read_summary(result, name) {
            Ok(r) => format!(
                "{name}: μ = {:.4} ± {:.4}, c* = {:.3} ± {:.3}, T* = {:.4e}",
                r.mu.0, r.mu.1, r.cohesion.0, r.cohesion.1, r.torque.0
            ),
            Err(e) => format!("{name}: finished ({e})"),
        }
    }
}
