//! From a soup to the triangles the queries use: welding, clean-up, orientation, closedness.
//!
//! Steps (the last three only with `repair`):
//! 1. Weld: positions with bit-identical coordinates (`-0.0` = `0.0`) become one vertex, so STL
//!    soups, which repeat every position per facet, get their shared edges back.
//! 2. Drop triangles that use one welded vertex twice: they bound nothing.
//! 3. Drop repeated triangles: the same three vertices in the same cyclic order. A repeat would
//!    count its solid angle twice; the same triangle in the *opposite* order is kept, since a
//!    face and its reverse cancel, which is right for two solids glued along a face.
//! 4. Orient: across every manifold edge (exactly two triangles), neighbours are made to agree
//!    (one traverses the edge forward, the other backward). Each edge-connected component then
//!    keeps the orientation of the larger part of its area as given, so a few flipped faces are
//!    turned back while a cavity, whose faces deliberately point inward, stays a cavity. Last,
//!    if the whole surface encloses negative volume it is turned inside out: a solid has
//!    positive volume, so a file whose every face points inward means the solid it bounds.
//!
//! Finally the surface is *closed* when every edge is traversed as often forward as backward.
//! Then the winding number is an integer off the surface and constant wherever the surface is
//! not crossed, which the samplers exploit (`sampler.rs`). Closedness is computed on the final
//! orientation, repaired or not.
//!
//! Invariant: the output depends only on the soup (sorts are total orders with the index as a
//! tie-break), not on thread count.

use crate::mesh_read::TriangleSoup;
use crate::vec3::{V3, add, cross, dot, max, min, norm, scale, sub};
use rayon::prelude::*;

pub(super) type Tri = [V3; 3];

/// What preparation did to a soup.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SurfaceReport {
    /// Triangles in the soup.
    pub triangles_in: usize,
    /// Triangles the queries use.
    pub triangles: usize,
    /// Distinct positions after welding.
    pub vertices: usize,
    /// Dropped because two corners are one welded vertex.
    pub degenerate: usize,
    /// Dropped as repeats of another triangle in the same orientation.
    pub duplicates: usize,
    /// Kept triangles whose winding was reversed.
    pub flipped: usize,
    /// Edge-connected components (connected through manifold edges).
    pub components: usize,
    /// Every edge is traversed as often in each direction: the winding number is an integer
    /// off the surface.
    pub closed: bool,
}

pub(super) struct Surface {
    pub triangles: Vec<Tri>,
    pub report: SurfaceReport,
}

/// Indices must be in range (checked by the caller).
pub(super) fn prepare(soup: &TriangleSoup, repair: bool) -> Surface {
    let canon = weld(&soup.positions);
    let welded: Vec<[u32; 3]> = soup
        .triangles
        .par_iter()
        .map(|t| t.map(|i| canon[i as usize]))
        .collect();
    let mut report = SurfaceReport {
        triangles_in: soup.triangles.len(),
        vertices: canon
            .iter()
            .enumerate()
            .filter(|&(i, &c)| i == c as usize)
            .count(),
        ..SurfaceReport::default()
    };

    let mut faces = welded;
    if repair {
        let before = faces.len();
        faces.retain(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0]);
        report.degenerate = before - faces.len();
        let before = faces.len();
        faces = without_repeats(faces);
        report.duplicates = before - faces.len();
    }

    let edges = sorted_edges(&faces);
    let mut flip = vec![false; faces.len()];
    if repair {
        let areas: Vec<f64> = faces
            .par_iter()
            .map(|t| norm(triangle_cross(&soup.positions, t)))
            .collect();
        report.components = orient(&faces, &edges, &areas, &mut flip);
        if signed_volume(&soup.positions, &faces, &flip) < 0.0 {
            flip.iter_mut().for_each(|f| *f = !*f);
        }
        report.flipped = flip.iter().filter(|&&f| f).count();
    }
    report.closed = balanced(&edges, &flip);
    report.triangles = faces.len();

    let triangles = faces
        .par_iter()
        .zip(&flip)
        .map(|(t, &f)| {
            let [a, b, c] = t.map(|i| soup.positions[i as usize]);
            if f { [a, c, b] } else { [a, b, c] }
        })
        .collect();
    Surface { triangles, report }
}

