//! The `islands` stage: an output's mesh without its loose pieces (`keep = "largest"`,
//! `min_island_volume = V`), between the stage that made the mesh (`contour`, `sdf`, `tile`)
//! and `write`. Only outputs that ask for it have the node, so adding or changing the two keys
//! reruns this stage and the write, nothing before.
//!
//! Invariants:
//! - A pure function of the filter and its input's payload; what a piece is, which cavity
//!   belongs to which piece, and the output's order are `latticebuild_geom::islands`'s.
//! - The result is a mesh payload of the kind of its input (whole, or chunked for a 3D
//!   tiling) whose summary (check, pieces) is of the kept mesh, with what was removed beside
//!   it (`MeshSummary::removed`); the input's tiling, shell and SDF box are carried over
//!   unchanged (they describe how the mesh was made).
//! - A tiled (chunked) input is never held whole: it is read from its cache entry two or three
//!   times, a chunk at a time (`geom::islands::IslandLabeller`: label the pieces; a ray pass
//!   when a cavity's owner must be found; `IslandKeeper`: keep), and the kept chunks, checked
//!   and counted as they pass, go to a chunked entry of their own ([`IslandsStage::run_chunked`]),
//!   as the tile stage's do. The bytes are those the whole-mesh filter would give.
//! - Planar regions (open surfaces measured by area) are refused: their SVG drawing is made
//!   with the region, before this stage, and would still show the removed parts.
//! - Removing every piece is an error naming the keys, never an empty file.

use std::sync::Arc;

use latticebuild_geom::islands::{
    IslandError, IslandFilter, IslandLabeller, Removal, remove_islands,
};
use latticebuild_geom::mesh::{Mesh, MeshChunk};
use latticebuild_geom::validate::{PieceCounter, StreamCheck};

