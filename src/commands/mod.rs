//! What the commands share: the manifest arguments, loading and compiling a manifest, the
//! cache, and how a command fails ([`Failure`], with its exit code). `build` is the one
//! command both the command line and `watch` run, so it lives here, below both of them.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args;

use crate::cache::Cache;
use crate::diagnostics::render;
use crate::graph::Graph;
use crate::manifest::{self, Manifest};

pub mod build;

#[derive(Args, Debug, Clone)]
pub struct ManifestArgs {
    /// The manifest (TOML)
    pub manifest: PathBuf,
    /// Override a manifest value, e.g. `--set outputs.g.offset=0.12` (repeatable)
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
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
                eprint!("{text}");
                ExitCode::from(2)
            }
            Failure::Build(text) => {
                eprintln!("error: {text}");
                ExitCode::from(1)
            }
        }
    }
}

/// Loads and validates the manifest, rendering every diagnostic on failure.
pub fn load_manifest(args: &ManifestArgs) -> Result<Manifest, Failure> {
    manifest::load(&args.manifest, &args.set).map_err(|diags| Failure::Usage(render(&diags)))
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

/// Every file the manifest's outputs write (each format, a planar drawing, the report), as
/// the writers name them: `out_dir` joined with the output's stem and extension.
fn output_files(manifest: &Manifest) -> Vec<PathBuf> {
    let outputs = (manifest.outputs.iter()).map(|(name, o)| (name, &o.stem, &o.formats));
    let sdf = (manifest.sdf_outputs.iter()).map(|(name, o)| (name, &o.stem, &o.formats));
    let tiled = (manifest.tiled_outputs.iter()).map(|(name, o)| (name, &o.stem, &o.formats));
    let mut files = Vec::new();
    for (name, stem, formats) in outputs.chain(sdf).chain(tiled) {
        let extensions = formats.iter().map(|f| f.name()).chain(["svg"]);
        files.extend(extensions.map(|ext| manifest.out_dir.join(format!("{stem}.{ext}"))));
        files.push(manifest.out_dir.join(format!("{name}.report.json")));
    }
    files
}

/// Removes the temporary files that killed builds left of the manifest's output files.
pub(crate) fn sweep_outputs(manifest: &Manifest, verbose: bool) {
    for path in crate::files::sweep_stale_temporaries(&output_files(manifest)) {
        if verbose {
            eprintln!(
                "  removed `{}`, left by an interrupted build",
                path.display()
            );
        }
    }
}
