//! `latticebuild watch`: build, then rebuild on every save of the manifest or a file it
//! references.
//!
//! Invariants: builds run one at a time on this thread (events that arrive during a build are
//! coalesced into one rebuild after it); a broken manifest prints its errors and keeps
//! watching; Ctrl-C ends the loop between builds, so no build is cut off half-way.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::mpsc;
use std::time::Duration;

use notify::RecursiveMode;
use notify_debouncer_full::{DebounceEventResult, new_debouncer};

use crate::cli::{BuildArgs, Failure, load_manifest, run_build};

enum Event {
    Changed(Vec<PathBuf>),
    Stop,
}

/// Absolute form of `path` for comparing event paths (the file may not exist yet).
fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

pub fn watch(args: &BuildArgs) -> ExitCode {
    let (tx, rx) = mpsc::channel::<Event>();
    let stop = tx.clone();
    if let Err(e) = ctrlc::set_handler(move || {
        let _ = stop.send(Event::Stop);
    }) {
        return Failure::Build(format!("cannot handle Ctrl-C: {e}")).exit();
    }
    let events = tx.clone();
    let debouncer = new_debouncer(
        Duration::from_millis(200),
        None,
        move |result: DebounceEventResult| {
            if let Ok(batch) = result {
                let paths = batch.into_iter().flat_map(|e| e.event.paths).collect();
                let _ = events.send(Event::Changed(paths));
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
                eprintln!("warning: cannot watch `{}`: {e}", dir.display());
            }
        }
        for dir in watched_dirs.difference(&dirs) {
            let _ = debouncer.unwatch(dir);
        }
        watched_dirs = dirs;

        match run_build(args) {
            Ok(()) => {}
            Err(Failure::Usage(text)) => eprint!("{text}"),
            Err(Failure::Build(text)) => eprintln!("error: {text}"),
        }
        if !args.quiet {
            eprintln!(
                "watching `{}` for changes (Ctrl-C to stop)",
                args.manifest.manifest.display()
            );
        }
        // Wait for a change to a file that matters; fold a burst of saves into one rebuild.
        loop {
            match rx.recv() {
                Err(_) | Ok(Event::Stop) => return ExitCode::SUCCESS,
                Ok(Event::Changed(paths)) => {
                    let mut relevant = paths.iter().any(|p| files.contains(&absolute(p)));
                    while let Ok(next) = rx.try_recv() {
                        match next {
                            Event::Stop => return ExitCode::SUCCESS,
                            Event::Changed(more) => {
                                relevant |= more.iter().any(|p| files.contains(&absolute(p)));
                            }
                        }
                    }
                    if relevant {
                        break;
                    }
                }
            }
        }
    }
}
