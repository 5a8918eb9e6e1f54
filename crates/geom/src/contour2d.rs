//! Marching squares of a planar field clipped to a 2D reference element.
//!
//! Reference elements are those of `docs/method.md` §Reference elements, in Cartesian coordinates:
//! the
//! square `[-½, ½]²` and the equilateral triangle of side 1 with centroid at the origin,
//! pointing to +y, vertices `(-½, -√3/6)`, `(½, -√3/6)`, `(0, √3/3)`.
//!
//! [`contour_planar`] returns the region `{Φ ≤ 0} ∩ element` (negative inside) as a
//! [`PlanarRegion`]: a triangle mesh in the plane `z = 0` and its boundary loops;
//! [`contour_planar_box`] does the same over an axis-aligned rectangle (a periodic 2D cell
//! repeated over a planar domain).
//!
//! [`contour_planar_band`] and [`contour_planar_box_band`] contour a shell over the square or a
//! rectangle as the band `lo < f < hi` of the field itself, cell by cell as the 3D contourer
//! caps a band on a cube face (`Tables::band_cap`): both levels' crossings, possibly on one
//! edge, so a wall between two samples is kept (sampled as `|f − c| − w/2` it vanished).
//!
//! The face rule is the one the 3D tables use on cube faces (see
//! [`crate::contour::table`]): in each grid cell the inside part is bounded by segments
//! separating inside corners from outside ones, and on an ambiguous cell (two inside corners on a
//! diagonal) each inside corner is cut off on its own. So a cell's inside part is one convex
//! polygon (fanned from its first vertex) or, when ambiguous, two corner triangles; two cells
//! sharing a side always agree on it, and a 2D section of a 3D contour matches the caps the 3D
//! contourer draws.
//!
//! Grids, chosen so that the element's sides are exact:
//! - **Square**: `samples` points per axis spanning the square; its sides are the grid's
//!   boundary, so the element clips itself and `Φ` is contoured as is.
//! - **Triangle**: the triangle's own subdivision into small triangles, `samples` nodes along
//!   each side, contoured by marching triangles (`simplex_contour`). The group D3 maps its nodes
//!   and cells onto themselves, so every side is cut alike (all three corners are nodes) and the
//!   region is symmetric to rounding; the sides are cell edges, so they are exact. Cells are
//!   triangles, so no cell is ambiguous and the face rule above concerns the square alone.
//!
//! Invariants of the output:
//! - Triangles are counter-clockwise seen from +z; vertices are shared (an interior edge is used
//!   by exactly two triangles, in opposite directions), so the mesh is edge-manifold.
//! - No two vertices coincide: crossings stay 1/256 of an edge away from its ends, as in 3D;
//!   over a rectangle ([`contour_planar_box`], placed anywhere) their `f32` positions also stay
//!   strictly inside their edge ([`crate::mesh::round_inside`], as in 3D), and a grid too fine
//!   for `f32` at its distance from the origin is refused ([`PlanarError::BeyondF32`]).
//!   Elements are near the origin, where 1/256 of an edge is many `f32` steps.
//! - `positions` holds every vertex in `f64`; `mesh.vertices` are their `f32` roundings (what
//!   the mesh writers store; a rectangle's crossings kept inside their edges), so areas are
//!   exact to `f64` rounding while the mesh is the crate's usual [`Mesh`].
//! - Every boundary loop point is a vertex (its `positions` entry), and the loops' edges are exactly the mesh edges used by one triangle, directed as in their triangle: the
//!   region lies on the left, so outer loops run counter-clockwise and holes clockwise.
//! - Deterministic: a pure function of the arguments, single-threaded.
//! - NaN samples count as outside.

use crate::contour::table::{CORNER_SLOT, EDGE_CORNERS, HI_SLOT, tables};
use crate::contour::{apart_in_f32, band_crossing, crossing_fraction, spans_band};
use crate::field::Band;
use crate::mesh::{Mesh, inseparable_edge, round_inside};
use crate::simplex_contour::contour_triangle;
use rayon::prelude::*;

/// A 2D reference element (docs/method.md §Reference elements), in Cartesian coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Element2 {
    /// `[-½, ½]²`.
    Square,
    /// Equilateral, side 1, centroid at the origin, pointing to +y.
    Triangle,
}

const SQRT3: f64 = 1.732_050_807_568_877_2;

