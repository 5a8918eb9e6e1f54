fn main() -> std::process::ExitCode {
    die_quietly_on_closed_pipes();
    // Before any thread starts: every thread must inherit the blocked signals.
    if let Err(e) = latticebuild::interrupt::install() {
        eprintln!("error: cannot take over Ctrl-C: {e}");
        return std::process::ExitCode::from(1);
    }
    latticebuild::cli::main()
}

/// Gives SIGPIPE back its default action, as `cat` or `grep` have it: a write to a pipe whose
/// reader is gone (`latticebuild cell --json | head -1`) ends the process quietly, with the
/// status of that signal. Rust's runtime ignores SIGPIPE, so such a write returns EPIPE
/// instead and `println!` panics on it (exit 101 and a backtrace). The alternative, checking
/// every write to stdout and stderr, would have to reach each `println!`/`eprintln!` of every
/// command, and miss the next one added. A pipe is the only thing this changes: files are
/// written as before, and what a build had written is in place (outputs are renamed into
/// place whole; the report goes to stdout last), as after Ctrl-C.
#[cfg(unix)]
fn die_quietly_on_closed_pipes() {
    // SAFETY: `signal` with `SIG_DFL` only resets the disposition; no handler runs Rust code,
    // and this runs before any other thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[cfg(not(unix))]
fn die_quietly_on_closed_pipes() {}
