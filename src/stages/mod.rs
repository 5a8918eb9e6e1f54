//! The stages: what each node of the graph computes, and what goes into its cache key.
//!
//! Invariants:
//! - A stage is a pure function of its parameters and its inputs' payloads. Only the write
//!   and preview stages have an effect, and they reach files solely through the
//!   [`OutputSink`] the CLI gives them; stages never open paths themselves.
//! - Everything a stage's result depends on is in its key: kind, version (bump it whenever the
//!   algorithm changes what it produces), parameters, and its inputs' payload hashes.
//!
//! | stage     | parameters in the key                                   | input          | payload |
//! |-----------|---------------------------------------------------------|----------------|---------|
//! | `file`    | — (the builder reads the file; its hash is the content's) | —            | the file's bytes (not cached) |
//! | `cell`    | source kind, TPMS name or expression text               | —              | canonical formula text |
//! | `mesh`    | format, placement, sample                               | file bytes     | placed soup ([`mesh`]), the `cell:` node of a mesh cell |
//! | `crystal` | format, species, tolerance, max_scale, include_images, optimize | file bytes | PS model ([`crystal`]), the `cell:` node of a crystal cell |
//! | `density` | group, region (period or element), distance level and scale (shells) | cell payload | `V(level)` quantile table ([`sizing`]) |
//! | `contour` | domain, cell size, solid, offset, thickness, sizing, samples, within, skin | cell payload (+ part file) (+ density table) | mesh + its check ([`artifact`]) |
//! | `sample`  | group, N, mirror, symmetrize                            | cell payload   | `N^d` samples of the sampling domain |
//! | `fit`     | group, N (or tolerance, mirror, symmetrize for `auto`)  | samples (or cell payload for `auto`) | coefficient table (JSON) |
//! | `blend`   | group, weights                                          | member coefficient tables | coefficient table |
//! | `minkowski` | group, op, N                                          | two coefficient tables | coefficient table |
//! | `constrain` | group, normal_to_faces, offset, invert, optimize      | coefficient table | coefficient table + constraint report |
//! | `tile`    | scaffold (extension, or grid), group, by, solid, offset, thickness, graded thickness/offset, sizing, resolution, skin | cell table(s) (+ scaffold file bytes) (+ density table) | mesh + its check + the tiling's counts and scaffold volume |
//! | `sdf`     | canonical program (paths as input numbers), bounds, samples or voxel | the `file` words' bytes | mesh + its check + the box |
//! | `islands` | keep, min_island_volume                                 | contour, sdf or tile payload | the kept mesh + its check + what was removed ([`islands`]) |
//! | `write`   | formats, encoding, path stem                            | contour payload| files written and the mesh summary (JSON) |
//! | `preview` | output name, path stem, size, domain, within            | mesh, write record, warning cells | the PNG written (JSON) |

pub mod artifact;
pub mod cell;
pub mod chunked;
pub mod contour;
pub mod crystal;
pub mod error;
pub mod file;
pub mod islands;
pub mod measure;
pub mod mesh;
pub mod points;
pub mod preview;
pub mod program;
pub mod sizing;
pub mod symmetric;
pub mod tile;
pub mod voxels;
pub mod warnings;
pub mod write;

use crate::cache::{ContentHash, Key, KeyBuilder, KeyDescription, KeyError};
use crate::manifest::{Cell, Output};

pub use artifact::{
    MeshArtifact, MeshSummary, Removed, ShellSummary, TilingSummary, WrittenFile, WrittenOutput,
};
pub use error::{GeomError, StageError};
pub use write::{OutputSink, PendingFile, Prewritten};

/// One node's computation, with its parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum Stage {
    File(file::FileStage),
    Cell(cell::CellStage),
    MeshCell(mesh::MeshCellStage),
    VoxelCell(voxels::VoxelCellStage),
    PointCell(points::PointCellStage),
    Crystal(crystal::CrystalStage),
    Sample(symmetric::SampleStage),
    Fit(symmetric::FitStage),
    Combine(symmetric::CombineStage),
    Constrain(symmetric::ConstrainStage),
    Density(sizing::DensityStage),
    Contour(contour::ContourStage),
    Program(program::ProgramStage),
    Tile(tile::TileStage),
    Islands(islands::IslandsStage),
    Write(write::WriteStage),
    Preview(preview::PreviewStage),
}

impl Stage {
    pub fn cell(cell: &Cell) -> Stage {
        Stage::Cell(cell::CellStage::new(cell))
    }

    /// The contour of `output`, reading a formula (`fitted == false`) or a fitted cell.
    pub fn contour(output: &Output, fitted: Option<&crate::manifest::Symmetric>) -> Stage {
        Stage::Contour(contour::ContourStage::new(output, fitted))
    }

