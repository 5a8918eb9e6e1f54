//! A closed skin of thickness `t` along a scaffold's boundary: the tiled solid becomes
//! `{Φ ≤ 0} ∪ {d_∂(x) ≤ t}`, with `d_∂` the unsigned distance to the scaffold's boundary faces
//! (model units), as the field `min(Φ, d_∂ − t)`.
//!
//! How it stays exact across faces: the skin term at a lattice point is evaluated at the
//! point's *intrinsic* position `Σ wᵢ xᵢ / Σ wᵢ` over its `(global corner node, weight)` list,
//! summed in increasing global node order — the same bits from both elements sharing a face.
//! (On curved quadratic elements this is the point of the linear element through the corners,
//! a fraction of the element's size from the curved one: the skin is as thick as asked, give or
//! take that.) The combination is pointwise in `(Φ, d_∂)`, so the samples of a shared face are
//! bitwise equal and the weld needs nothing new.
//!
//! Narrow band, as in [`crate::within`]: the skin term only matters within a couple of lattice
//! spacings (`margin`) of the skin's inner surface. Where `d_∂ − t ≥ margin` the sample is `Φ`
//! itself, so the lattice far from the boundary is exactly the lattice without a skin, and
//! every lattice edge crossing the inner surface has the exact skin term at both ends. An
//! element whose corners are all far (by a centroid distance and the element's radius) skips
//! the distance queries altogether.
//!
//! Invariants: the skin term depends only on global node ids, node positions and lattice
//! weights (never on the element's frame); the boundary faces are the faces used by one
//! element, with their corner nodes only (quadratic faces are flattened to their corners).

use crate::mesh::{Mesh, SpareArrays};
use crate::mesh_read::TriangleSoup;
use crate::mesh_sdf::{MeshSdf, SdfOptions};
use crate::scaffold::Scaffold;

use super::lattice::{MAX_CORNERS, Weights};
use super::scaffold::{Ordered, check_f32_room};
use super::{ChunkSink, TileError, TileStats, TiledSolid, stream_with, tile_with};

/// The skin term of one scaffold: distances to its boundary faces, and the band it matters in.
pub struct Skin {
    thickness: f64,
    /// Lattice spacings (model units) within which the skin term is used; beyond, `Φ` is.
    margin: f64,
    boundary: MeshSdf,
    nodes: Vec<[f64; 3]>,
}

impl Skin {
    /// The skin of thickness `thickness` (model units) along `scaffold`'s boundary, for a
    /// tiling with `resolution` samples per element edge.
    pub fn new(scaffold: &Scaffold, thickness: f64, resolution: usize) -> Result<Skin, TileError> {
        if !(thickness.is_finite() && thickness > 0.0) {
            return Err(TileError::Skin(format!(
                "the skin thickness must be a positive number, got {thickness}"
            )));
        }
        let corners = scaffold.kind.corner_count();
        let mut longest_edge: f64 = 0.0;
        let mut radius: f64 = 0.0;
        for e in 0..scaffold.element_count() {
            let nodes = &scaffold.element(e)[..corners];
            radius = radius.max(ball(nodes, &scaffold.nodes).1);
            for [a, b] in scaffold.kind.linear().edges() {
                let (p, q) = (
                    scaffold.nodes[nodes[*a] as usize],
                    scaffold.nodes[nodes[*b] as usize],
                );
                longest_edge = longest_edge.max(distance(p, q));
            }
        }
        let margin = 2.0 * longest_edge / (resolution.max(2) - 1) as f64;
        let mut soup = TriangleSoup {
            positions: scaffold.nodes.clone(),
            triangles: Vec::new(),
        };
        let faces = scaffold.kind.linear().faces();
        for facet in scaffold.facets().boundary {
            let side = facet.sides[0];
            let nodes = scaffold.element(side.element as usize);
            let face: Vec<u32> = faces[side.face as usize]
                .iter()
                .map(|&c| nodes[c])
                .collect();
            for k in 1..face.len() - 1 {
                soup.triangles.push([face[0], face[k], face[k + 1]]);
            }
        }
        let options = SdfOptions {
            // A centroid this far makes its element far (`is_far`), whatever the clamping.
            band: Some(thickness + 2.0 * margin + 2.0 * radius),
            ..SdfOptions::default()
        };
        let boundary = MeshSdf::new(&soup, options)
            .map_err(|e| TileError::Skin(format!("the scaffold's boundary faces: {e}")))?;
        Ok(Skin {
            thickness,
            margin,
            boundary,
            nodes: scaffold.nodes.clone(),
        })
    }

