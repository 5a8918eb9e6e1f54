//! Tiling a [`Scaffold`] read from a file or generated: its corners name vertices across
//! elements, its isoparametric maps (linear or quadratic) place them.
//!
//! Invariant: only volume scaffolds (tet4/tet10, hex8/hex20/hex27) are tiled here; the first
//! `corner_count` nodes of every kind are its corners in the reference element's order.

use super::{ElementMap, Elements, Nodes, TileError, TileStats, TiledSolid, tile};
use crate::element::Element3;
use crate::mesh::Mesh;
use crate::scaffold::{ElementKind, Scaffold};

impl ElementMap for Scaffold {
    fn map(&self, element: usize, xi: [f64; 3]) -> [f64; 3] {
        Scaffold::map(self, element, xi)
    }
}

/// The reference element of a volume element kind.
pub fn reference_element(kind: ElementKind) -> Option<Element3> {
    match kind {
        ElementKind::Tet4 | ElementKind::Tet10 => Some(Element3::Tetrahedron),
        ElementKind::Hex8 | ElementKind::Hex20 | ElementKind::Hex27 => Some(Element3::Cube),
        _ => None,
    }
}

/// Tiles `solid` into every element of `scaffold` (nodal arrays indexed like its nodes).
pub fn tile_scaffold(
    scaffold: &Scaffold,
    solid: &TiledSolid,
    resolution: usize,
) -> Result<(Mesh, TileStats), TileError> {
    check_f32_room(scaffold, resolution, 0.0)?;
    let ordered = Ordered::new(scaffold)?;
    tile(&ordered.elements(), solid, resolution).map_err(|e| ordered.tagged(e))
}

/// A volume scaffold's elements in the order they are tiled: along a Morton (Z-order) curve
/// through their corner centroids, so that consecutive elements — and a streamed tiling's
/// chunks — are compact in space and few vertices stay open between chunks. (In Gmsh's own
/// order about 9 % of a 100k-tet bracket's output vertices stayed open at once.) The output's
/// numbering follows this order; it depends only on the scaffold.
pub(super) struct Ordered<'s> {
    scaffold: &'s Scaffold,
    shape: Element3,
    /// Tiling position → element index in the scaffold.
    order: Vec<u32>,
    /// Corner nodes, element by element in tiling order.
    corners: Vec<u32>,
    /// Every node (corners first), element by element in tiling order.
    nodes: Vec<u32>,
}

impl<'s> Ordered<'s> {
    pub(super) fn new(scaffold: &'s Scaffold) -> Result<Ordered<'s>, TileError> {
        let shape =
            reference_element(scaffold.kind).ok_or(TileError::NotVolume(scaffold.kind.name()))?;
        let corners_per = scaffold.kind.corner_count();
        let order = morton_order(scaffold, corners_per);
        let corners = order
            .iter()
            .flat_map(|&e| scaffold.element(e as usize)[..corners_per].iter().copied())
            .collect();
        let nodes = order
            .iter()
            .flat_map(|&e| scaffold.element(e as usize).iter().copied())
            .collect();
        Ok(Ordered {
            scaffold,
            shape,
            order,
            corners,
            nodes,
        })
    }

    pub(super) fn elements(&self) -> Elements<'_> {
        Elements {
            shape: self.shape,
            corners: &self.corners,
            nodes: Nodes {
                kind: self.scaffold.kind,
                ids: &self.nodes,
            },
            map: self,
        }
    }

    /// The error with tiling positions replaced by the scaffold's element tags.
    pub(super) fn tagged(&self, error: TileError) -> TileError {
        let tags: Vec<u64> = self
            .order
            .iter()
            .map(|&e| {
                self.scaffold
                    .element_tags
                    .get(e as usize)
                    .copied()
                    .unwrap_or(u64::from(e))
            })
            .collect();
        error.tagged(&tags)
    }
}

impl ElementMap for Ordered<'_> {
    fn map(&self, element: usize, xi: [f64; 3]) -> [f64; 3] {
        Scaffold::map(self.scaffold, self.order[element] as usize, xi)
    }
}