use super::StageError;
use super::artifact::{MeshArtifact, MeshSummary, Removed};
use super::chunked::{ChunkedHead, ChunkedMesh, ReadAt, is_corrupt};
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
    Failed(StageError),
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

    /// Filters a whole mesh (a contour's or an SDF program's, or a 2D tiling's).
    pub fn run(&self, artifact: &MeshArtifact) -> Result<MeshArtifact, IslandsFailure> {
        if artifact.planar.is_some() {
            return Err(IslandsFailure::Failed(StageError::DoesNotFit(format!(
                "`outputs.{}` is a planar region: `keep` and `min_island_volume` apply only \
                 to solids (give the region a thickness, e.g. `extrude`, to make it one)",
                self.output
            ))));
        }
        self.filter(&artifact.mesh, artifact)
    }

    /// Filters a chunked mesh a chunk at a time (see the module docs): the kept chunks go to
    /// `chunks`, in order; the result is their head (summary with what was removed, the
    /// input's tiling and shell).
    pub fn run_chunked<R: ReadAt>(
        &self,
        input: &ChunkedMesh<R>,
        chunks: &mut dyn FnMut(Arc<MeshChunk>) -> Result<(), StageError>,
    ) -> Result<ChunkedHead, IslandsFailure> {
        let read = |e: std::io::Error| {
            if is_corrupt(&e) {
                IslandsFailure::CorruptInput(e.to_string())
            } else {
                IslandsFailure::Failed(StageError::ReadChunked(e))
            }
        };
        let mut labeller = IslandLabeller::new(false);
        input
            .for_each_whole_chunk(&mut |chunk| {
                labeller.push(chunk);
                Ok(())
            })
            .map_err(read)?;
        let mut plan = labeller.finish();
        if plan.needs_ray_pass() {
            input
                .for_each_whole_chunk(&mut |chunk| {
                    plan.ray_pass(chunk);
                    Ok(())
                })
                .map_err(read)?;
        }
        let mut keeper = plan.decide(&self.filter).map_err(|e| self.failure(e))?;
        let mut check = StreamCheck::new();
        let mut pieces = PieceCounter::new();
        // An error of the consumer, kept apart from the source's (which may be corruption).
        let mut sent = Ok(());
        input
            .for_each_whole_chunk(&mut |chunk| {
                let kept = Arc::new(keeper.push(chunk));
                if let Err(e) = chunks(Arc::clone(&kept)) {
                    sent = Err(e);
                    return Err(std::io::Error::other("the consumer stopped"));
                }
                rayon::join(|| check.push(&kept), || pieces.push(&kept));
                Ok(())
            })
            .or_else(|e| match &sent {
                Err(_) => Ok(()),
                Ok(()) => Err(read(e)),
            })?;
        sent.map_err(IslandsFailure::Failed)?;
        let head = &input.trailer.head;
        Ok(ChunkedHead {
            summary: MeshSummary {
                removed: Some(removed(keeper.removal())),
                ..MeshSummary::from_check(&check.finish()).with_pieces(&pieces.finish(), false)
            },
            tiling: head.tiling.clone(),
            shell: head.shell.clone(),
            sizing: head.sizing.clone(),
        })
    }

    /// The stage's failure for the filter's error, naming the keys.
    fn failure(&self, e: IslandError) -> IslandsFailure {
        IslandsFailure::Failed(match e {
            IslandError::NothingKept { .. } => StageError::geometry_of(
                format!(
                    "{} of `outputs.{}` would remove every piece",
                    self.keys(),
                    self.output
                ),
                e,
            ),
            _ => StageError::geometry_of(format!("`outputs.{}`", self.output), e),
        })
    }

    /// The filtered mesh, with `made`'s tiling, shell and box.
    fn filter(&self, mesh: &Mesh, made: &MeshArtifact) -> Result<MeshArtifact, IslandsFailure> {
        let filtered = remove_islands(mesh, &self.filter, false).map_err(|e| self.failure(e))?;
        let summary = MeshSummary {
            removed: Some(removed(filtered.removal)),
            ..MeshSummary::of_mesh(&filtered.mesh, false)
        };
        Ok(MeshArtifact {
            mesh: filtered.mesh,
            summary,
            planar: None,
            domain: made.domain,
            tiling: made.tiling.clone(),
            shell: made.shell.clone(),
            sizing: made.sizing.clone(),
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

/// What the report says was removed.
fn removed(r: Removal) -> Removed {
    Removed {
        pieces: r.pieces_removed as u64,
        volume: r.removed,
        largest_piece: r.largest_removed,
        triangles: r.triangles_removed as u64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stages::chunked::ChunkedWriter;
    use latticebuild_geom::mesh_io::{Encoding, Format, write_chunked, write_mesh};

    /// Boxes `(min, size, inward)` as one mesh; the second box's triangles interleaved with
    /// the others', so pieces span chunks.
    fn boxes(list: &[([f32; 3], f32, bool)]) -> Mesh {
        let mut mesh = Mesh::default();
        for &(min, size, inward) in list {
            let base = mesh.vertices.len() as u32;
            mesh.vertices.extend((0..8).map(|c: u32| {
                [0, 1, 2].map(|a| min[a] + if c >> a & 1 == 1 { size } else { 0.0 })
            }));
            for f in [
                [0, 2, 3, 1],
                [4, 5, 7, 6],
                [0, 1, 5, 4],
                [2, 6, 7, 3],
                [0, 4, 6, 2],
                [1, 3, 7, 5],
            ] {
                for t in [[f[0], f[1], f[2]], [f[0], f[2], f[3]]] {
                    let t = if inward { [t[0], t[2], t[1]] } else { t };
                    mesh.triangles.push(t.map(|v| v + base));
                }
            }
        }
        let n = mesh.triangles.len();
        mesh.triangles = (0..n).map(|k| mesh.triangles[(k * 29) % n]).collect();
        mesh
    }

    fn artifact(mesh: Mesh) -> MeshArtifact {
        MeshArtifact {
            summary: MeshSummary::of_mesh(&mesh, false),
            mesh,
            planar: None,
            domain: None,
            tiling: None,
            shell: None,
            sizing: None,
        }
    }

    #[test]
    fn streamed_and_whole_write_the_same_bytes_and_summary() {
        let mesh = boxes(&[
            ([0.0; 3], 10.0, false),
            ([1.0; 3], 8.0, true),
            ([3.0; 3], 2.0, false),
            ([20.0; 3], 1.0, false),
            ([30.0; 3], 3.0, false),
        ]);
        for filter in [
            IslandFilter {
                largest: true,
                min_volume: None,
            },
            IslandFilter {
                largest: false,
                min_volume: Some(5.0),
            },
        ] {
            let stage = IslandsStage {
                output: "x".into(),
                filter,
            };
            let whole = stage.run(&artifact(mesh.clone())).expect("whole");
            for per in [3, 10, 40] {
                let mut writer = ChunkedWriter::new(Vec::new()).expect("memory");
                for chunk in MeshChunk::split(&mesh, per) {
                    writer.push(&chunk).expect("memory");
                }
                let head = ChunkedHead {
                    summary: MeshSummary::of_mesh(&mesh, false),
                    tiling: None,
                    shell: None,
                    sizing: None,
                };
                let bytes = writer.finish(head).expect("memory").0;
                let input = ChunkedMesh::open(bytes).expect("opens");
                let mut kept: Vec<MeshChunk> = Vec::new();
                let head = stage
                    .run_chunked(&input, &mut |chunk| {
                        kept.push((*chunk).clone());
                        Ok(())
                    })
                    .map_err(|e| format!("{e:?}"))
                    .expect("streamed");
                for format in Format::ALL {
                    let (mut a, mut b) = (Vec::new(), Vec::new());
                    write_mesh(&whole.mesh, format, Encoding::Binary, &mut a).expect("whole");
                    write_chunked(&kept, format, Encoding::Binary, &mut b).expect("chunks");
                    assert!(a == b, "{filter:?}, {per} per chunk, {format:?}");
                }
                let (s, w) = (&head.summary, &whole.summary);
                assert_eq!(
                    (s.triangles, s.vertices, s.components, s.watertight),
                    (w.triangles, w.vertices, w.components, w.watertight)
                );
                let (rs, rw) = (s.removed.as_ref(), w.removed.as_ref());
                assert_eq!(rs.map(|r| r.pieces), rw.map(|r| r.pieces));
                assert!((s.volume - w.volume).abs() < 1e-9 * w.volume);
            }
        }
    }
}
