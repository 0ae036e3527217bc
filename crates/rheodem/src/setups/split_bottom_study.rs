//! Studies of the split-bottom cell (docs/studies.md): many split-bottom runs from one
//! study file, each run resumable in its own directory, finished runs archived as their
//! `summary.json`, and the report of [`super::wet_study`] over them.
//!
//! A point's table is the study's `[base]` merged with one combination of `[grid]` (or one
//! `[[point]]`); dotted keys set fields of the `cohesion` table:
//!
//! ```toml
//! title = "Cohesion against bridge volume"
//! setup = "split-bottom"
//! out = "runs/volumes"
//! [base]
//! cohesion = { law = "liquid_bridge", surface_tension = 0.02, volume = 75e-12 }
//! [grid]
//! "cohesion.volume" = [14e-12, 75e-12, 200e-12]
//! ```

use super::split_bottom::{SplitBottomSpec, Stage};
use super::sweep::{PointStatus, point_tables};
use crate::io::atomic::write_atomic;
use crate::run::{RunError, io_err};
use crate::scenario::ScenarioError;
use crate::setups::law_options::law_name;
use std::path::{Path, PathBuf};

/// The name of a point's directory, from its controls: the law and its parameters, `Ω`,
/// `g` and the seed (`willett-g0.02-v75-omega0.5-g9.81-s1`; volumes in nl).
pub fn point_name(spec: &SplitBottomSpec) -> String {
    let law = law_name(&spec.cohesion);
    format!("{law}-omega{}-g{}-s{}", spec.omega, spec.gravity, spec.seed)
}

/// The points of a split-bottom study: `base` with each combination of `grid` and each of
/// `points`, checked (the cell's geometry must build) and named by [`point_name`].
pub fn expand(
    base: &toml::Table,
    grid: &toml::Table,
    points: &[toml::Table],
) -> Result<Vec<(String, SplitBottomSpec)>, ScenarioError> {
    let mut out: Vec<(String, SplitBottomSpec)> = Vec::new();
    // Every key of [base] is checked first, so that a typo there is named even in a study
    // that has no points yet.
    SplitBottomSpec::from_table(base.clone())
        .map_err(|e| ScenarioError::Parse(format!("[base]: {e}")))?;
    for (k, t) in point_tables(base, grid, points)?.into_iter().enumerate() {
        let spec = SplitBottomSpec::from_table(t)
            .map_err(|e| ScenarioError::Parse(format!("study point {k}: {e}")))?;
        spec.geometry()
            .map_err(|e| ScenarioError::Parse(format!("study point {k}: {e}")))?;
        let name = point_name(&spec);
        if out.iter().any(|(n, _)| *n == name) {
            return Err(ScenarioError::Parse(format!(
                "study point {k} ({name}) duplicates an earlier point"
            )));
        }
        out.push((name, spec));
    }
    Ok(out)
}

/// The stage, time and spec a run's `summary.json` records.
#[derive(serde::Deserialize)]
struct Recorded {
    spec: SplitBottomSpec,
    stage: Stage,
    time: f64,
    settled: Option<super::split_bottom::SettleReport>,
}

fn recorded(summary: &Path) -> Option<Recorded> {
    serde_json::from_str(&std::fs::read_to_string(summary).ok()?).ok()
}

/// The status of the point `spec` whose run directory is `dir`: finished (with its
/// `summary.json`) only when the run is done with these parameters; otherwise running (a
/// process holds the directory's lock), stopped or not started, with the fraction of the
/// shear done.
pub fn point_status(dir: &Path, spec: &SplitBottomSpec) -> PointStatus<PathBuf> {
    let summary = dir.join("summary.json");
    let rec = recorded(&summary);
    if rec
        .as_ref()
        .is_some_and(|r| r.spec == *spec && r.stage == Stage::Done)
    {
        return PointStatus::Finished(summary);
    }
    if !dir.join("checkpoint.bin").exists() && !dir.join(crate::io::lock::LOCK_FILE).exists() {
        return PointStatus::Waiting;
    }
    let done = rec.as_ref().map_or(0.0, |r| match (r.stage, &r.settled) {
        (Stage::Shear, Some(s)) => ((r.time - s.time) / spec.duration).clamp(0.0, 1.0),
        (Stage::Done, _) => 1.0,
        _ => 0.0,
    });
    match crate::io::lock::DirLock::try_acquire(dir) {
        Err(crate::io::lock::LockError::Busy(_)) => PointStatus::Running(done),
        _ if dir.join("checkpoint.bin").exists() => PointStatus::Stopped(done),
        _ => PointStatus::Waiting,
    }
}

/// The archived `summary.json` of the point `name` in `archive`, if it is a finished run
/// of `spec`.
pub fn archived(archive: &Path, name: &str, spec: &SplitBottomSpec) -> Option<PathBuf> {
    let file = archive.join(format!("{name}.json"));
    recorded(&file)
        .filter(|r| r.spec == *spec && r.stage == Stage::Done)
        .map(|_| file)
}

/// Copies a finished run's `summary.json` into `archive` as `<name>.json`.
pub fn archive_point(archive: &Path, name: &str, summary: &Path) -> Result<(), RunError> {
    std::fs::create_dir_all(archive).map_err(io_err("create the directory", archive))?;
    let text = std::fs::read(summary).map_err(io_err("read", summary))?;
    let file = archive.join(format!("{name}.json"));
    write_atomic(&file, &text).map_err(io_err("write", &file))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::LawKind;

    /// A grid over dotted cohesion keys gives one named point per combination; a second
    /// point with the same controls is refused; a bad value names the point.
    #[test]
    fn the_grid_sets_nested_cohesion_fields() {
        let base: toml::Table = toml::from_str(
            "omega = 0.5\n[cohesion]\nlaw = \"willett\"\nsurface_tension = 0.02\nvolume = 75e-12",
        )
        .expect("base");
        let grid: toml::Table = toml::from_str(
            "\"cohesion.volume\" = [14e-12, 75e-12]\n\"cohesion.surface_tension\" = [0.02, 0.04]",
        )
        .expect("grid");
        let dry: toml::Table = toml::from_str("cohesion = { law = \"dry\" }").expect("dry");
        let points = expand(&base, &grid, &[dry]).expect("points");
        let names: Vec<&str> = points.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(
            names,
            [
                "willett-g0.02-v14-omega0.5-g9.81-s1",
                "willett-g0.02-v75-omega0.5-g9.81-s1",
                "willett-g0.04-v14-omega0.5-g9.81-s1",
                "willett-g0.04-v75-omega0.5-g9.81-s1",
                "dry-omega0.5-g9.81-s1"
            ]
        );
        // Grid keys combine in name order, the last varying fastest.
        let law = &points[2].1.cohesion;
        assert_eq!(law.law, LawKind::LiquidBridge);
        assert_eq!(law.value("surface_tension"), Some(0.04));
        assert!((law.value("volume").expect("a volume") - 14e-12).abs() < 1e-24);
        let twice = [base.clone(), base.clone()];
        let e = expand(&base, &toml::Table::new(), &twice).expect_err("duplicate");
        assert!(e.to_string().contains("duplicates"), "{e}");
        let bad: toml::Table = toml::from_str("omega = -1.0").expect("bad");
        let e = expand(&base, &toml::Table::new(), &[bad]).expect_err("negative Ω");
        assert!(e.to_string().contains("study point 0"), "{e}");
    }
}
