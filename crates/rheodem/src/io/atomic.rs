//! Crash-safe file writes: write a temporary file beside the target, flush it to disk, then
//! rename it over the target. A reader sees the old file or the new one, never a torn one.
//!
//! The temporary name is unique to the process and the call, so that two processes writing
//! the same file (two sweeps sharing a results table) never write into each other's
//! temporary; a write that fails removes its temporary.

use std::fs::{self, File};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Writes `bytes` to `path` atomically.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let tmp = temporary_name(path);
    let written = (|| {
        let mut f = File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if written.is_err() {
        // Best effort: the temporary may not exist (creation failed).
        let _ = fs::remove_file(&tmp);
    }
    written
}

/// Removes the temporaries that killed writers left in `dir` and its subdirectories one
/// level down (`.name.<pid>.<n>.tmp`), returning how many. Only for a directory whose
/// writers are all gone: a run directory whose lock the caller holds.
pub fn remove_stale_temporaries(dir: &Path) -> io::Result<usize> {
    let mut removed = 0;
    let mut dirs = vec![(dir.to_path_buf(), 0)];
    while let Some((d, depth)) = dirs.pop() {
        for entry in fs::read_dir(&d)? {
            let entry = entry?;
            let path = entry.path();
            let kind = entry.file_type()?;
            if kind.is_dir() && depth == 0 {
                dirs.push((path, 1));
            } else if kind.is_file() && is_temporary(&entry.file_name().to_string_lossy()) {
                fs::remove_file(&path)?;
                removed += 1;
            }
        }
    }
    Ok(removed)
}

/// Whether `name` is one of [`temporary_name`]'s: `.name.<pid>.<n>.tmp`.
fn is_temporary(name: &str) -> bool {
    let Some(inner) = name.strip_prefix('.').and_then(|n| n.strip_suffix(".tmp")) else {
        return false;
    };
    let mut parts = inner.rsplitn(3, '.');
    let numeric =
        |p: Option<&str>| p.is_some_and(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()));
    numeric(parts.next()) && numeric(parts.next()) && parts.next().is_some_and(|n| !n.is_empty())
}

/// `dir/.name.<pid>.<n>.tmp` beside `path`.
fn temporary_name(path: &Path) -> PathBuf {
    static CALLS: AtomicU64 = AtomicU64::new(0);
    let n = CALLS.fetch_add(1, Ordering::Relaxed);
    let name = path
        .file_name()
        .map_or_else(|| "file".into(), |s| s.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}.{}.{n}.tmp", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// R7 (second audit): the temporaries of a killed writer are removed, and only they.
    #[test]
    fn r7_stale_temporaries_are_removed() {
        let dir = temp_dir("stale");
        fs::create_dir_all(dir.join("snapshots")).expect("test fixture");
        for name in [
            ".checkpoint.bin.4242.7.tmp",
            "snapshots/.snap_0001.vtp.17.0.tmp",
        ] {
            fs::write(dir.join(name), b"half").expect("test fixture");
        }
        for keep in ["checkpoint.bin", "notes.tmp", ".hidden.tmp", ".a.b.tmp"] {
            fs::write(dir.join(keep), b"keep").expect("test fixture");
        }
        assert_eq!(remove_stale_temporaries(&dir).expect("test fixture"), 2);
        let mut left: Vec<String> = leftovers(&dir);
        left.sort();
        assert_eq!(left, [".a.b.tmp", ".hidden.tmp", "notes.tmp"]);
        assert!(leftovers(&dir.join("snapshots")).is_empty());
        assert!(is_temporary(
            &temporary_name(&dir.join("x.csv"))
                .file_name()
                .expect("test fixture")
                .to_string_lossy()
        ));
        fs::remove_dir_all(&dir).ok();
    }

    fn temp_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("rheodem-atomic-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).expect("temp dir");
        dir
    }

    fn leftovers(dir: &Path) -> Vec<String> {
        fs::read_dir(dir)
            .expect("list")
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".tmp"))
            .collect()
    }

    #[test]
    fn replaces_content_and_leaves_no_temporary() {
        let dir = temp_dir("replace");
        let p = dir.join("a.txt");
        write_atomic(&p, b"one").expect("write");
        write_atomic(&p, b"two").expect("write");
        assert_eq!(fs::read(&p).expect("read"), b"two");
        assert!(leftovers(&dir).is_empty());
        fs::remove_dir_all(&dir).ok();
    }

    /// D9: a write that fails (here: the rename, because the target is a non-empty
    /// directory) leaves no partial `.tmp` file behind.
    #[test]
    fn d9_failed_write_leaves_no_temporary() {
        let dir = temp_dir("failed");
        let target = dir.join("occupied");
        fs::create_dir_all(target.join("inside")).expect("dir");
        assert!(write_atomic(&target, b"data").is_err());
        assert!(leftovers(&dir).is_empty(), "{:?}", leftovers(&dir));
        fs::remove_dir_all(&dir).ok();
    }

    /// Concurrent writers of one file never mix their bytes: every read sees one complete
    /// version.
    #[test]
    fn concurrent_writers_never_tear_the_file() {
        let dir = temp_dir("concurrent");
        let p = dir.join("shared.txt");
        std::thread::scope(|s| {
            for k in 0..4u8 {
                let p = &p;
                s.spawn(move || {
                    let body = vec![b'a' + k; 100_000];
                    for _ in 0..20 {
                        write_atomic(p, &body).expect("write");
                    }
                });
            }
        });
        let text = fs::read(&p).expect("read");
        assert_eq!(text.len(), 100_000);
        assert!(text.iter().all(|&b| b == text[0]));
        assert!(leftovers(&dir).is_empty());
        fs::remove_dir_all(&dir).ok();
    }
}
