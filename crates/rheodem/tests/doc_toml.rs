//! Every TOML example in the documentation parses and validates, so that none can drift
//! from the file formats: the ```` ```toml ```` blocks of the doc comments of both crates'
//! sources and of the Markdown files at the top of the repository and in `docs/`.
//!
//! A block is accepted as the first of these that takes it: a complete scenario
//! (`Scenario::from_toml`, then `scenario::build` with the run cut to one step and any
//! preparation sped up), a sweep file (`SweepSpec`, every point expanded and validated), a
//! study file (`StudySpec`, both variants expanded and validated), a shear-box point (`ShearBoxSpec::derive`), or a scenario fragment (merged into a minimal
//! valid scenario, then parsed and built like a complete one). A block that is none of
//! them fails the test with every reason.

use rheodem::scenario::spec::PreparationSpec;
use rheodem::scenario::{Scenario, build};
use rheodem::setups::registry::study_points;
use rheodem::setups::shear_box::ShearBoxSpec;
use rheodem::setups::study::StudySpec;
use rheodem::setups::sweep::{SweepSpec, expand};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Files below `dir` (recursively) whose name ends with `ext`.
fn files(dir: &Path, ext: &str, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            files(&p, ext, out);
        } else if p.to_string_lossy().ends_with(ext) {
            out.push(p);
        }
    }
}

/// The text of the doc comments of a Rust source (`//!` and `///` lines, the marker and
/// one following space removed), with the line number of each line.
fn doc_lines(source: &str) -> Vec<(usize, String)> {
    source
        .lines()
        .enumerate()
        .filter_map(|(n, line)| {
            let t = line.trim_start();
            let rest = t
                .strip_prefix("//!")
                .or_else(|| t.strip_prefix("///").filter(|r| !r.starts_with('/')))?;
            Some((n + 1, rest.strip_prefix(' ').unwrap_or(rest).to_string()))
        })
        .collect()
}

/// The ```` ```toml ```` blocks of a sequence of lines: `(first line number, text)`.
fn toml_blocks(lines: &[(usize, String)]) -> Vec<(usize, String)> {
    let mut blocks = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (n, line) in lines {
        let t = line.trim();
        match &mut current {
            None => {
                if let Some(info) = t.strip_prefix("```")
                    && info.split(',').any(|w| w.trim() == "toml")
                {
                    current = Some((*n, String::new()));
                }
            }
            Some((_, text)) => {
                if t.starts_with("```") {
                    blocks.push(current.take().expect("open block"));
                } else {
                    text.push_str(line);
                    text.push('\n');
                }
            }
        }
    }
    assert!(current.is_none(), "unterminated ```toml block");
    blocks
}

/// A minimal valid scenario, the base of fragments (`z` closed, so that a fragment may add a
/// floor).
const MINIMAL: &str = r#"
[domain]
size = [0.01, 0.01, 0.01]
periodic = [true, true, false]
[[species]]
name = "glass"
density = 2000.0
[[contact]]
normal = { stiffness = 100.0, restitution = 0.8 }
[[particles]]
kind = "random"
species = "glass"
count = 10
mean_diameter = 1.0e-3
[run]
steps = 1
"#;

/// `base` with `extra` merged in: tables merged key by key, arrays of tables (`[[…]]`)
/// appended, other values replaced.
fn merge(base: &mut toml::Table, extra: toml::Table) {
    let tables = |a: &[toml::Value]| a.iter().all(toml::Value::is_table);
    for (k, v) in extra {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(e)) => merge(b, e),
            (Some(toml::Value::Array(b)), toml::Value::Array(e)) if tables(b) && tables(&e) => {
                b.extend(e)
            }
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

/// Builds a scenario (validation of every value) with its run cut to one step and its
/// preparation, if any, at the fastest accepted rate.
fn validate_scenario(mut s: Scenario) -> Result<(), String> {
    s.run.duration = None;
    s.run.steps = Some(1);
    if let Some(p) = &mut s.preparation {
        *p = PreparationSpec {
            strain_per_contact_time: Some(0.1),
            relax_contact_times: Some(1.0),
            ..p.clone()
        };
    }
    build(&s, &root()).map(|_| ()).map_err(|e| e.to_string())
}

/// Accepts a block as one of the documented formats, or says why it is none of them.
fn check_block(text: &str) -> Result<&'static str, String> {
    let mut why = Vec::new();
    match Scenario::from_toml(text) {
        Ok(s) => {
            return validate_scenario(s)
                .map(|()| "scenario")
                .map_err(|e| format!("a scenario that does not validate: {e}"));
        }
        Err(e) => why.push(format!("not a scenario: {e}")),
    }
    match toml::from_str::<SweepSpec>(text) {
        Ok(s) => {
            return expand(&s)
                .map(|_| "sweep")
                .map_err(|e| format!("a sweep whose points do not validate: {e}"));
        }
        Err(e) => why.push(format!("not a sweep: {e}")),
    }
    match StudySpec::from_toml(text) {
        Ok(s) => {
            // Both variants expand to valid points of a registered set-up.
            let variants: &[bool] = if s.quick.is_some() {
                &[false, true]
            } else {
                &[false]
            };
            for &quick in variants {
                study_points(&s, quick)
                    .map_err(|e| format!("a study whose points do not validate: {e}"))?;
            }
            return Ok("study");
        }
        Err(e) => why.push(format!("not a study: {e}")),
    }
    match toml::from_str::<ShearBoxSpec>(text) {
        Ok(p) => {
            return p
                .derive()
                .map(|_| "shear-box point")
                .map_err(|e| format!("a shear-box point that does not validate: {e}"));
        }
        Err(e) => why.push(format!("not a shear-box point: {e}")),
    }
    match toml::from_str::<toml::Table>(text) {
        Ok(fragment) => {
            let mut merged: toml::Table = toml::from_str(MINIMAL).expect("minimal scenario");
            merge(&mut merged, fragment);
            let whole = toml::to_string(&merged).expect("serialisable");
            match Scenario::from_toml(&whole) {
                Ok(s) => {
                    return validate_scenario(s)
                        .map(|()| "scenario fragment")
                        .map_err(|e| format!("a fragment that does not validate: {e}"));
                }
                Err(e) => why.push(format!("not a scenario fragment: {e}")),
            }
        }
        Err(e) => why.push(format!("not TOML: {e}")),
    }
    Err(why.join("; "))
}