/// The triangle's vertices, counter-clockwise from the bottom left.
const TRIANGLE_VERTICES: [[f64; 2]; 3] = [
    [-0.5, -SQRT3 / 6.0],
    [0.5, -SQRT3 / 6.0],
    [0.0, SQRT3 / 3.0],
];

impl Element2 {
    /// A clipping function of the element, negative inside. For the square it is the exact
    /// signed distance. For the triangle it is the largest signed distance to a side line: exact
    /// inside and wherever the nearest boundary point lies inside a side, a lower bound of the
    /// distance elsewhere outside (near the corners).
    pub fn signed_distance(&self, p: [f64; 2]) -> f64 {
        match self {
            Element2::Square => {
                let q = p.map(|c| c.abs() - 0.5);
                let outside = q[0].max(0.0).hypot(q[1].max(0.0));
                outside + q[0].max(q[1]).min(0.0)
            }
            Element2::Triangle => {
                // Unit outward normals of the sides; the inradius is √3/6.
                let normals = [[0.0, -1.0], [SQRT3 / 2.0, 0.5], [-SQRT3 / 2.0, 0.5]];
                normals
                    .iter()
                    .map(|n| n[0] * p[0] + n[1] * p[1] - SQRT3 / 6.0)
                    .fold(f64::NEG_INFINITY, f64::max)
            }
        }
    }

    /// Axis-aligned bounding box `(min, max)`.
    pub fn bbox(&self) -> ([f64; 2], [f64; 2]) {
        match self {
            Element2::Square => ([-0.5; 2], [0.5; 2]),
            Element2::Triangle => ([-0.5, -SQRT3 / 6.0], [0.5, SQRT3 / 3.0]),
        }
    }

    /// The element's corners, counter-clockwise (the outline for [`crate::mesh_io::svg`]).
    pub fn outline(&self) -> Vec<[f64; 2]> {
        match self {
            Element2::Square => vec![[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]],
            Element2::Triangle => TRIANGLE_VERTICES.to_vec(),
        }
    }

    /// Area: 1 for the square, √3/4 for the triangle.
    pub fn area(&self) -> f64 {
        match self {
            Element2::Square => 1.0,
            Element2::Triangle => SQRT3 / 4.0,
        }
    }
}

/// A planar region: its triangulation and its boundary.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlanarRegion {
    /// Triangles in `z = 0`, counter-clockwise seen from +z, sharing vertices.
    pub mesh: Mesh,
    /// The mesh's vertices in full precision (`mesh.vertices[i]` is `positions[i]` in `f32`,
    /// a rectangle's crossings kept strictly inside their edges).
    pub positions: Vec<[f64; 2]>,
    /// Closed loops (last point not repeated), region on the left: outer loops
    /// counter-clockwise, holes clockwise. Every point is an entry of `positions`.
    pub boundary: Vec<Vec<[f64; 2]>>,
}

impl PlanarRegion {
    /// Sum of the triangle areas, from the full-precision positions.
    pub fn area(&self) -> f64 {
        let p = |i: u32| self.positions[i as usize];
        self.mesh
            .triangles
            .iter()
            .map(|t| {
                let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
                0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
            })
            .sum()
    }
}

/// Why a planar field could not be contoured.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum PlanarError {
    #[error("the grid needs at least 2 samples per axis, got {0}")]
    TooFewSamples(usize),
    #[error("a grid of {0} samples per axis has more vertices than 32-bit indices can address")]
    TooManySamples(usize),
    /// Neighbouring samples with no 32-bit float between their roundings (see the 3D
    /// [`crate::contour::ContourError::BeyondF32`]).
    #[error(
        "the samples are too close together for 32-bit positions (what mesh files store) this far from the origin: along {} samples {index} and {} lie at {} and {}, with {} between them; place the domain nearer the origin or use fewer samples",
        ["x", "y"][*axis],
        index + 1,
        f64::from_bits(at_bits[0]),
        f64::from_bits(at_bits[1]),
        crate::mesh::room_wanting(*needed)
    )]
    BeyondF32 {
        axis: usize,
        index: usize,
        /// 32-bit values needed strictly between them: 1, or 2 for a band.
        needed: usize,
        /// The two coordinates, as bits (keeping the error `Eq`).
        at_bits: [u64; 2],
    },
}