/// Element indices sorted by the Morton code of their corner centroid in the scaffold's
/// bounding box (21 bits per axis); ties keep file order.
fn morton_order(scaffold: &Scaffold, corners_per: usize) -> Vec<u32> {
    let count = scaffold.element_count();
    let centroid = |e: usize| {
        let mut c = [0.0; 3];
        for &n in &scaffold.element(e)[..corners_per] {
            let p = scaffold.nodes.get(n as usize).copied().unwrap_or([0.0; 3]);
            for a in 0..3 {
                c[a] += p[a];
            }
        }
        c.map(|v| v / corners_per as f64)
    };
    let centroids: Vec<[f64; 3]> = (0..count).map(centroid).collect();
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for c in &centroids {
        for a in 0..3 {
            lo[a] = lo[a].min(c[a]);
            hi[a] = hi[a].max(c[a]);
        }
    }
    let cells = f64::from((1u32 << 21) - 1);
    let mut keyed: Vec<(u64, u32)> = centroids
        .iter()
        .enumerate()
        .map(|(e, c)| {
            let cell = |a: usize| {
                let span = hi[a] - lo[a];
                let t = if span > 0.0 {
                    (c[a] - lo[a]) / span
                } else {
                    0.0
                };
                // NaN (a broken node) sorts first: `as` saturates it to 0.
                (t * cells) as u64
            };
            (
                spread(cell(0)) | spread(cell(1)) << 1 | spread(cell(2)) << 2,
                e as u32,
            )
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, e)| e).collect()
}

/// The low 21 bits of `x`, spread to every third bit.
fn spread(x: u64) -> u64 {
    let mut x = x & 0x1f_ffff;
    x = (x | x << 32) & 0x1f_0000_0000_ffff;
    x = (x | x << 16) & 0x1f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

/// Refuses a tiling whose promise of distinct vertices `f32` cannot keep where the scaffold
/// lies.
///
/// The tiler keeps every crossing 1/256 of a lattice edge from the edge's ends (`local.rs`),
/// so that no vertex meets a lattice point's vertex (a cap's, or another crossing's there);
/// the mesh is then rounded to `f32`, what mesh files store. Far from the origin one `f32`
/// step can exceed that margin (2⁻¹⁴ ≈ 6.1e-5 at 1000): rounding then puts crossings onto
/// lattice points and onto each other — duplicate positions and flat triangles (0.25-unit
/// hexahedra at 1000 tiled at resolution 24: thousands of each). A lattice edge is a corner
/// edge of its element over `resolution − 1` (exactly so for affine elements: the lattices'
/// edges are parallel to the element's edges), so the margin is the shortest corner edge
/// over `256 (resolution − 1)`, and the step is the `f32` step at the largest coordinate
/// magnitude the output reaches (the nodes', plus `extra_reach`). A margin below the step is
/// [`TileError::BeyondF32`], naming the highest resolution that would do. A margin above it
/// does not prove every rounding distinct (two crossings near one lattice point along
/// different edges may still meet); the mesh check after the tiling has the last word.
///
/// Unlike the contourer's (axis-aligned edges, whose crossings are kept inside their edges
/// in `f32` exactly), the tiler's lattice edges run in any direction through curved maps,
/// so no per-coordinate rule keeps its vertices apart: refusing is the honest answer.
pub(super) fn check_f32_room(
    scaffold: &Scaffold,
    resolution: usize,
    extra_reach: f64,
) -> Result<(), TileError> {
    // Resolutions below 2 are the tiler's own error (`check_input`).
    if resolution < 2 {
        return Ok(());
    }
    let node = |n: u32| scaffold.nodes.get(n as usize).copied();
    let mut shortest = f64::INFINITY;
    for e in 0..scaffold.element_count() {
        let nodes = scaffold.element(e);
        for &[a, b] in scaffold.kind.edges() {
            if let (Some(p), Some(q)) = (node(nodes[a]), node(nodes[b])) {
                let length = (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt();
                // Degenerate elements are the scaffold check's to report.
                if length > 0.0 {
                    shortest = shortest.min(length);
                }
            }
        }
    }
    let reach = scaffold
        .nodes
        .iter()
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        + extra_reach.abs();
    let rounded = reach as f32;
    let step = f64::from(rounded.next_up()) - f64::from(rounded);
    let edge = shortest / (resolution - 1) as f64;
    let margin = edge / 256.0;
    if !shortest.is_finite() || !step.is_finite() || margin >= step {
        return Ok(());
    }
    Err(TileError::BeyondF32 {
        resolution,
        edge_bits: edge.to_bits(),
        margin_bits: margin.to_bits(),
        step_bits: step.to_bits(),
        reach_bits: reach.to_bits(),
        max_resolution: (shortest / (256.0 * step)).floor() as usize + 1,
    })
}
