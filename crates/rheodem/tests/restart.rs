//! Checkpoint and resume: a run stopped at a checkpoint and resumed from disk ends in the
//! same state, bit for bit, as an uninterrupted run; the same seed reproduces a run. The
//! particles are wet (Willett bridges), so open bridges must survive the checkpoint.

use rheodem::run::Run;
use rheodem::scenario::Scenario;
use std::path::{Path, PathBuf};

const SCENARIO: &str = r#"
seed = 11
[domain]
size = [0.03, 0.03, 0.03]
periodic = [true, true, true]
[[species]]
name = "glass"
density = 2000.0
[[contact]]
normal = { stiffness = 100.0, restitution = 0.8 }
friction = { stiffness_ratio = 0.2857, damping_ratio = 0.2857, mu = 0.5 }
rolling = { stiffness_ratio = 0.2857, damping_ratio = 0.2857, mu = 0.1 }
torsion = { stiffness_ratio = 0.2857, damping_ratio = 0.2857, mu = 0.1 }
adhesion = { law = "liquid_bridge", surface_tension = 0.02, contact_angle_deg = 20.0, volume = 75e-12 }
[[particles]]
kind = "random"
species = "glass"
count = 300
mean_diameter = 2.2e-3
polydispersity = 2.0
velocity_spread = 0.05
[preparation]
pressure = 200.0
relax_contact_times = 20.0
[run]
steps = 3000
[output]
timeseries_rows = 30
snapshots = 3
checkpoints = 6
"#;

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rheodem-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Final state as raw bits, in particle-id order, plus the time series.
fn fingerprint(run: &Run) -> (Vec<[u64; 9]>, String) {
    let p = &run.simulation.particles;
    let slot = p.slot_of();
    let state = slot
        .iter()
        .map(|&s| {
            let (r, v, w) = (
                p.position[s as usize],
                p.velocity[s as usize],
                p.angular_velocity[s as usize],
            );
            [r.x, r.y, r.z, v.x, v.y, v.z, w.x, w.y, w.z].map(f64::to_bits)
        })
        .collect();
    (state, rheodem::io::timeseries::to_csv(&run.rows))
}

fn start(dir: &Path) -> Run {
    start_scenario(SCENARIO, dir)
}

fn start_scenario(scenario: &str, dir: &Path) -> Run {
    let sc = Scenario::from_toml(scenario).expect("valid scenario");
    Run::start(sc, Path::new("."), dir, rayon::current_num_threads(), true).expect("run starts")
}