/// Contours `{Φ ≤ 0} ∩ element` (see the module docs). `samples` is the number of samples per
/// axis of the square, or along each side of the triangle; at least 2.
pub fn contour_planar(
    field: &(dyn Fn([f64; 2]) -> f64 + Sync),
    element: Element2,
    samples: usize,
) -> Result<PlanarRegion, PlanarError> {
    if samples < 2 {
        return Err(PlanarError::TooFewSamples(samples));
    }
    // Each node and each grid edge may carry a vertex: about three per node.
    let n = (samples as u64).saturating_add(1);
    if n.saturating_mul(n).saturating_mul(3) >= u64::from(u32::MAX) {
        return Err(PlanarError::TooManySamples(samples));
    }
    let lattice = match element {
        Element2::Square => {
            let h = 1.0 / (samples - 1) as f64;
            Lattice {
                origin: [-0.5, -0.5],
                axes: [[h, 0.0], [0.0, h]],
                counts: [samples, samples],
            }
        }
        Element2::Triangle => {
            let contoured = contour_triangle(field, samples - 1);
            return Ok(region_from(contoured.mesh, contoured.positions));
        }
    };
    Ok(region_of(&lattice, field, None))
}

/// Contours `{Φ ≤ 0}` over the rectangle `[min, max]` sampled at `counts` points per axis (at
/// least 2 each); the rectangle's sides are the grid's boundary, so the region is capped there
/// exactly as on the square element.
pub fn contour_planar_box(
    field: &(dyn Fn([f64; 2]) -> f64 + Sync),
    min: [f64; 2],
    max: [f64; 2],
    counts: [usize; 2],
) -> Result<PlanarRegion, PlanarError> {
    let lattice = box_lattice(min, max, counts, 1)?;
    Ok(region_of(&lattice, field, None))
}

/// Contours the band `lo < f < hi` of the field `f` over the rectangle, as
/// [`contour_planar_box`] contours one level (module docs).
pub fn contour_planar_box_band(
    field: &(dyn Fn([f64; 2]) -> f64 + Sync),
    band: Band,
    min: [f64; 2],
    max: [f64; 2],
    counts: [usize; 2],
) -> Result<PlanarRegion, PlanarError> {
    let lattice = box_lattice(min, max, counts, 2)?;
    Ok(region_of(&lattice, field, Some(band)))
}

/// Contours the band `lo < f < hi` of the field `f` over the square element, with `samples`
/// per axis (the triangle's clipped sides have no band rule: it is sampled as one function).
pub fn contour_planar_band(
    field: &(dyn Fn([f64; 2]) -> f64 + Sync),
    band: Band,
    samples: usize,
) -> Result<PlanarRegion, PlanarError> {
    contour_planar_box_band(field, band, [-0.5; 2], [0.5; 2], [samples; 2])
}

/// The lattice of a rectangle, refused where `needed` 32-bit values (one per level that may
/// cross an edge) do not fit between two neighbouring samples.
fn box_lattice(
    min: [f64; 2],
    max: [f64; 2],
    counts: [usize; 2],
    needed: usize,
) -> Result<Lattice, PlanarError> {
    let fewest = counts[0].min(counts[1]);
    if fewest < 2 {
        return Err(PlanarError::TooFewSamples(fewest));
    }
    // A band has two crossings per edge at most: about five vertices per node.
    let nodes = (counts[0] as u64 + 1).saturating_mul(counts[1] as u64 + 1);
    if nodes.saturating_mul(1 + 2 * needed as u64) >= u64::from(u32::MAX) {
        return Err(PlanarError::TooManySamples(counts[0].max(counts[1])));
    }
    let lattice = Lattice {
        origin: min,
        axes: [
            [(max[0] - min[0]) / (counts[0] - 1) as f64, 0.0],
            [0.0, (max[1] - min[1]) / (counts[1] - 1) as f64],
        ],
        counts,
    };
    for (axis, &count) in counts.iter().enumerate() {
        let coordinate = |i: usize| lattice.point_on(axis, i as f64);
        if let Some((index, a, b)) = inseparable_edge(count, needed, coordinate) {
            return Err(PlanarError::BeyondF32 {
                axis,
                index,
                needed,
                at_bits: [a.to_bits(), b.to_bits()],
            });
        }
    }
    Ok(lattice)
}

/// The region of `field` on `lattice`: `{Φ ≤ 0}`, or the band `lo < f < hi` of `f`.
fn region_of(
    lattice: &Lattice,
    field: &(dyn Fn([f64; 2]) -> f64 + Sync),
    band: Option<Band>,
) -> PlanarRegion {
    let values = lattice.sample(field);
    let (mesh, positions) = match band {
        None => march(lattice, &values),
        Some(band) => march_band(lattice, &values, band),
    };
    region_from(mesh, positions)
}

