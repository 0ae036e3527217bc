//! Regression tests of the second hostile-user audit (R2–R8), end to end through the
//! `rheodem` binary: one table of bad inputs, each with the command and the key its error
//! must name, and the tests of the run directories (stale results, mixed-up directories,
//! leftovers, failure status).

mod common;

use common::{rheodem_in, stderr, temp};
use std::process::Command;

/// A scenario of a 2 cm box (periodic along `periodic`) with `extra` appended: a particle
/// group, gravity, a skin.
fn scenario(periodic: &str, head: &str, extra: &str) -> String {
    format!(
        "seed = 1\n{head}\n[domain]\nsize = [0.02, 0.02, 0.02]\nperiodic = [{periodic}]\n\
         [[species]]\nname = \"g\"\ndensity = 2000.0\n[[contact]]\n\
         normal = {{ stiffness = 100.0, restitution = 0.8 }}\n[run]\nsteps = 10\n{extra}"
    )
}

fn one_sphere(position: &str) -> String {
    format!(
        "[[particles]]\nkind = \"explicit\"\nspecies = \"g\"\n\
         spheres = [{{ radius = 0.001, position = {position} }}]\n"
    )
}

fn random(count: &str) -> String {
    format!(
        "[[particles]]\nkind = \"random\"\nspecies = \"g\"\ncount = {count}\nmean_diameter = 0.002\n"
    )
}

/// A small split-bottom cell (about 800 grains) as a config file: runs in a few seconds.
const SMALL_CELL: &str = "inner_radius = 0.02\nouter_radius = 0.05\nsplit_radius = 0.035\n\
    height = 0.012\nomega = 1.0\nduration = 0.02\naverage_from = 0.01\nrows = 8\n\
    snapshots = 0\ntime_step = \"mean-pair\"\n";

/// The split-bottom options of a short run (the defaults' averaging window is too long).
const SHORT: [&str; 4] = ["--duration", "0.05", "--average-from", "0.01"];