    pub fn kind(&self) -> &'static str {
        match self {
            Stage::File(_) => "file",
            Stage::Cell(_) => "cell",
            Stage::MeshCell(_) => "mesh",
            Stage::VoxelCell(_) => "voxels",
            Stage::PointCell(_) => "points",
            Stage::Crystal(_) => "crystal",
            Stage::Sample(_) => "sample",
            Stage::Fit(_) => "fit",
            Stage::Combine(s) => s.kind(),
            Stage::Constrain(_) => "constrain",
            Stage::Density(_) => "density",
            Stage::Contour(_) => "contour",
            Stage::Program(_) => "sdf",
            Stage::Tile(_) => "tile",
            Stage::Islands(_) => "islands",
            Stage::Write(_) => "write",
            Stage::Preview(_) => "preview",
        }
    }

    /// Bumped whenever the stage's algorithm changes what it produces.
    pub fn version(&self) -> u32 {
        match self {
            Stage::Cell(_) => cell::VERSION,
            Stage::File(_) => file::VERSION,
            Stage::MeshCell(_) => mesh::VERSION,
            Stage::VoxelCell(_) => voxels::VERSION,
            Stage::PointCell(_) => points::VERSION,
            Stage::Crystal(_) => crystal::VERSION,
            Stage::Sample(_) | Stage::Fit(_) | Stage::Combine(_) | Stage::Constrain(_) => {
                symmetric::VERSION
            }
            Stage::Density(_) => sizing::VERSION,
            Stage::Contour(_) => contour::VERSION,
            Stage::Program(_) => program::VERSION,
            Stage::Tile(_) => tile::VERSION,
            Stage::Islands(_) => islands::VERSION,
            Stage::Write(_) => write::VERSION,
            Stage::Preview(_) => preview::VERSION,
        }
    }

    /// The cache key from the parameters and the payload hashes of the inputs, in order.
    pub fn key(&self, inputs: &[ContentHash]) -> Result<(Key, KeyDescription), KeyError> {
        let builder = KeyBuilder::new(self.kind(), self.version());
        let builder = match self {
            Stage::File(_) => builder,
            Stage::Cell(s) => s.key_params(builder),
            Stage::MeshCell(s) => s.key_params(builder),
            Stage::VoxelCell(s) => s.key_params(builder),
            Stage::PointCell(s) => s.key_params(builder),
            Stage::Crystal(s) => s.key_params(builder),
            Stage::Sample(s) => s.key_params(builder),
            Stage::Fit(s) => s.key_params(builder),
            Stage::Combine(s) => s.key_params(builder),
            Stage::Constrain(s) => s.key_params(builder),
            Stage::Density(s) => s.key_params(builder),
            Stage::Contour(s) => s.key_params(builder),
            Stage::Program(s) => s.key_params(builder),
            Stage::Tile(s) => s.key_params(builder),
            Stage::Islands(s) => s.key_params(builder),
            Stage::Write(s) => s.key_params(builder),
            Stage::Preview(s) => s.key_params(builder),
        };
        let builder = inputs
            .iter()
            .enumerate()
            .fold(builder, |b, (i, hash)| b.input(&self.input_name(i), *hash));
        builder.build()
    }

    /// The name of input `i`, as it appears in keys and `-v` explanations.
    pub fn input_name(&self, i: usize) -> String {
        match self {
            Stage::File(_) | Stage::Cell(_) => format!("input {i}"),
            Stage::MeshCell(_) => "mesh file".into(),
            Stage::VoxelCell(_) => "voxel file".into(),
            Stage::PointCell(_) => "point file".into(),
            Stage::Crystal(_) => "crystal file".into(),
            Stage::Sample(_) => "formula".into(),
            Stage::Fit(s) if s.reads_samples() => "samples".into(),
            Stage::Fit(_) => "formula".into(),
            Stage::Combine(_) => format!("cell {}", i + 1),
            Stage::Constrain(_) => "fit".into(),
            Stage::Density(_) => "cell".into(),
            Stage::Contour(_) if i == 0 => "cell".into(),
            Stage::Contour(s) if i == 1 && s.within.is_some() => "part".into(),
            Stage::Contour(_) => "density table".into(),
            Stage::Program(s) => format!("file {}", s.files.get(i).map_or("?", |f| f.as_str())),
            Stage::Tile(s) if i < s.cell_inputs() => format!("cell {}", i + 1),
            Stage::Tile(s) if i == s.cell_inputs() && s.reads_file() => "scaffold".into(),
            Stage::Tile(_) => "density table".into(),
            Stage::Islands(_) | Stage::Write(_) => "mesh".into(),
            Stage::Preview(_) if i == 0 => "mesh".into(),
            Stage::Preview(_) if i == 1 => "files".into(),
            Stage::Preview(s) => format!(
                "{} (its warnings)",
                s.carriers.get(i - 2).map_or("?", |c| c.as_str())
            ),
        }
    }
}
