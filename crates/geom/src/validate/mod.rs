//! Mesh validators: watertightness, manifoldness, Euler characteristic, volume, area.
//!
//! [`check`] measures a [`Mesh`] as it will be written (`f32` positions, `u32` indices) and
//! never fails: every problem is a count in [`MeshCheck`]. Definitions, as they appear in reports:
//!
//! - **Edge**: an unordered pair of distinct vertex indices `{a, b}` joined by a side of at
//!   least one triangle. Its *uses* are the triangle sides lying on it; a side `a → b` and a side
//!   `b → a` run in opposite directions. A triangle with a repeated index contributes only its
//!   sides between distinct indices (so `[a, a, b]` uses `{a, b}` once in each direction).
//! - **Boundary edge**: used exactly once. **Non-manifold edge**: used more than twice.
//!   **Misoriented edge**: used exactly twice, both times in the same direction (two neighbours
//!   with inconsistent winding).
//! - **Non-manifold vertex**: a referenced vertex whose incident triangles do not form one
//!   single fan, i.e. are not all connected to each other through edges incident to the vertex
//!   (two solids touching at a point, or two sheets crossing at one vertex).
//! - **Degenerate triangle**: a repeated index, or an area that is not a positive finite number
//!   when computed in `f64` from the `f32` positions (zero for collinear corners; `NaN` or
//!   infinite only for non-finite coordinates).
//! - **Duplicate position**: a referenced vertex whose position is bit-identical to that of a
//!   referenced vertex with a smaller index; a position shared by `k` vertices counts `k − 1`.
//!   STL stores positions, not indices, and readers weld bit-identical positions, so such a mesh
//!   would change topology on the way through STL.
//! - **Invalid triangle**: a triangle with an index past the end of `vertices`. It is counted
//!   and otherwise ignored (no edges, area or volume).
//! - **Referenced vertex**: used by at least one valid triangle. `vertices`, the Euler
//!   characteristic and the bounding box only consider referenced vertices.
//! - **Euler characteristic** `χ = V − E + F`: referenced vertices, edges, valid triangles
//!   (degenerate ones included). A closed orientable surface of genus `g` has `χ = 2 − 2g`.
//! - **Volume**: `Σ a · (b × c) / 6` over valid triangles, in `f64`: the signed volume enclosed,
//!   positive for outward (counter-clockwise seen from outside) winding. For a closed surface it
//!   does not depend on the origin; for an open one it is relative to the coordinate origin.
//! - **Area**: the sum of triangle areas in `f64`.
//!
//! Verdicts:
//! - **watertight**: at least one triangle, no invalid triangles, and no boundary, non-manifold
//!   or misoriented edges — every edge is shared by exactly two triangles traversing it in
//!   opposite directions.
//! - **manifold**: no invalid triangles, no non-manifold or misoriented edges, no non-manifold
//!   vertices, no degenerate triangles and no duplicate positions. Boundary edges are allowed
//!   (a manifold with boundary); an empty mesh is manifold but not watertight.
//!
//! Invariant: the result is a deterministic function of the mesh, independent of thread count
//! and scheduling (floating-point sums are taken over fixed chunks in a fixed order).
//!
//! Degenerate triangles take part in the edge counts like any other, so they do not by
//! themselves make a mesh non-watertight; `manifold` is the verdict that rejects them.
//!
//! Method, four passes, each parallel and each streaming through memory: (1) triangles: area,
//! volume, degeneracy, and the number of corners at every vertex; (2) vertices: where each
//! one's list will start, the bounding box, and duplicate positions by radix-partitioning
//! position hashes into cache-sized hash tables; (3) a counting sort lists, for every vertex,
//! the two other corners of each triangle at it (compressed rows); (4) every vertex examines
//! its own fan locally, and each edge `{a, b}` with `a < b` is classified from vertex `a`
//! only, so no global edge table is needed. Besides the mesh, the passes hold about 24 bytes
//! per triangle (the per-vertex lists) and a few tens of bytes per vertex.
//!
//! [`StreamCheck`] (`stream.rs`) gives the same measurements for a mesh that arrives as
//! [`MeshChunk`](crate::mesh::MeshChunk)s, holding one chunk and the open vertices at a time:
//! a vertex's fan is classified when no later chunk can touch it. It equals [`check`] in every
//! field except that duplicate positions are only matched between vertices alive together.

use crate::mesh::Mesh;
use crate::vec3::{cross, dot, sub};
use rayon::prelude::*;

mod closed_fan;
mod pieces;
mod stream;
use closed_fan::closed_fan;
pub use pieces::{Piece, PieceCounter, Pieces, pieces};
pub use stream::StreamCheck;

/// The measurements and verdicts of [`check`]. Counts follow the module definitions.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshCheck {
    /// All triangles of the mesh, valid or not.
    pub triangles: usize,
    /// Referenced vertices.
    pub vertices: usize,
    /// Distinct undirected edges.
    pub edges: usize,
    pub boundary_edges: usize,
    pub nonmanifold_edges: usize,
    pub misoriented_edges: usize,
    pub nonmanifold_vertices: usize,
    pub degenerate_triangles: usize,
    pub duplicate_positions: usize,
    pub unreferenced_vertices: usize,
    pub invalid_triangles: usize,
    pub euler_characteristic: i64,
    pub volume: f64,
    pub area: f64,
    /// Bounding box of the referenced vertices; zeros when there are none.
    pub bbox_min: [f64; 3],
    pub bbox_max: [f64; 3],
    pub watertight: bool,
    pub manifold: bool,
}

