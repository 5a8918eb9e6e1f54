//! An indexed triangle mesh, the one mesh type every stage passes around.
//!
//! Invariants: vertex positions are `f32` (what every writer stores, so what is validated is
//! what is written); triangles index `vertices`; winding is counter-clockwise seen from
//! outside, so the right-hand normal points out of the solid.

use std::sync::{Mutex, PoisonError};

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub vertices: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }
}

/// `x`, a point inside the grid edge from coordinate `a` to `b` (along one axis), rounded to
/// `f32` and then kept strictly between the `f32` roundings of `a` and `b`.
///
/// Why: the contourers keep crossings 1/256 of an edge from its ends, but far from the origin
/// that can be less than an `f32` step (at 1000, 2⁻¹⁴ ≈ 6.1e-5: a 0.01 spacing leaves 3.9e-5),
/// and a crossing rounded onto the `f32` of its sample point, where another crossing or a
/// cap's node vertex may sit too: duplicate positions and triangles of zero area in what is
/// written (and STL, read back welded by position, changes topology). Kept strictly inside its
/// edge, a crossing's rounded position differs from every other vertex's (they lie on other
/// edges or at nodes, and the rounded grid is still a box), so no two vertices share a
/// position and no triangle of one cell is flat. Where rounding already lands strictly
/// inside — everywhere but such far, fine grids — the value is the plain rounding, bit for
/// bit. Needs [`separable`]`(a, b)`; without it the result is the rounding of an end.
#[inline]
pub(crate) fn round_inside(x: f64, a: f64, b: f64) -> f32 {
    let (lo, hi) = (a as f32, b as f32);
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (hi, lo) };
    let c = x as f32;
    if c > lo && c < hi {
        c
    } else {
        // max then min, not clamp: never panics, whatever the ends.
        c.max(lo.next_up()).min(hi.next_down())
    }
}

/// Whether `needed` (1 or 2) `f32` values lie strictly between the `f32` roundings of `a` and
/// `b` (finite): the room [`round_inside`] needs for a vertex inside the edge from `a` to `b`
/// (two for two vertices on one edge, as a shell's two levels may have).
pub(crate) fn separable(a: f64, b: f64, needed: usize) -> bool {
    let (lo, hi) = (a as f32, b as f32);
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (hi, lo) };
    let inner = if needed > 1 {
        lo.next_up().next_up()
    } else {
        lo.next_up()
    };
    lo.is_finite() && hi.is_finite() && inner < hi
}

/// What an edge without room for `needed` `f32` values lacks, for the contourers' errors.
pub(crate) fn room_wanting(needed: usize) -> &'static str {
    if needed > 1 {
        "fewer than two 32-bit values (a shell's two walls can cross one edge)"
    } else {
        "no 32-bit value"
    }
}

/// The first edge `i → i + 1` of the grid coordinates `coordinate(0..count)` that
/// [`separable`] refuses (with `needed` values inside), with the two coordinates.
pub(crate) fn inseparable_edge(
    count: usize,
    needed: usize,
    coordinate: impl Fn(usize) -> f64,
) -> Option<(usize, f64, f64)> {
    (0..count.saturating_sub(1))
        .map(|i| (i, coordinate(i), coordinate(i + 1)))
        .find(|&(_, a, b)| !separable(a, b, needed))
}

/// One piece of a mesh that is produced, checked and written in order, so a mesh of any size
/// passes through memory a chunk at a time (tiling a large scaffold, `tile::stream`).
///
/// Invariants, for the chunks of one mesh taken in order:
/// - chunk `k` adds the vertices `first_vertex .. first_vertex + vertices.len()`, and
///   `first_vertex` is the previous chunk's end (0 for the first chunk): ids are dense;
/// - its triangles use ids of its own vertices or of earlier chunks' (never a later one), and
///   `borrowed` lists every earlier id they use, once, sorted by id, with its position (bitwise
///   the one its own chunk gave it);
/// - `open` lists, sorted and once each, the ids of this or earlier chunks that a triangle of a
///   *later* chunk may use: every id a later triangle uses is in it (it may hold a few more
///   that no later triangle ends up using — a producer may not know yet). An id missing from
///   it is finished: no later triangle touches it. The last chunk's `open` is empty.
///
/// Concatenating the chunks' vertices and triangles gives the whole mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshChunk {
    pub first_vertex: u32,
    pub vertices: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    pub borrowed: Vec<(u32, [f32; 3])>,
    pub open: Vec<u32>,
}

/// Vertex and triangle arrays of chunks whose consumers are done with them
/// ([`SpareArrays::recycle`]), for the next chunks of the same tiling
/// ([`crate::tile::stream_scaffold`]). A big tiling makes dozens to hundreds of chunks of
/// megabytes each; arrays made afresh for each one were handed back to the kernel when freed
/// and every page of them faulted in again. The caller owns the pool, so it lives as long as
/// its tiling and is shared by nothing else.
#[derive(Debug, Default)]
pub struct SpareArrays(Mutex<Vec<ChunkArrays>>);

/// How many pairs of arrays a [`SpareArrays`] keeps at most (chunks in flight between the
/// tiler and the last consumer; more are dropped).
const SPARE_SETS: usize = 4;

type ChunkArrays = (Vec<[f32; 3]>, Vec<[u32; 3]>);

impl SpareArrays {
    /// Empty vertex and triangle arrays for a new chunk: a recycled chunk's, with their
    /// capacity, or new ones.
    pub(crate) fn take(&self) -> ChunkArrays {
        self.0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .pop()
            .map(|(mut vertices, mut triangles)| {
                vertices.clear();
                triangles.clear();
                (vertices, triangles)
            })
            .unwrap_or_default()
    }

