//! `rheodem split-bottom` through the binary: bad options and configs get clear errors,
//! and a small cell runs end to end from a config file, then again from its settled state.

mod common;

use common::{rheodem_in, stderr, temp};

/// Each bad input fails with a message naming the key (or option) and what is allowed,
/// before any run directory is created.
#[test]
fn bad_input_is_refused_with_the_key_named() {
    let dir = temp("sb-cli", "bad");
    std::fs::write(dir.join("typo.toml"), "omgea = 1.0\n").expect("write");
    std::fs::write(dir.join("narrow.toml"), "wedge_deg = 4.0\n").expect("write");
    let cases: [(&[&str], &str); 5] = [
        (&["split-bottom", "--config", "typo.toml"], "omgea"),
        (
            &["split-bottom", "--config", "narrow.toml"],
            "must be at least",
        ),
        (&["split-bottom", "--omega", "-1"], "`omega` = -1"),
        (&["split-bottom", "--law", "linear"], "needs max_force"),
        (
            &["split-bottom", "--law", "glue"],
            "`law` = \"glue\": is not a known adhesive law; known: none (dry), reversible, \
             liquid_bridge (willett), linear_irreversible (linear)",
        ),
    ];
    for (args, expected) in cases {
        let out = rheodem_in(&dir, args);
        assert!(!out.status.success(), "{args:?} succeeded");
        let e = stderr(&out);
        assert!(e.contains(expected), "{args:?}: {e}");
        assert!(!e.contains("panicked"), "{args:?}: {e}");
    }
    assert!(
        !dir.join("runs").exists(),
        "no run directory for refused input"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A small cell from a config file runs to the end and reports torques and band fits; a
/// second run starts from its settled state with another Ω.
#[test]
fn small_cell_from_a_config_and_from_its_settled_state() {
    let dir = temp("sb-cli", "small");
    std::fs::write(
        dir.join("small.toml"),
        "inner_radius = 0.02\nouter_radius = 0.05\nsplit_radius = 0.035\nheight = 0.012\n\
         duration = 0.04\naverage_from = 0.02\nrows = 8\nsnapshots = 0\ntime_step = \"mean-pair\"\n",
    )
    .expect("write");
    let out = rheodem_in(
        &dir,
        &["split-bottom", "--config", "small.toml", "-o", "a", "-q"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("net torque"), "{text}");
    assert!(dir.join("a/settled.bin").exists());
    let out = rheodem_in(
        &dir,
        &[
            "split-bottom",
            "--config",
            "small.toml",
            "--from",
            "a",
            "--omega",
            "2",
            "-o",
            "b",
            "-q",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let summary = std::fs::read_to_string(dir.join("b/summary.json")).expect("summary");
    assert!(summary.contains("\"omega\": 2.0"), "{summary}");
    assert!(summary.contains("\"from\": \"a\""), "{summary}");
    // Starting from a settled state with another geometry is refused, naming the key.
    let out = rheodem_in(
        &dir,
        &[
            "split-bottom",
            "--config",
            "small.toml",
            "--from",
            "a",
            "--scale",
            "0.9",
            "-o",
            "c",
            "-q",
        ],
    );
    assert!(!out.status.success());
    assert!(stderr(&out).contains("`scale`"), "{}", stderr(&out));
    std::fs::remove_dir_all(&dir).ok();
}
