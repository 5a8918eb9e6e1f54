//! Streaming, watertight marching cubes with the solid capped on the domain box.
//!
//! Input: a [`PlaneSampler`] of the solid's implicit function (negative inside; NaN counts as
//! outside) and the grid of the same samples in model units. Output: one indexed [`Mesh`]
//! that is closed, manifold and outward-oriented whenever the solid touches the domain box,
//! because the cut through the solid on each box face is capped with the same face rule
//! that draws the surface (see [`table`]).
//!
//! Why our own: no crate is both streaming (never holding the N³ grid) and watertight with
//! shared vertices and caps; see `shared/docs/CRATES.md`.
//!
//! Invariants:
//! - Memory: a chunk holds two planes of samples and vertex ids at a time, so memory grows
//!   with N² (planes and the surface itself), never N³.
//! - Determinism: chunk boundaries depend only on the grid, chunks are assembled in order and
//!   samples are pure functions of their plane, so the mesh is bit-identical whatever the
//!   number of threads.
//! - No two vertices share an `f32` position and no triangle is flat, wherever the grid is
//!   placed. Crossings stay 1/256 of an edge from its ends (even where the field is exactly
//!   zero at a sample), and their `f32` positions strictly inside their edge's rounded ends
//!   ([`crate::mesh::round_inside`]): far from the origin 1/256 of an edge can be less than an
//!   `f32` step, and a crossing rounded onto its sample point collided with its neighbours (a
//!   gyroid on [1000, 1002]³ at 200 samples: 366 duplicate positions, 747 flat triangles).
//!   A grid whose rounded samples leave no `f32` strictly inside some edge cannot keep that
//!   promise and is refused ([`ContourError::BeyondF32`]): the mesh is written as `f32` (STL
//!   has nothing else), so no placement of its vertices would be honest. Vertices are
//!   computed once, in `f64` from the grid, and rounded once.

mod chunk;
pub mod table;

use rayon::prelude::*;

use crate::field::{Grid, PlaneSampler};
use crate::mesh::{Mesh, inseparable_edge};
use chunk::{ChunkContext, ChunkMesh, FOREIGN};

/// Why a grid could not be contoured.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum ContourError {
    #[error("the grid needs at least 2 samples per axis, got {0:?}")]
    TooFewSamples([usize; 3]),
    /// The box, as `[x0,x1]×[y0,y1]×[z0,z1]`.
    #[error(
        "the box {0} cannot be sampled: its sides must be finite and positive, and so must \
         the spacing of its samples"
    )]
    BadBox(String),
    #[error("the mesh would have {0} vertices, more than 32-bit indices can address")]
    TooManyVertices(u64),
    #[error("the sampler's grid has {sampler:?} samples but the model grid has {model:?}")]
    GridMismatch {
        sampler: [usize; 3],
        model: [usize; 3],
    },
    /// Two neighbouring samples so close for their distance from the origin that no 32-bit
    /// float lies between their own roundings: no vertex could be placed between them.
    #[error(
        "the samples are too close together for 32-bit positions (what mesh files store) this far from the origin: along {} samples {index} and {} lie at {} and {}, with no 32-bit value between them; place the domain nearer the origin or use fewer samples",
        ["x", "y", "z"][*axis],
        index + 1,
        f64::from_bits(at_bits[0]),
        f64::from_bits(at_bits[1])
    )]
    BeyondF32 {
        axis: usize,
        index: usize,
        /// The two coordinates, as bits (keeping the error `Eq`).
        at_bits: [u64; 2],
    },
}

/// Cube layers per chunk: about 32 chunks whatever the size, bounded so small grids still
/// split and big ones keep the duplicated seam planes rare. Depends only on the grid.
fn layers_per_chunk(cube_layers: usize) -> usize {
    cube_layers.div_ceil(32).clamp(4, 64)
}

/// Contours the solid `{g < 0}` sampled by `sampler` on `model` (same counts, model units).
/// `progress(n)` is called from worker threads as cube layers complete (total `nz − 1`).
pub fn contour(
    sampler: &dyn PlaneSampler,
    model: &Grid,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Mesh, ContourError> {
    let counts = model.counts;
    if counts.iter().any(|&n| n < 2) {
        return Err(ContourError::TooFewSamples(counts));
    }
    if sampler.grid().counts != counts {
        return Err(ContourError::GridMismatch {
            sampler: sampler.grid().counts,
            model: counts,
        });
    }
    for (axis, &count) in counts.iter().enumerate() {
        if let Some((index, a, b)) = inseparable_edge(count, |i| model.coord(axis, i)) {
            return Err(ContourError::BeyondF32 {
                axis,
                index,
                at_bits: [a.to_bits(), b.to_bits()],
            });
        }
    }
    let ctx = ChunkContext {
        sampler,
        model,
        tables: table::tables(),
    };
    let cube_layers = counts[2] - 1;
    let per_chunk = layers_per_chunk(cube_layers);
    let ranges: Vec<(usize, usize)> = (0..cube_layers)
        .step_by(per_chunk)
        .map(|k0| (k0, (k0 + per_chunk).min(cube_layers)))
        .collect();
    let chunks: Vec<ChunkMesh> = ranges
        .par_iter()
        .map_init(
            || ctx.scratch(),
            |scratch, &(k0, k1)| ctx.run(k0, k1, scratch, progress),
        )
        .collect();
    assemble(chunks)
}

/// Concatenates chunk meshes in order, turning local and foreign ids into global ones.
fn assemble(mut chunks: Vec<ChunkMesh>) -> Result<Mesh, ContourError> {
    let mut offsets = Vec::with_capacity(chunks.len() + 1);
    let mut total = 0u64;
    for c in &chunks {
        offsets.push(total);
        total += c.vertices.len() as u64;
    }
    offsets.push(total);
    if total > u64::from(u32::MAX) {
        return Err(ContourError::TooManyVertices(total));
    }
    chunks.par_iter_mut().enumerate().for_each(|(c, chunk)| {
        let (own, next) = (
            offsets[c] as u32,
            offsets[(c + 1).min(offsets.len() - 1)] as u32,
        );
        for tri in &mut chunk.triangles {
            for id in tri.iter_mut() {
                *id = if *id & FOREIGN != 0 {
                    next + (*id & !FOREIGN)
                } else {
                    own + *id
                };
            }
        }
    });
    let triangle_count = chunks.iter().map(|c| c.triangles.len()).sum();
    let mut mesh = Mesh {
        vertices: Vec::with_capacity(total as usize),
        triangles: Vec::with_capacity(triangle_count),
    };
    for chunk in chunks {
        mesh.vertices.extend_from_slice(&chunk.vertices);
        mesh.triangles.extend_from_slice(&chunk.triangles);
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests;
