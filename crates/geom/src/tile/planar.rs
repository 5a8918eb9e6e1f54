//! Tiling 2D scaffolds (tri3/tri6, quad4/quad8/quad9), planar or surfaces in 3D: the region
//! `{X_e(ξ) : Φ(ξ) < 0}` as one welded triangle mesh with its boundary loops, and the solids
//! made from it: `extrude` (a planar panel) and `thickness_normal` (a shell along the surface
//! normals).
//!
//! **Which entry point.** A scaffold of dimension 3 (`ElementKind::dimension`) is tiled by
//! [`super::tile_scaffold`] into a closed solid; one of dimension 2 by [`tile_surface_scaffold`]
//! into a [`TiledRegion`], which [`extrude`] or [`thickness_normal`] turn into closed solids
//! and [`region_svg`] draws.
//!
//! The exactness argument is the 3D one (module docs of [`super`]) one dimension down: the
//! cell (D4 on the square `[-½, ½]²`, D3 on the centred equilateral triangle) is sampled once
//! at one representative per orbit of the square's or triangle's lattice ([`super::square`],
//! [`super::triangle`]), contoured once (marching squares with the face rule, marching
//! triangles) into filled triangles, and welded by the same `(global corner node, weight)`
//! names, so two elements sharing an edge put the same vertices on it, by construction.
//! Transitions and graded thickness/offset come from nodal values exactly as in 3D.
//!
//! Invariants:
//! - The region mesh is edge-manifold: an edge is used by one or two triangles, by two in
//!   opposite directions; its boundary edges are contour segments or lie on scaffold boundary
//!   edges (no cracks along interior element edges).
//! - Triangles follow the elements' orientation (∂X/∂ξ₁ × ∂X/∂ξ₂). A planar scaffold (all nodes
//!   at one z) is put counter-clockwise seen from +z (a clockwise scaffold is flipped as a
//!   whole; mixed orientations are an error), its vertices get that z exactly, and its loops
//!   run outer counter-clockwise, holes clockwise (region on the left). A surface in 3D must be
//!   consistently oriented (each interior edge traversed in opposite directions by its two
//!   elements; an error names them otherwise).
//! - `thickness_normal` offsets every region vertex by `±h/2` along a unit normal interpolated
//!   (with the element's own shape functions) from nodal normals: each node's normal is the
//!   sum of the unit normals of the elements at that node, in element order, normalised. A
//!   welded vertex is placed once (by its lowest element), so both offset surfaces are welded
//!   exactly like the region. Where the surface curves with a radius below `h/2` the inner
//!   offset folds over: offset triangles that turn over against the mid-surface are counted
//!   and reported as [`RegionError::SelfOverlap`] rather than output. (Overlap between distant
//!   parts of the surface, closer than `h`, is not detected.)
//! - Everything is a pure function of the arguments: identical for any thread count.

use super::lattice::Lattice;
use super::scaffold::check_f32_room;
use super::square::SquareLattice;
use super::triangle::TriangleLattice;
use super::{
    ElementMap, Elements, Nodes, TileError, TileStats, TiledSolid, check_elements, tile_on,
};
use crate::contour2d::{Element2, boundary_loops};
use crate::mesh::Mesh;
use crate::scaffold::{ElementKind, Scaffold};

/// 2D elements to tile: their shape and, per element, the global node ids of its corners in
/// Gmsh's corner order; reference points are `[ξ₁, ξ₂, 0]`.
pub type Elements2<'a> = Elements<'a, Element2>;

/// Tiles `solid` into every 2D element: the welded region, triangles counter-clockwise in
/// reference coordinates.
pub fn tile_planar(
    elements: &Elements2,
    solid: &TiledSolid,
    resolution: usize,
) -> Result<(Mesh, TileStats), TileError> {
    check_elements(
        elements,
        surface_element(elements.nodes.kind),
        solid,
        resolution,
    )?;
    let lattice: Box<dyn Lattice> = match elements.shape {
        Element2::Square => Box::new(SquareLattice::new(resolution)),
        Element2::Triangle => Box::new(TriangleLattice::new(resolution)),
    };
    tile_on(elements, elements.nodes, lattice.as_ref(), solid, None)
}

