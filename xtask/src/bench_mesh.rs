//! `cargo xtask bench-mesh [triangles] [samples]`: builds and runs the release mesh SDF
//! benchmark (`crates/geom/examples/mesh_sdf_bench.rs`): a 1,000,000-triangle torus by default,
//! sampled on a 128³ grid.

use std::process::Command;

pub fn run(args: &[String]) -> Result<(), String> {
    for a in args {
        if a.parse::<u64>().is_err() {
            return Err(format!(
                "bench-mesh takes numbers (triangles, samples per axis), not `{a}`"
            ));
        }
    }
    super::run(
        Command::new(env!("CARGO"))
            .current_dir(super::root())
            .args([
                "run",
                "--release",
                "--quiet",
                "-p",
                "latticebuild-geom",
                "--example",
                "mesh_sdf_bench",
                "--",
            ])
            .args(args),
    )
}
