//! latticebuild: a TOML manifest of unit cells and outputs, compiled into a DAG of cached
//! stages that produce watertight lattice meshes. See `docs/ARCHITECTURE.md` for the map.

pub mod cache;
pub mod diagnostics;
pub mod manifest;