/// The reference element of a 2D element kind.
pub fn surface_element(kind: ElementKind) -> Option<Element2> {
    match kind {
        ElementKind::Tri3 | ElementKind::Tri6 => Some(Element2::Triangle),
        ElementKind::Quad4 | ElementKind::Quad8 | ElementKind::Quad9 => Some(Element2::Square),
        _ => None,
    }
}

/// The tiled region of a 2D scaffold.
#[derive(Clone, Debug, PartialEq)]
pub struct TiledRegion {
    /// The region's triangles (see the module invariants for their orientation).
    pub mesh: Mesh,
    /// Closed boundary loops as vertex ids (last not repeated), region on the left.
    pub loops: Vec<Vec<u32>>,
    /// Sum of the triangle areas of `mesh` (from its `f32` vertices, in `f64`).
    pub area: f64,
    /// Whether the scaffold lies in a plane `z = const` (then `mesh` does too).
    pub planar: bool,
    pub stats: TileStats,
}

/// A closed shell from [`thickness_normal`], with the mid-surface region it thickens.
#[derive(Clone, Debug, PartialEq)]
pub struct TiledShell {
    pub mesh: Mesh,
    pub mid: TiledRegion,
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RegionError {
    #[error(transparent)]
    Tile(#[from] TileError),
    #[error("{0} scaffolds are volumes: tile them with tile_scaffold")]
    NotSurface(&'static str),
    #[error(
        "element {ccw} is counter-clockwise seen from +z but element {cw} is clockwise: a planar scaffold needs one orientation"
    )]
    MixedOrientation { ccw: u64, cw: u64 },
    #[error(
        "elements {a} and {b} run through their shared edge (nodes {nodes:?}) in the same direction: the surface is not consistently oriented"
    )]
    Inconsistent { a: u64, b: u64, nodes: [u64; 2] },
    #[error("{0} needs a planar scaffold (every node at one z)")]
    NotPlanar(&'static str),
    #[error("{what} must be a finite length > 0, got {value}")]
    Length { what: &'static str, value: f64 },
    #[error(
        "thickness_normal = {h}: {triangles} offset triangles turn over against the surface (it curves with a radius below h/2 there), so the shell would overlap itself"
    )]
    SelfOverlap { h: f64, triangles: usize },
    #[error("the surface normal at node {0} is undefined (its elements' normals cancel)")]
    Normal(u64),
    #[error("cannot draw the region: {0}")]
    Svg(String),
}

/// The scaffold's corner nodes per element, after checking its kind.
fn surface_corners(scaffold: &Scaffold) -> Result<(Element2, Vec<u32>), RegionError> {
    let shape =
        surface_element(scaffold.kind).ok_or(RegionError::NotSurface(scaffold.kind.name()))?;
    let (per, corners) = (scaffold.kind.node_count(), scaffold.kind.corner_count());
    let list = scaffold
        .connectivity
        .chunks_exact(per)
        .flat_map(|element| element[..corners].iter().copied())
        .collect();
    Ok((shape, list))
}

/// `z` of a planar scaffold (every node at it, to 1e-12 of the scaffold's extent).
fn plane_z(scaffold: &Scaffold) -> Option<f64> {
    let z0 = scaffold.nodes.first()?[2];
    let extent = scaffold
        .nodes
        .iter()
        .flat_map(|p| p.iter().map(|c| c.abs()))
        .fold(0.0f64, f64::max);
    let tolerance = 1e-12 * extent.max(1.0);
    scaffold
        .nodes
        .iter()
        .all(|p| (p[2] - z0).abs() <= tolerance)
        .then_some(z0)
}