/// Measures `mesh`. See the module documentation for every definition.
pub fn check(mesh: &Mesh) -> MeshCheck {
    if links_fit::<u32>(mesh.triangles.len()) {
        analyse::<u32>(mesh)
    } else {
        analyse::<u64>(mesh)
    }
}

/// The number of connected pieces of `mesh`: valid triangles are connected when they share a
/// vertex index (so two solids touching at one vertex are one piece). Meshes read from
/// formats that store positions (STL) must be welded first. Vertices no valid triangle uses
/// are not counted.
pub fn components(mesh: &Mesh) -> usize {
    let n = mesh.vertices.len();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    let mut used = vec![false; n];
    for t in mesh.triangles.iter().filter(|t| is_valid(t, n)) {
        union(&mut parent, t[0], t[1]);
        union(&mut parent, t[1], t[2]);
        for &i in t {
            used[i as usize] = true;
        }
    }
    (0..n as u32)
        .filter(|&i| used[i as usize] && find(&mut parent, i) == i)
        .count()
}

/// The passes, each parallel inside, run one after the other: with few cores, running them
/// side by side only adds contention.
fn analyse<I: Index>(mesh: &Mesh) -> MeshCheck {
    let (geometry, degrees) = triangle_pass::<I>(mesh);
    let (cursors, vertices) = vertex_pass(mesh, degrees);
    let links = Links::scatter(mesh, cursors);
    let fans = fan_pass(&links);
    drop(links);
    report(
        mesh.triangles.len(),
        mesh.vertices.len(),
        &geometry,
        &vertices,
        &fans,
    )
}

/// The counts and verdicts from the passes' sums; shared with [`StreamCheck`] so both apply
/// the same definitions. `all_vertices` counts referenced and unreferenced vertices.
fn report(
    triangles: usize,
    all_vertices: usize,
    geometry: &Geometry,
    vertices: &VertexSums,
    fans: &FanSums,
) -> MeshCheck {
    let valid_triangles = triangles - geometry.invalid;
    let euler_characteristic =
        vertices.referenced as i64 - fans.edges as i64 + valid_triangles as i64;
    let watertight = valid_triangles > 0
        && geometry.invalid == 0
        && fans.boundary == 0
        && fans.nonmanifold_edges == 0
        && fans.misoriented == 0;
    let manifold = geometry.invalid == 0
        && fans.nonmanifold_edges == 0
        && fans.misoriented == 0
        && fans.nonmanifold_vertices == 0
        && geometry.degenerate == 0
        && vertices.duplicates == 0;
    let (bbox_min, bbox_max) = if vertices.referenced == 0 {
        ([0.0; 3], [0.0; 3])
    } else {
        (
            vertices.bbox_min.map(f64::from),
            vertices.bbox_max.map(f64::from),
        )
    };
    MeshCheck {
        triangles,
        vertices: vertices.referenced,
        edges: fans.edges,
        boundary_edges: fans.boundary,
        nonmanifold_edges: fans.nonmanifold_edges,
        misoriented_edges: fans.misoriented,
        nonmanifold_vertices: fans.nonmanifold_vertices,
        degenerate_triangles: geometry.degenerate,
        duplicate_positions: vertices.duplicates,
        unreferenced_vertices: all_vertices.saturating_sub(vertices.referenced),
        invalid_triangles: geometry.invalid,
        euler_characteristic,
        volume: geometry.volume,
        area: geometry.area,
        bbox_min,
        bbox_max,
        watertight,
        manifold,
    }
}

// ---------------------------------------------------------------------------------------------
// Index types.

/// An index type for adjacency offsets: `u32` when it can count every link (less memory),
/// `u64` otherwise.
trait Index: Copy + Default + Send + Sync {
    const MAX: u64;
    fn from_usize(value: usize) -> Self;
    fn to_usize(self) -> usize;
}

impl Index for u32 {
    const MAX: u64 = u32::MAX as u64;
    #[inline]
    fn from_usize(value: usize) -> Self {
        value as u32
    }
    #[inline]
    fn to_usize(self) -> usize {
        self as usize
    }
}

impl Index for u64 {
    const MAX: u64 = u64::MAX;
    #[inline]
    fn from_usize(value: usize) -> Self {
        value as u64
    }
    #[inline]
    fn to_usize(self) -> usize {
        self as usize
    }
}

/// Whether `I` can count the links (three per triangle) of `triangles` triangles.
fn links_fit<I: Index>(triangles: usize) -> bool {
    (triangles as u64)
        .checked_mul(3)
        .is_some_and(|n| n <= I::MAX)
}

// ---------------------------------------------------------------------------------------------
// Triangle pass: validity, degeneracy, area, volume, and vertex degrees.

