//! The split-bottom cell set-up: a small cell end to end, runs from one settled state,
//! resumption, and the errors of bad geometry.

use rheodem::run::RunError;
use rheodem::setups::split_bottom::{SplitBottomRun, SplitBottomSpec, Stage, TimeStepRule};
use std::path::Path;

/// A cell of about 800 particles: settles in about 0.2 s of simulated time.
fn small() -> SplitBottomSpec {
    SplitBottomSpec {
        inner_radius: 0.02,
        outer_radius: 0.05,
        split_radius: 0.035,
        height: 0.012,
        omega: 1.0,
        duration: 0.08,
        average_from: 0.04,
        rows: 16,
        snapshots: 1,
        checkpoints: 4,
        time_step: TimeStepRule::MeanPair,
        ..SplitBottomSpec::default()
    }
}

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("rheodem-sb-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn positions(run: &SplitBottomRun) -> Vec<[f64; 3]> {
    let p = &run.simulation.particles;
    let slot = p.slot_of();
    slot.iter()
        .map(|&s| p.position[s as usize].to_array())
        .collect()
}

/// The whole pipeline on a small cell: the filling settles (kinetic criterion met) to
/// about the height asked for, walls are frozen from the packing, the shear stage records
/// torques whose sum over all parts (the torque balance of the grains) is small against
/// the net torque, the band fits run, and every output file is written.
#[test]
fn small_cell_runs_end_to_end() {
    let dir = tmp("e2e");
    let mut run = SplitBottomRun::start(small(), &dir, false).expect("start");
    run.advance(&dir, |_, _, _| {}).expect("advance");
    assert_eq!(run.stage, Stage::Done);
    let settled = run.settled.clone().expect("settled");
    assert!(settled.criterion_met, "{settled:?}");
    // The count of particles assumes φ = 0.62 in the settled bed; a small cell's walls
    // and surface make the height uncertain by a particle diameter or two.
    let h = settled.surface_height;
    assert!((h - 0.012).abs() < 2.0 * 2.2e-3, "surface at {h}");
    assert!(settled.wall_particles.iter().all(|&n| n > 0), "{settled:?}");
    let res = run.results();
    let net = res.net_torque.expect("net torque");
    assert!(
        net.mean > 0.0,
        "the fixed parts are dragged forwards: {net:?}"
    );
    let balance = res.balance.expect("balance");
    // Over this short window the grains still accelerate a little: allow a tenth of the
    // net torque as imbalance, on top of the block-averaged error.
    assert!(
        balance.mean.abs() < 0.1 * net.mean + 3.0 * balance.error,
        "balance {balance:?} vs net {net:?}"
    );
    for f in [
        "summary.json",
        "timeseries.csv",
        "band.csv",
        "settled.bin",
        "split-bottom.toml",
    ] {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    assert!(dir.join("snapshots.pvd").exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// Two shear runs started from one settled state take identical steps (the settled
/// checkpoint carries the full state, contact history included), and a run killed after a
/// checkpoint and resumed ends bit-identical to one that ran straight through.
#[test]
fn runs_from_one_settled_state_and_resume_are_identical() {
    let source = tmp("settled");
    let mut spec = small();
    spec.duration = 0.02;
    spec.average_from = 0.01;
    let mut settle = SplitBottomRun::start(spec.clone(), &source, false).expect("start");
    settle.advance(&source, |_, _, _| {}).expect("advance");
    drop(settle);

    let (a, b) = (tmp("from-a"), tmp("from-b"));
    let mut ra = SplitBottomRun::from_settled(spec.clone(), &source, &a, false).expect("a");
    let mut rb = SplitBottomRun::from_settled(spec.clone(), &source, &b, false).expect("b");
    assert_eq!(positions(&ra), positions(&rb));
    ra.advance(&a, |_, _, _| {}).expect("advance a");
    // b: stop part-way (after its second checkpoint), drop, resume, finish.
    let start = rb.simulation.step;
    let stop = start + rb.shear_steps() / 2 + 3;
    rb.advance_until(&b, stop, &mut |_, _, _| {})
        .expect("first part");
    drop(rb);
    let mut rb = SplitBottomRun::resume(&b).expect("resume");
    assert!(
        rb.simulation.step < stop,
        "resumed from the last checkpoint"
    );
    rb.advance(&b, |_, _, _| {}).expect("rest");
    assert_eq!(ra.simulation.step, rb.simulation.step);
    assert_eq!(positions(&ra), positions(&rb));
    assert_eq!(ra.rows.len(), rb.rows.len());
    assert_eq!(ra.rows.last(), rb.rows.last());
    for d in [source, a, b] {
        std::fs::remove_dir_all(d).ok();
    }
}

fn error_of(spec: SplitBottomSpec) -> String {
    match SplitBottomRun::start(spec, Path::new("/nonexistent/never-created"), false) {
        Err(RunError::Scenario(e)) => e.to_string(),
        Err(e) => panic!("expected a scenario error, got {e}"),
        Ok(_) => panic!("expected an error"),
    }
}

/// Bad geometry is refused before anything is written, naming the key and the range.
#[test]
fn bad_geometry_gets_specific_errors() {
    let base = SplitBottomSpec::default();
    let cases: Vec<(SplitBottomSpec, &str)> = vec![
        (
            SplitBottomSpec {
                inner_radius: 0.09,
                ..base.clone()
            },
            "`split_radius`",
        ),
        (
            SplitBottomSpec {
                split_radius: 0.12,
                ..base.clone()
            },
            "`outer_radius`",
        ),
        (
            SplitBottomSpec {
                wedge_deg: 0.0,
                ..base.clone()
            },
            "`wedge_deg` = 0: must be in (0, 180]",
        ),
        (
            SplitBottomSpec {
                wedge_deg: 200.0,
                ..base.clone()
            },
            "`wedge_deg` = 200",
        ),
        (
            SplitBottomSpec {
                height: 0.0,
                ..base.clone()
            },
            "`height` = 0: must be a positive",
        ),
        (
            SplitBottomSpec {
                omega: -1.0,
                ..base.clone()
            },
            "`omega` = -1",
        ),
        (
            SplitBottomSpec {
                wedge_deg: 5.0,
                ..base.clone()
            },
            "must be at least",
        ),
        (
            SplitBottomSpec {
                scale: 0.01,
                ..base.clone()
            },
            "`scale`",
        ),
        (
            SplitBottomSpec {
                average_from: 10.0,
                ..base.clone()
            },
            "`average_from`",
        ),
    ];
    for (spec, expected) in cases {
        let e = error_of(spec);
        assert!(e.contains(expected), "{e:?} should contain {expected:?}");
    }
    // The narrow-wedge error names the smallest angle that works, and that angle passes.
    let e = error_of(SplitBottomSpec {
        wedge_deg: 5.0,
        ..base.clone()
    });
    let min: f64 = e
        .rsplit("at least ")
        .next()
        .and_then(|s| s.trim_end_matches('°').parse().ok())
        .expect("angle in the message");
    assert!(
        SplitBottomSpec {
            wedge_deg: min + 1e-3,
            ..base.clone()
        }
        .geometry()
        .is_ok()
    );
    assert!(
        SplitBottomSpec {
            wedge_deg: min - 1e-2,
            ..base
        }
        .geometry()
        .is_err()
    );
}
