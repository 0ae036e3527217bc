//! Regression tests of the robustness defects found by trying the program as a hostile
//! user would (D1–D9): each test is named after its defect and fails on the code that had
//! it.

use glam::DVec3;
use rheodem::run::{Run, RunError};
use rheodem::sanity::Instability;
use rheodem::scenario::{Scenario, build, check};
use rheodem::setups::shear_box::ShearBoxSpec;
use rheodem::setups::sweep::run_point;
use std::path::{Path, PathBuf};

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rheodem-robust-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// A small dry periodic gas: 60 spheres, 400 steps, a checkpoint every 100.
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
friction = { stiffness_ratio = 0.2857, damping_ratio = 0.2857, mu = 0.5 }
[[particles]]
kind = "random"
species = "glass"
count = 60
mean_diameter = 2.2e-3
polydispersity = 2.0
velocity_spread = 0.05
[run]
steps = 400
[output]
timeseries_rows = 8
snapshots = 4
checkpoints = 4
"#;

fn start(text: &str, dir: &Path) -> Run {
    let sc = Scenario::from_toml(text).expect("valid scenario");
    Run::start(sc, Path::new("."), dir, 1, true).expect("run starts")
}

fn summary(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary");
    serde_json::from_str(&text).expect("summary is JSON")
}