/// A region from its mesh and full-precision positions: its boundary loops added.
fn region_from(mesh: Mesh, positions: Vec<[f64; 2]>) -> PlanarRegion {
    let boundary: Vec<Vec<[f64; 2]>> = boundary_loops(&mesh)
        .iter()
        .map(|l| l.iter().map(|&v| positions[v as usize]).collect())
        .collect();
    PlanarRegion {
        mesh,
        positions,
        boundary,
    }
}

/// A parallelogram grid: node `(i, j)` sits at `origin + i·axes[0] + j·axes[1]`.
struct Lattice {
    origin: [f64; 2],
    axes: [[f64; 2]; 2],
    counts: [usize; 2],
}

impl Lattice {
    /// Position of the lattice point with fractional indices `(a, b)`.
    fn point(&self, a: f64, b: f64) -> [f64; 2] {
        std::array::from_fn(|d| self.origin[d] + a * self.axes[0][d] + b * self.axes[1][d])
    }

    /// Coordinate `axis` of the points with fractional index `a` along `axis`, for an
    /// axis-aligned lattice (a rectangle): exactly [`point`](Self::point)'s.
    fn point_on(&self, axis: usize, a: f64) -> f64 {
        let (i, j) = if axis == 0 { (a, 0.0) } else { (0.0, a) };
        self.point(i, j)[axis]
    }

    fn axis_aligned(&self) -> bool {
        self.axes[0][1] == 0.0 && self.axes[1][0] == 0.0
    }

    /// The field at every node, `i` fastest.
    fn sample(&self, field: &(dyn Fn([f64; 2]) -> f64 + Sync)) -> Vec<f64> {
        let [nx, ny] = self.counts;
        let mut values = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                values.push(field(self.point(i as f64, j as f64)));
            }
        }
        values
    }
}

/// Inside test shared by every use: NaN compares false, so it is outside.
#[inline]
fn inside(v: f64) -> bool {
    v < 0.0
}

/// Vertex ids created on demand: nodes, crossings on x-edges `(i,j)–(i+1,j)` and on y-edges
/// `(i,j)–(i,j+1)`. A vertex is created once and shared by every cell that uses it.
struct Vertices<'a> {
    lattice: &'a Lattice,
    values: &'a [f64],
    /// For a band, its levels: `values` are `f`, and each edge may hold both levels' crossings.
    band: Option<Band>,
    node: Vec<u32>,
    /// Crossings on x- and y-edges (a band's lower level), then a band's upper level's.
    edges: [Vec<u32>; 4],
    positions: Vec<[f64; 2]>,
    /// `positions` as the mesh stores them.
    rounded: Vec<[f32; 3]>,
}

const NONE: u32 = u32::MAX;

impl<'a> Vertices<'a> {
    fn new(lattice: &'a Lattice, values: &'a [f64], band: Option<Band>) -> Self {
        let [nx, ny] = lattice.counts;
        let hi = |n: usize| {
            if band.is_some() {
                vec![NONE; n]
            } else {
                Vec::new()
            }
        };
        Vertices {
            lattice,
            values,
            band,
            node: vec![NONE; nx * ny],
            edges: [
                vec![NONE; (nx - 1) * ny],
                vec![NONE; nx * (ny - 1)],
                hi((nx - 1) * ny),
                hi(nx * (ny - 1)),
            ],
            positions: Vec::new(),
            rounded: Vec::new(),
        }
    }

    fn add(&mut self, p: [f64; 2]) -> u32 {
        self.positions.push(p);
        self.rounded.push([p[0] as f32, p[1] as f32, 0.0]);
        (self.positions.len() - 1) as u32
    }

    fn node(&mut self, i: usize, j: usize) -> u32 {
        let slot = i + self.lattice.counts[0] * j;
        if self.node[slot] == NONE {
            self.node[slot] = self.add(self.lattice.point(i as f64, j as f64));
        }
        self.node[slot]
    }

    fn x_edge(&mut self, i: usize, j: usize) -> u32 {
        self.edge(i, j, 0, false)
    }

    fn y_edge(&mut self, i: usize, j: usize) -> u32 {
        self.edge(i, j, 1, false)
    }

