//! The shear box as an [`Experiment`]: one point run into its directory through
//! [`run_point`], resumed when the directory holds the same point and refused, naming
//! each changed key, when it holds another (unless `force`, which starts it over); and
//! in studies ([`Studied`]): its points expanded as a sweep's, its result file
//! `steady_state.json` (a [`PointResult`]), its archive with its table, its report against
//! the laws of Shi et al. 2020.

use super::point_result::PointResult;
use super::results_db::ResultsDb;
use super::runner::{Event, Experiment, Finished, RunOptions, no_start_from};
use super::schema::{SetUpSchema, spec_changes};
use super::shear_box::ShearBoxSpec;
use super::studied::Studied;
use super::study::{Report, StudySpec};
use super::sweep::{POINT_FILE, PointStatus, SweepSpec, expand, point_status, run_point};
use crate::driver::Progress;
use crate::io::made_by::{self, Maker};
use crate::run::{RunError, io_err};
use crate::scenario::ScenarioError;
use std::path::{Path, PathBuf};

/// The files that make a point finished or resumable: removed to start it over.
const POINT_STATE: [&str; 2] = ["checkpoint.bin", "steady_state.json"];

impl Experiment for ShearBoxSpec {
    const FROM: Option<&'static str> = None;

    const ESTIMATES_MEMORY: bool = false;

    fn run(
        self,
        options: &RunOptions<'_>,
        events: &mut dyn FnMut(Event<'_>),
    ) -> Result<Finished, RunError> {
        let dir = options.dir;
        if let Some(from) = options.from {
            return Err(no_start_from(Self::NAME, from));
        }
        let derived = self.derive()?;
        if options.force {
            // Only the files of a rheodem run are removed.
            if made_by::read(dir).is_some() {
                for file in POINT_STATE.map(|f| dir.join(f)) {
                    match std::fs::remove_file(&file) {
                        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                            return Err(io_err("remove", &file)(e));
                        }
                        _ => {}
                    }
                }
            }
        } else {
            made_by::expect(dir, Maker::ShearBox).map_err(RunError::OtherCommand)?;
            refuse_other_point(dir, &self)?;
        }
        events(Event::Note(&format!(
            "resolved: p = σ_yy target = {:.6e} Pa, γ̇ = {:.6e} 1/s, f_a^max = {:.6e} N, S_c = {:.4e} m, t_k = {:.4e} s, run {:.4e} s ({} strain)",
            derived.pressure,
            derived.shear_rate,
            derived.max_force,
            derived.rupture_distance,
            derived.stiffness_time,
            derived.duration,
            self.strain
        )));
        events(Event::Particles(self.particles));
        let name = dir
            .file_name()
            .map_or(Self::NAME.into(), |s| s.to_string_lossy().into_owned());
        let result = run_point(&name, &self, dir, options.threads, &mut |done, total| {
            events(Event::Progress(Progress {
                stage: "shear",
                done,
                total,
            }));
        })?;
        let (report, warnings) = result.report(dir);
        let summary = serde_json::to_value(&result).map_err(|e| RunError::Io {
            operation: "serialise",
            path: dir.join("steady_state.json"),
            source: e.into(),
        })?;
        Ok(Finished {
            summary,
            report,
            warnings,
        })
    }
}

/// Refuses a directory whose point (its `point.json`, with a checkpoint beside it) has
/// other settings than `spec`, naming each changed key.
fn refuse_other_point(dir: &Path, spec: &ShearBoxSpec) -> Result<(), RunError> {
    if !dir.join("checkpoint.bin").exists() {
        return Ok(());
    }
    let old = std::fs::read_to_string(dir.join(POINT_FILE))
        .ok()
        .and_then(|text| serde_json::from_str::<ShearBoxSpec>(&text).ok());
    match old {
        Some(old) if old != *spec => Err(RunError::Changed {
            dir: dir.to_path_buf(),
            changes: spec_changes(&old, spec),
        }),
        _ => Ok(()),
    }
}

/// The point result in a result file (`steady_state.json` or its archived copy).
fn read_point(file: &Path) -> Result<PointResult, String> {
    let text = std::fs::read_to_string(file)
        .map_err(|e| format!("cannot read {}: {e}", file.display()))?;
    serde_json::from_str(&text)
        .map_err(|e| format!("{} is not a shear-box result: {e}", file.display()))
}

impl Studied for ShearBoxSpec {
    fn points(variant: &SweepSpec) -> Result<Vec<(String, Self)>, ScenarioError> {
        expand(variant)
    }

    fn status(&self, name: &str, dir: &Path, archive: Option<&Path>) -> PointStatus<PathBuf> {
        if let Some(a) = archive
            && super::archive::archived(a, name, self).is_some()
        {
            return PointStatus::Finished(a.join(format!("{name}.json")));
        }
        match point_status(dir, Some(self)) {
            PointStatus::Finished(_) => PointStatus::Finished(dir.join("steady_state.json")),
            PointStatus::Running(x) => PointStatus::Running(x),
            PointStatus::Stopped(x) => PointStatus::Stopped(x),
            PointStatus::Failed(x, e) => PointStatus::Failed(x, e),
            PointStatus::Waiting => PointStatus::Waiting,
        }
    }

    fn archive(archive: &Path, name: &str, result: &Path) -> Result<(), String> {
        let r = read_point(result)?;
        super::archive::archive_point(
            archive,
            &PointResult {
                name: name.to_string(),
                ..r
            },
        )
        .map_err(|e| e.to_string())
    }

    fn store(db: &mut ResultsDb, study: &str, name: &str, result: &Path) -> Result<(), String> {
        let r = read_point(result)?;
        db.insert(
            study,
            &PointResult {
                name: name.to_string(),
                ..r
            },
        )
        .map_err(|e| e.to_string())
    }

    fn report(
        study: &StudySpec,
        variant: &str,
        total: usize,
        finished: &[(String, PathBuf)],
    ) -> Result<Report, String> {
        let results = finished
            .iter()
            .map(|(_, file)| read_point(file))
            .collect::<Result<Vec<_>, _>>()?;
        super::study::report(study, variant, total, &results)
    }

    fn outcome(name: &str, result: &Path) -> String {
        match read_point(result) {
            Ok(r) => match &r.steady_state {
                Some(ss) => format!(
                    "{name}: φ = {:.5} ± {:.5}, μ = {:.4} ± {:.4}{}",
                    ss.volume_fraction.mean,
                    ss.volume_fraction.error,
                    ss.friction.mean,
                    ss.friction.error,
                    if ss.steady { "" } else { " (not steady)" }
                ),
                None => format!("{name}: finished, too few rows to average"),
            },
            Err(e) => format!("{name}: finished ({e})"),
        }
    }
}
