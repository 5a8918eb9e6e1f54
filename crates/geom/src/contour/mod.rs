//! Streaming, watertight marching cubes with the solid capped on the domain box.
//!
//! Input: a [`PlaneSampler`] of the solid's implicit function (negative inside; NaN counts as
//! outside) and the grid of the same samples in model units. Output: one indexed [`Mesh`]
//! that is closed, manifold and outward-oriented whenever the solid touches the domain box,
//! because the cut through the solid on each box face is capped with the same face rule
//! that draws the surface (see [`table`]).
//!
//! Why our own: no crate is both streaming (never holding the N³ grid) and watertight with
//! shared vertices and caps: the extractors we measured hold the whole grid, are f32-only or
//! abandoned, or (surface nets) leave non-manifold edges on thin sheets.
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
//!   A shell's two levels can cross one edge; their crossings also stay 1/256 of an edge
//!   apart, and apart in `f32` (moved a step where rounding merges them). A grid whose
//!   rounded samples leave no `f32` strictly inside some edge (two, for a shell) cannot keep
//!   that promise and is refused ([`ContourError::BeyondF32`]): the mesh is written as `f32` (STL
//!   has nothing else), so no placement of its vertices would be honest. Vertices are
//!   computed once, in `f64` from the grid, and rounded once.
//!
//! Shells ([`contour_band`]). A shell `|f − c| ≤ w/2` sampled as one implicit function
//! `|f − c| − w/2` vanishes wherever its wall passes between two samples: `f − c` changes
//! sign there, but the sampled function is positive at both ends. So a shell is contoured as
//! the band `lo < f < hi` of `f` itself, each sample being below, between or above, and each
//! level's crossings interpolated linearly in `f` (both can lie on one edge); its volume then
//! converges like a level set's, at any wall the grid can place two crossings across. Why a
//! three-state marching cubes rather than contouring `{f ≤ hi}` and `{f ≥ lo}` separately and
//! combining them: the two levels never meet inside a cube, so the one-level tables serve
//! both (see [`table`]); only the caps on the box need a band table (the between part of a
//! face, which the combination would have had to compute as a 2D difference of two caps),
//! and one pass keeps one vertex numbering, the chunking, the seam rule and the determinism
//! as they are.

mod chunk;
pub(crate) use chunk::{apart_in_f32, band_crossing, band_fraction, crossing_fraction, spans_band};
pub mod table;
mod tetra;
pub use tetra::contour_tetrahedra;

use rayon::prelude::*;

use crate::field::{Band, Grid, PlaneSampler};
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
    /// Two neighbouring samples so close for their distance from the origin that fewer than
    /// `needed` (1, or 2 for a shell) 32-bit floats lie between their own roundings: the
    /// edge's crossings could not be placed between them.
    #[error(
        "the samples are too close together for 32-bit positions (what mesh files store) this far from the origin: along {} samples {index} and {} lie at {} and {}, with {} between them; place the domain nearer the origin or use fewer samples",
        ["x", "y", "z"][*axis],
        index + 1,
        f64::from_bits(at_bits[0]),
        f64::from_bits(at_bits[1]),
        crate::mesh::room_wanting(*needed)
    )]
    BeyondF32 {
        axis: usize,
        index: usize,
        needed: usize,
        /// The two coordinates, as bits (keeping the error `Eq`).
        at_bits: [u64; 2],
    },
}

/// How a solid is contoured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Contouring {
    /// Marching cubes (this module): fewer triangles, chunked in parallel.
    #[default]
    Cubes,
    /// Marching tetrahedra ([`contour_tetrahedra`]): six tetrahedra per cube, no tables.
    Tetrahedra,
}

impl Contouring {
    /// The name a manifest or command line gives it.
    pub fn name(self) -> &'static str {
        match self {
            Contouring::Cubes => "cubes",
            Contouring::Tetrahedra => "tetrahedra",
        }
    }

    /// The method named `name` (`cubes`, `tetrahedra`), if any.
    pub fn from_name(name: &str) -> Option<Contouring> {
        match name {
            "cubes" => Some(Contouring::Cubes),
            "tetrahedra" => Some(Contouring::Tetrahedra),
            _ => None,
        }
    }
}

