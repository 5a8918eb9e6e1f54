//! `latticebuild graph MANIFEST`: the stage graph in build order, one line per stage, marked
//! cached or stale (with the reason) and naming what it reads. It builds nothing and writes
//! nothing.

use super::{Failure, ManifestArgs, compile, load_manifest, open_cache};
use crate::files::OutputDir;

pub fn run(args: &ManifestArgs) -> Result<(), Failure> {
    let manifest = load_manifest(args)?;
    let graph = compile(&manifest)?;
    let cache = open_cache(&manifest.path, false)?;
    let sink = OutputDir::new(manifest.out_dir.clone());
    for line in crate::graph::status::lines(&graph, &cache, &sink) {
        println!("{line}");
    }
    Ok(())
}
