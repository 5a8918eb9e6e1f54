//! The connected pieces of a mesh and the volume and area of each, over a whole mesh or one
//! streamed a chunk at a time ([`PieceCounter`]): what tells a user that a "watertight,
//! manifold" result is in fact 5000 loose blobs.
//!
//! Invariants:
//! - Two valid triangles are in one piece when they share a vertex id, as in
//!   [`super::components`] (so two solids touching at one vertex are one piece; meshes read
//!   from formats that store positions must be welded first). Vertices no valid triangle uses
//!   make no piece.
//! - A piece's volume is the signed volume of its triangles (`p0 · (p1 × p2) / 6`, in `f64`
//!   from the `f32` positions), its area theirs (when asked for); both summed in triangle
//!   order.
//! - The pieces found are the same for any chunking of a mesh that keeps the [`MeshChunk`]
//!   invariants (tested against the whole mesh); a piece's sums may differ in the last bits,
//!   since they are added in chunk order.
//! - Memory: a label per open vertex and one chunk's union-find; a finished piece is two
//!   numbers. Nothing else grows with the finished part of the mesh.
//!
//! Method: a union-find per push over the open pieces carried from the previous push (one
//! node each: an open vertex is represented by its piece) and the chunk's own vertices. After
//! the triangles, the pieces that still hold an open vertex are carried, relabelled densely;
//! the others are finished. A triangle naming an id past the chunk's end, or an earlier id the
//! chunk does not lend a position for, is skipped, as `check` counts it invalid.

use std::collections::HashMap;

use super::find;
use crate::mesh::{Mesh, MeshChunk};
use crate::vec3::{cross, dot, norm, sub};

/// One piece's measures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Piece {
    pub volume: f64,
    pub area: f64,
}

/// The connected surfaces of a mesh, largest volume first (for equal volumes, largest area
/// first). In a closed, outward mesh a surface of negative volume bounds a cavity inside a
/// solid piece (a hollow ball is two surfaces, one solid), so the solid pieces are the
/// surfaces of positive volume; a planar region's pieces are all its surfaces.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Pieces {
    pub surfaces: Vec<Piece>,
}

impl Pieces {
    /// The measures of the pieces: the area of every surface of a planar region (`by_area`),
    /// else the volume of every surface of positive volume.
    fn measures(&self, by_area: bool) -> impl Iterator<Item = f64> + '_ {
        self.surfaces.iter().filter_map(move |p| match by_area {
            true => Some(p.area),
            false => (p.volume > 0.0).then_some(p.volume),
        })
    }

    /// The number of pieces (see [`Pieces`]).
    pub fn count(&self, by_area: bool) -> usize {
        self.measures(by_area).count()
    }

    /// The largest piece's share of all pieces' volume (area, `by_area`), each measured
    /// within its outer surface (a cavity is not subtracted: which piece holds it is not
    /// known here). 1 for one piece, 0 for none.
    pub fn largest_fraction(&self, by_area: bool) -> f64 {
        let total: f64 = self.measures(by_area).sum();
        match self.count(by_area) {
            0 => 0.0,
            1 => 1.0,
            _ => self.measures(by_area).fold(f64::MIN, f64::max) / total,
        }
    }
}

/// The pieces of a whole mesh, with their volumes and areas.
pub fn pieces(mesh: &Mesh) -> Pieces {
    let mut counter = PieceCounter::with_area();
    counter.push_view(ChunkView {
        first_vertex: 0,
        vertices: &mesh.vertices,
        triangles: &mesh.triangles,
        borrowed: &[],
        open: &[],
    });
    counter.finish()
}

/// Counts the pieces of a mesh pushed as [`MeshChunk`]s in order; see the module docs.
#[derive(Default)]
pub struct PieceCounter {
    /// Whether pieces' areas are summed (a planar region's pieces are measured by area); a
    /// square root per triangle, so solids go without.
    with_area: bool,
    /// Open vertex ids after the last push, sorted, with their piece's label.
    open: Vec<(u32, u32)>,
    /// Per label: the piece's measures so far, and whether it has a triangle yet.
    carried: Vec<(Piece, bool)>,
    finished: Vec<Piece>,
}

/// What a push reads of a chunk, so a whole mesh needs no copy.
struct ChunkView<'a> {
    first_vertex: u32,
    vertices: &'a [[f32; 3]],
    triangles: &'a [[u32; 3]],
    borrowed: &'a [(u32, [f32; 3])],
    open: &'a [u32],
}

impl PieceCounter {
    /// A counter of pieces by volume (`Piece::area` stays 0).
    pub fn new() -> PieceCounter {
        PieceCounter::default()
    }