/// A run stopped at step 1700 and resumed from its checkpoint at step 1500 ends in the bits
/// of the uninterrupted run; `check` sees the run as it was read back.
fn stop_resume_and_compare(scenario: &str, name: &str, check: impl FnOnce(&mut Run)) {
    let whole_dir = temp_dir(&format!("{name}-whole"));
    let mut whole = start_scenario(scenario, &whole_dir);
    whole.advance(&whole_dir, |_| {}).expect("run");
    let split_dir = temp_dir(&format!("{name}-split"));
    let mut first = start_scenario(scenario, &split_dir);
    first
        .advance_until(&split_dir, 1700, &mut |_| {})
        .expect("run");
    drop(first);
    let mut resumed = Run::resume(&split_dir).expect("checkpoint readable");
    assert_eq!(resumed.simulation.step, 1500);
    check(&mut resumed);
    resumed.advance(&split_dir, |_| {}).expect("run");
    assert!(
        fingerprint(&whole) == fingerprint(&resumed),
        "{name}: resume differs"
    );
    for d in [whole_dir, split_dir] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn a_plastic_contact_keeps_its_largest_overlap_through_a_checkpoint() {
    // Luding's elasto-plastic law keeps each contact's largest overlap as its state: the
    // checkpoint holds it, and the resumed run continues in the same bits.
    let scenario = SCENARIO.replace(
        "normal = { stiffness = 100.0, restitution = 0.8 }",
        "normal = { law = \"luding\", stiffness = 100.0, max_stiffness = 500.0, \
         adhesive_stiffness = 50.0, plasticity_depth = 0.05, restitution = 0.8 }",
    );
    assert_ne!(scenario, SCENARIO);
    stop_resume_and_compare(&scenario, "luding", |resumed| {
        let slices = resumed.simulation.neighbors.slices();
        let kept = slices.history.iter().filter(|h| h.state > 0.0).count();
        assert!(
            kept > 0,
            "the checkpoint holds the contacts' largest overlaps"
        );
    });
}

#[test]
fn a_mindlin_contact_keeps_its_contact_radius_through_a_checkpoint() {
    // Mindlin's sliding spring keeps each contact's radius at the last step as its state
    // (beside Hertz's normal law): the checkpoint holds it, and the resumed run continues
    // in the same bits.
    let scenario = SCENARIO
        .replace(
            "normal = { stiffness = 100.0, restitution = 0.8 }",
            "normal = { law = \"hertz\", youngs_modulus = 2.0e7, poisson_ratio = 0.3, \
             restitution = 0.8 }",
        )
        .replace(
            "friction = { stiffness_ratio = 0.2857, damping_ratio = 0.2857, mu = 0.5 }",
            "friction = { law = \"mindlin\", mu = 0.5, damping_ratio = 0.5 }",
        )
        .replace(
            "rolling = { stiffness_ratio = 0.2857, damping_ratio = 0.2857, mu = 0.1 }\n",
            "",
        )
        .replace(
            "torsion = { stiffness_ratio = 0.2857, damping_ratio = 0.2857, mu = 0.1 }\n",
            "",
        );
    assert!(!scenario.contains("stiffness_ratio"));
    stop_resume_and_compare(&scenario, "mindlin", |resumed| {
        let slices = resumed.simulation.neighbors.slices();
        let kept = slices
            .history
            .iter()
            .filter(|h| h.sliding_state > 0.0)
            .count();
        assert!(kept > 0, "the checkpoint holds the contacts' radii");
    });
}

#[test]
fn a_rabinovich_bridge_survives_a_checkpoint() {
    // Rabinovich's bridges form at contact and outlive it until they rupture: the
    // checkpoint holds the open ones, and the resumed run continues in the same bits.
    let scenario = SCENARIO.replace(
        "adhesion = { law = \"liquid_bridge\",",
        "adhesion = { law = \"rabinovich\",",
    );
    assert_ne!(scenario, SCENARIO);
    stop_resume_and_compare(&scenario, "rabinovich", |resumed| {
        let open = resumed.rows.last().map_or(0.0, |o| o.bridges_per_particle);
        assert!(open > 0.0, "the checkpoint holds open bridges");
    });
}

#[test]
fn resumed_run_is_bit_identical() {
    let whole_dir = temp_dir("whole");
    let mut whole = start(&whole_dir);
    whole.advance(&whole_dir, |_| {}).expect("run");
    assert!(whole.is_complete());

    let split_dir = temp_dir("split");
    let mut first = start(&split_dir);
    // Stop at step 1700; the last checkpoint on disk is at step 1500.
    first
        .advance_until(&split_dir, 1700, &mut |_| {})
        .expect("run");
    drop(first);
    let mut resumed = Run::resume(&split_dir).expect("checkpoint readable");
    assert_eq!(resumed.simulation.step, 1500);
    // The checkpoint holds open bridges (pairs apart that still attract).
    let open = resumed.rows.last().map_or(0.0, |o| o.bridges_per_particle);
    assert!(open > 0.0, "the test needs open bridges at the checkpoint");
    resumed.advance(&split_dir, |_| {}).expect("run");

    let (a, csv_a) = fingerprint(&whole);
    let (b, csv_b) = fingerprint(&resumed);
    assert!(a == b, "final states differ after resume");
    assert_eq!(csv_a, csv_b);
    // The files on disk match too.
    let read = |d: &Path| std::fs::read_to_string(d.join("timeseries.csv")).expect("csv");
    assert_eq!(read(&whole_dir), read(&split_dir));
    assert!(whole_dir.join("snapshots.pvd").exists());
    let summary = std::fs::read_to_string(split_dir.join("summary.json")).expect("summary");
    assert!(summary.contains("\"status\": \"completed\"") && summary.contains("\"seed\": 11"));

    // Same seed, fresh run: identical again.
    let again_dir = temp_dir("again");
    let mut again = start(&again_dir);
    again.advance(&again_dir, |_| {}).expect("run");
    assert!(fingerprint(&again).0 == a);

    for d in [whole_dir, split_dir, again_dir] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn starting_over_an_existing_run_is_refused() {
    let dir = temp_dir("exists");
    let _ = start(&dir);
    let sc = Scenario::from_toml(SCENARIO).expect("valid scenario");
    let err = Run::start(sc, Path::new("."), &dir, 1, false).expect_err("must refuse");
    assert!(err.to_string().contains("rheodem resume"));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn corrupt_checkpoint_is_an_error_not_a_panic() {
    let dir = temp_dir("corrupt");
    std::fs::create_dir_all(&dir).expect("dir");
    std::fs::write(dir.join("checkpoint.bin"), b"RHEODEM3garbage").expect("write");
    let err = Run::resume(&dir).expect_err("must fail");
    assert!(err.to_string().contains("not a usable checkpoint"));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_run_that_blows_up_stops_with_an_error_and_keeps_its_checkpoint() {
    let dir = temp_dir("diverged");
    let mut run = start(&dir);
    run.advance_until(&dir, 200, &mut |_| {})
        .expect("healthy start");
    // A non-finite velocity stands for any blow-up (a time step far too large, say).
    run.simulation.particles.velocity[0] = glam::DVec3::new(f64::NAN, 0.0, 0.0);
    let err = run
        .advance_until(&dir, run.plan.steps, &mut |_| {})
        .expect_err("must stop");
    assert!(
        matches!(
            err,
            rheodem::run::RunError::Unstable {
                cause: rheodem::sanity::Instability::NonFinite { .. },
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("became unstable at step"), "{err}");
    assert!(run.rows.iter().all(|r| r.is_finite()), "no NaN row kept");
    // The process ends (and releases the directory); the checkpoint on disk predates the
    // blow-up and resumes.
    drop(run);
    let resumed = Run::resume(&dir).expect("the last checkpoint is usable");
    assert!(resumed.simulation.particles.is_finite());
    assert!(resumed.rows.iter().all(|r| r.is_finite()));
    let _ = std::fs::remove_dir_all(dir);
}

/// The compatibility rule of docs/compatibility.md: a checkpoint of this format written by
/// an earlier version reads (fields added since take their defaults), one written by a
/// newer version is refused with a message that names both versions, and this version's
/// own checkpoints read back.
#[test]
fn checkpoints_of_earlier_versions_read_and_of_newer_ones_are_refused() {
    use rheodem::run::{read_checkpoint, write_checkpoint};
    let dir = temp_dir("versions");
    std::fs::create_dir_all(&dir).expect("dir");
    let state = vec![1.5f64, -2.0];
    let written_by = |version: &str| {
        let body = rmp_serde::to_vec_named(&(version, &state)).expect("encode");
        let mut bytes = b"RHEODEM3".to_vec();
        bytes.extend_from_slice(&crc32fast::hash(&body).to_le_bytes());
        bytes.extend_from_slice(&body);
        let path = dir.join(format!("checkpoint-{version}.bin"));
        std::fs::write(&path, bytes).expect("write");
        path
    };
    let old: Vec<f64> = read_checkpoint(&written_by("0.1.0")).expect("an earlier version");
    assert_eq!(old, state);
    let e = read_checkpoint::<Vec<f64>>(&written_by("99.0.0"))
        .expect_err("a newer version")
        .to_string();
    assert!(
        e.contains("written by rheodem 99.0.0, newer than this rheodem")
            && e.contains(rheodem::VERSION),
        "{e}"
    );
    let own = dir.join("own.bin");
    write_checkpoint(&own, &state).expect("write");
    assert_eq!(read_checkpoint::<Vec<f64>>(&own).expect("read"), state);
    let _ = std::fs::remove_dir_all(dir);
}
