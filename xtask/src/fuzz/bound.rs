//! The xtask binary's global allocator: the system allocator, counting live bytes, with a
//! bound that only the fuzz runner sets.
//!
//! An allocation that would take the live heap past the bound ends the process at once
//! with [`OVER_BOUND_EXIT`] and a line on stderr, before the memory is asked for, so a reader
//! that sizes a buffer from a declared count (`4294967297 nodes`) is caught whatever the
//! machine could have given, including through `try_reserve`, which a plain null return would
//! let it survive. Counting the heap rather than limiting the address space (`RLIMIT_AS`)
//! keeps thread stacks and allocator arenas out of the number.
//!
//! Invariants: without a bound (every chore but the runner) this is the system allocator plus
//! two relaxed atomic additions per call; nothing here allocates unless [`trace_on_bound`] was
//! set, and then only after the bound is lifted for the report.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Exit status of a runner that passed the allocation bound.
pub const OVER_BOUND_EXIT: i32 = 86;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static LIMIT: AtomicUsize = AtomicUsize::new(usize::MAX);
static TRACE: AtomicBool = AtomicBool::new(false);

pub struct Bounded;

/// Sets the bound on live heap bytes for the rest of the process.
pub fn set_bound(bytes: usize) {
    LIMIT.store(bytes, Ordering::Relaxed);
}

/// Whether to print a backtrace of the allocation that passes the bound (the runner's
/// confirmation runs; it costs nothing until then).
pub fn trace_on_bound(on: bool) {
    TRACE.store(on, Ordering::Relaxed);
}

/// Counts `size` more live bytes, or ends the process if that passes the bound.
fn admit(size: usize) {
    let before = LIVE.fetch_add(size, Ordering::Relaxed);
    let limit = LIMIT.load(Ordering::Relaxed);
    if before.saturating_add(size) > limit {
        over_bound(size, before, limit);
    }
}

#[cold]
fn over_bound(size: usize, live: usize, limit: usize) -> ! {
    let mut line = [0u8; 160];
    let mut n = 0;
    for part in [
        Part::Text("fuzz-runner: an allocation of "),
        Part::Number(size),
        Part::Text(" bytes would pass the bound of "),
        Part::Number(limit),
        Part::Text(" bytes ("),
        Part::Number(live),
        Part::Text(" live)\n"),
    ] {
        n += part.write(&mut line[n..]);
    }
    // SAFETY: writing a stack buffer to stderr; nothing here allocates.
    unsafe { libc::write(2, line.as_ptr().cast(), n) };
    if TRACE.load(Ordering::Relaxed) {
        LIMIT.store(usize::MAX, Ordering::Relaxed);
        eprintln!("{}", std::backtrace::Backtrace::force_capture());
    }
    // SAFETY: `_exit` ends the process without running destructors or atexit handlers, which
    // could allocate again.
    unsafe { libc::_exit(OVER_BOUND_EXIT) }
}

enum Part {
    Text(&'static str),
    Number(usize),
}

impl Part {
    fn write(&self, out: &mut [u8]) -> usize {
        match self {
            Part::Text(t) => {
                let n = t.len().min(out.len());
                out[..n].copy_from_slice(&t.as_bytes()[..n]);
                n
            }
            Part::Number(v) => {
                let mut digits = [0u8; 20];
                let mut i = digits.len();
                let mut v = *v;
                loop {
                    i -= 1;
                    digits[i] = b'0' + (v % 10) as u8;
                    v /= 10;
                    if v == 0 {
                        break;
                    }
                }
                let d = &digits[i..];
                let n = d.len().min(out.len());
                out[..n].copy_from_slice(&d[..n]);
                n
            }
        }
    }
}

// SAFETY: every call goes to `System` with the caller's layout; the counting around it
// touches only atomics (or ends the process).
unsafe impl GlobalAlloc for Bounded {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        admit(layout.size());
        // SAFETY: forwarded with the caller's guarantees.
        let p = unsafe { System.alloc(layout) };
        if p.is_null() {
            LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        admit(layout.size());
        // SAFETY: forwarded with the caller's guarantees.
        let p = unsafe { System.alloc_zeroed(layout) };
        if p.is_null() {
            LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded with the caller's guarantees.
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let old = layout.size();
        if new_size > old {
            admit(new_size - old);
        }
        // SAFETY: forwarded with the caller's guarantees.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if p.is_null() {
            if new_size > old {
                LIVE.fetch_sub(new_size - old, Ordering::Relaxed);
            }
        } else if new_size < old {
            LIVE.fetch_sub(old - new_size, Ordering::Relaxed);
        }
        p
    }
}