/// For each position, the smallest index of a position with the same coordinates.
fn weld(positions: &[V3]) -> Vec<u32> {
    // Keys computed once: sorting compares them many times.
    let mut keyed: Vec<([u64; 3], u32)> = positions
        .par_iter()
        .enumerate()
        .map(|(i, p)| (p.map(|c| (c + 0.0).to_bits()), i as u32))
        .collect();
    keyed.par_sort_unstable();
    let mut canon = vec![0u32; positions.len()];
    for run in keyed.chunk_by(|a, b| a.0 == b.0) {
        // Sorted by index within a run: the first is the smallest.
        let rep = run[0].1;
        for &(_, i) in run {
            canon[i as usize] = rep;
        }
    }
    canon
}

/// `faces` without later repeats of a triangle (same vertices, same cyclic order), in order.
fn without_repeats(faces: Vec<[u32; 3]>) -> Vec<[u32; 3]> {
    // The triangle rotated to start at its smallest index, and its position, in one `u128`.
    let key = |(i, t): (usize, &[u32; 3])| {
        let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
        let r = [t[k], t[(k + 1) % 3], t[(k + 2) % 3]].map(u128::from);
        (r[0] << 96) | (r[1] << 64) | (r[2] << 32) | i as u128
    };
    let mut keys: Vec<u128> = faces.par_iter().enumerate().map(key).collect();
    keys.par_sort_unstable();
    let mut keep = vec![true; faces.len()];
    for w in keys.windows(2) {
        if w[0] >> 32 == w[1] >> 32 {
            keep[(w[1] & 0xffff_ffff) as usize] = false;
        }
    }
    faces
        .into_iter()
        .zip(keep)
        .filter_map(|(t, k)| k.then_some(t))
        .collect()
}

/// One entry per triangle side: the undirected edge (low vertex, high vertex) packed in a
/// `u64`, and `3 * face + side` with the direction in bit 63 (set when the side runs from the
/// high vertex to the low one). Sorted by edge only, so the sides of one edge are adjacent in
/// an order that may vary; everything computed from a run of sides is independent of it.
fn sorted_edges(faces: &[[u32; 3]]) -> Vec<(u64, u64)> {
    let mut edges: Vec<(u64, u64)> = faces
        .par_iter()
        .enumerate()
        .flat_map_iter(|(f, t)| {
            (0..3).map(move |k| {
                let (u, v) = (t[k], t[(k + 1) % 3]);
                let key = (u64::from(u.min(v)) << 32) | u64::from(u.max(v));
                let backward = u64::from(u > v) << 63;
                (key, backward | (3 * f + k) as u64)
            })
        })
        .collect();
    edges.par_sort_unstable_by_key(|e| e.0);
    edges
}

fn side_face(side: u64) -> usize {
    ((side & !(1 << 63)) / 3) as usize
}

fn side_backward(side: u64) -> bool {
    side >> 63 == 1
}

/// Runs of sides sharing one edge.
fn edge_runs(edges: &[(u64, u64)]) -> impl Iterator<Item = &[(u64, u64)]> {
    edges.chunk_by(|a, b| a.0 == b.0)
}

/// Makes neighbours across manifold edges agree and each component keep its majority
/// orientation (by area). Returns the number of components.
fn orient(faces: &[[u32; 3]], edges: &[(u64, u64)], areas: &[f64], flip: &mut [bool]) -> usize {
    const NONE: u32 = u32::MAX;
    // Per face and side: the neighbour across a manifold edge, and whether the two traverse it
    // in the same direction (then one of them must be reversed).
    let mut neighbours = vec![[(NONE, false); 3]; faces.len()];
    for run in edge_runs(edges) {
        if let [(_, s), (_, t)] = run {
            let (fs, ft) = (side_face(*s), side_face(*t));
            if fs == ft {
                continue;
            }
            let same = side_backward(*s) == side_backward(*t);
            neighbours[fs][(*s & !(1 << 63)) as usize % 3] = (ft as u32, same);
            neighbours[ft][(*t & !(1 << 63)) as usize % 3] = (fs as u32, same);
        }
    }
    let mut seen = vec![false; faces.len()];
    let mut queue: Vec<u32> = Vec::new();
    let mut components = 0;
    for start in 0..faces.len() {
        if seen[start] {
            continue;
        }
        components += 1;
        queue.clear();
        queue.push(start as u32);
        seen[start] = true;
        let mut head = 0;
        while let Some(&f) = queue.get(head) {
            head += 1;
            for (g, same) in neighbours[f as usize] {
                if g != NONE && !seen[g as usize] {
                    seen[g as usize] = true;
                    flip[g as usize] = flip[f as usize] ^ same;
                    queue.push(g);
                }
            }
        }
        let flipped_area: f64 = queue
            .iter()
            .filter(|&&f| flip[f as usize])
            .map(|&f| areas[f as usize])
            .sum();
        let total: f64 = queue.iter().map(|&f| areas[f as usize]).sum();
        if flipped_area > 0.5 * total {
            for &f in &queue {
                flip[f as usize] = !flip[f as usize];
            }
        }
    }
    components
}

