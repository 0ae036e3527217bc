//! `rheodem sweep`, `compare`, `fit` and `db`: shear-box sweeps and their results.

use anyhow::{Context, Result, bail};
use rheodem::io::atomic::write_atomic;
use rheodem::run::RunError;
use rheodem::setups::archive::{archive_point, archived, read_archive, refresh_table};
use rheodem::setups::results_db::ResultsDb;
use rheodem::setups::sweep::{
    PointResult, PointStatus, SweepSpec, default_out, expand, point_status, results_csv, run_point,
};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Runs `sweep`: `jobs` points at once, one thread each.
pub fn sweep(path: &Path, jobs: Option<usize>, quiet: bool, db: Option<&Path>) -> Result<()> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let spec: SweepSpec =
        toml::from_str(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let study = path
        .file_stem()
        .map_or("sweep".into(), |s| s.to_string_lossy().into_owned());
    run_sweep(&spec, path, &study, jobs, quiet, db)
}

/// Where a sweep (read from `path`) writes its points, and its archive: paths in the file
/// are relative to the file, so that the sweep finds its points wherever it is started from.
pub(crate) fn sweep_dirs(spec: &SweepSpec, path: &Path) -> (PathBuf, Option<PathBuf>) {
    let here = path.parent().unwrap_or(Path::new(""));
    let out = spec
        .out
        .as_ref()
        .map_or_else(|| default_out(path), |o| beside(here, o));
    (out, spec.results.as_ref().map(|r| beside(here, r)))
}