    /// The crossing on the edge from node `(i, j)` along `axis`: of the zero level, or for a
    /// band of its lower level or (`upper`) its upper level. On a rectangle its `f32`
    /// coordinate along the edge stays strictly inside the edge, and a band's two crossings
    /// on one edge apart.
    fn edge(&mut self, i: usize, j: usize, axis: usize, upper: bool) -> u32 {
        let nx = self.lattice.counts[0];
        let (slot, next) = if axis == 0 {
            (i + (nx - 1) * j, i + 1 + nx * j)
        } else {
            (i + nx * j, i + nx * (j + 1))
        };
        let table = axis + 2 * usize::from(upper);
        if self.edges[table][slot] != NONE {
            return self.edges[table][slot];
        }
        let (v0, v1) = (self.values[i + nx * j], self.values[next]);
        let band = self.band;
        let at = |upper: bool| match band {
            None => crossing_fraction(v0, v1),
            Some(band) => band_crossing(v0, v1, band, upper),
        };
        let t = at(upper);
        let lattice = self.lattice;
        let (a, b) = (i as f64, j as f64);
        let p = if axis == 0 {
            lattice.point(a + t, b)
        } else {
            lattice.point(a, b + t)
        };
        let id = self.add(p);
        if lattice.axis_aligned() {
            let start = if axis == 0 { a } else { b };
            let ends = (
                lattice.point_on(axis, start),
                lattice.point_on(axis, start + 1.0),
            );
            let rounded = |t: f64| round_inside(lattice.point_on(axis, start + t), ends.0, ends.1);
            let mut coordinate = round_inside(p[axis], ends.0, ends.1);
            if band.is_some_and(|band| spans_band(v0, v1, band)) {
                let (t_lo, t_hi) = (at(false), at(true));
                let (lo, hi) =
                    apart_in_f32(rounded(t_lo), rounded(t_hi), t_hi > t_lo, ends.0, ends.1);
                coordinate = if upper { hi } else { lo };
            }
            self.rounded[id as usize][axis] = coordinate;
        }
        self.edges[table][slot] = id;
        id
    }
}

/// An item of a cell's inside polygon: one of its corners, or the crossing on one of its sides.
#[derive(Clone, Copy)]
enum Item {
    Corner(usize),
    Side(usize),
}

/// Marching squares with the face rule; triangles counter-clockwise in lattice coordinates,
/// which the lattice (positive determinant) keeps counter-clockwise in the plane.
fn march(lattice: &Lattice, values: &[f64]) -> (Mesh, Vec<[f64; 2]>) {
    let [nx, ny] = lattice.counts;
    let mut verts = Vertices::new(lattice, values, None);
    let mut triangles = Vec::new();
    let mut polygon: Vec<Item> = Vec::with_capacity(8);
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            // Corners counter-clockwise; side k runs from corner k to corner k + 1.
            let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let ins: [bool; 4] = corners.map(|(a, b)| inside(values[a + nx * b]));
            if !ins.iter().any(|&b| b) {
                continue;
            }
            let mut id = |item: Item| match item {
                Item::Corner(k) => verts.node(corners[k].0, corners[k].1),
                Item::Side(0) => verts.x_edge(i, j),
                Item::Side(1) => verts.y_edge(i + 1, j),
                Item::Side(2) => verts.x_edge(i, j + 1),
                Item::Side(_) => verts.y_edge(i, j),
            };
            let crossings = (0..4).filter(|&k| ins[k] != ins[(k + 1) % 4]).count();
            if crossings == 4 {
                // Ambiguous cell: the face rule separates the inside corners.
                for k in (0..4).filter(|&k| ins[k]) {
                    let tri = [Item::Corner(k), Item::Side(k), Item::Side((k + 3) % 4)];
                    triangles.push(tri.map(&mut id));
                }
                continue;
            }
            polygon.clear();
            for k in 0..4 {
                if ins[k] {
                    polygon.push(Item::Corner(k));
                }
                if ins[k] != ins[(k + 1) % 4] {
                    polygon.push(Item::Side(k));
                }
            }
            // One cut line leaves a convex inside part: a fan triangulates it.
            let ids: Vec<u32> = polygon.iter().map(|&item| id(item)).collect();
            for k in 1..ids.len() - 1 {
                triangles.push([ids[0], ids[k], ids[k + 1]]);
            }
        }
    }
    (
        Mesh {
            vertices: verts.rounded,
            triangles,
        },
        verts.positions,
    )
}

