//! Which command made a run directory: a small marker file written when a run starts, read
//! by every command before it touches an existing directory, so that a directory of one
//! kind is never resumed, overwritten or misread by a command of another. Directories made
//! before the marker existed are recognised by their files.

use crate::io::atomic::write_atomic;
use std::path::Path;

/// The marker's file name in a run directory.
pub const FILE: &str = "made-by";

/// The command family that made a run directory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Maker {
    /// `rheodem run` (a scenario file), continued by `rheodem resume`.
    Run,
    /// A shear-box point (`rheodem shear-box`, `sweep` or a shear-box study).
    ShearBox,
    /// A split-bottom cell (`rheodem split-bottom` or a split-bottom study).
    SplitBottom,
    /// A chute (`rheodem chute` or a chute study).
    Chute,
}

impl Maker {
    /// The name written in the marker.
    pub fn name(self) -> &'static str {
        match self {
            Maker::Run => "run",
            Maker::ShearBox => "shear-box",
            Maker::SplitBottom => "split-bottom",
            Maker::Chute => "chute",
        }
    }

    /// How a user continues a directory of this kind.
    pub fn how_to_continue(self, dir: &Path) -> String {
        let d = dir.display();
        match self {
            Maker::Run => format!("continue it with `rheodem resume {d}`"),
            Maker::ShearBox => format!(
                "continue it with the same `rheodem shear-box … --out {d}` (or the sweep or \
                 study that made it)"
            ),
            Maker::SplitBottom => format!(
                "continue it with the same `rheodem split-bottom … --out {d}` (or the study \
                 that made it)"
            ),
            Maker::Chute => format!(
                "continue it with the same `rheodem chute … --out {d}` (or the study that made \
                 it)"
            ),
        }
    }

    fn from_name(name: &str) -> Option<Maker> {
        [
            Maker::Run,
            Maker::ShearBox,
            Maker::SplitBottom,
            Maker::Chute,
        ]
        .into_iter()
        .find(|m| m.name() == name)
    }
}

/// Writes the marker of `maker` into the run directory `dir` (atomically).
pub fn mark(dir: &Path, maker: Maker) -> std::io::Result<()> {
    write_atomic(&dir.join(FILE), format!("{}\n", maker.name()).as_bytes())
}

/// The maker of the run directory `dir`: its marker, or for a directory without one, its
/// files (`split-bottom.toml`; `point.json`; `scenario.toml`, `resolved.json` or
/// `checkpoint.bin`). `None` for a missing or empty directory or one of unknown files.
pub fn read(dir: &Path) -> Option<Maker> {
    if let Ok(text) = std::fs::read_to_string(dir.join(FILE)) {
        return Maker::from_name(text.trim());
    }
    let has = |f: &str| dir.join(f).exists();
    if has("chute.toml") {
        Some(Maker::Chute)
    } else if has("split-bottom.toml") {
        Some(Maker::SplitBottom)
    } else if has("point.json") {
        Some(Maker::ShearBox)
    } else if has("scenario.toml") || has("resolved.json") || has("checkpoint.bin") {
        Some(Maker::Run)
    } else {
        None
    }
}

/// Refuses to use `dir` for a run of `wanted` when another command made it, saying how to
/// continue it instead (`Ok` for a missing, empty or matching directory).
pub fn expect(dir: &Path, wanted: Maker) -> Result<(), String> {
    match read(dir) {
        Some(found) if found != wanted => Err(format!(
            "{} holds a run of `rheodem {}`, not of `rheodem {}`: {}, or choose another directory",
            dir.display(),
            found.name(),
            wanted.name(),
            found.how_to_continue(dir)
        )),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markers_and_old_directories_are_recognised() {
        let dir = std::env::temp_dir().join(format!("rheodem-made-by-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(read(&dir), None);
        std::fs::create_dir_all(&dir).expect("test fixture");
        assert!(expect(&dir, Maker::Run).is_ok());
        // An old split-bottom directory: recognised by its spec file.
        std::fs::write(dir.join("split-bottom.toml"), "").expect("test fixture");
        assert_eq!(read(&dir), Some(Maker::SplitBottom));
        let e = expect(&dir, Maker::Run).expect_err("another maker");
        assert!(e.contains("split-bottom") && e.contains("--out"), "{e}");
        // The marker wins over the files.
        mark(&dir, Maker::ShearBox).expect("test fixture");
        assert_eq!(read(&dir), Some(Maker::ShearBox));
        assert!(expect(&dir, Maker::ShearBox).is_ok());
        std::fs::remove_dir_all(&dir).ok();
    }
}