/// Contours the solid `{g < 0}` with the method asked for (see [`contour`],
/// [`contour_tetrahedra`]).
pub fn contour_with(
    method: Contouring,
    sampler: &dyn PlaneSampler,
    model: &Grid,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Mesh, ContourError> {
    match method {
        Contouring::Cubes => contour(sampler, model, progress),
        Contouring::Tetrahedra => contour_tetrahedra(sampler, model, progress),
    }
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
    Ok(run(sampler, None, model, progress)?.0)
}

/// A band's mesh, and what the contourer saw of its wall.
#[derive(Clone, Debug, PartialEq)]
pub struct BandMesh {
    pub mesh: Mesh,
    /// The largest `|∇f|` in field units per sample step, over the cubes the band's middle
    /// level crosses (each cube's forward differences, averaged per axis); 0 if it crosses
    /// none. The wall there is about `(hi − lo) / steepest` sample spacings thick.
    pub steepest: f64,
}

impl BandMesh {
    /// The thinnest wall the samples saw, in sample spacings: the band's width over
    /// [`BandMesh::steepest`]. `None` when the middle level crosses no cube (or `f` is flat).
    pub fn thinnest_wall(&self, band: Band) -> Option<f64> {
        BandMesh::wall(band, self.steepest)
    }

    /// The wall of `band` where `f` is as steep as `steepest` (per sample step), in sample
    /// spacings; `None` for a flat or uncrossed field.
    pub fn wall(band: Band, steepest: f64) -> Option<f64> {
        (steepest > 0.0).then(|| (band.hi - band.lo) / steepest)
    }
}

/// Contours the band `lo < f < hi` of the field `f` sampled by `sampler` on `model`: a shell
/// (module docs). The mesh is closed, manifold and outward as [`contour`]'s, capped on the
/// box; an empty band (`lo ≥ hi`, or NaN) gives an empty mesh.
pub fn contour_band(
    sampler: &dyn PlaneSampler,
    band: Band,
    model: &Grid,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<BandMesh, ContourError> {
    // The three states need `hi` above `lo`: at or above `hi` must imply above `lo`.
    if band.lo.partial_cmp(&band.hi) != Some(std::cmp::Ordering::Less) {
        check_grids(sampler, Some(band), model)?;
        return Ok(BandMesh {
            mesh: Mesh::default(),
            steepest: 0.0,
        });
    }
    let (mesh, steepest_squared) = run(sampler, Some(band), model, progress)?;
    Ok(BandMesh {
        mesh,
        steepest: steepest_squared.sqrt(),
    })
}

/// [`BandMesh::steepest`] without contouring: the largest `|∇f|` per sample step over the
/// cubes where `f` crosses `level`, for shells another contourer draws (a shell confined to a
/// part). The same cubes and the same estimate as [`contour_band`]'s for a band about `level`;
/// a maximum, so the same for any number of threads.
pub fn steepest_at_level(sampler: &dyn PlaneSampler, level: f64) -> f64 {
    steepest_at_level_within(sampler, level, &|_| true)
}

/// [`steepest_at_level`] over the cubes whose centre `within` accepts (model coordinates):
/// the reference element's, for a tiled cell whose field outside it is never drawn.
pub fn steepest_at_level_within(
    sampler: &dyn PlaneSampler,
    level: f64,
    within: &(dyn Fn([f64; 3]) -> bool + Sync),
) -> f64 {
    let grid = *sampler.grid();
    let centre = |i: usize, j: usize, k: usize| {
        let at = [i, j, k];
        std::array::from_fn(|a| grid.origin[a] + (at[a] as f64 + 0.5) * grid.spacing[a])
    };
    let [nx, ny, nz] = grid.counts;
    if nx < 2 || ny < 2 || nz < 2 {
        return 0.0;
    }
    let cube_layers = nz - 1;
    let per_chunk = layers_per_chunk(cube_layers);
    let ranges: Vec<(usize, usize)> = (0..cube_layers)
        .step_by(per_chunk)
        .map(|k0| (k0, (k0 + per_chunk).min(cube_layers)))
        .collect();
    ranges
        .par_iter()
        .map(|&(k0, k1)| {
            let (mut lower, mut upper) = (vec![0.0; nx * ny], vec![0.0; nx * ny]);
            sampler.sample_plane(k0, &mut lower);
            let mut steepest_squared = 0.0f64;
            for k in k0..k1 {
                sampler.sample_plane(k + 1, &mut upper);
                for j in 0..ny - 1 {
                    for i in 0..nx - 1 {
                        let (a, b) = (j * nx + i, (j + 1) * nx + i);
                        let v = [
                            lower[a],
                            lower[a + 1],
                            lower[b],
                            lower[b + 1],
                            upper[a],
                            upper[a + 1],
                            upper[b],
                            upper[b + 1],
                        ];
                        // Crossed: some corner above the level, some not (NaN is not above).
                        let above = v.iter().filter(|&&x| x > level).count();
                        if above == 0 || above == 8 || !within(centre(i, j, k)) {
                            continue;
                        }
                        steepest_squared = steepest_squared.max(chunk::corner_gradient_squared(&v));
                    }
                }
                std::mem::swap(&mut lower, &mut upper);
            }
            steepest_squared
        })
        .reduce(|| 0.0, f64::max)
        .sqrt()
}

fn check_grids(
    sampler: &dyn PlaneSampler,
    band: Option<Band>,
    model: &Grid,
) -> Result<(), ContourError> {
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
    // A band's two levels may cross one edge, and need an `f32` each strictly inside it.
    let needed = if band.is_some() { 2 } else { 1 };
    for (axis, &count) in counts.iter().enumerate() {
        if let Some((index, a, b)) = inseparable_edge(count, needed, |i| model.coord(axis, i)) {
            return Err(ContourError::BeyondF32 {
                axis,
                index,
                needed,
                at_bits: [a.to_bits(), b.to_bits()],
            });
        }
    }
    Ok(())
}

/// Contours the chunks in parallel and assembles them; also the band's steepest `|∇f|²`.
fn run(
    sampler: &dyn PlaneSampler,
    band: Option<Band>,
    model: &Grid,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<(Mesh, f64), ContourError> {
    check_grids(sampler, band, model)?;
    let counts = model.counts;
    let ctx = ChunkContext {
        sampler,
        model,
        tables: table::tables(),
        band,
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
    // A maximum is exact in any order: the same whatever the number of threads.
    let steepest_squared = chunks
        .iter()
        .map(|c| c.steepest_squared)
        .fold(0.0, f64::max);
    Ok((assemble(chunks)?, steepest_squared))
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
#[cfg(test)]
mod tetra_tests;
