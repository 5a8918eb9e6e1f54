//! The `islands` stage: an output's mesh without its loose pieces (`keep = "largest"`,
//! `min_island_volume = V`), between the stage that made the mesh (`contour`, `sdf`, `tile`)
//! and `write`. Only outputs that ask for it have the node, so adding or changing the two keys
//! reruns this stage and the write, nothing before.
//!
//! Invariants:
//! - A pure function of the filter and its input's payload; what a piece is, which cavity
//!   belongs to which piece, and the output's order are `latticebuild_geom::islands`'s.
//! - The result is a whole mesh payload whose summary (check, pieces) is of the kept mesh,
//!   with what was removed beside it (`MeshSummary::removed`); the input's tiling, shell and
//!   SDF box are carried over unchanged (they describe how the mesh was made).
//! - A tiled (chunked) input is read whole into memory, chunk by chunk, before filtering: a
//!   piece's fate is known only once every chunk is labelled, and the cavities' owners only
//!   after that. Memory is then about the mesh's arrays twice (input and output) plus 12
//!   bytes per vertex; see the report of issue 24 for measurements.
//! - Planar regions (open surfaces measured by area) are refused: their SVG drawing is made
//!   with the region, before this stage, and would still show the removed parts.
//! - Removing every piece is an error naming the keys, never an empty file.

use latticebuild_geom::islands::{IslandError, IslandFilter, remove_islands};
use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::mesh_io::{ChunkSource, Pass};

use super::artifact::{MeshArtifact, MeshSummary, Removed};
use super::chunked::is_corrupt;
use super::write::MeshInput;
use crate::cache::{KeyBuilder, Param};

pub const VERSION: u32 = 1;

/// `islands`: one output's filter.
#[derive(Clone, Debug, PartialEq)]
pub struct IslandsStage {
    /// The output's name, for messages only (not in the key).
    pub output: String,
    pub filter: IslandFilter,
}

/// Why the stage failed.
#[derive(Debug)]
pub enum IslandsFailure {
    /// The chunked input's entry failed verification while being read.
    CorruptInput(String),
    Failed(String),
}

impl IslandsStage {
    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        key.param(
            "keep",
            if self.filter.largest {
                "largest"
            } else {
                "all"
            },
        )
        .param(
            "min_island_volume",
            Param::F64(self.filter.min_volume.unwrap_or(0.0)),
        )
    }

    pub fn run(&self, input: MeshInput) -> Result<MeshArtifact, IslandsFailure> {
        let fail = IslandsFailure::Failed;
        match input {
            MeshInput::Whole(artifact) => {
                if artifact.planar.is_some() {
                    return Err(fail(format!(
                        "`outputs.{}` is a planar region: `keep` and `min_island_volume` \
                         apply only to solids (give the region a thickness, e.g. `extrude`, \
                         to make it one)",
                        self.output
                    )));
                }
                self.filter(&artifact.mesh, artifact)
            }
            MeshInput::Chunked { chunks, head } => {
                let mesh = whole(chunks).map_err(|e| {
                    if is_corrupt(&e) {
                        IslandsFailure::CorruptInput(e.to_string())
                    } else {
                        fail(format!("cannot read the tiled mesh: {e}"))
                    }
                })?;
                let made = MeshArtifact {
                    mesh: Mesh::default(),
                    summary: head.summary.clone(),
                    planar: None,
                    domain: None,
                    tiling: head.tiling.clone(),
                    shell: head.shell.clone(),
                };
                self.filter(&mesh, &made)
            }
        }
    }

    /// The filtered mesh, with `made`'s tiling, shell and box.
    fn filter(&self, mesh: &Mesh, made: &MeshArtifact) -> Result<MeshArtifact, IslandsFailure> {
        let filtered = remove_islands(mesh, &self.filter, false).map_err(|e| {
            IslandsFailure::Failed(match e {
                IslandError::NothingKept { .. } => format!(
                    "{} of `outputs.{}` would remove every piece: {e}",
                    self.keys(),
                    self.output
                ),
                _ => format!("`outputs.{}`: {e}", self.output),
            })
        })?;
        let r = filtered.removal;
        let summary = MeshSummary {
            removed: Some(Removed {
                pieces: r.pieces_removed as u64,
                volume: r.removed,
                largest_piece: r.largest_removed,
                triangles: r.triangles_removed as u64,
            }),
            ..MeshSummary::of_mesh(&filtered.mesh, false)
        };
        Ok(MeshArtifact {
            mesh: filtered.mesh,
            summary,
            planar: None,
            domain: made.domain,
            tiling: made.tiling.clone(),
            shell: made.shell.clone(),
        })
    }

    /// The keys set, as the manifest spells them.
    fn keys(&self) -> String {
        let mut keys = Vec::new();
        if self.filter.largest {
            keys.push("`keep = \"largest\"`".to_string());
        }
        if let Some(v) = self.filter.min_volume {
            keys.push(format!("`min_island_volume = {v}`"));
        }
        keys.join(" with ")
    }
}

/// The whole mesh of a chunked source: the chunks' vertices and triangles concatenated (ids
/// are global and dense, see `MeshChunk`).
fn whole(chunks: &dyn ChunkSource) -> std::io::Result<Mesh> {
    let (nv, nt) = chunks.totals();
    let too_large = || std::io::Error::other("the tiled mesh is too large for this machine");
    let mut mesh = Mesh {
        vertices: Vec::with_capacity(usize::try_from(nv).map_err(|_| too_large())?),
        triangles: Vec::with_capacity(usize::try_from(nt).map_err(|_| too_large())?),
    };
    chunks.for_each_chunk(Pass::Facets, &mut |chunk| {
        mesh.vertices.extend_from_slice(&chunk.vertices);
        mesh.triangles.extend_from_slice(&chunk.triangles);
        Ok(())
    })?;
    Ok(mesh)
}
