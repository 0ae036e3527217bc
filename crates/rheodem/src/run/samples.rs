//! The stored samples of a run's fields (`[fields] records = true`; docs/coarse-graining.md
//! §9): under `fields/` of the run directory, each sample of step `N` is three files,
//! `sample_N.particles.csv` and `sample_N.contacts.csv` (the records of the snapshot files,
//! every number written to read back exactly) and `sample_N.box.json` (step, time and the
//! box with lab-frame boundaries). [`offline_fields`] reads them back and coarse-grains the
//! run again, with the run's settings or others: the same samples with the same settings
//! give the fields of the run to the bit.

use super::{RunError, ScenarioState, io_err, read_checkpoint};
use crate::cg::periodic::{BoxFields, LabView};
use crate::cg::snapshot::{contacts_csv, particles_csv, read_contacts_csv, read_particles_csv};
use crate::cg::{CgError, ContactRecord};
use crate::domain::Domain;
use crate::io::atomic::write_atomic;
use crate::scenario::spec::FieldsSpec;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The samples' directory within a run directory.
pub const SAMPLES_DIR: &str = "fields";

/// What `sample_N.box.json` holds.
#[derive(Serialize, Deserialize)]
struct SampleBox {
    step: u64,
    time: f64,
    domain: Domain,
}

/// The path of sample `step`'s file with `suffix` (`particles.csv`, `contacts.csv`,
/// `box.json`) in the run directory `dir`.
fn sample_path(dir: &Path, step: u64, suffix: &str) -> PathBuf {
    dir.join(SAMPLES_DIR)
        .join(format!("sample_{step:010}.{suffix}"))
}

/// Stores a sample of the run in `dir`: the lab view of a measured state with its step's
/// contacts. The box file is written last, so a sample counts only once complete.
///
/// # Errors
/// [`RunError::Io`] when a file cannot be written.
pub fn write(dir: &Path, view: &LabView, contacts: &[ContactRecord]) -> Result<(), RunError> {
    let folder = dir.join(SAMPLES_DIR);
    std::fs::create_dir_all(&folder).map_err(io_err("create the directory", &folder))?;
    let header = SampleBox {
        step: view.step,
        time: view.time,
        domain: view.domain.clone(),
    };
    let json = serde_json::to_string(&header).unwrap_or_default();
    for (suffix, text) in [
        ("particles.csv", particles_csv(&view.particles)),
        ("contacts.csv", contacts_csv(contacts)),
        ("box.json", json),
    ] {
        let path = sample_path(dir, view.step, suffix);
        write_atomic(&path, text.as_bytes()).map_err(io_err("write", &path))?;
    }
    Ok(())
}

/// Removes the samples of an earlier run from `dir`, complete or not.
///
/// # Errors
/// [`RunError::Io`] when a sample file cannot be removed.
pub fn remove_all(dir: &Path) -> Result<(), RunError> {
    for path in sample_files(dir)? {
        std::fs::remove_file(&path).map_err(io_err("remove", &path))?;
    }
    Ok(())
}

/// Every file named `sample_*` in the samples' directory of `dir` (none without one).
fn sample_files(dir: &Path) -> Result<Vec<PathBuf>, RunError> {
    let folder = dir.join(SAMPLES_DIR);
    let Ok(entries) = std::fs::read_dir(&folder) else {
        return Ok(Vec::new());
    };
    let mut files = Vec::new();
    for entry in entries {
        let entry = entry.map_err(io_err("list", &folder))?;
        if entry.file_name().to_string_lossy().starts_with("sample_") {
            files.push(entry.path());
        }
    }
    Ok(files)
}

/// The steps of the complete samples in `dir` (those with a box file), in order.
fn list(dir: &Path) -> Result<Vec<u64>, RunError> {
    let mut steps: Vec<u64> = sample_files(dir)?
        .iter()
        .filter_map(|p| {
            p.file_name()?
                .to_str()?
                .strip_prefix("sample_")?
                .strip_suffix(".box.json")?
                .parse()
                .ok()
        })
        .collect();
    steps.sort_unstable();
    Ok(steps)
}