/// Triangles per chunk of the floating-point sums. Fixed, so sums do not depend on scheduling.
const TRIANGLE_CHUNK: usize = 1 << 15;

/// At most this many private degree arrays (one per part of the triangle pass).
const MAX_PARTS: usize = 8;

#[inline]
fn is_valid(tri: &[u32; 3], vertex_count: usize) -> bool {
    tri.iter().all(|&i| (i as usize) < vertex_count)
}

#[inline]
fn position(mesh: &Mesh, index: u32) -> [f64; 3] {
    mesh.vertices[index as usize].map(f64::from)
}

/// Triangles summed a few at a time: one at a time, each area's square root held up the
/// loop (a quarter of the stream check's triangle pass).
const PENDING_TRIANGLES: usize = 8;

/// Triangles added to [`TriangleSums`] but not yet summed: their normals and volume terms.
#[derive(Default)]
struct PendingTriangles {
    len: usize,
    normals: [[f64; 3]; PENDING_TRIANGLES],
    six_volumes: [f64; PENDING_TRIANGLES],
    repeated: [bool; PENDING_TRIANGLES],
}

#[derive(Clone, Default)]
struct TriangleSums {
    invalid: usize,
    degenerate: usize,
    /// Σ (a − o) · n, with n = (b − a) × (c − a): six times the volume relative to `o`.
    six_volume: f64,
    /// Σ n: twice the vector area. Zero for a closed surface.
    twice_vector_area: [f64; 3],
    /// Σ |n|: twice the area.
    twice_area: f64,
}

impl TriangleSums {
    fn add(&mut self, other: &TriangleSums) {
        self.invalid += other.invalid;
        self.degenerate += other.degenerate;
        self.six_volume += other.six_volume;
        for (t, s) in self
            .twice_vector_area
            .iter_mut()
            .zip(other.twice_vector_area)
        {
            *t += s;
        }
        self.twice_area += other.twice_area;
    }

    /// Adds the valid triangle `tri` with corner positions `[a, b, c]`, volume relative to
    /// `reference`, through `pending` (whose triangles must be added with
    /// [`TriangleSums::flush`] before the sums are read). The one place this arithmetic is
    /// written, so [`check`] and [`StreamCheck`] sum bit-identical terms, in triangle order.
    #[inline]
    fn add_triangle(
        &mut self,
        pending: &mut PendingTriangles,
        tri: &[u32; 3],
        [a, b, c]: [[f64; 3]; 3],
        reference: [f64; 3],
    ) {
        let normal = cross(sub(b, a), sub(c, a));
        let k = pending.len;
        pending.normals[k] = normal;
        // (a − o) · ((b − o) × (c − o)) = (a − o) · ((b − a) × (c − a)).
        pending.six_volumes[k] = dot(sub(a, reference), normal);
        pending.repeated[k] = tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2];
        pending.len += 1;
        if pending.len == PENDING_TRIANGLES {
            self.flush(pending);
        }
    }

    /// Adds the pending triangles, in order, and empties `pending`.
    #[inline]
    fn flush(&mut self, pending: &mut PendingTriangles) {
        let mut twice_areas = [0.0; PENDING_TRIANGLES];
        // A loop of its own, so that the square roots vectorize.
        for (area, &n) in twice_areas.iter_mut().zip(&pending.normals) {
            *area = dot(n, n).sqrt();
        }
        let count = pending.len;
        let terms = twice_areas
            .iter()
            .zip(&pending.normals)
            .zip(&pending.six_volumes)
            .zip(&pending.repeated)
            .take(count);
        for (((&twice_area, normal), &six_volume), &repeated) in terms {
            if repeated || !(twice_area > 0.0 && twice_area.is_finite()) {
                self.degenerate += 1;
            }
            self.six_volume += six_volume;
            for (total, component) in self.twice_vector_area.iter_mut().zip(normal) {
                *total += component;
            }
            self.twice_area += twice_area;
        }
        pending.len = 0;
    }

    /// The totals, with the volume moved from `reference` back to the origin.
    fn geometry(&self, reference: [f64; 3]) -> Geometry {
        // Σ a · n = Σ (a − o) · n + o · Σ n.
        let six_volume = self.six_volume + dot(reference, self.twice_vector_area);
        Geometry {
            invalid: self.invalid,
            degenerate: self.degenerate,
            volume: six_volume / 6.0,
            area: self.twice_area / 2.0,
        }
    }
}

struct Geometry {
    invalid: usize,
    degenerate: usize,
    volume: f64,
    area: f64,
}

