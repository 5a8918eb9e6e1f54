//! The commands, one module each, and what they share: the manifest arguments, loading and
//! compiling a manifest, the cache, and how a command fails ([`Failure`], with its exit code).
//! `watch` runs `build` (a sibling); nothing here imports [`crate::cli`], which only parses
//! and dispatches.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args;

use crate::cache::Cache;
use crate::diagnostics::color::paint;
use crate::diagnostics::render;
use crate::graph::Graph;
use crate::manifest::{self, Manifest};

pub mod build;
pub mod cell;
pub mod clean;
pub mod crystal;
pub mod graph;
pub mod sdf;
pub mod watch;

#[derive(Args, Debug, Clone)]
pub struct ManifestArgs {
    /// The manifest (TOML)
    pub manifest: PathBuf,
    /// Override a manifest value, e.g. `--set outputs.g.offset=0.12` (repeatable)
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Remove a manifest key, e.g. `--unset outputs.g.voxel` (repeatable; applied before
    /// every `--set`)
    #[arg(long = "unset", value_name = "KEY")]
    pub unset: Vec<String>,
}

/// Why a build did not succeed, with its exit code.
pub enum Failure {
    /// Bad manifest or arguments: exit 2. The text is already rendered.
    Usage(String),
    /// The build itself failed: exit 1.
    Build(String),
}

impl Failure {
    pub fn exit(self) -> ExitCode {
        match self {
            Failure::Usage(text) => {
                eprint!("{}", paint(&text));
                ExitCode::from(2)
            }
            Failure::Build(text) => {
                eprint!("{}", paint(&format!("error: {text}\n")));
                ExitCode::from(1)
            }
        }
    }
}

/// Loads and validates the manifest, rendering every diagnostic on failure.
pub fn load_manifest(args: &ManifestArgs) -> Result<Manifest, Failure> {
    manifest::load_edited(&args.manifest, &args.set, &args.unset)
        .map_err(|diags| Failure::Usage(render(&diags)))
}

pub(crate) fn open_cache(path: &Path, quiet: bool) -> Result<Cache, Failure> {
    Cache::open_with(path, || {
        if !quiet {
            eprintln!(
                "waiting for another build of `{}` to finish…",
                path.display()
            );
        }
    })
    .map_err(|e| Failure::Build(e.to_string()))
}

pub(crate) fn compile(manifest: &Manifest) -> Result<Graph, Failure> {
    Graph::compile(manifest).map_err(|cycle| Failure::Usage(format!("error: {cycle}\n")))
}

/// Removes the temporary files that killed builds left of the manifest's output files.
pub(crate) fn sweep_outputs(manifest: &Manifest, verbose: bool) {
    for path in crate::files::sweep_stale_temporaries(&manifest::output_paths(manifest)) {
        if verbose {
            eprintln!(
                "  removed `{}`, left by an interrupted build",
                path.display()
            );
        }
    }
}
