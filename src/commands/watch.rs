//! `latticebuild watch`: build, then rebuild whenever the manifest or a file it references
//! changes content.
//!
//! Invariants:
//! - A rebuild happens only when the bytes of a watched file (the manifest and every input
//!   file the last loadable manifest names) differ from what they were when the last build
//!   started, or a watched file appeared or vanished. Events are only a cue to look: reading
//!   a file (the build's own reads raise access events), touching it, or saving the same bytes
//!   rebuild nothing, and neither do the build's writes of outputs and cache, which are not
//!   watched files. So an idle watch does nothing, whatever the last build did.
//! - Builds run one at a time on this thread; changes during a build are compared after it,
//!   against the contents from before it, so a save made mid-build gives one rebuild.
//! - A broken manifest prints its errors and keeps watching.
//! - Ctrl-C between builds ends the watch (exit 0); during a build it stops the build at once,
//!   removing its temporary files ([`crate::interrupt`]).

use std::collections::{BTreeMap, BTreeSet};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::mpsc;
use std::time::Duration;

use notify::RecursiveMode;
use notify_debouncer_full::{DebounceEventResult, new_debouncer};

use crate::commands::build::{BuildArgs, run_build};
use crate::commands::{Failure, load_manifest};
use crate::diagnostics::color::paint;
use crate::interrupt::set_idle;

/// What a watched file held: `None` when it could not be read as a regular file.
type Contents = BTreeMap<PathBuf, Option<blake3::Hash>>;

/// Absolute form of `path` for comparing event paths (the file may not exist yet).
fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

/// The hash of a regular file's bytes; `None` for anything else (absent, unreadable, or not a
/// regular file: a FIFO would block the read).
fn content_hash(path: &Path) -> Option<blake3::Hash> {
    if !std::fs::metadata(path).ok()?.is_file() {
        return None;
    }
    let mut file = std::fs::File::open(path).ok()?;
    let mut hasher = blake3::Hasher::new();
    let mut buffer = vec![0u8; 1 << 16];
    loop {
        match file.read(&mut buffer) {
            Ok(0) => return Some(hasher.finalize()),
            Ok(n) => {
                hasher.update(&buffer[..n]);
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(_) => return None,
        }
    }
}

fn contents(files: &BTreeSet<PathBuf>) -> Contents {
    files.iter().map(|f| (f.clone(), content_hash(f))).collect()
}

pub fn watch(args: &BuildArgs) -> ExitCode {
    let (tx, rx) = mpsc::channel::<Vec<PathBuf>>();
    let debouncer = new_debouncer(
        Duration::from_millis(200),
        None,
        move |result: DebounceEventResult| {
            let Ok(batch) = result else { return };
            // Opening and reading a file are not changes (the build's own reads raise them).
            let paths: Vec<PathBuf> = batch
                .into_iter()
                .filter(|e| !e.event.kind.is_access())
                .flat_map(|e| e.event.paths)
                .collect();
            if !paths.is_empty() {
                let _ = tx.send(paths);
            }
        },
    );
    let mut debouncer = match debouncer {
        Ok(d) => d,
        Err(e) => return Failure::Build(format!("cannot watch files: {e}")).exit(),
    };
    let mut watched_dirs: BTreeSet<PathBuf> = BTreeSet::new();
    loop {
        // Which files matter: the manifest, and whatever the last good manifest references.
        let mut files: BTreeSet<PathBuf> = BTreeSet::from([absolute(&args.manifest.manifest)]);
        if let Ok(manifest) = load_manifest(&args.manifest) {
            files.extend(manifest.inputs.iter().map(|p| absolute(p)));
        }
        // Watch directories, not files: editors save by replacing the file.
        let dirs: BTreeSet<PathBuf> = files
            .iter()
            .filter_map(|f| f.parent().map(Path::to_path_buf))
            .collect();
        for dir in dirs.difference(&watched_dirs) {
            if let Err(e) = debouncer.watch(dir, RecursiveMode::NonRecursive) {
                eprint!(
                    "{}",
                    paint(&format!("warning: cannot watch `{}`: {e}\n", dir.display()))
                );
            }
        }
        for dir in watched_dirs.difference(&dirs) {
            let _ = debouncer.unwatch(dir);
        }
        watched_dirs = dirs;

        let built_from = contents(&files);
        set_idle(false);
        match run_build(args) {
            Ok(()) => {}
            Err(Failure::Usage(text)) => eprint!("{}", paint(&text)),
            Err(Failure::Build(text)) => eprint!("{}", paint(&format!("error: {text}\n"))),
        }
        set_idle(true);
        if !args.quiet {
            eprintln!(
                "watching `{}` for changes (Ctrl-C to stop)",
                args.manifest.manifest.display()
            );
        }
        // Wait until a watched file's contents differ from those the build started from.
        loop {
            let Ok(paths) = rx.recv() else {
                return ExitCode::SUCCESS;
            };
            let mut relevant = paths.iter().any(|p| files.contains(&absolute(p)));
            // Fold a burst of saves into one look.
            while let Ok(more) = rx.try_recv() {
                relevant |= more.iter().any(|p| files.contains(&absolute(p)));
            }
            if relevant && contents(&files) != built_from {
                break;
            }
        }
    }
}
