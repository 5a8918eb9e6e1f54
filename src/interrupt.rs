//! Ctrl-C, SIGTERM and SIGHUP: the process removes the temporary files it is writing and
//! ends at once, killed by the same signal (so a parent such as `make` or a shell sees why).
//! Nothing it leaves is half-written: outputs and cache entries only ever reach their names by
//! a rename, so what is left is the last complete build's files.
//!
//! How: [`install`] blocks the three signals before any other thread exists, so every thread
//! inherits the mask, and one thread takes them with `sigwait`. Its handler is ordinary code
//! (no async-signal-safety limits), so it can lock the registry and remove files.
//!
//! Invariants:
//! - Every temporary file this process creates is in the registry from before it exists
//!   ([`Temporary::register`]) until it is renamed into place or removed.
//! - Once a signal is being handled, the registry stays locked until the process is gone: a
//!   thread that would create another temporary blocks instead, so none outlives the sweep.
//! - While [`set_idle`] says the process is waiting (`watch` between builds), a signal ends it
//!   with exit code 0: there is nothing to cut off.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

/// Temporary files that exist (or are about to) and are not yet in place.
static LIVE: Mutex<BTreeSet<PathBuf>> = Mutex::new(BTreeSet::new());

/// `watch` is waiting for a change: no build to interrupt.
static IDLE: AtomicBool = AtomicBool::new(false);

/// A temporary file's entry in the registry; dropping it removes the entry (not the file).
#[derive(Debug)]
pub struct Temporary(PathBuf);

impl Temporary {
    /// Registers `path` before the caller creates it.
    pub fn register(path: &Path) -> Temporary {
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
        if let Ok(mut live) = LIVE.lock() {
            live.insert(path.clone());
        }
        Temporary(path)
    }
}

impl Drop for Temporary {
    fn drop(&mut self) {
        if let Ok(mut live) = LIVE.lock() {
            live.remove(&self.0);
        }
    }
}

/// Whether a signal should end the process quietly (`watch` waiting between builds).
pub fn set_idle(idle: bool) {
    IDLE.store(idle, Ordering::SeqCst);
}

/// The registered temporaries, for tests.
pub fn live() -> Vec<PathBuf> {
    LIVE.lock()
        .map(|l| l.iter().cloned().collect())
        .unwrap_or_default()
}

#[cfg(unix)]
const SIGNALS: [libc::c_int; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP];

/// Takes over SIGINT, SIGTERM and SIGHUP for the whole process. Call it first thing in
/// `main`, before any thread is started (threads inherit the signal mask from their creator).
#[cfg(unix)]
pub fn install() -> std::io::Result<()> {
    // SAFETY: plain libc calls on a zeroed, then initialised, signal set owned by this frame
    // (and moved into the thread); `pthread_sigmask` only changes this thread's mask.
    unsafe {
        let mut set: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut set);
        for signal in SIGNALS {
            libc::sigaddset(&mut set, signal);
        }
        let rc = libc::pthread_sigmask(libc::SIG_BLOCK, &set, std::ptr::null_mut());
        if rc != 0 {
            return Err(std::io::Error::from_raw_os_error(rc));
        }
        std::thread::Builder::new()
            .name("signals".into())
            .spawn(move || {
                loop {
                    let mut signal: libc::c_int = 0;
                    if libc::sigwait(&set, &mut signal) == 0 {
                        end_on(signal);
                    }
                }
            })?;
    }
    Ok(())
}

#[cfg(not(unix))]
pub fn install() -> std::io::Result<()> {
    Ok(())
}

/// Removes the live temporaries and ends the process as `signal` would have.
#[cfg(unix)]
fn end_on(signal: libc::c_int) -> ! {
    // Held until the process ends: see the module's invariants.
    let live = LIVE.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    if IDLE.load(Ordering::SeqCst) {
        std::process::exit(0);
    }
    for path in live.iter() {
        let _ = std::fs::remove_file(path);
    }
    // SAFETY: restoring the default action and unblocking `signal` in this thread, then
    // raising it here, kills the process with it; nothing is touched afterwards.
    unsafe {
        libc::signal(signal, libc::SIG_DFL);
        let mut set: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut set);
        libc::sigaddset(&mut set, signal);
        libc::pthread_sigmask(libc::SIG_UNBLOCK, &set, std::ptr::null_mut());
        libc::raise(signal);
    }
    // Only if the signal did not end us (it always should).
    std::process::exit(128 + signal);
}