/// The band `lo < f < hi` of the samples `values` of `f`, cell by cell: the 3D tables' band
/// cap on the cube face z = 0 (corners 0–3 are the cell's, x fastest), reversed — caps face
/// outward, −z there, and regions face +z —, so a 2D band is what a 3D one draws on a face.
fn march_band(lattice: &Lattice, values: &[f64], band: Band) -> (Mesh, Vec<[f64; 2]>) {
    /// The cube's face z = 0 in the tables' cap order (`2 · axis + side`).
    const FACE_Z0: usize = 4;
    let tables = tables();
    let [nx, ny] = lattice.counts;
    let mut verts = Vertices::new(lattice, values, Some(band));
    let mut triangles = Vec::new();
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let at = |c: u8| (i + usize::from(c & 1), j + usize::from((c >> 1) & 1));
            let config = |bit: &dyn Fn(f64) -> bool| {
                (0..4u8).fold(0u8, |bits, c| {
                    let (a, b) = at(c);
                    bits | u8::from(bit(values[a + nx * b])) << c
                })
            };
            let p = config(&|v| v > band.lo);
            let q = config(&|v| v >= band.hi);
            let mut id = |slot: u8| {
                if (CORNER_SLOT..HI_SLOT).contains(&slot) {
                    let (a, b) = at(slot - CORNER_SLOT);
                    return verts.node(a, b);
                }
                let upper = slot >= HI_SLOT;
                let [c0, c1] = EDGE_CORNERS[usize::from(if upper { slot - HI_SLOT } else { slot })];
                let (a, b) = at(c0);
                let axis = if (c0 ^ c1) & 1 != 0 { 0 } else { 1 };
                verts.edge(a, b, axis, upper)
            };
            for tri in tables.band_cap(p, q, FACE_Z0) {
                triangles.push([id(tri[0]), id(tri[2]), id(tri[1])]);
            }
        }
    }
    (
        Mesh {
            vertices: verts.rounded,
            triangles,
        },
        verts.positions,
    )
}

/// Chains the edges used by one triangle into closed loops, directed as in their triangle.
/// Loops start at the earliest boundary edge in triangle order; at a vertex with several
/// outgoing boundary edges (where the region touches itself) the earliest unused is taken, so
/// the result is deterministic and every loop is closed. Edges are matched by sorting their
/// undirected keys (no hashing: this runs over tens of millions of edges).
pub(crate) fn boundary_loops(mesh: &Mesh) -> Vec<Vec<u32>> {
    let directed = |slot: usize| {
        let t = mesh.triangles[slot / 3];
        (t[slot % 3], t[(slot % 3 + 1) % 3])
    };
    let mut keys: Vec<(u64, u32)> = (0..mesh.triangles.len() * 3)
        .into_par_iter()
        .map(|slot| {
            let (a, b) = directed(slot);
            (u64::from(a.min(b)) << 32 | u64::from(a.max(b)), slot as u32)
        })
        .collect();
    keys.par_sort_unstable();
    // Keys used once are boundary edges (twice: interior, in opposite directions on an
    // edge-manifold region); in triangle order.
    let mut slots: Vec<u32> = Vec::new();
    let mut i = 0;
    while i < keys.len() {
        let mut j = i + 1;
        while j < keys.len() && keys[j].0 == keys[i].0 {
            j += 1;
        }
        if j - i == 1 {
            slots.push(keys[i].1);
        }
        i = j;
    }
    drop(keys);
    slots.sort_unstable();
    let edges: Vec<(u32, u32)> = slots.iter().map(|&s| directed(s as usize)).collect();
    // Outgoing edges of each vertex: a range of `starts`, in edge order.
    let mut starts: Vec<(u32, u32)> = edges
        .iter()
        .enumerate()
        .map(|(e, &(a, _))| (a, e as u32))
        .collect();
    starts.sort_unstable();
    let mut used = vec![false; edges.len()];
    let mut loops = Vec::new();
    for start in 0..edges.len() {
        if used[start] {
            continue;
        }
        let mut points = Vec::new();
        let mut e = start;
        loop {
            used[e] = true;
            let (a, b) = edges[e];
            points.push(a);
            let from = starts.partition_point(|&(v, _)| v < b);
            let next = starts[from..]
                .iter()
                .take_while(|&&(v, _)| v == b)
                .map(|&(_, e)| e as usize)
                .find(|&e| !used[e]);
            match next {
                Some(n) => e = n,
                None => break,
            }
        }
        loops.push(points);
    }
    loops
}
