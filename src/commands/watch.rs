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
//! - With `--serve`, the page ([`crate::serve`]) is told when a build starts and, after it,
//!   gets the reports, the stage graph and the error of the build (a failed build keeps the
//!   last good outputs); the meshes are read here, from the files the reports name, never by
//!   the server. Serving adds no build and no wake-up: an idle watch still does nothing.

use std::collections::{BTreeMap, BTreeSet};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::mpsc;
use std::time::Duration;

use notify::RecursiveMode;
use notify_debouncer_full::{DebounceEventResult, new_debouncer};

use clap::Args;

use crate::commands::build::{BuildArgs, Built, run_build_keeping};
use crate::commands::{Failure, load_manifest};
use crate::diagnostics::color::paint;
use crate::interrupt::set_idle;
use crate::serve::state::{DagNode, MeshCache};
use crate::serve::{Server, mesh, parse_address};

#[derive(Args, Debug, Clone)]
pub struct WatchArgs {
    #[command(flatten)]
    pub build: BuildArgs,
    /// Also serve a live 3D view of the outputs, their reports, the stage graph and the last
    /// error at ADDR (default 127.0.0.1:8700; port 0 picks a free one; the address is printed)
    #[arg(
        long,
        value_name = "ADDR",
        num_args = 0..=1,
        default_missing_value = "127.0.0.1:8700",
        value_parser = parse_address
    )]
    pub serve: Option<std::net::SocketAddr>,
}

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

/// The stage graph of `built` with each node's fate in this build.
fn dag(built: &Built) -> Vec<DagNode> {
    let mut cached: BTreeMap<&str, bool> = BTreeMap::new();
    for report in &built.reports {
        for stage in &report.stages {
            cached.insert(&stage.stage, stage.cached);
        }
    }
    let nodes = &built.graph.nodes;
    built
        .needed
        .iter()
        .map(|&id| DagNode {
            node: nodes[id].name.clone(),
            stage: nodes[id].stage.kind().to_string(),
            inputs: nodes[id]
                .inputs
                .iter()
                .map(|&i| nodes[i].name.clone())
                .collect(),
            status: match cached.get(nodes[id].name.as_str()) {
                Some(true) => "cached",
                Some(false) => "rebuilt",
                None => "not built",
            },
        })
        .collect()
}

/// Tells the page what the build gave: its outputs when it got as far as reports, and its
/// error (`None` clears the last one).
fn publish(
    server: &Server,
    meshes: &mut MeshCache,
    manifest: &Path,
    built: Option<Built>,
    error: Option<String>,
) {
    let mut next = match built {
        Some(built) => meshes.published(
            &manifest.display().to_string(),
            &built.reports,
            dag(&built),
            mesh::DEFAULT_BUDGET,
        ),
        None => (*server.shared.get()).clone(),
    };
    next.manifest = manifest.display().to_string();
    next.building = false;
    next.error = error;
    server.shared.publish(next);
}

pub fn watch(watch_args: &WatchArgs) -> ExitCode {
    let args = &watch_args.build;
    let server = match watch_args.serve {
        None => None,
        Some(address) => match Server::start(address) {
            Ok(server) => {
                println!("serving http://{}/ (Ctrl-C to stop)", server.address);
                Some(server)
            }
            Err(e) => return Failure::Build(format!("cannot serve on {address}: {e}")).exit(),
        },
    };
    let mut meshes = MeshCache::default();
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
        if let Some(server) = &server {
            server.shared.publish(server.shared.get().building());
        }
        let mut built = None;
        let error = match run_build_keeping(args, &mut built) {
            Ok(()) => None,
            Err(Failure::Usage(text)) => {
                eprint!("{}", paint(&text));
                Some(text)
            }
            Err(Failure::Build(text)) => {
                eprint!("{}", paint(&format!("error: {text}\n")));
                Some(format!("error: {text}\n"))
            }
        };
        if let Some(server) = &server {
            publish(server, &mut meshes, &args.manifest.manifest, built, error);
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