/// `∂X/∂ξ₁ × ∂X/∂ξ₂` of element `e` at `xi`.
fn normal_at(scaffold: &Scaffold, e: usize, xi: [f64; 3]) -> [f64; 3] {
    let j = scaffold.jacobian(e, xi);
    let a = [j[0][0], j[1][0], j[2][0]];
    let b = [j[0][1], j[1][1], j[2][1]];
    cross(a, b)
}

/// Whether a planar scaffold's elements are clockwise seen from +z (then the region is
/// flipped); mixed orientations are an error.
fn planar_flip(scaffold: &Scaffold) -> Result<bool, RegionError> {
    let (mut ccw, mut cw) = (None, None);
    for e in 0..scaffold.element_count() {
        // Degenerate elements (zero area) are `scaffold::check`'s to report.
        let z = normal_at(scaffold, e, [0.0; 3])[2];
        if z > 0.0 {
            ccw.get_or_insert(scaffold.element_tags[e]);
        } else if z < 0.0 {
            cw.get_or_insert(scaffold.element_tags[e]);
        }
    }
    match (ccw, cw) {
        (Some(ccw), Some(cw)) => Err(RegionError::MixedOrientation { ccw, cw }),
        (None, Some(_)) => Ok(true),
        _ => Ok(false),
    }
}

/// Each interior edge must be run through in opposite directions by its two elements.
fn check_consistent(scaffold: &Scaffold) -> Result<(), RegionError> {
    let faces = scaffold.kind.faces();
    for facet in scaffold.facets().interior {
        let direction = |side: &crate::scaffold::FacetSide| {
            let nodes = scaffold.element(side.element as usize);
            let face = faces[side.face as usize];
            (nodes[face[0]], nodes[face[1]])
        };
        let (a, b) = (&facet.sides[0], &facet.sides[1]);
        let (da, db) = (direction(a), direction(b));
        if da == db {
            let tag = |n: u32| scaffold.node_tags[n as usize];
            return Err(RegionError::Inconsistent {
                a: scaffold.element_tags[a.element as usize],
                b: scaffold.element_tags[b.element as usize],
                nodes: [tag(da.0), tag(da.1)],
            });
        }
    }
    Ok(())
}

/// Tiles `solid` into every element of a 2D scaffold (nodal arrays indexed like its nodes),
/// with `resolution` samples per element edge.
pub fn tile_surface_scaffold(
    scaffold: &Scaffold,
    solid: &TiledSolid,
    resolution: usize,
) -> Result<TiledRegion, RegionError> {
    let (shape, corners) = surface_corners(scaffold)?;
    check_f32_room(scaffold, resolution, 0.0)?;
    let plane = plane_z(scaffold);
    let flip = match plane {
        Some(_) => planar_flip(scaffold)?,
        None => {
            check_consistent(scaffold)?;
            false
        }
    };
    let elements = Elements2 {
        shape,
        corners: &corners,
        nodes: Nodes {
            kind: scaffold.kind,
            ids: &scaffold.connectivity,
        },
        map: scaffold,
    };
    let (mut mesh, stats) =
        tile_planar(&elements, solid, resolution).map_err(|e| e.tagged(&scaffold.element_tags))?;
    if let Some(z) = plane {
        for v in &mut mesh.vertices {
            v[2] = z as f32;
        }
    }
    if flip {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
    }
    Ok(region_of(mesh, stats, plane.is_some()))
}

fn region_of(mesh: Mesh, stats: TileStats, planar: bool) -> TiledRegion {
    let loops = boundary_loops(&mesh);
    let area = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| mesh.vertices[v as usize].map(f64::from));
            let n = cross(sub(b, a), sub(c, a));
            if planar { 0.5 * n[2] } else { 0.5 * norm(n) }
        })
        .sum();
    TiledRegion {
        mesh,
        loops,
        area,
        planar,
        stats,
    }
}

fn check_length(what: &'static str, value: f64) -> Result<(), RegionError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(RegionError::Length { what, value })
    }
}

