//! Sweep bookkeeping: results tables, the validation verdicts, and resuming a point only
//! when its directory holds a run of the same parameters.

use rheodem::rheology::PhiLaw;
use rheodem::run::RunError;
use rheodem::setups::compare::comparison_markdown;
use rheodem::setups::shear_box::ShearBoxSpec;
use rheodem::setups::sweep::{PointResult, results_csv, run_point};
use std::path::PathBuf;
use std::sync::OnceLock;

/// A small dry point: 200 spheres, 1 strain unit (a second or so).
const POINT: &str = "mu_p = 0.5\ninertial = 0.05\nsoftness = 0.01\npolydispersity = 2.0\n\
particles = 200\nstrain = 1.0\ntransient_strain = 0.5\ncontrol_time = 10.0\n\
rows_per_strain = 40\nsnapshots = 0\nseed = 5\n";

fn spec(text: &str) -> ShearBoxSpec {
    toml::from_str(text).unwrap_or_else(|e| panic!("spec {text}: {e}"))
}

fn temp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rheodem-sweep-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The point, run once for the table and verdict tests.
fn finished() -> &'static PointResult {
    static RESULT: OnceLock<PointResult> = OnceLock::new();
    RESULT.get_or_init(|| {
        let dir = temp("finished");
        let r = run_point("small", &spec(POINT), &dir, 1, &mut |_, _| {}).expect("run");
        let _ = std::fs::remove_dir_all(&dir);
        assert!(
            r.steady_state.is_some(),
            "the point has a steady-state window"
        );
        r
    })
}

#[test]
fn every_results_row_has_the_header_s_fields() {
    let done = finished().clone();
    let mut empty = done.clone();
    empty.steady_state = None;
    let csv = results_csv(&[done, empty]);
    let mut lines = csv.lines();
    let header = lines.next().expect("header").split(',').count();
    for line in lines {
        // Only the last field (the quoted note) may hold commas.
        let fields = line.split(",\"").next().expect("row").split(',').count() + 1;
        assert_eq!(fields, header, "row {line}");
    }
}

/// The verdict column of the comparison table for one result.
fn verdict(r: &PointResult) -> String {
    let table = comparison_markdown(std::slice::from_ref(r));
    let row = table.lines().nth(2).expect("one row");
    row.trim_end_matches('|')
        .rsplit('|')
        .next()
        .expect("verdict")
        .trim()
        .to_string()
}

/// The result with its steady-state `φ` set to `phi` and `μ` to the law of Shi et al. 2020.
fn with_values(phi: f64, steady: bool) -> PointResult {
    let mut r = finished().clone();
    let p = r.spec.clone();
    let ss = r.steady_state.as_mut().expect("steady state");
    ss.volume_fraction.mean = phi;
    ss.steady = steady;
    let mu = rheodem::rheology::MuLaw::for_mu_p(p.mu_p).expect("μ_p = 0.5 law");
    ss.friction.mean = mu.mu(p.inertial, p.softness, 0.0);
    r
}

#[test]
fn verdicts_pass_miss_and_unchecked() {
    let p = &finished().spec;
    let seed = PhiLaw::for_mu_p(p.mu_p)
        .expect("μ_p = 0.5 law")
        .phi(p.inertial, p.softness, 0.0);
    assert_eq!(verdict(&with_values(seed * 1.01, true)), "pass");
    assert!(verdict(&with_values(seed * 1.03, true)).starts_with("MISS"));
    assert_eq!(
        verdict(&with_values(seed, false)),
        "MISS not steady",
        "a drifting window never passes"
    );
    // No fitted law for this μ_p and no cohesion: nothing was compared.
    let mut other = with_values(seed, true);
    other.spec.mu_p = 0.25;
    assert_eq!(verdict(&other), "unchecked: no fitted law for this μ_p");
    // A cohesive point whose Δφ sign the validation criteria name (docs/model.md §9) cannot
    // pass without its Bo = 0 reference.
    let mut cohesive = with_values(0.58, true);
    cohesive.spec.bond = 1.0;
    cohesive.spec.inertial = 0.02;
    assert!(verdict(&cohesive).contains("no Bo = 0 reference yet"));
    assert!(verdict(&cohesive).starts_with("MISS"));
}

#[test]
fn a_point_resumes_only_a_run_of_its_own_parameters() {
    let dir = temp("resume");
    let point = spec(POINT);
    let first = run_point("p", &point, &dir, 1, &mut |_, _| {}).expect("first run");
    // Without its result file the point resumes from the final checkpoint: same result.
    std::fs::remove_file(dir.join("steady_state.json")).expect("result file");
    let again = run_point("p", &point, &dir, 1, &mut |_, _| {}).expect("resumed");
    assert_eq!(again.steady_state, first.steady_state);
    // A changed field that the directory name does not show is refused, not resumed.
    std::fs::remove_file(dir.join("steady_state.json")).expect("result file");
    let mut longer = point.clone();
    longer.strain = 2.0;
    let err = run_point("p", &longer, &dir, 1, &mut |_, _| {}).expect_err("other strain");
    assert!(matches!(err, RunError::Mismatch(_)), "{err}");
    assert!(err.to_string().contains("remove the directory"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn figures_show_the_points_that_belong_to_them() {
    // The small point sits at I = 0.05, p* = 0.01, Bo = 0: it belongs to the figures
    // against I only.
    let figures = rheodem::setups::compare::comparison_figures(std::slice::from_ref(finished()))
        .expect("figures");
    let names: Vec<&str> = figures.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["phi-vs-inertial", "mu-vs-inertial"]);
    for f in &figures {
        let name = &f.name;
        assert!(f.svg.starts_with("<svg"), "{name}");
        assert!(
            f.svg.contains("Shi et al. 2020"),
            "{name}: the law is drawn"
        );
        assert!(f.svg.contains("<circle"), "{name}: the point is drawn");
        assert!(f.png.starts_with(b"\x89PNG"), "{name}: a PNG too");
    }
    // No finished point, no figure.
    assert!(
        rheodem::setups::compare::comparison_figures(&[])
            .expect("nothing to draw is not an error")
            .is_empty()
    );
}