/// Sums the geometry of every triangle and counts the corners at every vertex. Returns the
/// geometry and the corner counts, one array per part (see below).
///
/// The triangles are cut into one contiguous part per thread (so each part reads its
/// triangles once, for both jobs); each part counts degrees into a private array, and the
/// arrays are summed afterwards.
fn triangle_pass<I: Index>(mesh: &Mesh) -> (Geometry, Vec<Vec<I>>) {
    let n = mesh.vertices.len();
    // Volumes are summed relative to a point on the mesh, which keeps the terms small when the
    // mesh sits far from the origin; the origin-relative volume is recovered exactly below.
    let reference = mesh
        .triangles
        .iter()
        .find(|tri| is_valid(tri, n))
        .map_or([0.0; 3], |tri| position(mesh, tri[0]));

    let chunks = mesh.triangles.len().div_ceil(TRIANGLE_CHUNK);
    let parts = rayon::current_num_threads()
        .clamp(1, MAX_PARTS)
        .min(chunks.max(1));
    let chunks_per_part = chunks.div_ceil(parts).max(1);
    let results: Vec<(Vec<TriangleSums>, Vec<I>)> = (0..parts)
        .into_par_iter()
        .map(|part| {
            let first = (part * chunks_per_part * TRIANGLE_CHUNK).min(mesh.triangles.len());
            let last = ((part + 1) * chunks_per_part * TRIANGLE_CHUNK).min(mesh.triangles.len());
            let mut degrees = vec![I::default(); n];
            let sums = mesh.triangles[first..last]
                .chunks(TRIANGLE_CHUNK)
                .map(|chunk| triangle_chunk(mesh, chunk, reference, &mut degrees))
                .collect();
            (sums, degrees)
        })
        .collect();

    let mut total = TriangleSums::default();
    for (sums, _) in &results {
        for chunk in sums {
            total.add(chunk);
        }
    }
    let geometry = total.geometry(reference);

    let degrees = results.into_iter().map(|(_, degrees)| degrees).collect();
    (geometry, degrees)
}

/// The geometry of one chunk of triangles; also counts their corners into `degrees`.
fn triangle_chunk<I: Index>(
    mesh: &Mesh,
    chunk: &[[u32; 3]],
    reference: [f64; 3],
    degrees: &mut [I],
) -> TriangleSums {
    let n = mesh.vertices.len();
    let mut sums = TriangleSums::default();
    let mut pending = PendingTriangles::default();
    for tri in chunk {
        if !is_valid(tri, n) {
            sums.invalid += 1;
            continue;
        }
        for &v in tri {
            let degree = &mut degrees[v as usize];
            *degree = I::from_usize(degree.to_usize() + 1);
        }
        sums.add_triangle(&mut pending, tri, tri.map(|i| position(mesh, i)), reference);
    }
    sums.flush(&mut pending);
    sums
}

// ---------------------------------------------------------------------------------------------
// Vertex → link adjacency, built by counting sort.

/// The counting sort's state between counting and scattering: `cursors[v + 1]` is the start of
/// vertex `v`'s links, `cursors[0]` is 0, `total` the number of links.
struct Cursors<I> {
    cursors: Vec<I>,
    total: usize,
}

/// The link of triangle corner `v` of `[v, next, prev]` (in winding order): its two sides
/// `v → next` and `prev → v`, packed as `next | prev << 32`.
#[inline]
fn link(next: u32, prev: u32) -> u64 {
    u64::from(next) | u64::from(prev) << 32
}

#[inline]
fn unlink(link: u64) -> (u32, u32) {
    (link as u32, (link >> 32) as u32)
}

/// Corner `i` of a triangle is followed by `NEXT[i]` and preceded by `PREV[i]`.
const NEXT: [usize; 3] = [1, 2, 0];
const PREV: [usize; 3] = [2, 0, 1];

/// For every vertex `v`, the links of the valid triangle corners at `v`:
/// `links[offsets[v]..offsets[v + 1]]`, in triangle order. Storing the two other corners
/// rather than a triangle id lets the fan pass read memory sequentially.
struct Links<I> {
    offsets: Vec<I>,
    links: Vec<u64>,
}

impl<I: Index> Links<I> {
    /// The scatter of the counting sort, parallel without atomics: each thread owns a
    /// contiguous range of vertices (and so of the cursors and links), scans every triangle and
    /// handles only the corners in its range. The scan is sequential and cheap; the scattered
    /// writes, which are what costs, are split between the threads. Each cursor advances from
    /// its vertex's start to its end, which is the next vertex's start: the cursors become the
    /// offsets.
    fn scatter(mesh: &Mesh, cursors: Cursors<I>) -> Self {
        let Cursors {
            cursors: mut offsets,
            total,
        } = cursors;
        let n = offsets.len() - 1;
        let parts = rayon::current_num_threads().max(1);
        let part_len = n.div_ceil(parts).max(1);
        let triangles = &mesh.triangles;

        let mut links = vec![0u64; total];
        let mut link_parts = Vec::with_capacity(parts);
        let mut rest = links.as_mut_slice();
        let mut taken = 0;
        for part in 1..parts {
            let boundary = offsets
                .get(part * part_len + 1)
                .map_or(total, |s| s.to_usize());
            let (head, tail) = rest.split_at_mut(boundary.max(taken) - taken);
            link_parts.push(head);
            taken = boundary.max(taken);
            rest = tail;
        }
        link_parts.push(rest);
        offsets[1..]
            .par_chunks_mut(part_len)
            .zip(link_parts)
            .enumerate()
            .for_each(|(part, (cursors, links))| {
                let first = part * part_len;
                let base = cursors.first().map_or(0, |c| c.to_usize());
                for tri in triangles.iter().filter(|tri| is_valid(tri, n)) {
                    for corner in 0..3 {
                        // One unsigned comparison tests first <= v < first + len.
                        let local = (tri[corner] as usize).wrapping_sub(first);
                        if let Some(cursor) = cursors.get_mut(local) {
                            let at = cursor.to_usize();
                            links[at - base] = link(tri[NEXT[corner]], tri[PREV[corner]]);
                            *cursor = I::from_usize(at + 1);
                        }
                    }
                }
            });
        Links { offsets, links }
    }