fn scenario_error(text: &str) -> String {
    let sc = Scenario::from_toml(text).expect("parses");
    match check(&sc, Path::new(".")) {
        Ok(_) => panic!("scenario accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// Two explicit spheres (radius 1 mm) at distance `distance` (m), in a closed box.
fn pair(distance: f64, speed: f64) -> String {
    format!(
        r#"
[domain]
size = [0.02, 0.02, 0.02]
lo = [-0.01, -0.01, -0.01]
[[species]]
name = "glass"
density = 2000.0
[[contact]]
normal = {{ stiffness = 100.0, restitution = 0.8 }}
[[particles]]
kind = "explicit"
species = "glass"
spheres = [
  {{ radius = 1e-3, position = [0.0, 0.0, 0.0], velocity = [{speed}, 0.0, 0.0] }},
  {{ radius = 1e-3, position = [{distance}, 0.0, 0.0] }},
]
[run]
steps = 10
"#
    )
}

/// D1: a kill between the final checkpoint and the final summary left `"status":
/// "running"` for ever; resuming the complete run now rewrites its outputs.
#[test]
fn d1_summary_of_a_run_killed_after_its_last_checkpoint_is_repaired() {
    let dir = temp_dir("d1");
    let mut run = start(GAS, &dir);
    run.advance(&dir, |_| {}).expect("run");
    drop(run);
    // What the kill left: the final checkpoint, and the summary of the one before.
    let mut stale = summary(&dir);
    stale["status"] = "running".into();
    stale["steps_done"] = 300.into();
    std::fs::write(dir.join("summary.json"), stale.to_string()).expect("write");

    let mut resumed = Run::resume(&dir).expect("resumes");
    assert!(resumed.is_complete());
    resumed.advance(&dir, |_| {}).expect("repair");
    let repaired = summary(&dir);
    assert_eq!(repaired["status"], "completed");
    assert_eq!(repaired["steps_done"], 400);
    assert_eq!(repaired["last_checkpoint_step"], 400);
    let _ = std::fs::remove_dir_all(dir);
}

/// D1: after a blow-up the summary stayed "running" with `steps_done` 0; it now says
/// "failed", where, and why.
#[test]
fn d1_summary_of_a_run_that_blew_up_says_failed_and_why() {
    let dir = temp_dir("d1-failed");
    let mut run = start(GAS, &dir);
    run.advance_until(&dir, 150, &mut |_| {}).expect("healthy");
    run.simulation.particles.velocity[7] = DVec3::new(f64::NAN, 0.0, 0.0);
    let id = run.simulation.particles.id[7];
    let err = run
        .advance_until(&dir, 400, &mut |_| {})
        .expect_err("stops");
    assert!(
        err.to_string().contains("last checkpoint (step 100)"),
        "{err}"
    );
    let s = summary(&dir);
    assert_eq!(s["status"], "failed");
    assert!(s["steps_done"].as_u64().expect("steps") > 150, "{s}");
    assert_eq!(s["last_checkpoint_step"], 100);
    let message = s["error"].as_str().expect("error message");
    assert!(message.contains(&format!("particle {id}")), "{message}");
    let _ = std::fs::remove_dir_all(dir);
}

/// D2: a planar wall across a periodic axis was accepted (particles fell through it by the
/// periodic image, and gained energy); it is refused naming the wall and the axis.
#[test]
fn d2_a_wall_across_a_periodic_axis_is_refused() {
    let text = format!("gravity = [0.0, 0.0, -9.81]\n{GAS}").replace(
        "[run]",
        "[[wall]]\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nspecies = \"glass\"\n[run]",
    );
    let err = scenario_error(&text);
    assert!(err.contains("wall[0].normal"), "{err}");
    assert!(err.contains("periodic axis z"), "{err}");
    // The same wall with z closed is fine.
    let closed = text.replace(
        "periodic = [true, true, true]",
        "periodic = [true, true, false]",
    );
    let sc = Scenario::from_toml(&closed).expect("parses");
    check(&sc, Path::new(".")).expect("a floor under a non-periodic z is valid");
}

/// D4: a checkpoint with one flipped bit resumed silently; the checksum now catches it.
#[test]
fn d4_a_checkpoint_with_a_flipped_bit_is_refused() {
    let dir = temp_dir("d4");
    let mut run = start(GAS, &dir);
    run.advance_until(&dir, 100, &mut |_| {}).expect("run");
    drop(run);
    let path = dir.join("checkpoint.bin");
    let good = std::fs::read(&path).expect("checkpoint");
    for byte in [20, good.len() / 2, good.len() - 1] {
        let mut bad = good.clone();
        bad[byte] ^= 0b0001_0000;
        std::fs::write(&path, &bad).expect("write");
        let err = Run::resume(&dir).expect_err("a damaged checkpoint must not load");
        assert!(
            matches!(err, RunError::Checkpoint { .. }) && err.to_string().contains("checksum"),
            "byte {byte}: {err}"
        );
    }
    std::fs::write(&path, &good).expect("restore");
    Run::resume(&dir).expect("the intact checkpoint loads");
    let _ = std::fs::remove_dir_all(dir);
}

/// D5: particles at 1000 m/s with `dt = t_c/10` ran to the end and reported absurd
/// pressures; a particle crossing more than a fraction of a radius per step now stops the
/// run, naming it.
#[test]
fn d5_a_particle_far_too_fast_stops_the_run_naming_it() {
    let dir = temp_dir("d5");
    let text = GAS.replace("[run]\n", "[run]\ndt_fraction = 0.1\n");
    let mut run = start(&text, &dir);
    run.advance_until(&dir, 50, &mut |_| {}).expect("healthy");
    run.simulation.particles.velocity[3] = DVec3::new(1000.0, 0.0, 0.0);
    let id = run.simulation.particles.id[3];
    let err = run
        .advance_until(&dir, 400, &mut |_| {})
        .expect_err("stops");
    match &err {
        RunError::Unstable {
            cause: Instability::TooFast { id: got, .. },
            checkpoint: Some(0),
            ..
        } => assert_eq!(*got, id),
        other => panic!("{other}"),
    }
    assert!(err.to_string().contains("run.max_displacement"), "{err}");
    let _ = std::fs::remove_dir_all(dir);
}

/// D5: an initial speed far beyond what the contacts resolve (1e8 m/s) is refused by
/// `check` naming the sphere's velocity key.
#[test]
fn d5_an_impossible_initial_speed_is_refused_by_check() {
    let err = scenario_error(&pair(0.005, 1e8));
    assert!(err.contains("particles[0].spheres[0].velocity"), "{err}");
}

/// D5: coincident spheres passed `check` and then "blew up at step 0" with a message that
/// promised a checkpoint that did not exist; `check` now refuses them naming the pair.
#[test]
fn d5_coincident_spheres_are_refused_naming_the_pair() {
    let err = scenario_error(&pair(0.0, 0.0));
    assert!(
        err.contains("particles[0].spheres[0] and particles[0].spheres[1]"),
        "{err}"
    );
    assert!(err.contains("coincide"), "{err}");
}

/// D5: the deep overlaps of a legitimate dense state pass (the limit is not a trap).
#[test]
fn d5_a_moderate_overlap_runs() {
    let sc = Scenario::from_toml(&pair(1.6e-3, 0.0)).expect("parses");
    let dir = temp_dir("d5-moderate");
    let mut run = Run::start(sc, Path::new("."), &dir, 1, true).expect("starts");
    run.advance(&dir, |_| {})
        .expect("an overlap of 0.4 radii runs");
    let _ = std::fs::remove_dir_all(dir);
}

/// D9: explicit spheres overlapping by 95 % of their radius were accepted silently; they
/// are accepted with a warning naming the pair and the overlap.
#[test]
fn d9_deeply_overlapping_explicit_spheres_give_a_warning() {
    let sc = Scenario::from_toml(&pair(1.05e-3, 0.0)).expect("parses");
    let checked = check(&sc, Path::new(".")).expect("accepted");
    let warning = checked.resolved.warnings.join("\n");
    assert!(
        warning.contains("particles[0].spheres[0] and particles[0].spheres[1]")
            && warning.contains("95.0 %"),
        "{warning}"
    );
    let built = build(&sc, Path::new(".")).expect("builds");
    assert_eq!(built.resolved.warnings, checked.resolved.warnings);
    let apart = Scenario::from_toml(&pair(2.5e-3, 0.0)).expect("parses");
    let fine = check(&apart, Path::new(".")).expect("accepted");
    assert!(fine.resolved.warnings.is_empty());
}

/// D6: two processes could both run the same point; the second now finds the directory
/// locked and is told so instead of corrupting the first one's files.
#[test]
fn d6_a_point_being_run_elsewhere_is_busy() {
    let dir = temp_dir("d6");
    let point: ShearBoxSpec = toml::from_str(
        "mu_p = 0.5\ninertial = 0.05\nsoftness = 0.01\npolydispersity = 2.0\nparticles = 150\n\
         strain = 0.2\ntransient_strain = 0.1\nsnapshots = 0\nseed = 5\n",
    )
    .expect("point");
    // Another process's run: here a lock held by this one.
    let held = rheodem::run::lock(&dir).expect("free");
    let err = run_point("p", &point, &dir, 1, &mut |_, _| {}).expect_err("busy");
    assert!(matches!(err, RunError::Busy(_)), "{err}");
    assert!(err.to_string().contains("another process"), "{err}");
    drop(held);
    let done = run_point("p", &point, &dir, 1, &mut |_, _| {}).expect("runs once free");
    assert_eq!(done.spec, point);
    let _ = std::fs::remove_dir_all(dir);
}

/// D6: every I/O error names the operation, the path and the operating system's reason.
#[test]
fn d6_io_errors_name_operation_path_and_reason() {
    let blocker = temp_dir("d6-io");
    std::fs::write(&blocker, b"a file where a directory should be").expect("write");
    let sc = Scenario::from_toml(GAS).expect("valid");
    let err = Run::start(sc, Path::new("."), &blocker.join("run"), 1, true)
        .expect_err("cannot create a directory inside a file");
    let text = err.to_string();
    assert!(
        text.contains("cannot create the directory")
            && text.contains(&blocker.display().to_string())
            && text.to_lowercase().contains("not a directory"),
        "{text}"
    );
    let _ = std::fs::remove_file(blocker);
}

/// D7: `run --force` left the old run's snapshots beside the new ones.
#[test]
fn d7_starting_over_removes_the_old_snapshots() {
    let dir = temp_dir("d7");
    let mut run = start(GAS, &dir);
    run.advance(&dir, |_| {}).expect("run");
    drop(run);
    let shorter = GAS.replace("steps = 400", "steps = 200");
    let mut again = start(&shorter, &dir);
    again.advance(&dir, |_| {}).expect("run");
    let mut files: Vec<String> = std::fs::read_dir(dir.join("snapshots"))
        .expect("snapshots")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    let listed: Vec<String> = again
        .snapshots
        .iter()
        .map(|(_, name)| name.trim_start_matches("snapshots/").to_string())
        .collect();
    assert_eq!(
        files, listed,
        "snapshots on disk are exactly those of the new run"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// D8: `steps` had no upper bound although `duration` had one.
#[test]
fn d8_steps_beyond_the_limit_are_refused() {
    for steps in ["100000000000000", "9223372036854775807"] {
        let err = scenario_error(&GAS.replace("steps = 400", &format!("steps = {steps}")));
        assert!(
            err.contains("run.steps") && err.contains("[1, 1e13]"),
            "{err}"
        );
    }
    let err = scenario_error(&GAS.replace("steps = 400", "steps = 0"));
    assert!(err.contains("run.steps"), "{err}");
}

/// `check` validates and resolves only: it runs no preparation (it used to compress and
/// relax the packing, which takes minutes for large ones).
#[test]
fn check_does_not_run_the_preparation() {
    let text = GAS.replace("[run]", "[preparation]\nvolume_fraction = 0.1\n[run]");
    let sc = Scenario::from_toml(&text).expect("valid");
    let checked = check(&sc, Path::new(".")).expect("valid");
    assert!(checked.resolved.preparation.is_none());
    assert!(
        checked
            .preparation
            .as_deref()
            .is_some_and(|p| p.contains("volume fraction 0.1")),
        "{:?}",
        checked.preparation
    );
    // The box is still the loose one: nothing was compressed.
    assert_eq!(checked.resolved.box_size, [0.03; 3]);
    let built = build(&sc, Path::new(".")).expect("builds");
    assert!(built.resolved.preparation.is_some());
    assert!(built.resolved.box_size[0] < 0.03);
}