    /// Whether every lattice point of the element with corner nodes `corners` is at least
    /// `margin` outside the skin (so its samples are the lattice's own). The test asks for
    /// twice the margin, so rounding in the positions cannot matter.
    pub(super) fn is_far(&self, corners: &[u32]) -> bool {
        let (centre, radius) = ball(corners, &self.nodes);
        let d = self.boundary.unsigned_distance(centre);
        d - radius - self.thickness >= 2.0 * self.margin
    }

    /// The sample `phi` of the lattice combined with the skin at the lattice point with corner
    /// weights `weights` of the element with corner nodes `corners`.
    pub(super) fn apply(&self, phi: f64, corners: &[u32], weights: &Weights) -> f64 {
        let x = intrinsic_position(corners, weights, &self.nodes);
        combine(
            phi,
            self.boundary.unsigned_distance(x) - self.thickness,
            self.margin,
        )
    }
}

/// The lattice value `phi` with the skin term `s = d_∂ − t`: `min(Φ, s)` near the skin,
/// `Φ` where `s ≥ margin` (module docs).
#[inline]
pub fn combine(phi: f64, s: f64, margin: f64) -> f64 {
    if s >= margin { phi } else { phi.min(s) }
}

/// `Σ W_c x(node_c) / Σ W_c`, summed in increasing global node order.
fn intrinsic_position(corners: &[u32], weights: &Weights, nodes: &[[f64; 3]]) -> [f64; 3] {
    let mut terms = [(u32::MAX, 0u32); MAX_CORNERS];
    let list = weights.as_slice();
    for (slot, &(c, w)) in terms.iter_mut().zip(list) {
        *slot = (corners[c as usize], w);
    }
    let terms = &mut terms[..list.len()];
    terms.sort_unstable();
    let mut sum = [0.0; 3];
    let mut total = 0u32;
    for &(node, w) in terms.iter() {
        let p = nodes[node as usize];
        for a in 0..3 {
            sum[a] += f64::from(w) * p[a];
        }
        total += w;
    }
    sum.map(|s| s / f64::from(total))
}

/// The centroid of the corner nodes and the largest distance from it to a corner: a ball
/// holding every convex combination of the corners.
fn ball(corners: &[u32], nodes: &[[f64; 3]]) -> ([f64; 3], f64) {
    let mut centre = [0.0; 3];
    for &c in corners {
        for a in 0..3 {
            centre[a] += nodes[c as usize][a];
        }
    }
    let centre = centre.map(|v| v / corners.len() as f64);
    let radius = corners
        .iter()
        .map(|&c| distance(centre, nodes[c as usize]))
        .fold(0.0, f64::max);
    (centre, radius)
}

fn distance(p: [f64; 3], q: [f64; 3]) -> f64 {
    (0..3).map(|a| (p[a] - q[a]).powi(2)).sum::<f64>().sqrt()
}

/// Tiles `solid` into every element of `scaffold`, with a skin of `skin` model units along its
/// boundary when given ([`super::tile_scaffold`] otherwise).
pub fn tile_scaffold_with_skin(
    scaffold: &Scaffold,
    solid: &TiledSolid,
    skin: Option<f64>,
    resolution: usize,
) -> Result<(Mesh, TileStats), TileError> {
    let Some(thickness) = skin else {
        return super::tile_scaffold(scaffold, solid, resolution);
    };
    check_f32_room(scaffold, resolution, 0.0)?;
    let ordered = Ordered::new(scaffold)?;
    let skin = Skin::new(scaffold, thickness, resolution)?;
    tile_with(&ordered.elements(), solid, Some(&skin), resolution).map_err(|e| ordered.tagged(e))
}

/// [`tile_scaffold_with_skin`], handing the mesh to `sink` a chunk of `chunk_elements` elements
/// at a time, in element order ([`crate::mesh::MeshChunk`]; see
/// [`super::chunk_elements_for`]). The chunks concatenate to the mesh
/// [`tile_scaffold_with_skin`] makes, bit for bit, whatever the chunk size. Each chunk's
/// arrays come from `spare`, where the sink may hand finished chunks back
/// ([`SpareArrays::recycle`]).
pub fn stream_scaffold(
    scaffold: &Scaffold,
    solid: &TiledSolid,
    skin: Option<f64>,
    resolution: usize,
    chunk_elements: usize,
    spare: &SpareArrays,
    sink: &mut ChunkSink,
) -> Result<TileStats, TileError> {
    check_f32_room(scaffold, resolution, 0.0)?;
    let ordered = Ordered::new(scaffold)?;
    let skin = skin
        .map(|t| Skin::new(scaffold, t, resolution))
        .transpose()?;
    let elements = ordered.elements();
    stream_with(
        &elements,
        solid,
        skin.as_ref(),
        resolution,
        chunk_elements,
        spare,
        sink,
    )
    .map_err(|e| ordered.tagged(e))
}
