//! The archive of finished sweep points: one `<name>.json` per point (a [`PointResult`]),
//! kept for example in version control so that a finished point is never run again, and a
//! `results.csv` table of every point archived there, whichever sweep or study ran it.
//!
//! Several processes may archive points into one directory at once (the workers of a
//! sweep, two sweeps on one machine, the array tasks of a cluster job): each point file is
//! written atomically under its own name, and the table is rewritten under the archive's
//! lock (`.lock`, waited for), so that the last writer's table lists every point.

use super::point_result::{PointResult, results_csv};
use super::shear_box::ShearBoxSpec;
use crate::io::atomic::write_atomic;
use crate::io::lock::{DirLock, LockError};
use std::path::{Path, PathBuf};

/// Name of the table of an archive.
pub const TABLE: &str = "results.csv";

/// Why an archive could not be read or written; names the file.
#[derive(Debug, thiserror::Error)]
pub enum ArchiveError {
    /// A file or directory could not be read or written.
    #[error("cannot {operation} {}: {source}", path.display())]
    Io {
        /// What was attempted.
        operation: &'static str,
        /// The file or directory.
        path: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// A `.json` file of the archive is not a point result.
    #[error("{} is not a point result: {reason}", path.display())]
    NotAPoint {
        /// The file.
        path: PathBuf,
        /// What the JSON reader said.
        reason: String,
    },
    /// The archive's lock could not be taken.
    #[error(transparent)]
    Lock(#[from] LockError),
}

fn io(operation: &'static str, path: &Path) -> impl FnOnce(std::io::Error) -> ArchiveError + use<> {
    let path = path.to_path_buf();
    move |source| ArchiveError::Io {
        operation,
        path,
        source,
    }
}

/// The point `name` archived in `dir`, if it is there and is a result of `spec` (a point
/// archived with other parameters under the same name does not count as finished).
pub fn archived(dir: &Path, name: &str, spec: &ShearBoxSpec) -> Option<PointResult> {
    let text = std::fs::read_to_string(dir.join(format!("{name}.json"))).ok()?;
    serde_json::from_str::<PointResult>(&text)
        .ok()
        .filter(|r| r.spec == *spec)
}

/// Every point result archived in `dir`, in file-name order.
pub fn read_archive(dir: &Path) -> Result<Vec<PointResult>, ArchiveError> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io("read the directory", dir))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    files
        .iter()
        .map(|file| {
            let text = std::fs::read_to_string(file).map_err(io("read", file))?;
            serde_json::from_str::<PointResult>(&text).map_err(|e| ArchiveError::NotAPoint {
                path: file.clone(),
                reason: e.to_string(),
            })
        })
        .collect()
}

/// Rewrites the archive's table from its points, under its lock, if it is out of date.
pub fn refresh_table(dir: &Path) -> Result<(), ArchiveError> {
    let _lock = DirLock::acquire(dir)?;
    let table = dir.join(TABLE);
    let csv = results_csv(&read_archive(dir)?);
    if std::fs::read_to_string(&table).ok().as_deref() != Some(csv.as_str()) {
        write_atomic(&table, csv.as_bytes()).map_err(io("write", &table))?;
    }
    Ok(())
}

/// Archives a finished point as `dir/<name>.json` (creating `dir`) and rewrites the table.
pub fn archive_point(dir: &Path, result: &PointResult) -> Result<(), ArchiveError> {
    std::fs::create_dir_all(dir).map_err(io("create the directory", dir))?;
    let json = serde_json::to_string_pretty(result).map_err(|e| ArchiveError::NotAPoint {
        path: dir.join(&result.name),
        reason: e.to_string(),
    })?;
    let file = dir.join(format!("{}.json", result.name));
    write_atomic(&file, json.as_bytes()).map_err(io("write", &file))?;
    refresh_table(dir)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::setups::sweep::expand;

    fn results(n: usize) -> Vec<PointResult> {
        let sweep: crate::setups::sweep::SweepSpec = toml::from_str(
            "[base]\nmu_p = 0.5\ninertial = 0.1\nsoftness = 0.01\nparticles = 80\n\
             polydispersity = 1.2\ncohesion = \"reversible\"\n\
             [grid]\nbond = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]",
        )
        .expect("sweep");
        expand(&sweep)
            .expect("points")
            .into_iter()
            .take(n)
            .map(|(name, spec)| PointResult {
                derived: spec.derive().expect("derived"),
                name,
                spec,
                steady_state: None,
                wall_seconds: 1.0,
                commit: String::new(),
            })
            .collect()
    }

    /// Eight threads archive one point each into one directory: every point file is there,
    /// and the table lists all eight (the last rewrite saw every file).
    #[test]
    fn concurrent_archivers_leave_a_complete_table() {
        let dir = std::env::temp_dir().join(format!("rheodem-archive-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let points = results(8);
        std::thread::scope(|s| {
            for r in &points {
                let dir = &dir;
                s.spawn(move || archive_point(dir, r).expect("archived"));
            }
        });
        let back = read_archive(&dir).expect("readable");
        assert_eq!(back.len(), 8);
        let table = std::fs::read_to_string(dir.join(TABLE)).expect("table");
        assert_eq!(table.lines().count(), 9, "{table}");
        for r in &points {
            assert!(table.contains(&r.name), "{} missing", r.name);
            assert_eq!(
                archived(&dir, &r.name, &r.spec).map(|a| a.name),
                Some(r.name.clone())
            );
        }
        // Another point's parameters under the same name: not finished.
        assert!(archived(&dir, &points[0].name, &points[1].spec).is_none());
        std::fs::write(dir.join("junk.json"), "{}").expect("junk");
        let err = read_archive(&dir).expect_err("junk");
        assert!(err.to_string().contains("junk.json"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
