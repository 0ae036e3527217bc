//! Coarse-grained fields of the shear box, sampled on the fly by a run
//! (docs/coarse-graining.md §7): the slabs integrate to the box's own measurements at the
//! same rows, a run killed and resumed gives the same sums as one run straight through,
//! the lab and affine-drag descriptions of one state give the same fields, and the stored
//! samples coarse-grained afterwards give the run's own fields.

use rheodem::cg::periodic::{BoxFields, LabView, snapshot};
use rheodem::cg::{CgSums, ContactRecords, Kernel, fields};
use rheodem::domain::ShearDynamics;
use rheodem::run::{Run, samples};
use rheodem::scenario::{Scenario, build};
use rheodem::setups::shear_box::{ShearBoxSpec, SlabRates};
use std::path::{Path, PathBuf};

/// A fresh directory for one test's run.
fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rheodem-box-fields-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// A short frictional shear box of 256 particles with 6 slabs along `y`, averaged from a
/// strain of 1 to 2.
fn spec(dynamics: &str) -> ShearBoxSpec {
    toml::from_str(&format!(
        "mu_p = 0.3\ninertial = 0.05\nsoftness = 0.01\nparticles = 256\nstrain = 2.0\n\
         transient_strain = 1.0\ncheckpoints = 4\ncg_slabs = 6\nshear_dynamics = \"{dynamics}\""
    ))
    .expect("spec")
}

fn run(scenario: Scenario, dir: &Path, stop: Option<u64>) -> Run {
    let mut run = Run::start(scenario, Path::new("."), dir, 1, true).expect("start");
    match stop {
        Some(s) => {
            run.advance_until(dir, s, &mut |_| {}).expect("advance");
            drop(run);
            let mut run = Run::resume(dir).expect("resume");
            run.advance(dir, |_| {}).expect("advance");
            run
        }
        None => {
            run.advance(dir, |_| {}).expect("advance");
            run
        }
    }
}