/// Every input quoted in R2–R8 that a command must refuse before it runs: the files it
/// needs, the command, and what its error must say (the key, and never the wrong one).
#[test]
fn r2_to_r8_bad_inputs_are_refused_naming_their_key() {
    let dir = temp("audit2", "table");
    let files: &[(&str, String)] = &[
        (
            "big.toml",
            scenario("true, true, true", "", &random("1000000")),
        ),
        (
            "negative-count.toml",
            scenario("true, true, true", "", &random("-3")),
        ),
        (
            "fractional-count.toml",
            scenario("true, true, true", "", &random("2.5")),
        ),
        (
            "outside.toml",
            scenario("true, true, false", "", &one_sphere("[0.01, 0.01, 0.5]")),
        ),
        (
            "gravity.toml",
            scenario(
                "true, true, true",
                "gravity = [0.0, 0.0, -1e300]",
                &one_sphere("[0.01, 0.01, 0.01]"),
            ),
        ),
        (
            "skin.toml",
            scenario(
                "true, true, true",
                "",
                &format!(
                    "[neighbor]\nskin = 0.01\n{}",
                    one_sphere("[0.01, 0.01, 0.01]")
                ),
            ),
        ),
        ("bad-mu.toml", "mu_p = \"x\"\n".to_string()),
        (
            "negative-tension-study.toml",
            "title = \"t\"\nsetup = \"split-bottom\"\nout = \"runs\"\n[base]\n\
             duration = 0.05\naverage_from = 0.01\n\
             cohesion = { law = \"willett\", surface_tension = 0.02, volume = 75e-12 }\n\
             [grid]\n\"cohesion.surface_tension\" = [0.02, -0.02]\n"
                .to_string(),
        ),
        (
            "base-typo-study.toml",
            "title = \"t\"\nsetup = \"split-bottom\"\nout = \"runs\"\n[base]\nomgea = 0.5\n"
                .to_string(),
        ),
    ];
    for (name, text) in files {
        std::fs::write(dir.join(name), text).expect("fixture");
    }
    let with_short = |args: &[&'static str]| -> Vec<&'static str> {
        let mut v = vec!["split-bottom"];
        v.extend_from_slice(args);
        v.extend_from_slice(&SHORT);
        v.extend_from_slice(&["--out", "never"]);
        v
    };
    // (what, command, the error must contain all of, and none of)
    type Row<'a> = (&'a str, Vec<&'a str>, Vec<&'a str>, Vec<&'a str>);
    let table: Vec<Row> = vec![
        (
            "R2 absurd scale",
            with_short(&["--scale", "100"]),
            vec!["`scale`"],
            vec![],
        ),
        (
            "R2 scale beyond the memory limit",
            with_short(&["--scale", "2", "--max-memory", "100MB"]),
            vec!["`scale`", "--max-memory"],
            vec![],
        ),
        (
            "R2 scenario beyond the memory limit (run)",
            vec!["run", "big.toml", "--out", "never", "--max-memory", "100MB"],
            vec!["particles[0].count", "--max-memory"],
            vec![],
        ),
        (
            "R2 scenario beyond the memory limit (check)",
            vec!["check", "big.toml", "--max-memory", "100MB"],
            vec!["particles[0].count"],
            vec![],
        ),
        (
            "R2 a malformed memory limit",
            vec!["check", "big.toml", "--max-memory", "lots"],
            vec!["--max-memory"],
            vec![],
        ),
        (
            "R3 negative surface tension",
            with_short(&["--law", "willett", "--surface-tension", "-0.02"]),
            vec!["`surface_tension` = -0.02"],
            vec![],
        ),
        (
            "R3 negative surface tension in a study grid",
            vec!["study", "run", "negative-tension-study.toml"],
            vec!["surface_tension"],
            vec!["line"],
        ),
        (
            "R3 surface tension without the Willett law",
            with_short(&["--surface-tension", "0.02"]),
            vec!["`surface_tension`", "law = liquid_bridge"],
            vec![],
        ),
        (
            "R3 bridge volume without the Willett law",
            with_short(&["--volume-nl", "75"]),
            vec!["`volume_nl`"],
            vec![],
        ),
        (
            "R3 negative maximum force",
            with_short(&[
                "--law",
                "linear",
                "--max-force",
                "-1",
                "--adhesive-stiffness",
                "1",
            ]),
            vec!["`max_force` = -1"],
            vec![],
        ),
        (
            "R3 a sphere outside a non-periodic box",
            vec!["check", "outside.toml"],
            vec!["particles[0].spheres[0].position", "non-periodic axis z"],
            vec![],
        ),
        (
            "R3 absurd gravity",
            vec!["check", "gravity.toml"],
            vec!["`gravity`", "max_overlap"],
            vec![],
        ),
        (
            "R3 a bad config value hidden by an option",
            vec![
                "shear-box",
                "--config",
                "bad-mu.toml",
                "--mu-p",
                "0.5",
                "--inertial",
                "0.1",
                "--softness",
                "0.01",
                "--out",
                "never",
            ],
            vec!["mu_p", "bad-mu.toml"],
            vec![],
        ),
        (
            "R4 a huge bridge volume",
            with_short(&["--law", "willett", "--volume-nl", "1e9"]),
            vec!["cohesion.volume"],
            vec!["wedge_deg"],
        ),
        (
            "R4 a huge skin",
            vec!["check", "skin.toml"],
            vec!["neighbor.skin"],
            vec!["domain.size"],
        ),
        (
            "R4 a negative count",
            vec!["check", "negative-count.toml"],
            vec!["`particles[0].count` = -3"],
            vec![],
        ),
        (
            "R4 a fractional count",
            vec!["check", "fractional-count.toml"],
            vec!["`particles[0].count` = 2.5"],
            vec![],
        ),
        (
            "R4 a typo in a study's [base]",
            vec!["study", "run", "base-typo-study.toml"],
            vec!["omgea"],
            vec!["[[point]]"],
        ),
    ];
    for (what, args, must, must_not) in table {
        let out = rheodem_in(&dir, &args);
        let err = stderr(&out);
        assert!(!out.status.success(), "{what}: accepted ({args:?})");
        assert_eq!(
            out.status.code(),
            Some(1),
            "{what}: not a clean error: {err}"
        );
        for m in must {
            assert!(
                err.contains(m),
                "{what}: the error does not name {m}: {err}"
            );
        }
        for m in must_not {
            assert!(!err.contains(m), "{what}: the error names {m}: {err}");
        }
        assert!(!dir.join("never").exists(), "{what}: left a run directory");
    }
    // R4: an operating system's error is printed once.
    let out = rheodem_in(&dir, &["run", "missing.toml"]);
    let err = stderr(&out);
    assert_eq!(err.matches("os error 2").count(), 1, "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// R5: a split-bottom command with other settings than the run in its directory is
/// refused, naming what changed (with --force to replace it); the same command resumes.
/// R6: each command refuses a directory another command made, and says how to continue
/// it. R7: a killed writer's temporaries are removed when a command takes the directory.
/// R8: `cg` refuses a run without snapshots before writing anything.
#[test]
fn r5_to_r8_run_directories() {
    let dir = temp("audit2", "dirs");
    std::fs::write(dir.join("small.toml"), SMALL_CELL).expect("config");
    let cell = [
        "split-bottom",
        "--config",
        "small.toml",
        "--out",
        "cell",
        "--quiet",
    ];
    let out = rheodem_in(&dir, &cell);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        std::fs::read_to_string(dir.join("cell/made-by"))
            .expect("marker")
            .trim(),
        "split-bottom"
    );
    // R5: other settings are refused, the same command resumes (and rewrites outputs).
    let mut faster = cell.to_vec();
    faster.extend_from_slice(&["--omega", "2"]);
    let out = rheodem_in(&dir, &faster);
    let err = stderr(&out);
    assert!(!out.status.success(), "a changed run was resumed");
    assert!(
        err.contains("omega: 1.0 → 2.0") && err.contains("--force"),
        "{err}"
    );
    // R7: a stale temporary goes when the directory is taken again.
    let stale = dir.join("cell/.checkpoint.bin.999999.3.tmp");
    std::fs::write(&stale, b"half a checkpoint").expect("stale file");
    let out = rheodem_in(&dir, &cell);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(!stale.exists(), "the stale temporary is left");

    // R6: a scenario run beside it.
    let box_run = scenario("true, true, true", "", &one_sphere("[0.01, 0.01, 0.01]"));
    std::fs::write(dir.join("one.toml"), box_run).expect("scenario");
    let out = rheodem_in(&dir, &["run", "one.toml", "--out", "box", "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    for (args, must) in [
        (
            vec!["run", "one.toml", "--out", "cell"],
            "rheodem split-bottom",
        ),
        (vec!["resume", "cell"], "rheodem split-bottom"),
        (
            vec![
                "split-bottom",
                "--out",
                "box",
                "--duration",
                "0.05",
                "--average-from",
                "0.01",
            ],
            "rheodem resume box",
        ),
        (
            vec![
                "shear-box",
                "--mu-p",
                "0.5",
                "--inertial",
                "0.1",
                "--softness",
                "0.01",
                "--out",
                "box",
            ],
            "rheodem resume box",
        ),
    ] {
        let out = rheodem_in(&dir, &args);
        let err = stderr(&out);
        assert!(!out.status.success(), "{args:?} accepted");
        assert!(err.contains(must), "{args:?}: {err}");
    }
    // A run killed before its first checkpoint: its marker says what to do.
    std::fs::create_dir_all(dir.join("killed")).expect("dir");
    std::fs::write(dir.join("killed/made-by"), "run\n").expect("marker");
    let err = stderr(&rheodem_in(&dir, &["resume", "killed"]));
    assert!(
        err.contains("rheodem run SCENARIO --out killed --force"),
        "{err}"
    );
    // A directory of old files, made before the marker: recognised by its files.
    std::fs::create_dir_all(dir.join("old")).expect("dir");
    std::fs::write(dir.join("old/split-bottom.toml"), SMALL_CELL).expect("old spec");
    let err = stderr(&rheodem_in(&dir, &["resume", "old"]));
    assert!(err.contains("rheodem split-bottom"), "{err}");

    // R8: no snapshots, no fields: refused, nothing written.
    let out = rheodem_in(&dir, &["cg", "cell"]);
    let err = stderr(&out);
    assert!(!out.status.success(), "cg accepted a run without snapshots");
    assert!(err.contains("`snapshots`"), "{err}");
    assert!(!dir.join("cell/cg").exists(), "cg wrote outputs");
    std::fs::remove_dir_all(&dir).ok();
}

/// R7: a split-bottom run that cannot write its outputs (here `band.csv` is a directory,
/// as a full disk would refuse a file) records the failure in its summary.
#[test]
fn r7_a_failed_split_bottom_run_says_so_in_its_summary() {
    let dir = temp("audit2", "failed");
    std::fs::write(dir.join("small.toml"), SMALL_CELL).expect("config");
    std::fs::create_dir_all(dir.join("cell/band.csv")).expect("blocking directory");
    let out = rheodem_in(
        &dir,
        &[
            "split-bottom",
            "--config",
            "small.toml",
            "--out",
            "cell",
            "--quiet",
        ],
    );
    assert!(!out.status.success(), "the run succeeded");
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("cell/summary.json")).expect("summary"),
    )
    .expect("json");
    assert_eq!(summary["status"], "failed", "{summary}");
    assert!(
        summary["error"]
            .as_str()
            .is_some_and(|e| e.contains("band.csv")),
        "{summary}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// The `--help` text of `command`, its whitespace folded.
fn help_of(command: &str) -> String {
    let out = rheodem_in(&std::env::temp_dir(), &[command, "--help"]);
    String::from_utf8_lossy(&out.stdout)
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

/// The default `--help` shows for `flag`: the first `[default: …]` after its name.
fn shown_default<'a>(help: &'a str, flag: &str) -> &'a str {
    help.split(&format!("{flag} <"))
        .nth(1)
        .and_then(|rest| rest.split("[default: ").nth(1))
        .and_then(|rest| rest.split(']').next())
        .unwrap_or_else(|| panic!("{flag} shows no default: {help}"))
}

/// `split-bottom --help` shows the cell's defaults (the values of the library's default
/// cell, so that the two cannot drift apart) and the allowed ranges.
#[test]
fn split_bottom_help_shows_the_defaults() {
    use rheodem::setups::split_bottom::SplitBottomSpec;
    let d = SplitBottomSpec::default();
    let help = help_of("split-bottom");
    for (flag, value) in [
        ("--omega", d.omega),
        ("--gravity", d.gravity),
        ("--mu-p", d.friction),
        ("--duration", d.duration),
        ("--average-from", d.average_from),
        ("--scale", d.scale),
        ("--wedge-deg", d.wedge_deg),
        ("--seed", d.seed as f64),
    ] {
        assert_eq!(shown_default(&help, flag), value.to_string(), "{flag}");
    }
}

/// When standard error is not a terminal, a long command writes a progress line now and
/// then (every minute; here every step, by `RHEODEM_PROGRESS_SECONDS = 0`).
#[test]
fn progress_lines_when_not_on_a_terminal() {
    let dir = temp("audit2", "progress");
    std::fs::write(dir.join("small.toml"), SMALL_CELL).expect("config");
    let out = Command::new(env!("CARGO_BIN_EXE_rheodem"))
        .args(["split-bottom", "--config", "small.toml", "--out", "cell"])
        .env("RHEODEM_PROGRESS_SECONDS", "0")
        .current_dir(&dir)
        .output()
        .expect("the binary runs");
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    for stage in ["settle: step", "shear: step"] {
        assert!(err.contains(stage), "no `{stage}` line: {err}");
    }
    assert!(err.contains("M particle-steps/s, ETA"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `shear-box --help` shows the defaults of the shear-box spec (read from a spec with only
/// the required controls given, so that the help and the library cannot drift apart).
#[test]
fn shear_box_help_shows_the_defaults() {
    let d: rheodem::setups::shear_box::ShearBoxSpec =
        toml::from_str("mu_p = 0.5\ninertial = 0.1\nsoftness = 0.01").expect("spec");
    let help = help_of("shear-box");
    for (flag, value) in [
        ("--bond", d.bond),
        ("--range", d.range),
        ("--diameter", d.diameter),
        ("--density", d.density),
        ("--stiffness", d.stiffness),
        ("--restitution", d.restitution),
        ("--polydispersity", d.polydispersity),
        ("--particles", d.particles as f64),
        ("--strain", d.strain),
        ("--transient-strain", d.transient_strain),
        ("--seed", d.seed as f64),
    ] {
        assert_eq!(shown_default(&help, flag), value.to_string(), "{flag}");
    }
}

/// R3: a sphere outside the box along a periodic axis is wrapped into it, and `check` says
/// so.
#[test]
fn r3_spheres_wrapped_on_a_periodic_axis_are_reported() {
    let dir = temp("audit2", "wrap");
    let text = scenario("true, true, true", "", &one_sphere("[0.5, 0.01, 0.01]"));
    std::fs::write(dir.join("wrap.toml"), text).expect("scenario");
    let out = rheodem_in(&dir, &["check", "wrap.toml"]);
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("wrapped into it: particles[0].spheres[0] (x = 5e-1 m)"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
