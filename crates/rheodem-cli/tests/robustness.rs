//! Regression tests of the program's robustness defects (D1, D3, D6, D9 of the hostile-user
//! review), end to end through the `rheodem` binary.

mod common;

use common::{rheodem_in, stderr, stdout, temp, workspace};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A sweep of `n` tiny dry points (150 spheres, 0.3 strain units) with paths relative to
/// the file.
fn tiny_sweep(dir: &Path, inertial: &[f64]) -> PathBuf {
    let list: Vec<String> = inertial.iter().map(|i| format!("{i}")).collect();
    let text = format!(
        "out = \"runs\"\nresults = \"archive\"\n[base]\nmu_p = 0.5\nsoftness = 0.01\n\
         polydispersity = 2.0\nparticles = 150\nstrain = 0.3\ntransient_strain = 0.1\n\
         control_time = 10.0\nsnapshots = 0\nseed = 3\n[grid]\ninertial = [{}]\n",
        list.join(", ")
    );
    let file = dir.join("sweep.toml");
    std::fs::write(&file, text).expect("sweep file");
    file
}

/// D3: `--threads` had no upper bound (10000 threads for 100 particles); it is refused
/// with the allowed range, for `run`, `shear-box` and `bench` alike, and so is `--jobs 0`
/// (D9) and an absurd `--jobs`.
#[test]
fn d3_thread_and_job_counts_are_bounded() {
    let ws = workspace();
    for args in [
        vec!["run", "examples/dense-packing.toml", "--threads", "10000"],
        vec![
            "shear-box",
            "--mu-p",
            "0.5",
            "--inertial",
            "0.02",
            "--softness",
            "0.01",
            "--threads",
            "10000",
        ],
        vec![
            "bench",
            "--threads",
            "1,10000",
            "--steps",
            "1",
            "--warmup",
            "0",
        ],
        vec!["run", "examples/dense-packing.toml", "--threads", "0"],
    ] {
        let out = rheodem_in(&ws, &args);
        assert!(!out.status.success(), "{args:?} accepted");
        let err = stderr(&out);
        assert!(
            err.contains("--threads") && err.contains("must lie in [1, "),
            "{args:?}: {err}"
        );
    }
    let dir = temp("robust-cli", "d3");
    let sweep = tiny_sweep(&dir, &[0.05]);
    for jobs in ["0", "100000"] {
        let out = rheodem_in(&ws, &["sweep", &sweep.to_string_lossy(), "--jobs", jobs]);
        assert!(!out.status.success(), "--jobs {jobs} accepted");
        assert!(stderr(&out).contains("--jobs"), "{}", stderr(&out));
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// D6: two sweeps on one file both simulated the same point and often one died with a
/// bare path as its message. With the points locked, both finish cleanly, sharing the
/// work, and a later sweep collects every point.
#[test]
fn d6_two_concurrent_sweeps_share_the_points() {
    let dir = temp("robust-cli", "d6");
    let sweep = tiny_sweep(&dir, &[0.05, 0.08, 0.1, 0.12]);
    let file = sweep.to_string_lossy().into_owned();
    let spawn = || {
        Command::new(env!("CARGO_BIN_EXE_rheodem"))
            .args(["sweep", &file, "--jobs", "1", "--quiet"])
            .current_dir(&dir)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("starts")
    };
    let (a, b) = (spawn(), spawn());
    for child in [a, b] {
        let out = child.wait_with_output().expect("finishes");
        assert!(out.status.success(), "{}\n{}", stdout(&out), stderr(&out));
    }
    let again = rheodem_in(&dir, &["sweep", &file, "--quiet"]);
    assert!(again.status.success(), "{}", stderr(&again));
    assert!(
        stdout(&again).contains("4 of 4 points finished"),
        "{}",
        stdout(&again)
    );
    let table = std::fs::read_to_string(dir.join("archive/results.csv")).expect("table");
    assert_eq!(table.lines().count(), 5, "{table}");
    let leftovers: Vec<_> = walk(&dir)
        .into_iter()
        .filter(|p| p.to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    let _ = std::fs::remove_dir_all(dir);
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(walk(&p));
        }
        out.push(p);
    }
    out
}

/// D9: the sweep file's `out` and `results` resolved against the current directory, so the
/// same sweep started elsewhere reran every point; they are relative to the file.
#[test]
fn d9_sweep_paths_are_relative_to_the_sweep_file() {
    let dir = temp("robust-cli", "d9-paths");
    let sweep = tiny_sweep(&dir, &[0.05]);
    let file = sweep.to_string_lossy().into_owned();
    let elsewhere = temp("robust-cli", "d9-elsewhere");
    let first = rheodem_in(&elsewhere, &["sweep", &file, "--quiet"]);
    assert!(first.status.success(), "{}", stderr(&first));
    assert!(dir.join("archive/results.csv").exists());
    assert!(dir.join("runs").is_dir());
    assert!(
        std::fs::read_dir(&elsewhere).expect("dir").next().is_none(),
        "nothing is written where the sweep was started"
    );
    // Started from a third place, the archived point is found: nothing runs.
    std::fs::remove_dir_all(dir.join("runs")).expect("remove runs");
    let second = rheodem_in(&workspace(), &["sweep", &file, "--quiet"]);
    assert!(second.status.success(), "{}", stderr(&second));
    assert!(stdout(&second).contains("1 of 1 points finished"));
    let reruns = std::fs::read_dir(dir.join("runs"))
        .expect("out directory")
        .filter(|e| e.as_ref().is_ok_and(|e| e.path().is_dir()))
        .count();
    assert_eq!(reruns, 0, "the archived point was run again");
    let _ = std::fs::remove_dir_all(dir);
    let _ = std::fs::remove_dir_all(elsewhere);
}

/// D9: `compare` on a directory holding no sweep returned 0, and called plain run
/// directories "checkpointed" sweep points.
#[test]
fn d9_compare_refuses_a_directory_without_a_sweep() {
    let empty = temp("robust-cli", "d9-empty");
    let out = rheodem_in(&workspace(), &["compare", &empty.to_string_lossy()]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("holds no sweep results"),
        "{}",
        stderr(&out)
    );

    // A directory of plain runs (as `rheodem run` writes them) is no sweep either.
    let runs = temp("robust-cli", "d9-runs");
    let scenario = runs.join("gas.toml");
    std::fs::write(&scenario, GAS).expect("scenario");
    let one = runs.join("one");
    let out = rheodem_in(
        &runs,
        &[
            "run",
            "gas.toml",
            "--out",
            &one.to_string_lossy(),
            "--quiet",
            "--threads",
            "1",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let out = rheodem_in(&workspace(), &["compare", &runs.to_string_lossy()]);
    assert!(!out.status.success(), "{}", stdout(&out));
    assert!(!stdout(&out).contains("checkpointed"));
    let out = rheodem_in(&workspace(), &["compare", &one.to_string_lossy()]);
    assert!(stderr(&out).contains("single run"), "{}", stderr(&out));
    let _ = std::fs::remove_dir_all(empty);
    let _ = std::fs::remove_dir_all(runs);
}

/// A small dry periodic gas: 60 spheres, 300 steps.
const GAS: &str = r#"
seed = 3
[domain]
size = [0.03, 0.03, 0.03]
periodic = [true, true, true]
[[species]]
name = "glass"
density = 2000.0
[[contact]]
normal = { stiffness = 100.0, restitution = 0.8 }
[[particles]]
kind = "random"
species = "glass"
count = 60
mean_diameter = 2.2e-3
polydispersity = 2.0
velocity_spread = 0.05
[run]
steps = 300
[output]
timeseries_rows = 6
checkpoints = 3
"#;

/// D1: `rheodem resume` on a complete run whose summary a kill left at "running" said
/// "already complete" and left it so; it now repairs the summary.
#[test]
fn d1_resume_repairs_the_summary_of_a_complete_run() {
    let dir = temp("robust-cli", "d1");
    std::fs::write(dir.join("gas.toml"), GAS).expect("scenario");
    let out = rheodem_in(
        &dir,
        &[
            "run",
            "gas.toml",
            "--out",
            "run",
            "--quiet",
            "--threads",
            "1",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let path = dir.join("run/summary.json");
    let text = std::fs::read_to_string(&path).expect("summary");
    std::fs::write(&path, text.replace("\"completed\"", "\"running\"")).expect("stale summary");
    let out = rheodem_in(&dir, &["resume", "run", "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stdout(&out).contains("already complete"));
    let repaired = std::fs::read_to_string(&path).expect("summary");
    assert!(repaired.contains("\"status\": \"completed\""), "{repaired}");
    let _ = std::fs::remove_dir_all(dir);
}

/// `check` validates and resolves only ("without running"): it used to run the
/// preparation's dynamics.
#[test]
fn check_describes_the_preparation_without_running_it() {
    let dir = temp("robust-cli", "check");
    let scenario = GAS.replace("[run]", "[preparation]\nvolume_fraction = 0.1\n[run]");
    std::fs::write(dir.join("gas.toml"), scenario).expect("scenario");
    let out = rheodem_in(&dir, &["check", "gas.toml"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("not run by `check`"),
        "{}",
        stderr(&out)
    );
    assert!(
        stdout(&out).contains("\"preparation\": null"),
        "{}",
        stdout(&out)
    );
    assert!(
        std::fs::read_dir(&dir).expect("dir").count() == 1,
        "check writes nothing"
    );
    let _ = std::fs::remove_dir_all(dir);
}