/// Every ```` ```toml ```` block of the doc comments in `crates/*/src` and of the Markdown
/// files at the top and in `docs/` is a valid scenario, sweep, study, shear-box point or scenario fragment (see
/// the module comment). At least the two known blocks (the scenario format in
/// `scenario/spec.rs`, the sweep format in `setups/sweep.rs`) must be found, so that a
/// broken extraction cannot pass vacuously.
#[test]
fn every_toml_example_in_the_docs_is_valid() {
    let root = root();
    let mut sources = Vec::new();
    for krate in ["crates/rheodem/src", "crates/rheodem-cli/src"] {
        files(&root.join(krate), ".rs", &mut sources);
    }
    let mut blocks = Vec::new();
    for path in &sources {
        let text = std::fs::read_to_string(path).expect("source");
        for (line, block) in toml_blocks(&doc_lines(&text)) {
            blocks.push((path.clone(), line, block));
        }
    }
    let mut docs: Vec<PathBuf> = [root.clone(), root.join("docs")]
        .iter()
        .flat_map(|d| std::fs::read_dir(d).expect("repository root and docs/"))
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    assert!(docs.iter().any(|p| p.ends_with("README.md")));
    for path in &docs {
        let text = std::fs::read_to_string(path).expect("markdown");
        let lines: Vec<(usize, String)> = text
            .lines()
            .enumerate()
            .map(|(n, l)| (n + 1, l.to_string()))
            .collect();
        for (line, block) in toml_blocks(&lines) {
            blocks.push((path.clone(), line, block));
        }
    }

    let mut failures = Vec::new();
    let mut kinds = Vec::new();
    for (path, line, block) in &blocks {
        let at = format!(
            "{}:{line}",
            path.strip_prefix(&root).unwrap_or(path).display()
        );
        match check_block(block) {
            Ok(kind) => kinds.push((at, kind)),
            Err(why) => failures.push(format!("{at}: {why}")),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let found =
        |file: &str, kind: &str| kinds.iter().any(|(at, k)| at.contains(file) && *k == kind);
    assert!(found("scenario/spec.rs", "scenario"), "{kinds:?}");
    assert!(found("setups/sweep.rs", "sweep"), "{kinds:?}");
}

/// The extraction itself: doc-comment markers are stripped (`////` is not a doc
/// comment), fences with `toml` in the info string open a block, others do not, and
/// fragments merge into the minimal scenario.
#[test]
fn toml_blocks_are_extracted_from_doc_comments() {
    let src = "//! intro\n//! ```toml\n//! seed = 3\n//! ```\n/// ```rust\n/// let x = 1;\n/// ```\n//// ```toml\n    /// ```toml,ignore\n    /// [run]\n    /// steps = 2\n    /// ```\nfn f() {}\n";
    let blocks = toml_blocks(&doc_lines(src));
    assert_eq!(
        blocks,
        vec![
            (2, "seed = 3\n".to_string()),
            (9, "[run]\nsteps = 2\n".to_string())
        ]
    );
    assert_eq!(check_block("seed = 3\n"), Ok("scenario fragment"));
    assert_eq!(
        check_block(
            "[[wall]]\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nspecies = \"glass\"\n"
        ),
        Ok("scenario fragment")
    );
    assert!(check_block("[domain]\nsize = [0.01, 0.01]\n").is_err());
    assert!(check_block("sede = 3\n").is_err());
}