    /// A counter that also sums each piece's area.
    pub fn with_area() -> PieceCounter {
        PieceCounter {
            with_area: true,
            ..PieceCounter::default()
        }
    }

    pub fn push(&mut self, chunk: &MeshChunk) {
        self.push_view(ChunkView {
            first_vertex: chunk.first_vertex,
            vertices: &chunk.vertices,
            triangles: &chunk.triangles,
            borrowed: &chunk.borrowed,
            open: &chunk.open,
        });
    }

    fn push_view(&mut self, chunk: ChunkView) {
        let carried = self.carried.len();
        let first = chunk.first_vertex;
        let own = chunk.vertices.len();
        // Nodes: the carried pieces, the chunk's own vertices, then earlier ids that were not
        // open (a chunk breaking the invariants), each numbered once. Each node holds what its
        // triangles (those it is the first corner of) add; the roots gather it at the end.
        let mut parent: Vec<u32> = (0..(carried + own) as u32).collect();
        let mut measures: Vec<(Piece, bool)> = self.carried.clone();
        measures.resize(carried + own, (Piece::default(), false));
        let mut extra: HashMap<u32, u32> = HashMap::new();
        // The borrowed ids' nodes, beside their positions.
        let borrowed: Vec<u32> = chunk
            .borrowed
            .iter()
            .map(
                |&(id, _)| match self.open.binary_search_by_key(&id, |&(v, _)| v) {
                    Ok(k) => self.open[k].1,
                    Err(_) => *extra.entry(id).or_insert_with(|| {
                        parent.push(parent.len() as u32);
                        measures.push((Piece::default(), false));
                        (parent.len() - 1) as u32
                    }),
                },
            )
            .collect();
        let resolve = |id: u32| -> Option<(u32, [f64; 3])> {
            if id >= first {
                let k = (id - first) as usize;
                let p = chunk.vertices.get(k)?;
                Some(((carried + k) as u32, p.map(f64::from)))
            } else {
                let k = chunk.borrowed.binary_search_by_key(&id, |&(i, _)| i).ok()?;
                Some((borrowed[k], chunk.borrowed[k].1.map(f64::from)))
            }
        };
        for t in chunk.triangles {
            let (Some((a, p0)), Some((b, p1)), Some((c, p2))) =
                (resolve(t[0]), resolve(t[1]), resolve(t[2]))
            else {
                continue;
            };
            // Linked by hand, the smaller root staying (as `union` does): each root found once.
            let mut root = find(&mut parent, a);
            for other in [b, c] {
                let other = find(&mut parent, other);
                if other != root {
                    let (keep, gone) = (root.min(other), root.max(other));
                    parent[gone as usize] = keep;
                    root = keep;
                }
            }
            let at = &mut measures[a as usize];
            at.0.volume += dot(p0, cross(p1, p2)) / 6.0;
            if self.with_area {
                at.0.area += 0.5 * norm(cross(sub(p1, p0), sub(p2, p0)));
            }
            at.1 = true;
        }
        // Every node's share to its root; roots are the smallest node of their set, so a
        // node's root comes before it and is already whole when later nodes add to it.
        for n in 0..parent.len() as u32 {
            let root = find(&mut parent, n);
            if root != n {
                let (piece, has_triangle) = measures[n as usize];
                let into = &mut measures[root as usize];
                into.0.volume += piece.volume;
                into.0.area += piece.area;
                into.1 |= has_triangle;
            }
        }
        // Pieces still open are carried under dense labels, in the order of their first open
        // vertex; every other root with a triangle is finished.
        let mut label_of_root: HashMap<u32, u32> = HashMap::new();
        let mut next_open = Vec::with_capacity(chunk.open.len());
        let mut next_carried = Vec::new();
        let mut open_ids: Vec<u32> = chunk.open.to_vec();
        open_ids.sort_unstable();
        open_ids.dedup();
        for id in open_ids {
            let n = if id >= first {
                let k = (id - first) as usize;
                if k >= own {
                    continue;
                }
                (carried + k) as u32
            } else {
                match self.open.binary_search_by_key(&id, |&(v, _)| v) {
                    Ok(k) => self.open[k].1,
                    Err(_) => match extra.get(&id) {
                        Some(&n) => n,
                        None => continue,
                    },
                }
            };
            let root = find(&mut parent, n);
            let label = *label_of_root.entry(root).or_insert_with(|| {
                next_carried.push(measures[root as usize]);
                (next_carried.len() - 1) as u32
            });
            next_open.push((id, label));
        }
        for n in 0..parent.len() as u32 {
            if find(&mut parent, n) == n && !label_of_root.contains_key(&n) {
                let (piece, has_triangle) = measures[n as usize];
                if has_triangle {
                    self.finished.push(piece);
                }
            }
        }
        self.open = next_open;
        self.carried = next_carried;
    }