    /// Takes back `chunk`'s vertex and triangle arrays for the chunks made next, once
    /// nothing needs the chunk any more.
    pub fn recycle(&self, chunk: MeshChunk) {
        let mut spare = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        if spare.len() < SPARE_SETS {
            spare.push((chunk.vertices, chunk.triangles));
        }
    }
}

impl MeshChunk {
    /// The id one past this chunk's last vertex (the next chunk's `first_vertex`).
    pub fn end_vertex(&self) -> u32 {
        self.first_vertex + self.vertices.len() as u32
    }

    /// The position of vertex `id`, which is this chunk's own or one it borrows.
    pub fn position(&self, id: u32) -> Option<[f32; 3]> {
        if id >= self.first_vertex {
            return self
                .vertices
                .get((id - self.first_vertex) as usize)
                .copied();
        }
        self.borrowed
            .binary_search_by_key(&id, |&(i, _)| i)
            .ok()
            .map(|k| self.borrowed[k].1)
    }

    /// Cuts a whole mesh into chunks of about `triangles_per_chunk` triangles that satisfy the
    /// invariants above (for tests and for meshes that were made whole).
    pub fn split(mesh: &Mesh, triangles_per_chunk: usize) -> Vec<MeshChunk> {
        let per = triangles_per_chunk.max(1);
        let n = mesh.vertices.len();
        // A vertex belongs to the chunk of the first triangle that uses it, and is open until
        // the chunk of the last one; unreferenced vertices go with the chunk where their id
        // falls between referenced ones, so ids stay dense and increasing.
        let mut first_use = vec![usize::MAX; n];
        let mut last_use = vec![0usize; n];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for &v in tri {
                let v = v as usize;
                if v < n {
                    first_use[v] = first_use[v].min(t / per);
                    last_use[v] = last_use[v].max(t / per);
                }
            }
        }
        // Ids must grow with the chunk, and a chunk may only use ids of its own or earlier
        // chunks: vertex v goes to the earliest chunk that uses v or any later id.
        let chunks = mesh.triangles.len().div_ceil(per).max(1);
        let mut owner = vec![0usize; n];
        let mut suffix_min = chunks - 1;
        for v in (0..n).rev() {
            suffix_min = suffix_min.min(first_use[v]);
            owner[v] = suffix_min;
        }
        let mut out: Vec<MeshChunk> = (0..chunks).map(|_| MeshChunk::default()).collect();
        for v in 0..n {
            out[owner[v]].vertices.push(mesh.vertices[v]);
        }
        let mut next = 0u32;
        for chunk in &mut out {
            chunk.first_vertex = next;
            next = chunk.end_vertex();
        }
        for (t, tri) in mesh.triangles.iter().enumerate() {
            out[t / per].triangles.push(*tri);
        }
        for chunk in &mut out {
            let mut borrowed: Vec<u32> = chunk
                .triangles
                .iter()
                .flatten()
                .copied()
                .filter(|&v| v < chunk.first_vertex)
                .collect();
            borrowed.sort_unstable();
            borrowed.dedup();
            chunk.borrowed = borrowed
                .into_iter()
                .map(|v| (v, mesh.vertices[v as usize]))
                .collect();
        }
        for v in 0..n {
            if first_use[v] != usize::MAX {
                for chunk in &mut out[owner[v]..last_use[v]] {
                    chunk.open.push(v as u32);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of `n` quads, numbered so that later triangles reuse early vertices.
    fn strip(n: u32) -> Mesh {
        let mut mesh = Mesh::default();
        for i in 0..=n {
            mesh.vertices.push([i as f32, 0.0, 0.0]);
            mesh.vertices.push([i as f32, 1.0, 0.0]);
        }
        for i in 0..n {
            let (a, b, c, d) = (2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1);
            mesh.triangles.push([a, b, c]);
            mesh.triangles.push([a, c, d]);
        }
        // A triangle back to the start, so vertex 0 stays open to the end.
        mesh.triangles.push([0, 2 * n, 1]);
        mesh
    }

    #[test]
    fn split_chunks_keep_the_invariants_and_concatenate_to_the_mesh() {
        let mesh = strip(10);
        for per in [1, 3, 7, 100] {
            let chunks = MeshChunk::split(&mesh, per);
            let mut whole = Mesh::default();
            let mut next = 0;
            for (k, chunk) in chunks.iter().enumerate() {
                assert_eq!(chunk.first_vertex, next);
                next = chunk.end_vertex();
                for t in &chunk.triangles {
                    for &v in t {
                        assert!(v < chunk.end_vertex(), "a later id {v}");
                        assert_eq!(chunk.position(v), Some(mesh.vertices[v as usize]));
                    }
                }
                // Open: used by a later chunk's triangle, and nothing else.
                let later: std::collections::BTreeSet<u32> = chunks[k + 1..]
                    .iter()
                    .flat_map(|c| c.triangles.iter().flatten().copied())
                    .filter(|&v| v < chunk.end_vertex())
                    .collect();
                assert_eq!(chunk.open, later.into_iter().collect::<Vec<_>>());
                whole.vertices.extend(&chunk.vertices);
                whole.triangles.extend(&chunk.triangles);
            }
            assert_eq!(whole, mesh);
            assert!(chunks.last().is_some_and(|c| c.open.is_empty()));
            assert!(chunks.len() > 1 || per >= mesh.triangles.len());
        }
    }
}