/// Reads sample `step` of the run in `dir`.
fn read(dir: &Path, step: u64) -> Result<(LabView, Vec<ContactRecord>), RunError> {
    let text = |suffix: &str| {
        let path = sample_path(dir, step, suffix);
        std::fs::read_to_string(&path)
            .map(|t| (t, path.display().to_string()))
            .map_err(io_err("read", &sample_path(dir, step, suffix)))
    };
    let (json, what) = text("box.json")?;
    let header: SampleBox = serde_json::from_str(&json)
        .map_err(|e| CgError::Invalid(format!("{what}: not a sample's box file: {e}")))?;
    let (csv, what) = text("particles.csv")?;
    let particles = read_particles_csv(&csv, &what)?;
    let (csv, what) = text("contacts.csv")?;
    let contacts = read_contacts_csv(&csv, &what)?;
    Ok((
        LabView {
            step: header.step,
            time: header.time,
            domain: header.domain,
            particles,
        },
        contacts,
    ))
}

/// The run in `dir` as of its last checkpoint, read without locking or changing the
/// directory.
///
/// # Errors
/// [`RunError`] when the checkpoint cannot be read.
pub fn read_run(dir: &Path) -> Result<ScenarioState, RunError> {
    read_checkpoint(&dir.join("checkpoint.bin"))
}

/// The stored samples of `run` (read from `dir` by [`read_run`]) from time `start` (s) up
/// to its last checkpoint, in step order, read one at a time.
fn window<'a>(
    dir: &'a Path,
    run: &'a ScenarioState,
    start: f64,
) -> Result<impl Iterator<Item = Result<(LabView, Vec<ContactRecord>), RunError>> + 'a, RunError> {
    let steps = list(dir)?;
    Ok(steps
        .into_iter()
        .take_while(|&step| step <= run.simulation.step)
        .map(move |step| read(dir, step))
        .filter(move |sample| sample.as_ref().map_or(true, |(view, _)| view.time >= start)))
}

/// The error of a window without samples.
fn no_samples(dir: &Path, start: f64) -> RunError {
    CgError::Invalid(format!(
        "{}: no stored samples from t = {start} s up to the last checkpoint (a run stores them \
         with `records = true` in [fields], the shear box with `cg_records`)",
        dir.display()
    ))
    .into()
}

/// The fields of `run` (read from `dir` by [`read_run`]) coarse-grained again from its
/// stored samples with `spec`: the samples from `spec.start` up to the last checkpoint, in
/// step order.
///
/// # Errors
/// [`RunError`] when a sample cannot be read, there is none to use, or `spec` is out of
/// range.
pub fn offline_fields(
    dir: &Path,
    run: &ScenarioState,
    spec: &FieldsSpec,
) -> Result<BoxFields, RunError> {
    let mut fields = BoxFields::new(spec)?;
    for sample in window(dir, run, spec.start)? {
        let (view, contacts) = sample?;
        fields.add(&view, &contacts)?;
    }
    if fields.sums.is_none() {
        return Err(no_samples(dir, spec.start));
    }
    Ok(fields)
}

/// Writes `mercury.data` and `mercury.fstat` into `out`: the stored samples of `run` from
/// time `start` (s) in MercuryDPM's formats ([`crate::cg::mercury`]; positions wrapped into
/// the box, velocities in the lab frame); returns how many.
///
/// # Errors
/// [`RunError`] when a sample cannot be read or exported, there is none, or a file cannot
/// be written.
pub fn export_mercury(
    dir: &Path,
    run: &ScenarioState,
    start: f64,
    out: &Path,
) -> Result<usize, RunError> {
    let (mut data, mut fstat, mut count) = (String::new(), String::new(), 0);
    for sample in window(dir, run, start)? {
        let (view, contacts) = sample?;
        crate::cg::mercury::data_block(&mut data, view.time, &view.particles)?;
        crate::cg::mercury::fstat_block(&mut fstat, view.time, &view.particles, &contacts)?;
        count += 1;
    }
    if count == 0 {
        return Err(no_samples(dir, start));
    }
    for (name, text) in [("mercury.data", data), ("mercury.fstat", fstat)] {
        let path = out.join(name);
        write_atomic(&path, text.as_bytes()).map_err(io_err("write", &path))?;
    }
    Ok(count)
}
