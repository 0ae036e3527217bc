//! Advisory locks on run directories, so that several processes (two `rheodem sweep`s on
//! one sweep file, or the array jobs of a cluster) share the points of a sweep without
//! ever running one twice at the same time.
//!
//! The lock is an exclusive `flock` on `DIR/.lock`, held for as long as the [`DirLock`]
//! lives; the operating system releases it when the process ends, however it ends (a
//! `kill -9` leaves no stale lock behind).

use std::fs::{File, OpenOptions, TryLockError};
use std::io;
use std::path::{Path, PathBuf};

/// Name of the lock file inside a locked directory.
pub const LOCK_FILE: &str = ".lock";

/// An exclusive lock on a directory, released on drop.
#[derive(Debug)]
pub struct DirLock {
    file: File,
    path: PathBuf,
}

/// Why a directory could not be locked.
#[derive(Debug, thiserror::Error)]
pub enum LockError {
    /// Another process (or another handle in this one) holds the lock.
    #[error("{} is locked by another process", .0.display())]
    Busy(PathBuf),
    /// The lock file could not be opened or locked.
    #[error("cannot lock {}: {source}", path.display())]
    Io {
        /// The lock file.
        path: PathBuf,
        /// The cause.
        source: io::Error,
    },
}

impl DirLock {
    /// Opens (creating) the lock file of `dir`.
    fn open(dir: &Path) -> Result<(File, PathBuf), LockError> {
        DirLock::open_file(dir.join(LOCK_FILE))
    }

    /// Opens (creating) the lock file `path`.
    fn open_file(path: PathBuf) -> Result<(File, PathBuf), LockError> {
        match OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
        {
            Ok(file) => Ok((file, path)),
            Err(source) => Err(LockError::Io { path, source }),
        }
    }

    /// Takes the lock of `dir` (which must exist) without waiting.
    pub fn try_acquire(dir: &Path) -> Result<DirLock, LockError> {
        let (file, path) = DirLock::open(dir)?;
        match file.try_lock() {
            Ok(()) => Ok(DirLock { file, path }),
            Err(TryLockError::WouldBlock) => Err(LockError::Busy(dir.to_path_buf())),
            Err(TryLockError::Error(source)) => Err(LockError::Io { path, source }),
        }
    }

    /// Takes the lock of `dir` (which must exist), waiting for whoever holds it: for short
    /// critical sections (rewriting a shared table), never for whole runs.
    pub fn acquire(dir: &Path) -> Result<DirLock, LockError> {
        DirLock::wait_for(DirLock::open(dir)?)
    }

    /// Takes the lock on the file `lock_file` itself (created if missing; its directory
    /// must exist), waiting for whoever holds it: for guarding one shared file, such as a
    /// database's first set-up, with `FILE.lock` beside it.
    pub fn acquire_file(lock_file: &Path) -> Result<DirLock, LockError> {
        DirLock::wait_for(DirLock::open_file(lock_file.to_path_buf())?)
    }

    fn wait_for((file, path): (File, PathBuf)) -> Result<DirLock, LockError> {
        match file.lock() {
            Ok(()) => Ok(DirLock { file, path }),
            Err(source) => Err(LockError::Io { path, source }),
        }
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for DirLock {
    fn drop(&mut self) {
        // Closing the file releases the lock as well; unlocking first makes it immediate
        // even if another handle to the file is still open.
        let _ = self.file.unlock();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_waits_for_the_first_to_be_released() {
        let dir = std::env::temp_dir().join(format!("rheodem-lock-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let first = DirLock::try_acquire(&dir).expect("free");
        let second = DirLock::try_acquire(&dir);
        assert!(matches!(second, Err(LockError::Busy(_))), "{second:?}");
        drop(first);
        let held = DirLock::try_acquire(&dir).expect("released");
        // A blocking acquire returns once the holder lets go.
        let waiter = std::thread::spawn({
            let dir = dir.clone();
            move || DirLock::acquire(&dir).map(|_| std::time::Instant::now())
        });
        std::thread::sleep(std::time::Duration::from_millis(100));
        let released = std::time::Instant::now();
        drop(held);
        let got = waiter.join().expect("thread").expect("acquired");
        assert!(got >= released, "the blocking lock did not wait");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_missing_directory_is_an_error_naming_the_lock_file() {
        let err = DirLock::try_acquire(Path::new("/no/such/rheodem/dir")).expect_err("missing");
        assert!(
            err.to_string().contains("/no/such/rheodem/dir/.lock"),
            "{err}"
        );
    }
}