    fn vertex_count(&self) -> usize {
        self.offsets.len() - 1
    }

    #[inline]
    fn at(&self, v: usize) -> &[u64] {
        &self.links[self.offsets[v].to_usize()..self.offsets[v + 1].to_usize()]
    }

    /// The links from `v`'s first on, to the end.
    #[inline]
    fn onward(&self, v: usize) -> &[u64] {
        &self.links[self.offsets[v].to_usize()..]
    }
}

// ---------------------------------------------------------------------------------------------
// Fan pass: edges and vertex fans.

/// Vertices per parallel work item of the fan pass.
const VERTEX_BLOCK: usize = 1 << 13;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct FanSums {
    edges: usize,
    boundary: usize,
    nonmanifold_edges: usize,
    misoriented: usize,
    nonmanifold_vertices: usize,
}

impl FanSums {
    fn merge(self, other: FanSums) -> FanSums {
        FanSums {
            edges: self.edges + other.edges,
            boundary: self.boundary + other.boundary,
            nonmanifold_edges: self.nonmanifold_edges + other.nonmanifold_edges,
            misoriented: self.misoriented + other.misoriented,
            nonmanifold_vertices: self.nonmanifold_vertices + other.nonmanifold_vertices,
        }
    }
}

/// One side of a triangle at the vertex under examination `v`, seen from `v`.
#[derive(Clone, Copy)]
struct Side {
    /// The other end of the side.
    other: u32,
    /// Which of `v`'s corners (position in its link list) the side belongs to.
    corner: u32,
    /// `v → other` (the side leaving `v`) rather than `other → v`.
    outgoing: bool,
}

/// Per-thread scratch space, reused from vertex to vertex.
#[derive(Default)]
struct FanScratch {
    sides: Vec<Side>,
    parent: Vec<u32>,
}

/// Fans with at most this many corners try the closed-fan check first (almost every vertex
/// of a real mesh: marching-cubes vertices have at most 12).
const SMALL_FAN: usize = 16;

fn fan_pass<I: Index>(links: &Links<I>) -> FanSums {
    let n = links.vertex_count();
    (0..n.div_ceil(VERTEX_BLOCK))
        .into_par_iter()
        .map_init(FanScratch::default, |scratch, block| {
            let mut sums = FanSums::default();
            for v in block * VERTEX_BLOCK..((block + 1) * VERTEX_BLOCK).min(n) {
                let fan = links.at(v);
                // A referenced vertex has a u32 index, so `v as u32` is exact where it is used.
                let vertex = v as u32;
                if fan.is_empty() {
                    continue;
                }
                if fan.len() > SMALL_FAN
                    || !closed_fan(links.onward(v), fan.len(), vertex, &mut sums)
                {
                    general_fan(fan, vertex, scratch, &mut sums);
                }
            }
            sums
        })
        .reduce(FanSums::default, FanSums::merge)
}

/// Classifies the edges `{v, w}` with `w > v` and counts the pieces of `v`'s fan, for any fan.
fn general_fan(fan: &[u64], vertex: u32, scratch: &mut FanScratch, sums: &mut FanSums) {
    let sides = &mut scratch.sides;
    sides.clear();
    // Corners of [v, v, v] triangles: no side to another vertex, three corners per triangle.
    let mut isolated_corners = 0;
    for (slot, &l) in fan.iter().enumerate() {
        let (next, prev) = unlink(l);
        let corner = slot as u32;
        if next != vertex {
            sides.push(Side {
                other: next,
                corner,
                outgoing: true,
            });
        }
        if prev != vertex {
            sides.push(Side {
                other: prev,
                corner,
                outgoing: false,
            });
        }
        if next == vertex && prev == vertex {
            isolated_corners += 1;
        }
    }
    sides.sort_unstable_by_key(|side| side.other);

    let parent = &mut scratch.parent;
    parent.clear();
    parent.extend(0..fan.len() as u32);
    for group in sides.chunk_by(|x, y| x.other == y.other) {
        if group[0].other > vertex {
            sums.edges += 1;
            let outgoing = group.iter().filter(|side| side.outgoing).count();
            match group.len() {
                1 => sums.boundary += 1,
                2 if outgoing != 1 => sums.misoriented += 1,
                2 => {}
                _ => sums.nonmanifold_edges += 1,
            }
        }
        // Corners sharing the edge {v, other} are neighbours in v's fan.
        for side in &group[1..] {
            union(parent, group[0].corner, side.corner);
        }
    }

    // Corners never joined to another are roots; the three corners of one [v, v, v] triangle
    // are one piece of the fan, not three.
    let roots = (0..parent.len() as u32)
        .filter(|&c| find(parent, c) == c)
        .count();
    let pieces = roots - isolated_corners + isolated_corners / 3;
    if pieces > 1 {
        sums.nonmanifold_vertices += 1;
    }
}

