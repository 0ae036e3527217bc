//! `rheodem study submit --slurm`: the job scripts run as they are under bash, and, where a
//! Slurm cluster answers (CI starts a one-node one with `.ci/slurm-local.sh`), a study is
//! submitted, run by the scheduler, gathered into its database and reported.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn rheodem(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rheodem"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn ok(out: &Output) -> String {
    assert!(
        out.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A three-point study of 80 spheres over one strain unit (about a second a point), with
/// an archive and a database, in a fresh directory.
fn tiny_study(name: &str) -> (PathBuf, String) {
    let dir = std::env::temp_dir().join(format!("rheodem-slurm-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("tiny.toml");
    std::fs::write(
        &file,
        "title = \"three points on a cluster\"\nout = \"runs/tiny\"\nresults = \"results\"\n\
         database = \"results.sqlite\"\n[base]\nmu_p = 0.5\ninertial = 0.1\nsoftness = 0.01\n\
         polydispersity = 1.2\nparticles = 80\nstrain = 1.0\ntransient_strain = 0.5\n\
         checkpoints = 1\nsnapshots = 0\ncohesion = \"reversible\"\n[grid]\n\
         bond = [0.0, 1.0, 2.0]\n",
    )
    .expect("study file");
    let f = file.to_string_lossy().into_owned();
    (dir, f)
}

/// The submission directory (the only one under `runs/tiny/slurm`).
fn submission(dir: &Path) -> PathBuf {
    let mut subs: Vec<PathBuf> = std::fs::read_dir(dir.join("runs/tiny/slurm"))
        .expect("slurm dir")
        .map(|e| e.expect("entry").path())
        .collect();
    assert_eq!(subs.len(), 1, "{subs:?}");
    subs.remove(0)
}

/// What is common to both tests once the points ran: the archive, the database and the
/// report hold the three points, and a new submission finds nothing to do.
fn check_gathered(dir: &Path, f: &str) {
    let status = ok(&rheodem(&["study", "status", f]));
    assert!(status.contains("tiny: 3 of 3 points finished"), "{status}");
    assert!(status.contains("3 points of tiny"), "{status}");
    let table = std::fs::read_to_string(dir.join("results/results.csv")).expect("table");
    assert_eq!(table.lines().count(), 4, "{table}");
    let db = dir.join("results.sqlite").to_string_lossy().into_owned();
    assert!(ok(&rheodem(&["db", "status", "--db", &db])).contains("tiny: 3 points"));
    let report = ok(&rheodem(&["study", "report", f]));
    assert!(report.contains("3 of 3 points finished"), "{report}");
    let md = std::fs::read_to_string(dir.join("runs/tiny/report/report.md")).expect("report");
    assert!(md.starts_with("# three points on a cluster"));
    let again = ok(&rheodem(&["study", "submit", f, "--slurm"]));
    assert!(again.contains("nothing to submit"), "{again}");
}

/// `--dry-run` writes the scripts without a scheduler; run under bash, task by task as
/// Slurm would (`SLURM_ARRAY_TASK_ID`), then the collect job, they finish the study.
#[test]
fn the_job_scripts_run_the_study_under_bash() {
    let (dir, f) = tiny_study("bash");
    let out = ok(&rheodem(&[
        "study",
        "submit",
        &f,
        "--slurm",
        "--dry-run",
        "--time",
        "00:10:00",
    ]));
    assert!(
        out.contains("3 points of tiny not submitted (dry run)"),
        "{out}"
    );
    let sub = submission(&dir);
    let points = std::fs::read_to_string(sub.join("points.txt")).expect("list");
    assert_eq!(points.lines().count(), 3);
    let array = std::fs::read_to_string(sub.join("array.sh")).expect("array script");
    assert!(array.contains("#SBATCH --array=0-2\n") && array.contains("#SBATCH --time=00:10:00\n"));
    for task in 0..3 {
        let run = Command::new("bash")
            .arg(sub.join("array.sh"))
            .env("SLURM_ARRAY_TASK_ID", task.to_string())
            .current_dir(&sub)
            .output()
            .expect("bash runs");
        ok(&run);
    }
    // Nothing is in the database until the collect job has run.
    assert!(!dir.join("results.sqlite").exists());
    let collect = Command::new("bash")
        .arg(sub.join("collect.sh"))
        .output()
        .expect("bash runs");
    assert!(ok(&collect).contains("3 stored under study \"tiny\""));
    std::fs::remove_dir_all(sub).expect("remove the dry run's scripts");
    check_gathered(&dir, &f);
    // A task of a point that is finished does nothing; an unknown point is named.
    let out = ok(&rheodem(&[
        "study",
        "run-point",
        &f,
        "--point",
        points.lines().next().expect("a point"),
    ]));
    assert!(out.contains("finished already"), "{out}");
    let out = rheodem(&["study", "run-point", &f, "--point", "mu9"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no point named \"mu9\""));
    let out = rheodem(&["study", "submit", &f]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("--slurm"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Whether a Slurm controller answers here. `RHEODEM_REQUIRE_SLURM=1` (set by `.ci/run`)
/// turns its absence into a failure instead of a skip.
fn slurm_answers() -> bool {
    let up = Command::new("sinfo")
        .arg("-h")
        .output()
        .is_ok_and(|o| o.status.success());
    let required = std::env::var("RHEODEM_REQUIRE_SLURM").is_ok_and(|v| v == "1");
    assert!(
        up || !required,
        "RHEODEM_REQUIRE_SLURM=1 but no Slurm controller answers `sinfo` (start one with \
         `bash .ci/slurm-local.sh` and export its SLURM_CONF)"
    );
    if !up {
        eprintln!("skipped: no Slurm controller answers `sinfo` here");
    }
    up
}

/// A three-point study submitted to a real Slurm: the array runs the points, the collect
/// job (after the array) stores them, `study status` follows it, and the report builds.
/// Ignored by default, so that a machine without Slurm shows it as not run rather than
/// passed; `.ci/run` starts a cluster and runs it with `--ignored`.
#[test]
#[ignore = "needs a Slurm controller: `bash .ci/slurm-local.sh`, then `cargo test --release -p rheodem-cli --test slurm -- --ignored`"]
fn a_study_runs_on_slurm_end_to_end() {
    if !slurm_answers() {
        return;
    }
    let (dir, f) = tiny_study("cluster");
    let out = ok(&rheodem(&["study", "submit", &f, "--slurm"]));
    assert!(
        out.contains("submitted 3 points of tiny as job array"),
        "{out}"
    );
    let sub = submission(&dir);
    let record: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(sub.join("submission.json")).expect("record"),
    )
    .expect("json");
    let collect_job = record["collect_job"]
        .as_str()
        .expect("collect id")
        .to_string();
    // Submitting again while the tasks are queued or running adds nothing.
    let again = ok(&rheodem(&["study", "submit", &f, "--slurm"]));
    assert!(again.contains("nothing to submit"), "{again}");
    let start = Instant::now();
    loop {
        let queue = Command::new("squeue")
            .args(["-h", "-o", "%i"])
            .output()
            .expect("squeue");
        let queue = String::from_utf8_lossy(&queue.stdout).into_owned();
        if !queue.lines().any(|l| l.trim() == collect_job) && dir.join("results.sqlite").exists() {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "the jobs did not finish in 5 minutes; queue:\n{queue}\nstatus:\n{}",
            String::from_utf8_lossy(&rheodem(&["study", "status", &f]).stdout)
        );
        std::thread::sleep(Duration::from_millis(500));
    }
    for task in 0..3 {
        let log = std::fs::read_to_string(sub.join(format!("task-{task}.out"))).expect("log");
        assert!(
            log.contains("steady state over strain"),
            "task {task}: {log}"
        );
    }
    check_gathered(&dir, &f);
    let _ = std::fs::remove_dir_all(&dir);
}
