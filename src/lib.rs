//! latticebuild: a TOML manifest of unit cells and outputs, compiled into a DAG of cached
//! stages that produce watertight lattice meshes. See `docs/ARCHITECTURE.md` for the map.

pub mod budget;
pub mod build;
pub mod cache;
pub mod cli;
pub mod commands;
pub mod diagnostics;
pub mod direct_file;
pub mod early;
pub mod files;
pub mod graph;
pub mod interrupt;
pub mod manifest;
pub mod progress;
pub mod report;
pub mod serve;
pub mod stages;

#[cfg(test)]
mod boundary_tests;