fn triangle_cross(positions: &[V3], t: &[u32; 3]) -> V3 {
    let [a, b, c] = t.map(|i| positions[i as usize]);
    cross(sub(b, a), sub(c, a))
}

/// Six times the volume enclosed, measured from the centre of the bounding box so that open
/// surfaces, whose "volume" depends on the origin, are judged from somewhere sensible.
fn signed_volume(positions: &[V3], faces: &[[u32; 3]], flip: &[bool]) -> f64 {
    let (lo, hi) = faces
        .par_iter()
        .flatten()
        .map(|&i| (positions[i as usize], positions[i as usize]))
        .reduce(
            || ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
            |a, b| (min(a.0, b.0), max(a.1, b.1)),
        );
    let o = scale(add(lo, hi), 0.5);
    // Fixed blocks, their sums added in order: the sign (and so the orientation chosen for a
    // nearly flat soup) is the same for every thread count.
    const BLOCK: usize = 1 << 14;
    let sums: Vec<f64> = faces
        .par_chunks(BLOCK)
        .zip(flip.par_chunks(BLOCK))
        .map(|(faces, flip)| {
            faces
                .iter()
                .zip(flip)
                .map(|(t, &f)| {
                    let [a, b, c] = t.map(|i| sub(positions[i as usize], o));
                    let v = dot(a, cross(b, c));
                    if f { -v } else { v }
                })
                .sum::<f64>()
        })
        .collect();
    sums.iter().sum()
}

/// Every edge traversed equally often in both directions (after `flip`).
fn balanced(edges: &[(u64, u64)], flip: &[bool]) -> bool {
    edges.par_chunk_by(|a, b| a.0 == b.0).all(|run| {
        let backward = run
            .iter()
            .filter(|(_, s)| side_backward(*s) ^ flip[side_face(*s)])
            .count();
        2 * backward == run.len()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The volume that decides a soup's orientation is summed by fixed blocks in order: the
    /// same bits on any pool (with rayon's `sum`, 1 and 3 threads disagreed in the last bits,
    /// which for a nearly flat soup is its sign).
    #[test]
    fn signed_volume_is_bitwise_equal_on_any_thread_count() {
        // A closed fan of 2·60 000 triangles over a wavy rim (apexes above and below): large
        // enough for several blocks, with terms of both signs.
        let n = 60_000u32;
        let mut positions: Vec<V3> = (0..n)
            .map(|i| {
                let t = std::f64::consts::TAU * f64::from(i) / f64::from(n);
                [t.cos(), t.sin(), 0.1 * (7.0 * t).sin()]
            })
            .collect();
        positions.push([0.0, 0.0, 1.0]);
        positions.push([0.0, 0.0, -1.0]);
        let faces: Vec<[u32; 3]> = (0..n)
            .flat_map(|i| [[i, (i + 1) % n, n], [(i + 1) % n, i, n + 1]])
            .collect();
        let flip: Vec<bool> = (0..faces.len()).map(|i| i % 7 == 0).collect();
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            pool.install(|| signed_volume(&positions, &faces, &flip))
                .to_bits()
        };
        let one = on(1);
        for threads in [2, 3, 5] {
            assert_eq!(on(threads), one, "{threads} threads");
        }
        // The sequential sum of the same terms, block by block, gives the same bits.
        let (lo, hi) = positions.iter().fold(
            ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
            |(lo, hi), &p| (min(lo, p), max(hi, p)),
        );
        let o = scale(add(lo, hi), 0.5);
        let term = |(t, &f): (&[u32; 3], &bool)| {
            let [a, b, c] = t.map(|i| sub(positions[i as usize], o));
            let v = dot(a, cross(b, c));
            if f { -v } else { v }
        };
        let blocks: Vec<f64> = faces
            .chunks(1 << 14)
            .zip(flip.chunks(1 << 14))
            .map(|(t, f)| t.iter().zip(f).map(term).sum())
            .collect();
        assert_eq!(blocks.iter().sum::<f64>().to_bits(), one);
    }
}