/// The root of `x`'s set in a union-find, halving paths on the way (shared by the piece
/// counts, the island filter and the genus).
#[inline]
pub(crate) fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        // Path halving keeps later finds short.
        let grandparent = parent[parent[x as usize] as usize];
        parent[x as usize] = grandparent;
        x = grandparent;
    }
    x
}

#[inline]
fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

// ---------------------------------------------------------------------------------------------
// Vertex pass: referenced vertices, bounding box, duplicate positions.

/// Average number of vertices per partition of the duplicate search: few enough partitions
/// for the grouping's write streams to stay cache- and TLB-friendly, small enough partitions
/// for their hash tables to stay in the cache.
const PARTITION_SIZE: usize = 1 << 14;

/// Vertices per parallel work item of the vertex pass (each groups its own duplicate-search
/// entries).
const VERTEX_CHUNK: usize = 1 << 17;

struct VertexSums {
    referenced: usize,
    duplicates: usize,
    bbox_min: [f32; 3],
    bbox_max: [f32; 3],
}

/// Visits every vertex once: sums its corner counts over the parts of the triangle pass (into
/// the counting sort's cursors), and if it is referenced, bounds it and prepares the search
/// for duplicate positions, which counts referenced vertices whose position bit-equals that
/// of a referenced vertex with a smaller index (a position shared by `k` vertices counts
/// `k − 1`).
///
/// Duplicates are found by radix partitioning and small hash tables instead of one global
/// table, for cache locality. Each referenced vertex becomes an [`Entry`]. Vertex chunks, in
/// parallel, group their entries by partition (high hash bits) with a counting sort; then each
/// partition, in parallel, puts the entries of every chunk into a table of its own. Entries
/// with equal hash bits have their actual positions compared, so hash collisions never count.
fn vertex_pass<I: Index>(mesh: &Mesh, degrees: Vec<Vec<I>>) -> (Cursors<I>, VertexSums) {
    let n = mesh.vertices.len();
    let bits = (n / PARTITION_SIZE)
        .max(1)
        .next_power_of_two()
        .trailing_zeros()
        .min(16);
    let partitions = 1usize << bits;
    let partition_of = |entry: Entry| (entry.hash() >> (31 - bits)) as usize;

    struct Chunk {
        /// Entries grouped by partition; partition `p` is `entries[starts[p]..starts[p + 1]]`.
        starts: Vec<usize>,
        entries: Vec<Entry>,
        bbox_min: [f32; 3],
        bbox_max: [f32; 3],
    }
    // cursors[v + 1] = degree of v for now.
    let mut cursors = vec![I::default(); n + 1];
    let chunks: Vec<Chunk> = cursors[1..]
        .par_chunks_mut(VERTEX_CHUNK)
        .enumerate()
        .map_init(Vec::new, |entries: &mut Vec<Entry>, (chunk, out)| {
            let first = chunk * VERTEX_CHUNK;
            let mut bbox_min = [f32::INFINITY; 3];
            let mut bbox_max = [f32::NEG_INFINITY; 3];
            entries.clear();
            for (i, slot) in out.iter_mut().enumerate() {
                let v = first + i;
                let degree: usize = degrees.iter().map(|part| part[v].to_usize()).sum();
                *slot = I::from_usize(degree);
                if degree > 0 {
                    let p = &mesh.vertices[v];
                    for a in 0..3 {
                        bbox_min[a] = bbox_min[a].min(p[a]);
                        bbox_max[a] = bbox_max[a].max(p[a]);
                    }
                    entries.push(Entry::new(v, p));
                }
            }
            let mut starts = vec![0usize; partitions + 1];
            for &entry in entries.iter() {
                starts[partition_of(entry) + 1] += 1;
            }
            for p in 0..partitions {
                starts[p + 1] += starts[p];
            }
            let mut next = starts.clone();
            let mut grouped = vec![Entry::EMPTY; entries.len()];
            for &entry in entries.iter() {
                let at = &mut next[partition_of(entry)];
                grouped[*at] = entry;
                *at += 1;
            }
            Chunk {
                starts,
                entries: grouped,
                bbox_min,
                bbox_max,
            }
        })
        .collect();
    drop(degrees);

    // cursors[v + 1] = start of v.
    let mut total = 0;
    for slot in &mut cursors[1..] {
        let degree = slot.to_usize();
        *slot = I::from_usize(total);
        total += degree;
    }

    let duplicates = (0..partitions)
        .into_par_iter()
        .map_init(Vec::new, |table, p| {
            let members = || {
                chunks
                    .iter()
                    .flat_map(|chunk| &chunk.entries[chunk.starts[p]..chunk.starts[p + 1]])
            };
            let count = chunks
                .iter()
                .map(|chunk| chunk.starts[p + 1] - chunk.starts[p])
                .sum();
            duplicates_among(mesh, count, members(), table)
        })
        .sum();

    let mut sums = VertexSums {
        referenced: chunks.iter().map(|chunk| chunk.entries.len()).sum(),
        duplicates,
        bbox_min: [f32::INFINITY; 3],
        bbox_max: [f32::NEG_INFINITY; 3],
    };
    for chunk in &chunks {
        for a in 0..3 {
            sums.bbox_min[a] = sums.bbox_min[a].min(chunk.bbox_min[a]);
            sums.bbox_max[a] = sums.bbox_max[a].max(chunk.bbox_max[a]);
        }
    }
    (Cursors { cursors, total }, sums)
}

