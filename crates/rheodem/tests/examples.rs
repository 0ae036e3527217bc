//! Every file in `examples/` runs: scenarios through `Run::start` / `Run::advance` (the
//! path of `rheodem run`), shear-box points through `ShearBoxSpec::scenario` (the path of
//! `rheodem shear-box`), each cut to a handful of steps so that the test stays fast. The
//! directory is enumerated, so a new example is covered without touching this file.

use rheodem::run::Run;
use rheodem::scenario::Scenario;
use rheodem::scenario::spec::PreparationSpec;
use rheodem::setups::shear_box::ShearBoxSpec;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Steps of every shortened run.
const STEPS: u64 = 20;

fn examples_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

/// What an example file is.
enum Example {
    Scenario(Box<Scenario>),
    ShearBox(ShearBoxSpec),
}

/// Reads an example as a scenario or, failing that, as a shear-box point; panics with
/// both errors when it is neither.
fn parse(path: &Path) -> Example {
    let text = std::fs::read_to_string(path).expect("readable example");
    match Scenario::from_toml(&text) {
        Ok(s) => Example::Scenario(Box::new(s)),
        Err(as_scenario) => match toml::from_str::<ShearBoxSpec>(&text) {
            Ok(p) => Example::ShearBox(p),
            Err(as_point) => panic!(
                "{}: neither a scenario ({as_scenario}) nor a shear-box point ({as_point})",
                path.display()
            ),
        },
    }
}

/// The same scenario, cut short: `STEPS` steps, one output of each kind, and a
/// preparation (if any) at the fastest accepted compression (0.1 strain per contact time)
/// with one contact time of relaxation. Everything else — particles, laws, walls, box —
/// is the example's.
fn shortened(mut s: Scenario) -> Scenario {
    s.run.duration = None;
    s.run.steps = Some(STEPS);
    s.output.timeseries_rows = STEPS;
    s.output.snapshots = 1;
    s.output.checkpoints = 1;
    if let Some(p) = &mut s.preparation {
        *p = PreparationSpec {
            strain_per_contact_time: Some(0.1),
            relax_contact_times: Some(1.0),
            ..p.clone()
        };
    }
    s
}

/// Runs every example for `STEPS` steps and checks the run: it completes (`STEPS` steps,
/// simulated time `STEPS · dt`), every time-series row is finite with energies ≥ 0
/// (kinetic; the elastic energy includes negative adhesive potentials), a volume fraction
/// in `(0, 0.74]` equal to the free particles' volume over the box's, a coordination
/// number `2 N_c / N`, and every free particle still inside the box along the
/// non-periodic axes. A scenario with a pressure preparation reports its compression and
/// starts its run compressed (`tr σ / 3 > 0`; the target itself is reached only
/// dynamically at this compression rate, so it is not checked); a shear-box point starts
/// sheared at its `γ̇`, under `σ_yy` control, with `σ_yy > 0`.
/// Each example must finish within 10 s (measured: well under 2 s each).
#[test]
fn every_example_runs_a_few_steps() {
    let mut files: Vec<PathBuf> = std::fs::read_dir(examples_dir())
        .expect("examples/")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 3, "examples found: {files:?}");
    let mut kinds = (0, 0);
    for path in &files {
        let start = Instant::now();
        let name = path.file_name().expect("name").to_string_lossy();
        let (scenario, shear_rate) = match parse(path) {
            Example::Scenario(s) => {
                kinds.0 += 1;
                (*s, None)
            }
            Example::ShearBox(point) => {
                kinds.1 += 1;
                let derived = point.derive().expect("valid point");
                (point.scenario().expect("point scenario"), Some(derived))
            }
        };
        let pressure_target = scenario.preparation.as_ref().and_then(|p| p.pressure);
        let scenario = shortened(scenario);
        let dir = std::env::temp_dir().join(format!(
            "rheodem-example-{}-{}",
            name.trim_end_matches(".toml"),
            std::process::id()
        ));
        let base = path.parent().expect("examples/");
        let mut run =
            Run::start(scenario, base, &dir, 1, true).unwrap_or_else(|e| panic!("{name}: {e}"));
        run.advance(&dir, |_| {})
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let sim = &run.simulation;
        assert!(run.is_complete(), "{name}");
        assert_eq!(sim.step, STEPS, "{name}");
        assert!(
            (sim.time / (STEPS as f64 * sim.dt) - 1.0).abs() < 1e-12,
            "{name}"
        );
        assert_eq!(
            run.rows.len() as u64,
            STEPS + 1,
            "{name}: the initial row and one per step"
        );
        let p = &sim.particles;
        let free = p.free_count();
        for o in &run.rows {
            assert!(o.is_finite(), "{name}: {o:?}");
            assert!(o.kinetic_translational >= 0.0 && o.kinetic_rotational >= 0.0);
            assert!(
                o.volume_fraction > 0.0 && o.volume_fraction <= 0.74,
                "{name}: {o:?}"
            );
            assert!((o.coordination - 2.0 * o.contacts as f64 / free as f64).abs() < 1e-12);
        }
        let last = run.rows.last().expect("rows");
        let volume = last.box_size.iter().product::<f64>();
        assert!(
            (last.volume_fraction * volume / p.free_volume() - 1.0).abs() < 1e-12,
            "{name}"
        );
        let (lo, hi) = (sim.domain.lo, sim.domain.hi);
        for i in 0..p.len() {
            for k in 0..3 {
                if !sim.domain.periodic[k] && p.motion[i].is_free() {
                    assert!(
                        p.position[i][k] > lo[k] - p.radius[i]
                            && p.position[i][k] < hi[k] + p.radius[i],
                        "{name}: particle {i} left the box: {}",
                        p.position[i]
                    );
                }
            }
        }
        if pressure_target.is_some() {
            assert!(last.mean_stress() > 0.0, "{name}: {last:?}");
            let report = run.resolved.preparation.as_ref().expect("prepared");
            assert!(
                report.compression_steps > 0 && report.mean_stress > 0.0,
                "{name}"
            );
        }
        if let Some(derived) = shear_rate {
            let le = sim.domain.as_lees_edwards().expect("sheared box");
            assert_eq!(le.shear_rate, derived.shear_rate, "{name}");
            assert!(last.stress[1][1] > 0.0, "{name}: {last:?}");
            assert!(sim.stress_control.is_some(), "{name}");
        }
        for f in [
            "scenario.toml",
            "resolved.json",
            "timeseries.csv",
            "summary.json",
        ] {
            assert!(dir.join(f).exists(), "{name}: no {f}");
        }
        let _ = std::fs::remove_dir_all(&dir);
        let seconds = start.elapsed().as_secs_f64();
        eprintln!(
            "{name}: {STEPS} steps of {} particles in {seconds:.2} s",
            p.len()
        );
        assert!(seconds < 10.0, "{name} took {seconds:.1} s");
    }
    assert!(
        kinds.0 >= 1 && kinds.1 >= 1,
        "scenarios and shear-box points"
    );
}
