//! `latticebuild clean MANIFEST`: removes the manifest's cache and the temporary files
//! interrupted builds left among its outputs. The outputs themselves stay.

use super::{Failure, ManifestArgs, load_manifest, open_cache, sweep_outputs};

pub fn run(args: &ManifestArgs) -> Result<(), Failure> {
    let manifest = load_manifest(args)?;
    let mut cache = open_cache(&manifest.path, false)?;
    sweep_outputs(&manifest, false);
    cache.clean().map_err(|e| Failure::Build(e.to_string()))?;
    eprintln!("removed the cache of `{}`", manifest.path.display());
    Ok(())
}
