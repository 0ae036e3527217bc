//! A registered set-up run by name through the registry, as every front end runs it: the
//! spec made from given values, the run to its end with its events, the summary it
//! returns equal to the file it wrote; the same call again finds the run finished; other
//! settings are refused naming the changed key; a start from another run is refused by a
//! set-up that has none.

use rheodem::run::RunError;
use rheodem::setups::registry::find;
use rheodem::setups::runner::{Event, RunOptions};
use rheodem::setups::schema::Values;
use toml::Value;

/// The smallest sensible shear-box point (as in the doc example of `run_point`).
fn point(mu_p: f64) -> Values {
    vec![
        ("mu_p", Value::Float(mu_p)),
        ("inertial", Value::Float(0.1)),
        ("softness", Value::Float(0.01)),
        ("bond", Value::Float(0.0)),
        ("particles", Value::Integer(80)),
        ("polydispersity", Value::Float(1.2)),
        ("strain", Value::Float(0.4)),
        ("transient_strain", Value::Float(0.2)),
    ]
}

#[test]
fn a_set_up_runs_by_name_resumes_and_refuses_other_settings() {
    let dir = std::env::temp_dir().join(format!("rheodem-setup-runner-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    let info = find("shear-box").expect("the shear box is registered");
    let options = RunOptions {
        dir: &dir,
        threads: 1,
        force: false,
        from: None,
        max_memory: None,
    };
    let (mut particles, mut steps, mut notes) = (None, 0u64, Vec::new());
    let finished = (info.run)(
        toml::Table::new(),
        &point(0.1),
        &options,
        &mut |e| match e {
            Event::Particles(n) => particles = Some(n),
            Event::Progress(p) => {
                assert_eq!(p.stage, "shear");
                assert!(p.done <= p.total);
                steps = p.done;
            }
            Event::Note(text) => notes.push(text.to_string()),
            Event::Warning(_) => {}
        },
    )
    .expect("the point runs");
    assert_eq!(particles, Some(80));
    assert!(steps > 0, "no progress was reported");
    assert!(
        notes
            .iter()
            .any(|n| n.starts_with("resolved: p = σ_yy target"))
    );
    let on_disk: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("steady_state.json")).expect("the result file"),
    )
    .expect("JSON");
    assert_eq!(finished.summary, on_disk);
    assert_eq!(finished.summary["spec"]["mu_p"], 0.1);
    assert!(
        finished
            .report
            .starts_with("steady state over strain 0.2–0.4: φ = ")
    );
    // Half a strain unit is too short to be steady, and the warning says so.
    assert!(
        finished
            .warnings
            .iter()
            .any(|w| w.contains("did NOT reach a steady state")),
        "{:?}",
        finished.warnings
    );

    // The same call finds the point finished: no step, the same summary.
    let mut stepped = false;
    let again = (info.run)(toml::Table::new(), &point(0.1), &options, &mut |e| {
        stepped |= matches!(e, Event::Progress(_));
    })
    .expect("the finished point");
    assert!(!stepped);
    assert_eq!(again.summary, finished.summary);

    // Other settings are refused, naming what changed; nothing on disk changes.
    let refused = (info.run)(toml::Table::new(), &point(0.2), &options, &mut |_| {})
        .expect_err("another point in the same directory");
    match refused {
        RunError::Changed { changes, .. } => assert_eq!(changes, ["mu_p: 0.1 → 0.2"]),
        other => panic!("refused for another reason: {other}"),
    }
    let kept: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("point.json")).expect("the point file"),
    )
    .expect("JSON");
    assert_eq!(kept["mu_p"], 0.1);

    // The shear box cannot start from another run: the key is named.
    let from = RunOptions {
        from: Some(&dir),
        ..options
    };
    let e = (info.run)(toml::Table::new(), &point(0.1), &from, &mut |_| {})
        .expect_err("a start from another run");
    assert!(
        e.to_string().contains("`from`") && e.to_string().contains("cannot start from"),
        "{e}"
    );
    assert!(info.from.is_none() && !info.estimates_memory);
    let cell = find("split-bottom").expect("the cell is registered");
    assert!(cell.from.is_some() && cell.estimates_memory);
    std::fs::remove_dir_all(&dir).ok();
}