/// `here/relative` with `name/..` pairs removed (`studies/../runs` reads `runs`), for the
/// paths a sweep or study file gives relative to itself.
pub(crate) fn beside(here: &Path, relative: impl AsRef<Path>) -> PathBuf {
    use std::path::Component;
    let mut out = PathBuf::new();
    for c in here.join(relative).components() {
        match c {
            Component::ParentDir
                if matches!(out.components().next_back(), Some(Component::Normal(_))) =>
            {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

/// Runs the points of `spec` (read from `path`) that are not finished, storing each
/// finished point in the database `db` (if any) under `study`.
pub(crate) fn run_sweep(
    spec: &SweepSpec,
    path: &Path,
    study: &str,
    jobs: Option<usize>,
    quiet: bool,
    db: Option<&Path>,
) -> Result<()> {
    let points = expand(spec)?;
    let (out, archive) = sweep_dirs(spec, path);
    let jobs = crate::worker_count(
        "--jobs",
        jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
    )?;
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    eprintln!(
        "{} points, {} at a time → {}",
        points.len(),
        jobs,
        out.display()
    );
    // Every finished point also goes into the results database, under the study's name.
    let database = db.map(ResultsDb::open).transpose()?.map(Mutex::new);
    let results: Mutex<Vec<Option<PointResult>>> = Mutex::new(vec![None; points.len()]);
    let errors: Mutex<Vec<String>> = Mutex::new(Vec::new());
    let busy: Mutex<Vec<String>> = Mutex::new(Vec::new());
    let table = out.join("results.csv");
    let pool_errors = crate::for_each_point(points.len(), jobs, |k, pool| {
        let (name, point) = &points[k];
        let dir = out.join(name);
        let mut last = 0u64;
        let kept = archive.as_deref().and_then(|a| archived(a, name, point));
        let fresh = kept.is_none();
        let outcome = match kept {
            Some(r) => Ok(r),
            None => pool.install(|| {
                run_point(name, point, &dir, 1, &mut |done, total| {
                    let pct = done * 100 / total.max(1);
                    if !quiet && pct >= last + 10 {
                        last = pct;
                        eprintln!("  {name}: {pct} %");
                    }
                })
            }),
        };
        match outcome {
            Ok(r) => {
                if !quiet {
                    let (text, warnings) = r.report(&dir);
                    print!("{text}");
                    for w in warnings {
                        eprintln!("warning: {w}");
                    }
                }
                // One worker at a time writes the tables and the archive.
                let Ok(mut all) = results.lock() else {
                    return;
                };
                let archived = match (&archive, fresh) {
                    (Some(a), true) => archive_point(a, &r).map_err(Into::into),
                    _ => Ok(()),
                };
                let stored = match &database {
                    Some(d) => d
                        .lock()
                        .map_err(|_| anyhow::anyhow!("database lock poisoned"))
                        .and_then(|mut d| Ok(d.insert(study, &r)?)),
                    None => Ok(()),
                };
                all[k] = Some(r);
                let done: Vec<PointResult> = all.iter().flatten().cloned().collect();
                let written = write_atomic(&table, results_csv(&done).as_bytes())
                    .with_context(|| format!("cannot write {}", table.display()));
                drop(all);
                if let Err(e) = archived.and(written).and(stored) {
                    errors
                        .lock()
                        .map(|mut v| v.push(format!("{name}: {e:#}")))
                        .ok();
                }
            }
            Err(RunError::Busy(_)) => {
                if !quiet {
                    eprintln!("  {name}: being run by another process; skipped");
                }
                busy.lock().map(|mut v| v.push(name.clone())).ok();
            }
            Err(e) => {
                errors
                    .lock()
                    .map(|mut v| v.push(format!("{name}: {e:#}")))
                    .ok();
            }
        }
    });
    errors.lock().map(|mut v| v.extend(pool_errors)).ok();
    let mut errors = errors.into_inner().unwrap_or_default();
    // The archive's table lists every point archived there, whichever sweep ran it; it is
    // rewritten only when it differs (e.g. after another sweep file added points).
    if let Some(Err(e)) = archive.as_deref().filter(|a| a.is_dir()).map(refresh_table) {
        errors.push(e.to_string());
    }
    let done = results
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .flatten()
        .count();
    println!(
        "{done} of {} points finished; table in {}",
        points.len(),
        table.display()
    );
    let busy = busy.into_inner().unwrap_or_default();
    if !busy.is_empty() {
        println!(
            "{} points are being run by another process ({}); run the sweep again once they \
             finish to collect them in the table",
            busy.len(),
            busy.join(", ")
        );
    }
    if !errors.is_empty() {
        bail!("{} errors:\n{}", errors.len(), errors.join("\n"));
    }
    Ok(())
}

/// The finished points of a sweep directory (its archive and its point directories) and a
/// progress line for each point still running.
fn load_results(dir: &Path) -> Result<(Vec<PointResult>, Vec<String>)> {
    if dir.join("checkpoint.bin").exists() {
        bail!(
            "{} is the directory of a single run, not of a sweep: give the `out` directory \
             of a sweep, or its `results` archive",
            dir.display()
        );
    }
    let mut finished = Vec::new();
    let mut running = Vec::new();
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    finished.extend(read_archive(dir)?);
    let names: std::collections::HashSet<String> =
        finished.iter().map(|r| r.name.clone()).collect();
    for point in entries.into_iter().filter(|p| p.is_dir()) {
        let name = point
            .file_name()
            .map_or(String::new(), |s| s.to_string_lossy().into_owned());
        if names.contains(&name) {
            continue;
        }
        match point_status(&point, None) {
            PointStatus::Finished(r) => finished.push(*r),
            PointStatus::Waiting => {}
            status => running.push(format!("- `{name}`: {status}")),
        }
    }
    if finished.is_empty() && running.is_empty() {
        bail!(
            "{} holds no sweep results: give the `out` directory of a sweep, or its \
             `results` archive",
            dir.display()
        );
    }
    Ok((finished, running))
}

/// The finished points of several sweep directories or archives, a point of a later one
/// replacing the point of the same name of an earlier one, and the progress lines of the
/// points still running in any (unless finished in another).
fn load_merged(dirs: &[PathBuf]) -> Result<(Vec<PointResult>, Vec<String>)> {
    let mut finished: Vec<PointResult> = Vec::new();
    let mut running = Vec::new();
    for dir in dirs {
        let (done, going) = load_results(dir)?;
        for r in done {
            match finished.iter_mut().find(|f| f.name == r.name) {
                Some(f) => *f = r,
                None => finished.push(r),
            }
        }
        running.extend(going);
    }
    // A point finished anywhere is not listed as running.
    running.retain(|line: &String| {
        !finished
            .iter()
            .any(|r| line.starts_with(&format!("- `{}`:", r.name)))
    });
    Ok((finished, running))
}

/// Runs `compare`: the validation table of sweep directories (merged as by
/// [`load_merged`]), plus the progress of the points still running; with `figures`, the
/// validation figures written there as SVG.
pub fn compare(dirs: &[PathBuf], figures: Option<&Path>) -> Result<()> {
    let (finished, running) = load_merged(dirs)?;
    print!(
        "{}",
        rheodem::setups::compare::comparison_markdown(&finished)
    );
    if let Some(out) = figures {
        std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
        let svgs = rheodem::setups::compare::comparison_figures(&finished)
            .map_err(|e| anyhow::anyhow!("cannot draw the figures: {e}"))?;
        // And the Δφ figures at the phase diagram's state (I, p*) = (0.02, 0.01).
        use rheodem::setups::phase_diagram::{delta_phi_figures, delta_phi_points};
        let points = delta_phi_points(&finished, 0.02, 0.01);
        let figures = delta_phi_figures(&points, 0.02, 0.01)
            .map_err(|e| anyhow::anyhow!("cannot draw the Δφ figures: {e}"))?;
        let cohesion = rheodem::setups::cohesion_figures::cohesion_figures(&finished, 0.02, 0.01)
            .map_err(|e| anyhow::anyhow!("cannot draw the cohesion figures: {e}"))?;
        for fig in svgs.into_iter().chain(figures).chain(cohesion) {
            for (ext, bytes) in [("svg", fig.svg.as_bytes()), ("png", fig.png.as_slice())] {
                let file = out.join(format!("{}.{ext}", fig.name));
                write_atomic(&file, bytes)
                    .with_context(|| format!("cannot write {}", file.display()))?;
                eprintln!("wrote {}", file.display());
            }
        }
    }
    if !running.is_empty() {
        println!("\nNot finished:\n{}", running.join("\n"));
    }
    Ok(())
}

/// Runs `fit`: the laws of Shi et al. 2020 fitted to the finished points of sweep
/// directories (merged as by [`load_merged`]), per `μ_p` and shear dynamics, in the
/// layout of the paper's tables (markdown).
pub fn fit(dirs: &[PathBuf]) -> Result<()> {
    let (finished, running) = load_merged(dirs)?;
    print!("{}", rheodem::setups::law_fits::fit_tables(&finished));
    if !running.is_empty() {
        println!("\nNot finished (left out):\n{}", running.join("\n"));
    }
    Ok(())
}

/// The `db` subcommands: the results database (docs/studies.md).
#[derive(clap::Subcommand)]
pub enum DbCommand {
    /// Store the finished points of a sweep directory or results archive.
    Import {
        /// The sweep's output directory or its results archive.
        dir: PathBuf,
        /// The database file (created if missing).
        #[arg(long)]
        db: PathBuf,
        /// Study name to file the points under (default: the directory's name).
        #[arg(long)]
        study: Option<String>,
    },
    /// Write the shear-box points (of one study, or all) as CSV; or the split-bottom cells,
    /// or every stored value of any set-up.
    Export {
        /// The database file.
        #[arg(long)]
        db: PathBuf,
        /// Only this study.
        #[arg(long)]
        study: Option<String>,
        /// The split-bottom cells (view `cells`) instead of the shear-box points.
        #[arg(long, conflicts_with = "values")]
        cells: bool,
        /// Every stored number and name of the runs of any set-up, one row per key
        /// (table `run_values`: study, name, setup, kind, key, value, error, text).
        #[arg(long)]
        values: bool,
        /// Output file (default: standard output).
        #[arg(long, short)]
        out: Option<PathBuf>,
    },
    /// Count the points per study.
    Status {
        /// The database file.
        #[arg(long)]
        db: PathBuf,
    },
}

/// Runs a `db` subcommand.
pub fn db(cmd: DbCommand) -> Result<()> {
    match cmd {
        DbCommand::Import { dir, db, study } => {
            let (finished, running) = load_results(&dir)?;
            let study = study.unwrap_or_else(|| {
                dir.file_name()
                    .map_or("imported".into(), |s| s.to_string_lossy().into_owned())
            });
            let mut database = ResultsDb::open(&db)?;
            for r in &finished {
                database.insert(&study, r)?;
            }
            println!(
                "{} points stored under study {study:?} in {} ({} in that study; {} not \
                 finished, left out)",
                finished.len(),
                db.display(),
                database.count(Some(&study))?,
                running.len()
            );
        }
        DbCommand::Export {
            db,
            study,
            cells,
            values,
            out,
        } => {
            if !db.exists() {
                bail!("{} does not exist", db.display());
            }
            let database = ResultsDb::open(&db)?;
            let csv = if values {
                database.export_values_csv(study.as_deref())?
            } else if cells {
                database.export_cells_csv(study.as_deref())?
            } else {
                database.export_csv(study.as_deref())?
            };
            match out {
                Some(f) => write_atomic(&f, csv.as_bytes())
                    .with_context(|| format!("cannot write {}", f.display()))?,
                None => print!("{csv}"),
            }
        }
        DbCommand::Status { db } => {
            if !db.exists() {
                bail!("{} does not exist", db.display());
            }
            let database = ResultsDb::open(&db)?;
            for s in &database.studies()? {
                let (points, cells) = (database.count(Some(s))?, database.count_cells(Some(s))?);
                match (points, cells) {
                    (p, 0) => println!("{s}: {p} points"),
                    (0, c) => println!("{s}: {c} split-bottom cells"),
                    (p, c) => println!("{s}: {p} points, {c} split-bottom cells"),
                }
            }
            println!(
                "total: {} points and {} split-bottom cells in {}",
                database.count(None)?,
                database.count_cells(None)?,
                db.display()
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::beside;
    use std::path::Path;

    #[test]
    fn paths_beside_a_file_drop_their_parent_steps() {
        assert_eq!(
            beside(Path::new("/w/studies"), "../runs/x"),
            Path::new("/w/runs/x")
        );
        assert_eq!(
            beside(Path::new("studies"), "./out"),
            Path::new("studies/out")
        );
        assert_eq!(beside(Path::new(""), "../up"), Path::new("../up"));
    }
}
