//! Freeing big files the build no longer needs (replaced outputs, collected cache entries)
//! after the command has returned, in a detached `latticebuild free-files` process, as
//! `git gc --auto` detaches.
//!
//! Why: on a file system that discards freed blocks (ext4 `-o discard`, as here), unlinking a
//! 2 GB file waits about 0.4 s for the device. It uses no CPU, but a process cannot exit while
//! one of its threads is in that unlink, so a thread does not help: a build that replaces a
//! 2.2 GB STL ended with half a second of idle cores.
//!
//! Invariants:
//! - Only files already renamed to one of our temporary names (a leading `.` and `.tmp-` in
//!   the name, never a name a user gave) are handed over; `free-files` refuses anything else.
//! - Nothing is left behind in-process: a [`Deferred`] dropped with paths still in it removes
//!   them there and then (library users and failed builds). Only the CLI takes them out and
//!   hands them to [`free_detached`], which removes them itself if the process cannot start.
//! - A temporary name carries the builder's pid, so should the helper die, the next build's
//!   sweep of stale temporary files removes what it left.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Mutex;

/// Files from this size on are freed later; smaller ones cost nothing to remove at once.
pub const DEFER_BYTES: u64 = 64 << 20;

/// Files renamed out of the way, to be freed.
#[derive(Debug, Default)]
pub struct Deferred(Mutex<Vec<PathBuf>>);

impl Deferred {
    /// Frees `path` later when it is big, at once otherwise.
    pub fn free(&self, path: PathBuf) {
        let big = std::fs::metadata(&path).is_ok_and(|m| m.len() >= DEFER_BYTES);
        match self.0.lock() {
            Ok(mut paths) if big => paths.push(path),
            _ => {
                let _ = std::fs::remove_file(path);
            }
        }
    }

    /// The paths held so far, which the caller now frees.
    pub fn take(&self) -> Vec<PathBuf> {
        self.0
            .lock()
            .map(|mut paths| std::mem::take(&mut *paths))
            .unwrap_or_default()
    }
}

impl Drop for Deferred {
    fn drop(&mut self) {
        for path in self.take() {
            let _ = std::fs::remove_file(path);
        }
    }
}

/// Helpers started and not yet seen to finish: reaped as new ones start, so a long `watch`
/// collects no zombies.
static HELPERS: Mutex<Vec<Child>> = Mutex::new(Vec::new());

/// Starts `latticebuild free-files PATHS…` without waiting for it; removes the paths here if
/// it cannot start.
pub fn free_detached(paths: Vec<PathBuf>) {
    if paths.is_empty() {
        return;
    }
    let started = std::env::current_exe().and_then(|exe| {
        Command::new(exe)
            .arg("free-files")
            .arg("--")
            .args(&paths)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
    });
    match started {
        Ok(child) => {
            if let Ok(mut helpers) = HELPERS.lock() {
                helpers.retain_mut(|h| matches!(h.try_wait(), Ok(None)));
                helpers.push(child);
            }
        }
        Err(_) => {
            for path in paths {
                let _ = std::fs::remove_file(path);
            }
        }
    }
}

/// Whether `path` names one of our temporary files.
pub fn is_temporary(path: &Path) -> bool {
    path.file_name()
        .and_then(|n| n.to_str())
        .is_some_and(|n| n.starts_with('.') && n.contains(".tmp-"))
}

/// `latticebuild free-files`: removes each temporary file given, ignoring anything else.
pub fn free_files(paths: &[PathBuf]) {
    for path in paths.iter().filter(|p| is_temporary(p)) {
        let _ = std::fs::remove_file(path);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_temporary_names_are_freed() {
        let dir = tempfile::tempdir().expect("temp dir");
        let kept = dir.path().join("part.stl");
        let temp = dir.path().join(".part.stl.tmp-1-2");
        let cache_temp = dir.path().join(".tmp-1-2-00ff");
        for p in [&kept, &temp, &cache_temp] {
            std::fs::write(p, b"x").expect("write");
        }
        free_files(&[kept.clone(), temp.clone(), cache_temp.clone()]);
        assert!(kept.exists());
        assert!(!temp.exists() && !cache_temp.exists());
    }

    #[test]
    fn a_dropped_deferred_frees_what_it_holds() {
        let dir = tempfile::tempdir().expect("temp dir");
        let big = dir.path().join(".big.tmp-1-1");
        let small = dir.path().join(".small.tmp-1-2");
        std::fs::File::create(&big)
            .and_then(|f| f.set_len(DEFER_BYTES))
            .expect("big file");
        std::fs::write(&small, b"x").expect("small file");
        let deferred = Deferred::default();
        deferred.free(big.clone());
        deferred.free(small.clone());
        assert!(big.exists(), "a big file waits");
        assert!(!small.exists(), "a small file goes at once");
        drop(deferred);
        assert!(!big.exists());
    }
}
