//! The chute set-up: the static balance of a tilted layer at rest (the closed form that
//! steady uniform flow must also obey), runs tilted from one settled layer, resumption,
//! and the refusals of other settings.

use rheodem::run::RunError;
use rheodem::setups::chute::{ChuteRun, ChuteSpec, Stage};
use std::path::{Path, PathBuf};

/// A layer of about 350 grains, 6 × 6 d_p and 6 d_p deep, resting at 10°, far below the
/// angle at which a layer of μ_p = 0.5 starts to flow (about 20°).
fn small() -> ChuteSpec {
    ChuteSpec {
        angle_deg: 10.0,
        height: 6.0,
        length: 6.0,
        width: 6.0,
        duration: 0.1,
        average_from: 0.04,
        bulk_margin: 1.5,
        rows: 20,
        snapshots: 1,
        checkpoints: 4,
        cg_every: 0.004,
        ..ChuteSpec::default()
    }
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rheodem-chute-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn positions(run: &ChuteRun) -> Vec<[f64; 3]> {
    let p = &run.simulation.particles;
    p.slot_of()
        .iter()
        .map(|&s| p.position[s as usize].to_array())
        .collect()
}

fn settled(dir: &Path) -> ChuteRun {
    let mut run = ChuteRun::open(small(), dir, None, false).expect("start");
    run.advance(dir, |_| {}).expect("advance");
    run
}

/// A layer at rest on the tilted base is in static equilibrium, so the closed forms of
/// steady uniform flow hold exactly in every coarse-grained slab: the normal stress is the
/// weight of the grains above, `σ_zz = ρ_p g cos θ ∫_z φ dz'`, and `|σ_xz|/σ_zz = tan θ`.
/// The tolerances (2 % on the bulk means, 5 % on the worst slab) cover the midpoint rule
/// of the integral over slabs half a diameter apart and the layer's residual creep; a
/// gravity component lost or doubled, or a stress off by the slab area, misses them by
/// far more.
#[test]
fn a_layer_at_rest_carries_its_weight_at_tan_theta() {
    let dir = tmp("rest");
    let run = settled(&dir);
    assert_eq!(run.stage, Stage::Done);
    let s = run.settled.as_ref().expect("settled");
    assert!(s.criterion_met, "{s:?}");
    // The surface near the height asked for (6 d_p above the base top).
    let d = run.spec.diameter;
    let depth = (s.surface_height - s.base_top) / d;
    assert!((5.0..7.5).contains(&depth), "layer {depth} d_p deep");
    let last = run.rows.last().expect("rows");
    assert!(
        last.mean_velocity.abs() < 1e-3,
        "the layer creeps at {} m/s",
        last.mean_velocity
    );
    let r = run.results().expect("results").expect("sampled");
    let bulk = r.bulk.as_ref().expect("a bulk");
    assert!(bulk.slabs >= 4, "{bulk:?}");
    let ratio = bulk.normal_stress_ratio.expect("ratio").mean;
    assert!((ratio - 1.0).abs() < 0.02, "σ_zz / weight above = {ratio}");
    assert!(bulk.normal_stress_worst < 0.05, "{bulk:?}");
    let mu = bulk.friction.expect("μ").mean;
    let tan = 10f64.to_radians().tan();
    assert!((mu / tan - 1.0).abs() < 0.02, "μ = {mu}, tan θ = {tan}");
    for p in r
        .profiles
        .iter()
        .filter(|p| (bulk.z[0]..=bulk.z[1]).contains(&p.z))
    {
        assert!(
            (p.friction / tan - 1.0).abs() < 0.05,
            "slab at z = {}: μ = {}",
            p.z,
            p.friction
        );
    }
    // Every output is there.
    for f in [
        "chute.toml",
        "summary.json",
        "timeseries.csv",
        "profiles.csv",
        "velocity.svg",
        "friction.svg",
        "volume-fraction.svg",
        "flow.svg",
        "settled.bin",
        "snapshots.pvd",
    ] {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    std::fs::remove_dir_all(dir).ok();
}

/// Runs tilted from one settled layer start from the same grains; a run stopped after a
/// checkpoint and resumed ends bit-identical to one that ran straight through; a changed
/// setting is refused naming the key, a settled layer of another chute too.
#[test]
fn runs_from_one_settled_layer_and_resume_are_identical() {
    let source = tmp("source");
    drop(settled(&source));
    let steep = ChuteSpec {
        angle_deg: 30.0,
        duration: 0.05,
        average_from: 0.02,
        ..small()
    };
    let (a, b) = (tmp("a"), tmp("b"));
    let mut ra = ChuteRun::open(steep.clone(), &a, Some(&source), false).expect("a");
    let mut rb = ChuteRun::open(steep.clone(), &b, Some(&source), false).expect("b");
    assert_eq!(positions(&ra), positions(&rb));
    assert_eq!(ra.stage, Stage::Flow);
    ra.advance(&a, |_| {}).expect("advance a");
    let stop = rb.simulation.step + rb.flow_steps() / 2 + 3;
    rb.advance_until(&b, stop, &mut |_| {}).expect("first part");
    drop(rb);
    let mut rb = ChuteRun::open(steep.clone(), &b, Some(&source), false).expect("resume");
    assert!(
        rb.simulation.step < stop,
        "resumed from the last checkpoint"
    );
    rb.advance(&b, |_| {}).expect("rest");
    assert_eq!(ra.simulation.step, rb.simulation.step);
    assert_eq!(positions(&ra), positions(&rb));
    assert_eq!(ra.rows.last(), rb.rows.last());
    // Steeper than the rest angle, the layer has started to flow down the slope.
    assert!(ra.rows.last().expect("rows").mean_velocity > 1e-3);
    drop((ra, rb));

    let e = match ChuteRun::open(
        ChuteSpec {
            angle_deg: 25.0,
            ..steep.clone()
        },
        &a,
        Some(&source),
        false,
    ) {
        Err(e) => e,
        Ok(_) => panic!("other settings resumed"),
    };
    assert!(
        matches!(&e, RunError::Changed { changes, .. } if changes.iter().any(|c| c.contains("angle_deg"))),
        "{e}"
    );
    let e = match ChuteRun::open(
        ChuteSpec {
            height: 8.0,
            ..steep
        },
        &tmp("c"),
        Some(&source),
        false,
    ) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("another layer tilted"),
    };
    assert!(e.contains("`height`") && e.contains("settled chute"), "{e}");
    for d in [source, a, b, tmp("c")] {
        std::fs::remove_dir_all(d).ok();
    }
}