/// The closed solid between two copies of a region's triangulation: `top` keeps the region's
/// orientation, `bottom` is reversed, and each loop edge `a → b` gets a wall of two triangles
/// facing to the edge's right (away from the region).
fn close_between(bottom: Vec<[f32; 3]>, top: Vec<[f32; 3]>, region: &TiledRegion) -> Mesh {
    let n = top.len() as u32;
    let mut triangles = region.mesh.triangles.clone();
    triangles.extend(
        region
            .mesh
            .triangles
            .iter()
            .map(|t| [t[0] + n, t[2] + n, t[1] + n]),
    );
    for lp in &region.loops {
        for (k, &a) in lp.iter().enumerate() {
            let b = lp[(k + 1) % lp.len()];
            triangles.push([a + n, b + n, b]);
            triangles.push([a + n, b, a]);
        }
    }
    let mut vertices = top;
    vertices.extend(bottom);
    Mesh {
        vertices,
        triangles,
    }
}

/// A planar region extruded by `h` along +z into a closed, outward-oriented solid (top at
/// `z + h`, bottom at the region's `z`, walls along every boundary loop): its volume is
/// `area × h` up to rounding.
pub fn extrude(region: &TiledRegion, h: f64) -> Result<Mesh, RegionError> {
    if !region.planar {
        return Err(RegionError::NotPlanar("extrude"));
    }
    check_length("extrude", h)?;
    let bottom = region.mesh.vertices.clone();
    let top = bottom
        .iter()
        .map(|v| [v[0], v[1], (f64::from(v[2]) + h) as f32])
        .collect();
    Ok(close_between(bottom, top, region))
}

/// The map of a scaffold pushed by `shift` along its interpolated unit normals.
struct OffsetMap<'s> {
    scaffold: &'s Scaffold,
    normals: &'s [[f64; 3]],
    shift: f64,
}

impl ElementMap for OffsetMap<'_> {
    fn map(&self, element: usize, xi: [f64; 3]) -> [f64; 3] {
        let x = self.scaffold.map(element, xi);
        if self.shift == 0.0 {
            return x;
        }
        let mut shape = [0.0; ElementKind::MAX_NODES];
        self.scaffold.kind.shape(xi, &mut shape);
        let mut n = [0.0; 3];
        for (&node, &w) in self.scaffold.element(element).iter().zip(&shape) {
            let m = self.normals[node as usize];
            for a in 0..3 {
                n[a] += w * m[a];
            }
        }
        let length = norm(n);
        if length == 0.0 {
            // Opposite nodal normals cancel: no direction to offset along. The turned-over
            // check of `thickness_normal` reports the flattened triangles this leaves.
            return x;
        }
        std::array::from_fn(|a| x[a] + self.shift * n[a] / length)
    }
}

/// Unit normal per node: the element normals at it, summed in element order, normalised.
fn nodal_normals(scaffold: &Scaffold) -> Result<Vec<[f64; 3]>, RegionError> {
    let kind = scaffold.kind;
    let mut sum = vec![[0.0; 3]; scaffold.nodes.len()];
    let mut used = vec![false; scaffold.nodes.len()];
    for e in 0..scaffold.element_count() {
        for (i, &node) in scaffold.element(e).iter().enumerate() {
            let n = normal_at(scaffold, e, kind.reference_node(i));
            let length = norm(n);
            used[node as usize] = true;
            if length > 0.0 {
                for a in 0..3 {
                    sum[node as usize][a] += n[a] / length;
                }
            }
        }
    }
    sum.iter()
        .zip(&used)
        .enumerate()
        .map(|(node, (&s, &used))| {
            let length = norm(s);
            if length > 1e-9 {
                Ok(s.map(|c| c / length))
            } else if used {
                Err(RegionError::Normal(scaffold.node_tags[node]))
            } else {
                Ok([0.0; 3])
            }
        })
        .collect()
}

