//! `latticebuild graph MANIFEST`: the stage graph in build order, one line per stage, marked
//! cached or stale (with the reason) and naming what it reads; `--json` prints the same as a
//! JSON array, `--dot` as a Graphviz digraph. It builds nothing and writes nothing.

use clap::Args;

use super::{Failure, ManifestArgs, compile, load_manifest, open_cache};
use crate::files::OutputDir;
use crate::graph::status;

#[derive(Args, Debug, Clone)]
pub struct GraphArgs {
    #[command(flatten)]
    pub manifest: ManifestArgs,
    /// Print the graph as JSON: an array of `{id, kind, status, why, inputs}` in build order
    #[arg(long, conflicts_with = "dot")]
    pub json: bool,
    /// Print the graph in Graphviz's DOT language (`| dot -Tsvg > graph.svg`)
    #[arg(long)]
    pub dot: bool,
}

pub fn run(args: &GraphArgs) -> Result<(), Failure> {
    let manifest = load_manifest(&args.manifest)?;
    let graph = compile(&manifest)?;
    let cache = open_cache(&manifest.path, false)?;
    let sink = OutputDir::new(manifest.out_dir.clone());
    let nodes = status::statuses(&graph, &cache, &sink);
    if args.json {
        let json = serde_json::to_string_pretty(&nodes).expect("statuses serialize");
        println!("{json}");
    } else if args.dot {
        print!("{}", status::dot(&nodes));
    } else {
        for line in status::lines(&nodes) {
            println!("{line}");
        }
    }
    Ok(())
}
