//! The staged run driver's contract, on a set-up of its own: a sphere falling freely under
//! gravity in two stages ("fall", then "coast"), whose height follows `z₀ − ½ g t²`. The
//! driver stops at a stage's end, checkpoints on the set-up's cadence, resumes bit for bit,
//! refuses to overwrite a run, and records where a failure happened.

use rheodem::Simulation;
use rheodem::cg::ContactRecord;
use rheodem::driver::{Driver, Progress, RunError, Session, SetUp, StepNeeds};
use rheodem::io::made_by::Maker;
use rheodem::scenario::{Scenario, build};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

const FALL: &str = r#"
    gravity = [0.0, 0.0, -9.81]
    [domain]
    size = [0.1, 0.1, 0.1]
    [[species]]
    name = "glass"
    density = 2000.0
    [[contact]]
    normal = { stiffness = 100.0, restitution = 0.8 }
    [[particles]]
    kind = "explicit"
    species = "glass"
    spheres = [{ radius = 1.1e-3, position = [0.05, 0.05, 0.09] }]
    [run]
    steps = 80
"#;

/// Steps of each stage.
const STAGE_STEPS: u64 = 40;

/// The falling sphere's set-up: two stages of [`STAGE_STEPS`] steps, a row of heights every
/// 5 steps, a checkpoint every 10, and an operation that fails at step `fail_at`.
#[derive(Debug, Serialize, Deserialize)]
struct Fall {
    simulation: Simulation,
    heights: Vec<(f64, f64)>,
    wall_seconds: f64,
    fail_at: Option<u64>,
}

impl SetUp for Fall {
    const MAKER: Maker = Maker::Run;

    fn simulation(&self) -> &Simulation {
        &self.simulation
    }

    fn simulation_mut(&mut self) -> &mut Simulation {
        &mut self.simulation
    }

    fn is_complete(&self) -> bool {
        self.simulation.step >= 2 * STAGE_STEPS
    }

    fn progress(&self) -> Progress {
        let step = self.simulation.step;
        if step < STAGE_STEPS {
            Progress {
                stage: "fall",
                done: step,
                total: STAGE_STEPS,
            }
        } else {
            Progress {
                stage: "coast",
                done: step - STAGE_STEPS,
                total: STAGE_STEPS,
            }
        }
    }

    fn needs(&self) -> StepNeeds {
        StepNeeds {
            measure: (self.simulation.step + 1).is_multiple_of(5),
            contacts: false,
        }
    }

    fn after_step(
        &mut self,
        session: &mut Session<'_>,
        contacts: Option<&[ContactRecord]>,
    ) -> Result<bool, RunError> {
        assert!(contacts.is_none(), "records were not asked for");
        let step = self.simulation.step;
        if self.fail_at == Some(step) {
            return Err(RunError::Io {
                operation: "write",
                path: session.dir.join("blocked"),
                source: std::io::Error::other("the test's failure"),
            });
        }
        if step.is_multiple_of(5) {
            session.sane(&self.simulation)?;
            let z = self.simulation.particles.position[0].z;
            self.heights.push((self.simulation.time, z));
        }
        Ok(step.is_multiple_of(10))
    }

    fn wall_seconds_mut(&mut self) -> &mut f64 {
        &mut self.wall_seconds
    }

    fn write_outputs(&self, dir: &Path) -> Result<serde_json::Value, RunError> {
        let path = dir.join("heights.csv");
        let text: String = self
            .heights
            .iter()
            .map(|(t, z)| format!("{t:e},{z:e}\n"))
            .collect();
        std::fs::write(&path, text).map_err(rheodem::driver::io_err("write", &path))?;
        Ok(self.summary())
    }