/// A referenced vertex in the duplicate search: a marker bit (so no entry is zero, the empty
/// table slot), 31 bits of its position hash, and its index.
#[derive(Clone, Copy, PartialEq, Eq)]
struct Entry(u64);

impl Entry {
    const EMPTY: Entry = Entry(0);

    #[inline]
    fn new(v: usize, p: &[f32; 3]) -> Entry {
        // v < 2^32: it is referenced by a u32 index.
        Entry(1 << 63 | (position_hash(p) >> 33) << 32 | v as u64)
    }

    #[inline]
    fn hash(self) -> u32 {
        (self.0 >> 32) as u32 & 0x7fff_ffff
    }

    #[inline]
    fn vertex(self) -> usize {
        self.0 as u32 as usize
    }
}

/// Counts the `count` entries of `members` whose position equals an earlier entry's, with an
/// open-addressing table of entries.
fn duplicates_among<'a>(
    mesh: &Mesh,
    count: usize,
    members: impl Iterator<Item = &'a Entry>,
    table: &mut Vec<Entry>,
) -> usize {
    // Load factor at most 3/4 keeps probe sequences short.
    let table_bits = (count + count / 3 + 1)
        .max(16)
        .next_power_of_two()
        .trailing_zeros();
    table.clear();
    table.resize(1 << table_bits, Entry::EMPTY);
    let mask = table.len() - 1;
    let position = |entry: Entry| mesh.vertices[entry.vertex()].map(f32::to_bits);
    let mut duplicates = 0;
    for &entry in members {
        // Multiplicative hashing spreads the low hash bits (the high ones chose the
        // partition, so they are nearly equal here) over the table.
        let mut slot = (u64::from(entry.hash()).wrapping_mul(0x9e37_79b9_7f4a_7c15)
            >> (64 - table_bits)) as usize;
        loop {
            let occupant = table[slot];
            if occupant == Entry::EMPTY {
                table[slot] = entry;
                break;
            }
            if occupant.hash() == entry.hash() && position(occupant) == position(entry) {
                duplicates += 1;
                break;
            }
            slot = (slot + 1) & mask;
        }
    }
    duplicates
}

/// A well-mixed 64-bit hash of the position's bits.
#[inline]
fn position_hash(p: &[f32; 3]) -> u64 {
    let xy = u64::from(p[0].to_bits()) | (u64::from(p[1].to_bits()) << 32);
    mix(mix(xy) ^ u64::from(p[2].to_bits()))
}