    /// The pieces, once every chunk is pushed (pieces left open are finished here).
    pub fn finish(mut self) -> Pieces {
        self.finished.extend(
            self.carried
                .iter()
                .filter(|(_, has_triangle)| *has_triangle)
                .map(|&(piece, _)| piece),
        );
        let mut surfaces = self.finished;
        surfaces.sort_by(|a, b| {
            b.volume
                .total_cmp(&a.volume)
                .then(b.area.total_cmp(&a.area))
        });
        Pieces { surfaces }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An outward axis-aligned box with vertex ids from `base`.
    fn cube(min: [f32; 3], size: f32, base: u32) -> Mesh {
        crate::test_meshes::cube(min, size, base, false)
    }

    /// Cubes of sides 1, 2, 3, …, apart, as one mesh.
    fn cubes(n: usize) -> Mesh {
        let mut mesh = Mesh::default();
        for k in 0..n {
            let c = cube(
                [10.0 * k as f32, 0.0, 0.0],
                (k + 1) as f32,
                mesh.vertices.len() as u32,
            );
            mesh.vertices.extend(c.vertices);
            mesh.triangles.extend(c.triangles);
        }
        mesh
    }

    #[test]
    fn separate_cubes_are_pieces_with_their_volumes_largest_first() {
        let found = pieces(&cubes(4));
        assert_eq!(found.count(false), 4);
        let volumes: Vec<f64> = found.surfaces.iter().map(|p| p.volume).collect();
        for (v, expected) in volumes.iter().zip([64.0, 27.0, 8.0, 1.0]) {
            assert!((v - expected).abs() < 1e-12, "{volumes:?}");
        }
        assert!((found.surfaces[0].area - 6.0 * 16.0).abs() < 1e-12);
        assert!((found.largest_fraction(false) - 64.0 / 100.0).abs() < 1e-12);
        assert_eq!(pieces(&cubes(1)).largest_fraction(false), 1.0);
        assert_eq!(pieces(&Mesh::default()).largest_fraction(false), 0.0);
    }

    /// A cube with a cube-shaped cavity: two surfaces, one solid piece.
    #[test]
    fn a_cavity_is_not_a_piece() {
        let mut mesh = cube([0.0; 3], 4.0, 0);
        let mut hole = cube([1.0; 3], 1.0, 8);
        for t in hole.triangles.iter_mut() {
            t.swap(1, 2);
        }
        mesh.vertices.extend(hole.vertices);
        mesh.triangles.extend(hole.triangles);
        let found = pieces(&mesh);
        assert_eq!(found.surfaces.len(), 2);
        assert_eq!(
            (found.count(false), found.largest_fraction(false)),
            (1, 1.0)
        );
        // As a surface measure (a planar region's), both count.
        assert_eq!(found.count(true), 2);
    }

    #[test]
    fn a_shared_vertex_joins_pieces_and_unused_vertices_make_none() {
        let mut mesh = cubes(2);
        // The second cube's first corner becomes the first cube's last: one vertex shared.
        for t in mesh.triangles.iter_mut() {
            for v in t.iter_mut() {
                if *v == 8 {
                    *v = 7;
                }
            }
        }
        mesh.vertices.push([100.0; 3]);
        let found = pieces(&mesh);
        assert_eq!(found.count(false), 1);
        assert_eq!(found.surfaces.len(), super::super::components(&mesh));
    }

    #[test]
    fn any_chunking_finds_the_same_pieces() {
        // Pieces that span chunks: a chain of cubes sharing corners, and loose ones.
        let mut mesh = cubes(9);
        for k in 0..4u32 {
            let (from, to) = (8 * (2 * k) + 7, 8 * (2 * k + 1));
            for t in mesh.triangles.iter_mut() {
                for v in t.iter_mut() {
                    if *v == to {
                        *v = from;
                    }
                }
            }
        }
        let whole = pieces(&mesh);
        assert_eq!(whole.count(false), 5);
        for per_chunk in [1, 2, 5, 13, 100] {
            let mut counter = PieceCounter::with_area();
            for chunk in MeshChunk::split(&mesh, per_chunk) {
                counter.push(&chunk);
            }
            let streamed = counter.finish();
            assert_eq!(
                streamed.surfaces.len(),
                whole.surfaces.len(),
                "{per_chunk} per chunk"
            );
            for (a, b) in streamed.surfaces.iter().zip(&whole.surfaces) {
                assert!(
                    (a.volume - b.volume).abs() < 1e-9,
                    "{per_chunk}: {a:?} vs {b:?}"
                );
                assert!(
                    (a.area - b.area).abs() < 1e-9,
                    "{per_chunk}: {a:?} vs {b:?}"
                );
            }
        }
    }
}