    fn summary(&self) -> serde_json::Value {
        serde_json::json!({
            "program": "fall",
            "steps": self.simulation.step,
            "rows": self.heights.len(),
        })
    }
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rheodem-driver-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn fall(fail_at: Option<u64>) -> Fall {
    let scenario = Scenario::from_toml(FALL).expect("valid");
    let built = build(&scenario, Path::new(".")).expect("builds");
    Fall {
        simulation: built.simulation,
        heights: Vec::new(),
        wall_seconds: 0.0,
        fail_at,
    }
}

fn start(dir: &Path, fail_at: Option<u64>) -> Driver<Fall> {
    Driver::create(dir, false, |_| Ok(fall(fail_at))).expect("starts")
}

fn summary(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary");
    serde_json::from_str(&text).expect("json")
}

#[test]
fn stages_end_where_the_set_up_says_and_the_fall_follows_the_closed_form() {
    let dir = temp_dir("stages");
    let mut run = start(&dir, None);
    assert_eq!(summary(&dir)["status"], "running");
    let mut seen = Vec::new();
    run.advance_stage(&dir, &mut |p| seen.push(p))
        .expect("first stage");
    assert_eq!(run.simulation.step, STAGE_STEPS, "stops at the stage's end");
    assert_eq!(seen.first().map(|p| p.stage), Some("fall"));
    assert_eq!(seen.last().map(|p| p.stage), Some("coast"));
    run.advance_stage(&dir, &mut |_| {}).expect("second stage");
    assert!(run.is_complete());
    let s = summary(&dir);
    assert_eq!(s["status"], "completed");
    assert_eq!(s["last_checkpoint_step"], 2 * STAGE_STEPS);
    assert_eq!(s["rows"], 16);
    assert!(s["error"].is_null());
    // Velocity Verlet is exact for a constant force, up to rounding.
    for &(t, z) in &run.heights {
        assert!(
            (z - (0.09 - 0.5 * 9.81 * t * t)).abs() < 1e-12,
            "t = {t}: z = {z}"
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_run_stopped_and_resumed_ends_in_the_same_bits() {
    let (whole, split) = (temp_dir("whole"), temp_dir("split"));
    let mut a = start(&whole, None);
    a.advance(&whole, |_| {}).expect("whole");
    let mut b = start(&split, None);
    // Stops after step 27: its last checkpoint is step 20.
    b.advance_until(&split, 27, &mut |_| {}).expect("part");
    drop(b);
    let mut b: Driver<Fall> = Driver::resume(&split).expect("resumes");
    assert_eq!(b.simulation.step, 20);
    b.advance(&split, |_| {}).expect("rest");
    let bits = |run: &Driver<Fall>| {
        let p = &run.simulation.particles;
        (
            p.position[0].to_array().map(f64::to_bits),
            run.heights.len(),
        )
    };
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(
        std::fs::read(whole.join("heights.csv")).expect("a"),
        std::fs::read(split.join("heights.csv")).expect("b")
    );
    let _ = std::fs::remove_dir_all(whole);
    let _ = std::fs::remove_dir_all(split);
}

#[test]
fn a_directory_is_locked_and_never_overwritten_without_force() {
    let dir = temp_dir("refuse");
    let run = start(&dir, None);
    let busy = Driver::<Fall>::resume(&dir).expect_err("locked while the run lives");
    assert!(matches!(busy, RunError::Busy(_)), "{busy}");
    drop(run);
    let exists = Driver::create(&dir, false, |_| Ok(fall(None))).expect_err("holds a run");
    assert!(matches!(exists, RunError::Exists(_)), "{exists}");
    Driver::create(&dir, true, |_| Ok(fall(None))).expect("--force starts over");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn failures_say_where_they_happened() {
    // A failed start removes the directory it created...
    let dir = temp_dir("fail-new");
    let refuse = |_: &mut Session<'_>| -> Result<Fall, RunError> {
        Err(RunError::Checkpoint {
            path: PathBuf::from("nowhere"),
            reason: "the test's refusal".into(),
        })
    };
    Driver::create(&dir, false, refuse).expect_err("refused");
    assert!(!dir.exists(), "a failed start left its new directory");
    // ... and records the failure in one that existed.
    std::fs::create_dir_all(&dir).expect("dir");
    Driver::create(&dir, false, refuse).expect_err("refused");
    let s = summary(&dir);
    assert_eq!(s["status"], "failed");
    assert_eq!(s["failed_at"], "start");
    assert!(
        s["error"].as_str().is_some_and(|e| e.contains("refusal")),
        "{s}"
    );
    let _ = std::fs::remove_dir_all(&dir);

    // An operation that fails mid-run: the summary names the stage, time and step.
    let dir = temp_dir("fail-mid");
    let mut run = start(&dir, Some(STAGE_STEPS + 3));
    let err = run.advance(&dir, |_| {}).expect_err("fails");
    assert!(err.to_string().contains("the test's failure"), "{err}");
    let s = summary(&dir);
    assert_eq!(s["status"], "failed");
    assert_eq!(s["failed_at"]["stage"], "coast");
    assert_eq!(s["failed_at"]["steps"], STAGE_STEPS + 3);
    assert_eq!(s["last_checkpoint_step"], STAGE_STEPS);
    let _ = std::fs::remove_dir_all(dir);
}
