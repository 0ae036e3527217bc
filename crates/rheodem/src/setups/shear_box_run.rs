//! The shear box as an [`Experiment`]: one point run into its directory through
//! [`run_point`], resumed when the directory holds the same point and refused, naming
//! each changed key, when it holds another (unless `force`, which starts it over).

use super::runner::{Event, Experiment, Finished, RunOptions, no_start_from};
use super::schema::{SetUpSchema, spec_changes};
use super::shear_box::ShearBoxSpec;
use super::sweep::{POINT_FILE, run_point};
use crate::driver::Progress;
use crate::io::made_by::{self, Maker};
use crate::run::{RunError, io_err};
use std::path::Path;

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
