//! The `rheodem` program end to end: exit codes, messages, outputs.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn rheodem(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rheodem"))
        .args(args)
        .current_dir(workspace())
        .output()
        .expect("the binary runs")
}

/// Asserts that the program exited successfully, showing its error output otherwise.
fn assert_success(out: &Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn temp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rheodem-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn every_example_scenario_is_valid() {
    for example in ["examples/dense-packing.toml", "examples/wet-settling.toml"] {
        let out = rheodem(&["check", example]);
        assert!(
            out.status.success(),
            "{example}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let resolved = String::from_utf8_lossy(&out.stdout);
        assert!(resolved.contains("\"dt\"") && resolved.contains("\"seed\""));
    }
    let text =
        std::fs::read_to_string(workspace().join("examples/shear-box.toml")).expect("example");
    let spec: rheodem::setups::shear_box::ShearBoxSpec =
        toml::from_str(&text).expect("valid shear-box point");
    spec.scenario().expect("the point resolves to a scenario");
    let text =
        std::fs::read_to_string(workspace().join("validation/shear-box.toml")).expect("sweep");
    let sweep: rheodem::setups::sweep::SweepSpec = toml::from_str(&text).expect("valid sweep file");
    assert!(
        rheodem::setups::sweep::expand(&sweep)
            .expect("points expand")
            .len()
            >= 18
    );
}

#[test]
fn bad_input_exits_non_zero_with_the_key() {
    let out = rheodem(&[
        "shear-box",
        "--mu-p",
        "0.5",
        "--inertial",
        "-1",
        "--softness",
        "0.01",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("inertial") && err.contains("(0, 2]"), "{err}");

    let out = rheodem(&["run", "no/such/scenario.toml"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read no/such/scenario.toml"));

    let out = rheodem(&["resume", "no/such/run"]);
    assert!(!out.status.success());
}

#[test]
fn run_writes_its_outputs_and_resume_sees_it_complete() {
    let dir = temp("run");
    let scenario = dir.with_extension("toml");
    let text =
        std::fs::read_to_string(workspace().join("examples/dense-packing.toml")).expect("example");
    // A shorter version of the default job.
    let short = text
        .replace("count = 1000", "count = 150")
        .replace("duration = 0.3", "duration = 0.01")
        .replace("size = [0.04, 0.04, 0.04]", "size = [0.022, 0.022, 0.022]");
    std::fs::write(&scenario, short).expect("write scenario");
    let dir_s = dir.to_string_lossy().into_owned();
    let out = rheodem(&[
        "run",
        &scenario.to_string_lossy(),
        "--out",
        &dir_s,
        "--quiet",
        "--threads",
        "1",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in [
        "scenario.toml",
        "resolved.json",
        "timeseries.csv",
        "snapshots.pvd",
        "checkpoint.bin",
        "summary.json",
    ] {
        assert!(dir.join(f).exists(), "missing {f}");
    }
    let summary = std::fs::read_to_string(dir.join("summary.json")).expect("summary");
    assert!(summary.contains("\"status\": \"completed\""));
    assert!(summary.contains("\"commit\""));
    let out = rheodem(&["resume", &dir_s, "--quiet"]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("already complete"));
    let out = rheodem(&[
        "run",
        &scenario.to_string_lossy(),
        "--out",
        &dir_s,
        "--quiet",
    ]);
    assert!(
        !out.status.success(),
        "a second run into the same directory must be refused"
    );
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_file(&scenario);
}

/// A shear box that stores its fields' samples is coarse-grained again by `rheodem cg`:
/// with its own settings the file equals the run's `fields.csv`, with another slab count
/// it has that many rows, and `--mercury` exports the samples; a run without samples is
/// refused.
#[test]
fn cg_coarse_grains_a_shear_box_again_from_its_samples() {
    let dir = temp("cg-box");
    let dir_s = dir.to_string_lossy().into_owned();
    let out = rheodem(&[
        "shear-box",
        "--mu-p",
        "0.3",
        "--inertial",
        "0.05",
        "--softness",
        "0.01",
        "--particles",
        "256",
        "--strain",
        "1.5",
        "--transient-strain",
        "1",
        "--cg-slabs",
        "6",
        "--cg-records",
        "--out",
        &dir_s,
        "--quiet",
        "--threads",
        "1",
    ]);
    assert_success(&out);
    let out = rheodem(&["cg", &dir_s, "--threads", "1"]);
    assert_success(&out);
    let read = |p: PathBuf| std::fs::read_to_string(p).expect("fields.csv");
    assert_eq!(
        read(dir.join("cg/fields.csv")),
        read(dir.join("fields.csv")),
        "the run's own settings give the run's fields"
    );
    let again = dir.join("again");
    let out = rheodem(&[
        "cg",
        &dir_s,
        "--spacing",
        "0.5",
        "--width",
        "2",
        "--out",
        &again.to_string_lossy(),
    ]);
    assert_success(&out);
    let rows = read(again.join("fields.csv")).lines().count() - 1;
    assert!((10..=16).contains(&rows), "{rows} slabs of half a diameter");
    let out = rheodem(&["cg", &dir_s, "--mercury", "--out", &again.to_string_lossy()]);
    assert_success(&out);
    let data = read(again.join("mercury.data"));
    let blocks = data
        .lines()
        .filter(|l| l.split_whitespace().count() == 8)
        .count();
    let samples = std::fs::read_dir(dir.join("fields"))
        .expect("samples")
        .filter(|e| {
            e.as_ref()
                .is_ok_and(|e| e.file_name().to_string_lossy().ends_with(".box.json"))
        })
        .count();
    assert!(
        blocks > 0 && blocks == samples,
        "{blocks} blocks of {samples} samples"
    );
    let out = rheodem(&["cg", &dir_s, "--width=-1"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("--width"));
    std::fs::remove_dir_all(dir.join("fields")).expect("remove the samples");
    let out = rheodem(&["cg", &dir_s]);
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("no stored samples"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn contact_tools_write_csv_and_svg() {
    let dir = temp("curve");
    std::fs::create_dir_all(&dir).expect("dir");
    let prefix = dir.join("bridge");
    let out = rheodem(&[
        "contact",
        "curve",
        "--law",
        "liquid-bridge",
        "--out",
        &prefix.to_string_lossy(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = std::fs::read_to_string(prefix.with_extension("csv")).expect("csv");
    assert!(csv.starts_with("leg,overlap_m,normal_force_N"));
    let svg = std::fs::read_to_string(prefix.with_extension("svg")).expect("svg");
    assert!(svg.contains("<svg") && svg.contains("overlap"));
    // Any registered law by any of its names; its parameters by flag or by --param,
    // each error naming the option and the allowed range.
    let linear = dir.join("linear");
    let out = rheodem(&[
        "contact",
        "curve",
        "--law",
        "linear",
        "--param",
        "range=1e-4",
        "--out",
        &linear.to_string_lossy(),
    ]);
    assert_success(&out);
    let out = rheodem(&["contact", "curve", "--law", "willett", "--volume=-1e-12"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("--volume") && err.contains("zero or positive"),
        "{err}"
    );
    let out = rheodem(&[
        "contact",
        "curve",
        "--law",
        "reversible",
        "--param",
        "volume=1",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("--param volume") && err.contains("max_force"),
        "{err}"
    );
    let out = rheodem(&["contact", "curve", "--law", "glue"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("glue") && err.contains("liquid_bridge (willett"),
        "{err}"
    );
    let out = rheodem(&["contact", "equivalent", "--volume-nl", "75"]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("0.2622"));
    // Rabinovich's bridge: its curve drawn beside Willett's of the same γ, and its linear
    // equivalents (docs/model.md §2.11: f_max 1.71e-4 N at 75 nl, above Willett's 1.30e-4).
    let rabinovich = dir.join("rabinovich");
    let out = rheodem(&[
        "contact",
        "curve",
        "--law",
        "rabinovich",
        "--out",
        &rabinovich.to_string_lossy(),
    ]);
    assert_success(&out);
    let svg = std::fs::read_to_string(rabinovich.with_extension("svg")).expect("svg");
    assert!(svg.contains("Willett"), "no Willett curve beside it");
    let out = rheodem(&[
        "contact",
        "equivalent",
        "--law",
        "rabinovich",
        "--volume-nl",
        "75",
    ]);
    assert_success(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("Rabinovich") && text.contains("1.7106e-4"),
        "{text}"
    );
    // Every registry's laws, with the adhesive laws' parameters.
    let out = rheodem(&["contact", "laws"]);
    assert_success(&out);
    let listing = String::from_utf8_lossy(&out.stdout);
    for name in [
        "Normal laws",
        "linear (hooke)",
        "Spring laws",
        "linear (coulomb)",
        "luding (elasto_plastic, linear_plastic)",
        "plasticity_depth",
        "Adhesive laws",
        "liquid_bridge (willett",
        "surface_tension",
        "linear_irreversible",
    ] {
        assert!(listing.contains(name), "{name} missing from:\n{listing}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn sweep_archives_finished_points_and_does_not_rerun_them() {
    let dir = temp("sweep");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let out = dir.join("runs");
    let archive = dir.join("results");
    let sweep = dir.join("sweep.toml");
    let text = format!(
        "out = {:?}\nresults = {:?}\n[base]\nmu_p = 0.5\nsoftness = 0.01\n\
         polydispersity = 2.0\nparticles = 200\nstrain = 1.0\ntransient_strain = 0.5\n\
         control_time = 10.0\nsnapshots = 0\nseed = 3\n[grid]\ninertial = [0.05, 0.1]\n",
        out.display().to_string(),
        archive.display().to_string()
    );
    std::fs::write(&sweep, text).expect("sweep file");
    let sweep = sweep.display().to_string();

    let first = rheodem(&["sweep", &sweep, "--jobs", "2", "--quiet"]);
    assert!(first.status.success(), "{first:?}");
    assert!(String::from_utf8_lossy(&first.stdout).contains("2 of 2 points finished"));
    // (and the archive's lock file, `.lock`, which git ignores)
    let mut files: Vec<PathBuf> = std::fs::read_dir(&archive)
        .expect("archive written")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.file_name().is_some_and(|n| n != ".lock"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 3, "two points and results.csv: {files:?}");
    let before: Vec<Vec<u8>> = files
        .iter()
        .map(|f| std::fs::read(f).expect("read"))
        .collect();
    let table = std::fs::read_to_string(archive.join("results.csv")).expect("table");
    assert_eq!(
        table.lines().count(),
        3,
        "header and one row per point:\n{table}"
    );

    // A second run finds both points in the archive: nothing runs, nothing is rewritten
    // (not even in the last digit of a float).
    std::fs::remove_dir_all(&out).expect("remove run directories");
    let second = rheodem(&["sweep", &sweep, "--quiet"]);
    assert!(second.status.success(), "{second:?}");
    assert!(String::from_utf8_lossy(&second.stdout).contains("2 of 2 points finished"));
    let after: Vec<Vec<u8>> = files
        .iter()
        .map(|f| std::fs::read(f).expect("read"))
        .collect();
    assert_eq!(before, after, "archived results were rewritten");
    let reruns = std::fs::read_dir(&out)
        .expect("out directory")
        .filter(|e| e.as_ref().is_ok_and(|e| e.path().is_dir()))
        .count();
    assert_eq!(reruns, 0, "an archived point was run again");

    // A stale or missing archive table is rebuilt from the archived points.
    std::fs::remove_file(archive.join("results.csv")).expect("remove table");
    let third = rheodem(&["sweep", &sweep, "--quiet"]);
    assert!(third.status.success(), "{third:?}");
    let rebuilt = std::fs::read_to_string(archive.join("results.csv")).expect("table");
    assert_eq!(rebuilt, table);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `predict` prints the tabulated laws at a point (the numbers of Eq. 16 and Eq. 1A with the
/// shipped tables), JSON on request, and names a bad argument.
#[test]
fn predict_prints_the_laws_and_names_bad_arguments() {
    let out = rheodem(&[
        "predict",
        "--mu-p",
        "0.5",
        "--inertial",
        "0.02",
        "--softness",
        "0.01",
    ]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    // φ = 0.595 (1 − 0.02/5.383)(1 + 0.01/0.287) = 0.6134; regime (iii).
    assert!(text.contains("φ  = 0.6134"), "{text}");
    assert!(text.contains("regime (iii)"), "{text}");
    let out = rheodem(&[
        "predict",
        "--mu-p",
        "0.3",
        "--inertial",
        "0.02",
        "--softness",
        "0.01",
        "--bond",
        "3",
        "--json",
    ]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(v["regime"], "Reentrant");
    assert!(v["mu"].is_null(), "no Table 7 row at μ_p = 0.3");
    let dphi = v["delta_phi"]["value"].as_f64().expect("Δφ");
    assert!((dphi - -0.0072).abs() < 1e-4, "Δφ = {dphi}");
    let out = rheodem(&[
        "predict",
        "--mu-p",
        "0.3",
        "--inertial",
        "-0.02",
        "--softness",
        "0.01",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("inertial = -0.02") && err.contains("> 0"),
        "{err}"
    );
}

/// `fit` on the committed validation archive: the μ_p = 0.01 lab-frame points determine
/// Table 3's coefficients, printed above the paper's row; groups with too few points say so.
#[test]
fn fit_tabulates_the_archive_against_the_paper() {
    let out = rheodem(&["fit", "validation/results"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("## Shear dynamics: lab"), "{text}");
    let row = text
        .lines()
        .find(|l| l.starts_with("| 0.01 | this work (lab) | 0.65"))
        .unwrap_or_else(|| panic!("no fitted φ_0 ≈ 0.65 row at μ_p = 0.01:\n{text}"));
    assert!(row.contains(" ± "), "{row}");
    assert!(
        text.contains("| 0.01 | Shi et al. 2020 | 0.653 | 2.246 | 0.272 |"),
        "{text}"
    );
    assert!(
        text.contains("at least"),
        "the thin groups say what they lack: {text}"
    );
    let out = rheodem(&["fit", "examples"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no sweep results"));
}

/// `wet-study` over the committed split-bottom validation runs: the per-run table, the
/// fit of Eq. 20 over the three bridge volumes at 0.020 N/m beside the papers' slope, the
/// figures; a directory without runs is named in the error.
#[test]
fn wet_study_fits_the_committed_split_bottom_runs() {
    let figures = temp("wet-figures");
    let fig = figures.to_string_lossy().into_owned();
    let out = rheodem(&[
        "wet-study",
        "validation/runs-split-bottom-fields",
        "--figures",
        &fig,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("| wet-g0.02-v75 | Willett 75 nl, 0.02 N/m | 0.5 | 9.81 | 0.225 | 0.402 |"),
        "{text}"
    );
    assert!(text.contains("the papers give `a` = 0.9805"), "{text}");
    assert!(
        text.lines()
            .any(|l| l.starts_with("| 0.02 | 0.5, 9.81 | 3 | ")),
        "{text}"
    );
    for name in [
        "cstar-vs-rupture",
        "cstar-vs-tension",
        "torque-macro-vs-wall",
    ] {
        assert!(figures.join(format!("{name}.png")).exists(), "{name}");
    }
    let out = rheodem(&["wet-study", "examples"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no finished split-bottom run"));
    let _ = std::fs::remove_dir_all(&figures);
}

/// Four processes import the validation archive into one database at the same moment,
/// under four study names: every point of every study is there, and the CSV export lists
/// them.
#[test]
fn concurrent_processes_write_the_database_without_loss() {
    let dir = temp("db");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let db = dir.join("results.sqlite");
    let db_arg = db.to_string_lossy().into_owned();
    let archive = std::fs::read_dir(workspace().join("validation/results"))
        .expect("archive")
        .filter(|e| {
            e.as_ref()
                .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "json"))
        })
        .count();
    let children: Vec<_> = (0..4)
        .map(|k| {
            Command::new(env!("CARGO_BIN_EXE_rheodem"))
                .args(["db", "import", "validation/results", "--db", &db_arg])
                .args(["--study", &format!("s{k}")])
                .current_dir(workspace())
                .spawn()
                .expect("spawns")
        })
        .collect();
    for mut c in children {
        assert!(c.wait().expect("waits").success());
    }
    let out = rheodem(&["db", "status", "--db", &db_arg]);
    let text = String::from_utf8_lossy(&out.stdout);
    for k in 0..4 {
        assert!(text.contains(&format!("s{k}: {archive} points")), "{text}");
    }
    let out = rheodem(&["db", "export", "--db", &db_arg, "--study", "s2"]);
    let csv = String::from_utf8_lossy(&out.stdout);
    assert_eq!(csv.lines().count(), archive + 1, "{csv}");
    assert!(csv.lines().skip(1).all(|l| l.starts_with("s2,")));
    // The long form: one row per stored key, each point's `mu_p` among them.
    let out = rheodem(&["db", "export", "--db", &db_arg, "--study", "s2", "--values"]);
    assert_success(&out);
    let values = String::from_utf8_lossy(&out.stdout);
    assert!(values.starts_with("study,name,setup,kind,key,value,error,text\n"));
    let mu_rows = values
        .lines()
        .filter(|l| l.starts_with("s2,") && l.contains(",shear-box,parameter,mu_p,"))
        .count();
    assert_eq!(mu_rows, archive, "{values}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A tiny study end to end: `study run` runs its two points, a second `run` finds them
/// finished and runs nothing, `study status` counts them, and `study report` writes the
/// Markdown and the self-contained HTML with the validation table and the figures.
#[test]
fn a_tiny_study_runs_resumes_and_reports() {
    let dir = temp("study");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("tiny.toml");
    std::fs::write(
        &file,
        "title = \"tiny study\"\nout = \"runs/tiny\"\ndatabase = \"results.sqlite\"\n\
         [base]\nmu_p = 0.01\nsoftness = 0.01\nparticles = 512\nstrain = 2.0\n\
         transient_strain = 1.0\n[grid]\ninertial = [0.1, 0.2]\n",
    )
    .expect("study file");
    let f = file.to_string_lossy().into_owned();
    let out = rheodem(&["study", "run", &f, "--jobs", "2", "--quiet"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let point = dir.join("runs/tiny/mu0.01_i0.1_p0.01_bo0_none_w3_n512_s1/steady_state.json");
    let first = std::fs::metadata(&point)
        .and_then(|m| m.modified())
        .expect("finished");
    let out = rheodem(&["study", "run", &f, "--quiet"]);
    assert!(out.status.success());
    let again = std::fs::metadata(&point)
        .and_then(|m| m.modified())
        .expect("still there");
    assert_eq!(first, again, "a finished point was run again");
    let out = rheodem(&["study", "status", &f]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("2 of 2 points finished"));
    let out = rheodem(&["study", "report", &f]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report = dir.join("runs/tiny/report");
    let md = std::fs::read_to_string(report.join("report.md")).expect("markdown");
    assert!(
        md.starts_with("# tiny study") && md.contains("| 0.01 | 0.2 | 0.01 | 0 |"),
        "{md}"
    );
    let html = std::fs::read_to_string(report.join("index.html")).expect("html");
    assert!(html.contains("<table>") && html.contains("data:image/png;base64,"));
    let db = dir.join("results.sqlite").to_string_lossy().into_owned();
    let out = rheodem(&["db", "status", "--db", &db]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("tiny: 2 points"));
    let out = rheodem(&["study", "run", &f, "--quick"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no [quick] variant"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A split-bottom study end to end on a small cell: `study run` runs its two points (dry
/// and wet, chosen through a dotted grid key), a second run finds them archived, the status
/// counts them, the report builds from the archive, and a cluster task of a finished point
/// does nothing.
#[test]
fn a_split_bottom_study_runs_and_reports() {
    let dir = temp("cell-study");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("cells.toml");
    std::fs::write(
        &file,
        "title = \"two small cells\"\nsetup = \"split-bottom\"\nout = \"runs/cells\"\n\
         results = \"archive\"\ndatabase = \"results.sqlite\"\n[base]\n\
         inner_radius = 0.02\nouter_radius = 0.05\n\
         split_radius = 0.035\nheight = 0.012\nomega = 1.0\nduration = 0.08\n\
         average_from = 0.04\nrows = 16\nsnapshots = 1\ncheckpoints = 2\n\
         time_step = \"mean-pair\"\n[grid]\n\"cohesion.law\" = [\"dry\"]\n\
         [[point]]\ncohesion = { law = \"willett\", surface_tension = 0.02, volume = 75e-12 }\n",
    )
    .expect("study file");
    let f = file.to_string_lossy().into_owned();
    let out = rheodem(&["study", "run", &f, "--jobs", "2", "--quiet"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("2 of 2 points finished"));
    let archived = dir.join("archive/willett-g0.02-v75-omega1-g9.81-s1.json");
    let first = std::fs::metadata(&archived)
        .and_then(|m| m.modified())
        .expect("archived");
    let out = rheodem(&["study", "run", &f, "--quiet"]);
    assert!(out.status.success());
    let again = std::fs::metadata(&archived)
        .and_then(|m| m.modified())
        .expect("still archived");
    assert_eq!(first, again, "a finished point was run again");
    // A point finished in its directory but missing from the archive (a run killed before
    // it archived it) is archived by the next `study run`, without running it.
    let summary = dir.join("runs/cells/willett-g0.02-v75-omega1-g9.81-s1/summary.json");
    let ran = std::fs::metadata(&summary)
        .and_then(|m| m.modified())
        .expect("its summary");
    std::fs::remove_file(&archived).expect("remove the archived copy");
    let out = rheodem(&["study", "run", &f, "--quiet"]);
    assert!(out.status.success());
    assert!(archived.exists(), "the finished point was not archived");
    let still = std::fs::metadata(&summary)
        .and_then(|m| m.modified())
        .expect("its summary");
    assert_eq!(ran, still, "a finished point was opened again");
    let out = rheodem(&["study", "status", &f]);
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("cells: 2 of 2 points finished"),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    // The run directories may go: the report reads the archive.
    std::fs::remove_dir_all(dir.join("runs/cells/dry-omega1-g9.81-s1")).expect("remove");
    let out = rheodem(&["study", "report", &f]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let md = std::fs::read_to_string(dir.join("runs/cells/report/report.md")).expect("report");
    assert!(md.starts_with("# two small cells"), "{md}");
    assert!(md.contains("2 of 2 points finished"), "{md}");
    let out = rheodem(&["study", "run-point", &f, "--point", "dry-omega1-g9.81-s1"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("finished already"));
    // Both cells went into the database as they finished; collect stores them again.
    let db = dir.join("results.sqlite").to_string_lossy().into_owned();
    let out = rheodem(&["db", "status", "--db", &db]);
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("cells: 2 split-bottom cells"),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    let out = rheodem(&["study", "collect", &f]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("2 stored under study \"cells\""));
    let out = rheodem(&["db", "export", "--db", &db, "--cells"]);
    let csv = String::from_utf8_lossy(&out.stdout);
    assert!(csv.starts_with("study,name,law,"), "{csv}");
    assert_eq!(csv.lines().count(), 3, "{csv}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every shipped study reads, and has a quick variant of at most 10 points.
#[test]
fn shipped_studies_are_valid_and_have_quick_variants() {
    let mut n = 0;
    for entry in std::fs::read_dir(workspace().join("studies")).expect("studies/") {
        let path = entry.expect("entry").path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let text = std::fs::read_to_string(&path).expect("readable");
        let study = rheodem::setups::study::StudySpec::from_toml(&text)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        // Both variants expand to valid points of a registered set-up.
        rheodem::setups::registry::study_points(&study, false)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let quick = rheodem::setups::registry::study_points(&study, true)
            .unwrap_or_else(|e| panic!("{}: quick variant: {e}", path.display()))
            .1
            .len();
        assert!(quick <= 10, "{}: {quick} quick points", path.display());
        n += 1;
    }
    assert!(n >= 3, "{n} studies shipped");
}

/// `rheodem setups` lists every registered set-up; with a name it prints that set-up's
/// parameter table (the split-bottom cell's `mu_p`, stored as `friction`, shows the spec's
/// default); an unknown name is refused with the known ones.
#[test]
fn setups_lists_the_set_ups_and_their_parameters() {
    let out = rheodem(&["setups"]);
    assert_success(&out);
    let list = String::from_utf8_lossy(&out.stdout);
    assert!(
        list.contains("shear-box") && list.contains("split-bottom") && list.contains("chute"),
        "{list}"
    );
    let out = rheodem(&["setups", "split-bottom"]);
    assert_success(&out);
    let table = String::from_utf8_lossy(&out.stdout);
    let default = rheodem::setups::split_bottom::SplitBottomSpec::default().friction;
    let row = table
        .lines()
        .find(|l| l.starts_with("| `mu_p` |"))
        .unwrap_or_else(|| panic!("no mu_p row: {table}"));
    assert!(row.ends_with(&format!("| {default} |")), "{row}");
    let out = rheodem(&["setups", "chute"]);
    assert_success(&out);
    assert!(String::from_utf8_lossy(&out.stdout).contains("| `angle_deg` |"));
    let out = rheodem(&["setups", "hopper"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("`hopper` is not a set-up; known: shear-box, split-bottom, chute"),
        "{err}"
    );
}

/// `compare` and `fit` over several directories: a later directory's point replaces the
/// point of the same name (the validation's two points rerun to 60 strain units), so the
/// table shows the long run, steady and passing, where the first directory alone shows the
/// 15-strain run flagged not steady; the fit changes with it.
#[test]
fn later_directories_replace_points_of_the_same_name() {
    let results = workspace().join("validation/results");
    let long = workspace().join("validation/results-long");
    let (results, long) = (
        results.to_string_lossy().into_owned(),
        long.to_string_lossy().into_owned(),
    );
    let row = |args: &[&str]| {
        let out = rheodem(args);
        assert!(out.status.success(), "{args:?}: {out:?}");
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .find(|l| l.starts_with("| 0.01 | 0.15 | 0.005 | 0 | none |"))
            .map(str::to_string)
            .expect("the point's row")
    };
    let alone = row(&["compare", &results]);
    assert!(
        alone.contains("5.0–15.0") && alone.ends_with("MISS not steady |"),
        "{alone}"
    );
    let merged = row(&["compare", &results, &long]);
    assert!(
        merged.contains("20.0–60.0") && merged.ends_with("pass |"),
        "{merged}"
    );
    let fit = |args: &[&str]| String::from_utf8_lossy(&rheodem(args).stdout).into_owned();
    let (before, after) = (fit(&["fit", &results]), fit(&["fit", &results, &long]));
    assert!(
        before.contains("| 0.01 | this work (lab) | 0.65233"),
        "{before}"
    );
    assert!(
        after.contains("| 0.01 | this work (lab) | 0.65192"),
        "{after}"
    );
    let out = rheodem(&["fit"]);
    assert!(!out.status.success(), "a directory is required");
}

/// `bench` takes the normal law and the chute problem, and refuses the options a problem
/// does not have, naming them.
#[test]
fn bench_takes_its_problems_and_names_what_they_refuse() {
    let out = rheodem(&[
        "bench",
        "--normal",
        "hertz",
        "--threads",
        "1",
        "--warmup",
        "0",
        "--steps",
        "5",
        "--cohesion",
        "none",
    ]);
    assert_success(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("hertz, frictional") && text.contains("throughput:"),
        "{text}"
    );
    let out = rheodem(&["bench", "--problem", "chute", "--cohesion", "reversible"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--cohesion"), "{err}");
    let out = rheodem(&["bench", "--write-lammps-data", "x.data"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("--problem chute"),
        "{err}"
    );
    let out = rheodem(&["bench", "--problem", "hopper"]);
    assert!(!out.status.success());
}

/// `bench` saves a warmed-up state and times it again on any thread count, the members
/// of a team in turn included; it refuses thread counts past its range and options a
/// loaded state already fixes, naming them.
#[test]
fn bench_saves_a_state_and_times_it_on_many_threads() {
    let dir = temp("bench-state");
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    let state = dir.join("state.bin");
    let state = state.to_str().expect("a UTF-8 temporary path");
    let out = rheodem(&[
        "bench",
        "--threads",
        "1",
        "--cohesion",
        "none",
        "--warmup",
        "5",
        "--save-state",
        state,
    ]);
    assert_success(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("4096 particles at step 5"), "{text}");
    let out = rheodem(&[
        "bench",
        "--threads",
        "1,3",
        "--members-in-turn",
        "--load-state",
        state,
        "--warmup",
        "0",
        "--steps",
        "3",
    ]);
    assert_success(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("state, threads 1:") && text.contains("state, threads 3:"),
        "{text}"
    );
    for (args, named) in [
        (vec!["--threads", "0"], "--threads 0"),
        (vec!["--threads", "2000"], "--threads 2000"),
        (
            vec!["--load-state", state, "--cohesion", "reversible"],
            "--cohesion",
        ),
        (
            vec!["--problem", "chute", "--replicate", "2"],
            "--replicate",
        ),
    ] {
        let out = rheodem(&[&["bench"], &args[..]].concat());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(named),
            "{args:?}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