/// The region of a 2D scaffold thickened by `h` along its normals (`±h/2` about the surface)
/// and closed by walls along its boundary loops: a closed, manifold, outward-oriented shell
/// lattice of volume ≈ `area × h` (exactly so in the plane; on a surface of radius `R` the
/// offset adds a relative `h²/(12R²)`).
pub fn thickness_normal(
    scaffold: &Scaffold,
    solid: &TiledSolid,
    resolution: usize,
    h: f64,
) -> Result<TiledShell, RegionError> {
    check_length("thickness_normal", h)?;
    let (shape, corners) = surface_corners(scaffold)?;
    // The offset surfaces reach h/2 farther than the scaffold.
    check_f32_room(scaffold, resolution, 0.5 * h)?;
    check_consistent(scaffold)?;
    let normals = nodal_normals(scaffold)?;
    let tile_at = |shift: f64| {
        let map = OffsetMap {
            scaffold,
            normals: &normals,
            shift,
        };
        let elements = Elements2 {
            shape,
            corners: &corners,
            nodes: Nodes {
                kind: scaffold.kind,
                ids: &scaffold.connectivity,
            },
            map: &map,
        };
        tile_planar(&elements, solid, resolution).map_err(|e| e.tagged(&scaffold.element_tags))
    };
    let (mid, stats) = tile_at(0.0)?;
    let (top, _) = tile_at(0.5 * h)?;
    let (bottom, _) = tile_at(-0.5 * h)?;
    let triangle_normal = |mesh: &Mesh, t: &[u32; 3]| {
        let [a, b, c] = t.map(|v| mesh.vertices[v as usize].map(f64::from));
        cross(sub(b, a), sub(c, a))
    };
    let turned = mid
        .triangles
        .iter()
        .filter(|t| {
            let n = triangle_normal(&mid, t);
            norm(n) > 0.0
                && (dot(n, triangle_normal(&top, t)) <= 0.0
                    || dot(n, triangle_normal(&bottom, t)) <= 0.0)
        })
        .count();
    if turned > 0 {
        return Err(RegionError::SelfOverlap {
            h,
            triangles: turned,
        });
    }
    let mid = region_of(mid, stats, false);
    let mesh = close_between(bottom.vertices, top.vertices, &mid);
    Ok(TiledShell { mesh, mid })
}

/// The region of a planar scaffold as an SVG document: filled, with the scaffold's element
/// edges drawn faintly (quadratic edges as 8-segment polylines through the map).
pub fn region_svg(region: &TiledRegion, scaffold: &Scaffold) -> Result<String, RegionError> {
    if !region.planar {
        return Err(RegionError::NotPlanar("an SVG drawing"));
    }
    let xy = |v: u32| {
        let p = region.mesh.vertices[v as usize];
        [f64::from(p[0]), f64::from(p[1])]
    };
    let loops: Vec<Vec<[f64; 2]>> = region
        .loops
        .iter()
        .map(|lp| lp.iter().map(|&v| xy(v)).collect())
        .collect();
    let kind = scaffold.kind;
    let segments = if kind.order() > 1 { 8 } else { 1 };
    let facets = scaffold.facets();
    let lines: Vec<Vec<[f64; 2]>> = facets
        .interior
        .iter()
        .chain(&facets.boundary)
        .chain(&facets.overused)
        .map(|facet| {
            let side = facet.sides[0];
            let face = kind.faces()[side.face as usize];
            let (a, b) = (kind.reference_node(face[0]), kind.reference_node(face[1]));
            (0..=segments)
                .map(|k| {
                    let t = k as f64 / segments as f64;
                    let xi = std::array::from_fn(|c| a[c] + t * (b[c] - a[c]));
                    let x = scaffold.map(side.element as usize, xi);
                    [x[0], x[1]]
                })
                .collect()
        })
        .collect();
    crate::mesh_io::svg::scaffold_svg(&loops, &lines).map_err(|e| RegionError::Svg(e.to_string()))
}

type P3 = [f64; 3];

fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: P3, b: P3) -> P3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn norm(a: P3) -> f64 {
    dot(a, a).sqrt()
}

#[cfg(test)]
mod tests;