/// The slab fields averaged over the grid equal the box's time series averaged over the
/// same rows: `φ` (the mass identity) and the stress components `σ_xy`, `σ_yy` (the
/// identity `∫ σ dV = Σ f ⊗ l` plus the kinetic part). The tolerance, 1e-4 relative,
/// covers the midpoint rule of the slab sum of a kernel smooth to its second derivative
/// (2e-6 measured at 512 particles) and the change of `L_y` under the stress control after
/// the grid was laid at the first sample. `σ_xx` is left out: its kinetic part is taken
/// about the local mean velocity here and about the imposed profile in the time series
/// (0.15 % apart at 512 particles).
#[test]
fn slabs_integrate_to_the_box_measurements_of_the_same_rows() {
    let dir = temp_dir("slabs");
    let scenario = spec("lab").scenario().expect("scenario");
    let start = scenario.fields.as_ref().expect("fields").start;
    let done = run(scenario, &dir, None);
    let fields = done.fields.as_ref().expect("fields");
    let sums = fields.sums.as_ref().expect("sampled");
    let rows: Vec<_> = done.rows.iter().filter(|r| r.time >= start).collect();
    assert_eq!(sums.snapshots as usize, rows.len(), "one sample per row");
    assert!(rows.len() > 20, "{} rows", rows.len());
    let (_, points) = fields.points().expect("points");
    assert_eq!(points.len(), 6);
    let mean = |q: &dyn Fn(usize) -> f64, n: usize| (0..n).map(q).sum::<f64>() / n as f64;
    let checks: [(&str, f64, f64); 3] = [
        (
            "φ",
            mean(&|k| points[k].volume_fraction, 6),
            mean(&|k| rows[k].volume_fraction, rows.len()),
        ),
        (
            "σ_xy",
            mean(&|k| points[k].stress[1], 6),
            mean(&|k| rows[k].stress[0][1], rows.len()),
        ),
        (
            "σ_yy",
            mean(&|k| points[k].stress[4], 6),
            mean(&|k| rows[k].stress[1][1], rows.len()),
        ),
    ];
    for (what, cg, series) in checks {
        assert!(
            (cg / series - 1.0).abs() < 1e-4,
            "{what}: slabs {cg} vs time series {series}"
        );
    }
    // The local dimensionless numbers come with the material the shear box passes.
    for p in &points {
        assert!(p.inertial_number > 0.0 && p.softness > 0.0, "{p:?}");
        assert_eq!(p.bond_number, 0.0);
    }
    // The spread of the slabs' rates about γ̇: their mean is γ̇ within the noise of a
    // short small run, and the extremes bracket it.
    let shear_rate = spec("lab").derive().expect("derived").shear_rate;
    let rates = SlabRates::of(&points, shear_rate).expect("rates");
    assert_eq!(rates.slabs, 6);
    assert!(rates.min <= 1.0 && 1.0 <= rates.max, "{rates:?}");
    let mean = points.iter().map(|p| p.strain_rate).sum::<f64>() / 6.0 / shear_rate;
    assert!((mean - 1.0).abs() < 0.3, "mean local rate {mean} γ̇");
    let csv = std::fs::read_to_string(dir.join("fields.csv")).expect("fields.csv");
    assert_eq!(csv.lines().count(), 7, "header and one row per slab");
    assert!(dir.join("fields.vti").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The sums live in the checkpoint: a run stopped half-way through its averaging window
/// and resumed ends with the same sums, bit for bit, as one run straight through.
#[test]
fn a_resumed_run_has_the_sums_of_an_uninterrupted_one() {
    let scenario = spec("lab").scenario().expect("scenario");
    let (a, b) = (temp_dir("straight"), temp_dir("resumed"));
    let straight = run(scenario.clone(), &a, None);
    let steps = straight.plan.steps;
    let resumed = run(scenario, &b, Some(steps * 3 / 4));
    let sums = |r: &Run| -> CgSums {
        r.fields
            .as_ref()
            .and_then(|f| f.sums.clone())
            .expect("sums")
    };
    assert_eq!(sums(&straight), sums(&resumed));
    for d in [a, b] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// One state described in the lab frame and under affine drag (stored velocities without
/// the mean flow, images without the velocity jump) gives the same snapshot velocities,
/// the same images and so the same fields.
#[test]
fn lab_and_affine_drag_descriptions_of_a_state_give_the_same_fields() {
    let scenario = spec("lab").scenario().expect("scenario");
    let mut lab = build(&scenario, Path::new(".")).expect("build").simulation;
    for _ in 0..200 {
        lab.step(false).expect("step");
    }
    let contacts = lab.step_with::<ContactRecords>().expect("step").0;
    let mut affine = lab.clone();
    let le = affine.domain.as_lees_edwards_mut().expect("sheared");
    le.dynamics = ShearDynamics::AffineDrag;
    for i in 0..affine.particles.len() {
        let r = affine.particles.position[i];
        affine.particles.velocity[i] -= affine.domain.mean_flow(r);
    }
    let box_fields = BoxFields::new(scenario.fields.as_ref().expect("fields")).expect("fields");
    let grid = box_fields.grid(&lab.domain).expect("grid");
    let (s_lab, s_affine) = (
        snapshot(&LabView::of(&lab), &contacts, &grid),
        snapshot(&LabView::of(&affine), &contacts, &grid),
    );
    assert_eq!(s_lab.images.len(), 2, "the two images along y");
    for (a, b) in s_lab.images.iter().zip(&s_affine.images) {
        assert_eq!(a, b);
    }
    for (a, b) in s_lab.bodies.iter().zip(&s_affine.bodies) {
        assert!((a.velocity - b.velocity).length() <= 1e-12 * a.velocity.length().max(1e-9));
    }
    let spec = scenario.fields.as_ref().expect("fields");
    let kernel = Kernel::new(spec.kernel, spec.width).expect("kernel");
    let field = |s| {
        let mut sums = CgSums::new(grid.clone()).expect("grid");
        sums.add_snapshot(&kernel, s);
        fields(&sums, spec.material.as_ref())
    };
    for (a, b) in field(&s_lab).iter().zip(&field(&s_affine)) {
        assert!((a.velocity[0] - b.velocity[0]).abs() <= 1e-9 * a.velocity[0].abs().max(1e-6));
        assert!((a.strain_rate / b.strain_rate - 1.0).abs() < 1e-9);
    }
}

/// A run that stores its samples (`cg_records`), killed in its averaging window and
/// resumed, coarse-grained afterwards from them gives its own on-the-fly fields bit for
/// bit (affine drag, so that the stored lab-frame view is exercised); with a wider kernel
/// the same samples keep the box's mass; starting over removes them; a run without samples
/// is refused by name.
#[test]
fn stored_samples_coarse_grained_afterwards_give_the_run_s_fields() {
    let mut box_spec = spec("affine-drag");
    box_spec.cg_records = true;
    let scenario = box_spec.scenario().expect("scenario");
    let dir = temp_dir("records");
    let steps = Run::start(scenario.clone(), Path::new("."), &dir, 1, true)
        .expect("start")
        .plan
        .steps;
    let done = run(scenario.clone(), &dir, Some(steps * 3 / 4));
    let on_the_fly = done.fields.as_ref().expect("fields");
    let read = samples::read_run(&dir).expect("read");
    let offline = samples::offline_fields(&dir, &read, &on_the_fly.spec).expect("offline");
    assert_eq!(
        offline.sums, on_the_fly.sums,
        "offline sums equal the run's"
    );

    let mut wide = on_the_fly.spec.clone();
    wide.width *= 2.0;
    let wider = samples::offline_fields(&dir, &read, &wide).expect("wider");
    let (_, narrow_points) = on_the_fly.points().expect("points");
    let (_, wide_points) = wider.points().expect("points");
    let mean_phi = |p: &[rheodem::cg::FieldPoint]| {
        p.iter().map(|q| q.volume_fraction).sum::<f64>() / p.len() as f64
    };
    // The grid is laid over the box of the first sample; the stress control changes `L_y`
    // afterwards, and the slab means of φ then differ between kernels by up to the
    // relative change of `L_y` over the window.
    let start = on_the_fly.spec.start;
    let heights: Vec<f64> = done
        .rows
        .iter()
        .filter(|r| r.time >= start)
        .map(|r| r.box_size[1])
        .collect();
    let spread = heights
        .iter()
        .fold(0.0f64, |m, &h| m.max((h / heights[0] - 1.0).abs()));
    let (a, b) = (mean_phi(&narrow_points), mean_phi(&wide_points));
    eprintln!("mean φ {a} and {b}; L_y spread {spread:e}");
    assert!(
        (a / b - 1.0).abs() <= spread.max(1e-6),
        "mean φ {a} against {b} with the wider kernel (L_y changed by {spread:e})"
    );

    // Starting over removes the earlier run's samples.
    drop(done);
    drop(Run::start(scenario, Path::new("."), &dir, 1, true).expect("start over"));
    let left = std::fs::read_dir(dir.join(samples::SAMPLES_DIR))
        .expect("samples' directory")
        .count();
    assert_eq!(left, 0, "samples left from the earlier run");

    let plain = temp_dir("no-records");
    run(spec("lab").scenario().expect("scenario"), &plain, None);
    let read = samples::read_run(&plain).expect("read");
    let spec = read.fields.as_ref().expect("fields").spec.clone();
    let err = samples::offline_fields(&plain, &read, &spec).expect_err("no samples");
    assert!(err.to_string().contains("no stored samples"), "{err}");
    for d in [dir, plain] {
        let _ = std::fs::remove_dir_all(d);
    }
}
