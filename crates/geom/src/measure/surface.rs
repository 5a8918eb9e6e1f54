//! The mesh near a voxel: the sub-voxel half of the measure.
//!
//! Invariants:
//! - Triangles are binned by their bounding boxes into cubes of one voxel whose corners are
//!   voxel centres, so the ball of radius below one voxel round a centre meets exactly the
//!   eight bins round it; a triangle with non-finite corners, or of no area, is left out.
//! - [`Surface::patch`] is exact within its reach (at most one voxel): the nearest point of
//!   the mesh, and its triangle's unit normal (outward for an outward mesh).
//!
//! Method: closest point on a triangle by its Voronoi regions (vertex, edge, face), in `f64`.

use std::sync::atomic::{AtomicU32, Ordering};

use rayon::prelude::*;

use super::voxel::{Grid, triangle};
use crate::mesh::Mesh;
use crate::vec3::{cross, dot, norm, sub};

/// Where the mesh passes a voxel: its nearest point and that triangle's unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Patch {
    pub point: [f64; 3],
    pub normal: [f64; 3],
}

impl Patch {
    /// The signed distance of `p` from the patch's tangent plane (positive outside).
    pub fn height(&self, p: [f64; 3]) -> f64 {
        dot(sub(p, self.point), self.normal)
    }
}

/// A mesh's triangles binned over a grid (by index: the corners are read from the mesh when
/// a query needs them, so binning a mesh of tens of millions of triangles copies nothing).
pub struct Surface<'a> {
    mesh: &'a Mesh,
    origin: [f64; 3],
    side: f64,
    dims: [usize; 3],
    /// CSR: bin `b`'s triangles are `members[start[b]..start[b + 1]]`, in no set order (a
    /// query breaks ties by triangle index, so its answer does not depend on it).
    start: Vec<u32>,
    members: Vec<u32>,
}

impl<'a> Surface<'a> {
    pub fn new(mesh: &'a Mesh, grid: &Grid) -> Surface<'a> {
        let mut surface = Surface {
            mesh,
            origin: grid.origin,
            side: grid.spacing,
            dims: grid.dims.map(|d| d.max(1)),
            start: Vec::new(),
            members: Vec::new(),
        };
        let bins = surface.dims.iter().product::<usize>();
        // Counted and filled in parallel: atomic counters, then atomic cursors.
        let count: Vec<AtomicU32> = (0..bins).map(|_| AtomicU32::new(0)).collect();
        mesh.triangles.par_iter().for_each(|t| {
            if let Some(p) = surface.corners(t) {
                surface.for_bins(&p, |b| {
                    count[b].fetch_add(1, Ordering::Relaxed);
                });
            }
        });
        let mut start = vec![0u32; bins + 1];
        for b in 0..bins {
            start[b + 1] = start[b] + count[b].load(Ordering::Relaxed);
        }
        drop(count);
        let cursor: Vec<AtomicU32> = start[..bins].iter().map(|&s| AtomicU32::new(s)).collect();
        let members: Vec<AtomicU32> = (0..start[bins]).map(|_| AtomicU32::new(0)).collect();
        mesh.triangles.par_iter().enumerate().for_each(|(id, t)| {
            if let Some(p) = surface.corners(t) {
                surface.for_bins(&p, |b| {
                    let slot = cursor[b].fetch_add(1, Ordering::Relaxed);
                    members[slot as usize].store(id as u32, Ordering::Relaxed);
                });
            }
        });
        surface.start = start;
        surface.members = members.into_iter().map(AtomicU32::into_inner).collect();
        surface
    }

    /// A triangle's corners, or `None` for one with a bad index, a non-finite corner or no
    /// area (whose normal is undefined).
    fn corners(&self, t: &[u32; 3]) -> Option<[[f64; 3]; 3]> {
        let p = triangle(self.mesh, t)?;
        (plane(&p).0 != [0.0; 3]).then_some(p)
    }

    fn bin_of(&self, q: [f64; 3]) -> [usize; 3] {
        std::array::from_fn(|a| {
            let c = ((q[a] - self.origin[a]) / self.side).floor();
            c.clamp(0.0, (self.dims[a] - 1) as f64) as usize
        })
    }

    fn for_bins(&self, p: &[[f64; 3]; 3], mut visit: impl FnMut(usize)) {
        let lo = self.bin_of(std::array::from_fn(|a| p[0][a].min(p[1][a]).min(p[2][a])));
        let hi = self.bin_of(std::array::from_fn(|a| p[0][a].max(p[1][a]).max(p[2][a])));
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    visit(x + self.dims[0] * (y + self.dims[1] * z));
                }
            }
        }
    }

    /// The nearest point of the mesh to `p` within `reach` (capped just below one voxel)
    /// and its triangle's normal; `None` when no triangle comes that near.
    pub fn patch(&self, p: [f64; 3], reach: f64) -> Option<Patch> {
        let reach = reach.min(self.side * (1.0 - 1e-9));
        let lo = self.bin_of(p.map(|c| c - reach));
        let hi = self.bin_of(p.map(|c| c + reach));
        let mut best: Option<(f64, [f64; 3], u32, [f64; 3])> = None;
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let b = x + self.dims[0] * (y + self.dims[1] * z);
                    for &id in &self.members[self.start[b] as usize..self.start[b + 1] as usize] {
                        let Some(corners) = triangle(self.mesh, &self.mesh.triangles[id as usize])
                        else {
                            continue;
                        };
                        let bound = best.map_or(reach, |(d, ..)| d);
                        let (n, off) = plane(&corners);
                        if (dot(n, p) - off).abs() > bound {
                            continue;
                        }
                        let q = closest_on_triangle(p, &corners);
                        let d = distance(p, q);
                        // Ties go to the lower index: the bins' order is the threads'.
                        let better =
                            best.is_none_or(|(bd, _, bid, _)| d < bd || (d == bd && id < bid));
                        if d <= bound && better {
                            best = Some((d, q, id, n));
                        }
                    }
                }
            }
        }
        best.map(|(_, point, _, normal)| Patch { point, normal })
    }
}

/// A triangle's unit normal and offset; a zero normal (and offset) for a degenerate one,
/// which the plane test then never rejects.
fn plane(t: &[[f64; 3]; 3]) -> ([f64; 3], f64) {
    let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    let l = norm(n);
    if l > 0.0 && l.is_finite() {
        let n = n.map(|c| c / l);
        (n, dot(n, t[0]))
    } else {
        ([0.0; 3], 0.0)
    }
}

pub(crate) fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    norm(sub(a, b))
}

fn along(a: [f64; 3], d: [f64; 3], t: f64) -> [f64; 3] {
    [a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2]]
}

/// The point of triangle `t` nearest `p`, by the Voronoi region `p` projects into.
pub fn closest_on_triangle(p: [f64; 3], t: &[[f64; 3]; 3]) -> [f64; 3] {
    let [a, b, c] = *t;
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return along(a, ab, d1 / (d1 - d3));
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return along(a, ac, d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return along(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if denom == 0.0 || !denom.is_finite() {
        // A degenerate triangle that fell through: its nearest corner.
        return *[a, b, c]
            .iter()
            .min_by(|x, y| distance(p, **x).total_cmp(&distance(p, **y)))
            .unwrap_or(&a);
    }
    let (v, w) = (vb / denom, vc / denom);
    [
        a[0] + ab[0] * v + ac[0] * w,
        a[1] + ab[1] * v + ac[1] * w,
        a[2] + ab[2] * v + ac[2] * w,
    ]
}