/// The splitmix64 finaliser: every input bit affects every output bit.
#[inline]
fn mix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic generator (64-bit LCG, high bits).
    struct Lcg(u64);

    impl Lcg {
        fn below(&mut self, n: u32) -> u32 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((self.0 >> 33) as u32) % n
        }
    }

    #[test]
    fn components_count_pieces_joined_through_shared_vertices() {
        // Two tetrahedra apart, then sharing one vertex; an unused vertex and an invalid
        // triangle count for nothing.
        let tetra = |o: u32| {
            [
                [o, o + 1, o + 2],
                [o, o + 3, o + 1],
                [o, o + 2, o + 3],
                [o + 1, o + 3, o + 2],
            ]
        };
        let vertices = vec![[0.0f32; 3]; 9];
        let mut triangles: Vec<[u32; 3]> = tetra(0).into_iter().chain(tetra(4)).collect();
        triangles.push([0, 1, 99]);
        let apart = Mesh {
            vertices: vertices.clone(),
            triangles: triangles.clone(),
        };
        assert_eq!(components(&apart), 2);
        // The second tetrahedron's first corner becomes the first's vertex 3.
        for t in &mut triangles[4..8] {
            for i in t.iter_mut() {
                if *i == 4 {
                    *i = 3;
                }
            }
        }
        let touching = Mesh {
            vertices,
            triangles,
        };
        assert_eq!(components(&touching), 1);
        assert_eq!(components(&Mesh::default()), 0);
    }

    #[test]
    fn triangle_sums_are_the_one_at_a_time_sums_bit_for_bit() {
        // The lanes of `flush` against the definitions written out per triangle, for every
        // count of pending triangles at the end (0 to 7 left over).
        let mut rng = Lcg(23);
        let coordinate = |rng: &mut Lcg| f64::from(rng.below(2001)) * 0.37 - 370.0;
        for count in 90usize..106 {
            let reference = [1.5, -2.25, 0.125];
            let triangles: Vec<[[f64; 3]; 3]> = (0..count)
                .map(|_| [0; 3].map(|_| [0; 3].map(|_| coordinate(&mut rng))))
                .collect();
            let mut sums = TriangleSums::default();
            let mut pending = PendingTriangles::default();
            for (t, corners) in triangles.iter().enumerate() {
                // Every tenth triangle has a repeated index.
                let tri = if t % 10 == 0 { [0, 0, 1] } else { [0, 1, 2] };
                sums.add_triangle(&mut pending, &tri, *corners, reference);
            }
            sums.flush(&mut pending);
            let (mut six_volume, mut twice_area, mut vector) = (0.0, 0.0, [0.0f64; 3]);
            for [a, b, c] in &triangles {
                let (u, v) = (
                    [0, 1, 2].map(|i| b[i] - a[i]),
                    [0, 1, 2].map(|i| c[i] - a[i]),
                );
                let n = [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ];
                six_volume += dot([0, 1, 2].map(|i| a[i] - reference[i]), n);
                twice_area += dot(n, n).sqrt();
                for i in 0..3 {
                    vector[i] += n[i];
                }
            }
            assert_eq!(sums.six_volume.to_bits(), six_volume.to_bits(), "{count}");
            assert_eq!(sums.twice_area.to_bits(), twice_area.to_bits(), "{count}");
            assert_eq!(
                sums.twice_vector_area.map(f64::to_bits),
                vector.map(f64::to_bits)
            );
            assert_eq!(sums.degenerate, count.div_ceil(10), "{count}");
        }
    }

    /// The corners of a closed fan round `ring`: triangles `[v, ring[i], ring[i + 1]]`.
    fn ring_fan(ring: &[u32]) -> Vec<u64> {
        (0..ring.len())
            .map(|i| link(ring[i], ring[(i + 1) % ring.len()]))
            .collect()
    }

    fn check_fan(fan: &[u64], vertex: u32) -> (FanSums, Option<FanSums>) {
        let mut general = FanSums::default();
        general_fan(fan, vertex, &mut FanScratch::default(), &mut general);
        let mut fast = FanSums::default();
        let answered = closed_fan(fan, fan.len(), vertex, &mut fast);
        (general, answered.then_some(fast))
    }

    #[test]
    fn closed_fan_agrees_with_the_general_check() {
        let mut rng = Lcg(11);
        let vertex = 500;
        let mut answered = 0;
        for round in 0..100_000 {
            // Both lane widths: up to SMALL_FAN / 2 corners and up to SMALL_FAN.
            let k = 2 + rng.below(SMALL_FAN as u32 - 1) as usize;
            // Neighbours from a small range, so repeats are common.
            let neighbour = |rng: &mut Lcg| {
                if rng.below(8) == 0 {
                    vertex
                } else {
                    rng.below(1000)
                }
            };
            let mut fan = match round % 4 {
                // One closed ring (distinct neighbours).
                0 | 1 => {
                    let mut ring: Vec<u32> = Vec::new();
                    while ring.len() < k {
                        let w = neighbour(&mut rng);
                        if w != vertex && !ring.contains(&w) {
                            ring.push(w);
                        }
                    }
                    ring_fan(&ring)
                }
                // Two rings sharing only the vertex (a pinch), or sharing a neighbour.
                2 => {
                    let a = [1, 2, 3].map(|i| i + 600);
                    let b = if rng.below(2) == 0 {
                        [4, 5, 6].map(|i| i + 600)
                    } else {
                        [601, 7 + 600, 8 + 600]
                    };
                    [ring_fan(&a), ring_fan(&b)].concat()
                }
                // Anything.
                _ => (0..k)
                    .map(|_| link(neighbour(&mut rng), neighbour(&mut rng)))
                    .collect(),
            };
            // The fast path must not depend on the corners' order.
            for i in (1..fan.len()).rev() {
                fan.swap(i, rng.below(i as u32 + 1) as usize);
            }
            let (general, fast) = check_fan(&fan, vertex);
            if let Some(fast) = fast {
                assert_eq!(fast, general, "fan {fan:x?}");
                answered += 1;
            }
        }
        assert!(
            answered > 40_000,
            "the fast path answers closed fans ({answered})"
        );
    }

    #[test]
    fn closed_fans_at_the_lane_widths() {
        // Rings that fill the narrow lanes, spill into the wide ones, and fill those.
        for k in [3, SMALL_FAN / 2, SMALL_FAN / 2 + 1, SMALL_FAN] {
            let ring: Vec<u32> = (1..=k as u32).map(|w| 10 * w).collect();
            let (general, fast) = check_fan(&ring_fan(&ring), 0);
            assert_eq!(fast, Some(general));
            assert_eq!((general.edges, general.nonmanifold_vertices), (k, 0));
        }
        // Two rings of eight pinched at the vertex: sixteen corners, two pieces.
        let a: Vec<u32> = (1..=8).collect();
        let b: Vec<u32> = (11..=18).collect();
        let pinched = [ring_fan(&a), ring_fan(&b)].concat();
        let (general, fast) = check_fan(&pinched, 0);
        assert_eq!(fast, Some(general));
        assert_eq!((general.edges, general.nonmanifold_vertices), (16, 1));
        // A ring with one side missing is left to the general check, which finds a boundary.
        let mut open = ring_fan(&a);
        open.pop();
        let (general, fast) = check_fan(&open, 0);
        assert_eq!(fast, None);
        assert!(general.boundary > 0);
    }
}
