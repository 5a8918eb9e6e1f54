//! Exact distance from a point to a mesh near a hint: the sub-voxel half of the measure.
//!
//! Invariants:
//! - [`Surface::nearest`] is exact: the nearest point of the mesh's (finite) triangles,
//!   given an upper bound on its distance (a known point of the mesh, or a point across the
//!   surface); every bin the ball of that radius meets is searched unless its box lies
//!   farther than the best distance found.
//! - Triangles are binned by their bounding boxes into cubes of [`BIN_VOXELS`] voxels, and
//!   the bins grouped in blocks of `8³` with an occupancy flag, so the empty space round a
//!   deep point costs one look per block; a triangle with non-finite corners is left out.
//!
//! Method: closest point on a triangle by its Voronoi regions (vertex, edge, face), in `f64`.

use super::voxel::{Grid, triangle};
use crate::mesh::Mesh;
use crate::vec3::{dot, norm, sub};

/// The side of a bin, in voxels.
pub const BIN_VOXELS: f64 = 1.0;

/// A mesh's triangles binned over a grid.
pub struct Surface {
    corners: Vec<[[f64; 3]; 3]>,
    /// Per triangle, its unit normal and `n·a`: a point farther from the plane than the best
    /// distance so far needs no closest-point test.
    planes: Vec<([f64; 3], f64)>,
    origin: [f64; 3],
    side: f64,
    dims: [usize; 3],
    /// CSR: bin `b`'s triangles are `members[start[b]..start[b + 1]]`.
    start: Vec<u32>,
    members: Vec<u32>,
    /// Blocks of `BLOCK³` bins, and whether each holds a triangle: what lets a search skip
    /// the empty space round a deep point.
    blocks: [usize; 3],
    occupied: Vec<bool>,
}

/// Bins per block side.
const BLOCK: usize = 8;

impl Surface {
    pub fn new(mesh: &Mesh, grid: &Grid) -> Surface {
        let side = grid.spacing * BIN_VOXELS;
        let origin = grid.origin.map(|o| o - 0.5 * grid.spacing);
        let dims = grid
            .dims
            .map(|d| ((d as f64 / BIN_VOXELS).ceil() as usize).max(1));
        let corners: Vec<[[f64; 3]; 3]> = mesh
            .triangles
            .iter()
            .filter_map(|t| triangle(mesh, t))
            .collect();
        let planes = corners.iter().map(plane).collect();
        let mut surface = Surface {
            corners,
            planes,
            origin,
            side,
            dims,
            start: Vec::new(),
            members: Vec::new(),
            blocks: dims.map(|d| d.div_ceil(BLOCK)),
            occupied: Vec::new(),
        };
        let bins = dims[0] * dims[1] * dims[2];
        let mut count = vec![0u32; bins + 1];
        for p in &surface.corners {
            surface.for_bins(p, |b| count[b] += 1);
        }
        let mut start = vec![0u32; bins + 1];
        for b in 0..bins {
            start[b + 1] = start[b] + count[b];
        }
        let mut fill = start.clone();
        let mut members = vec![0u32; start[bins] as usize];
        for (id, p) in surface.corners.iter().enumerate() {
            surface.for_bins(p, |b| {
                members[fill[b] as usize] = id as u32;
                fill[b] += 1;
            });
        }
        let blocks = surface.blocks;
        let mut occupied = vec![false; blocks[0] * blocks[1] * blocks[2]];
        for (b, &n) in count.iter().enumerate().take(bins) {
            if n > 0 {
                let c = super::edt::coords(dims, b);
                occupied[c[0] / BLOCK + blocks[0] * (c[1] / BLOCK + blocks[1] * (c[2] / BLOCK))] =
                    true;
            }
        }
        surface.start = start;
        surface.members = members;
        surface.occupied = occupied;
        surface
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

    /// The nearest point of the mesh to `p` and its distance, given that some point of the
    /// mesh lies within `upper` of `p` (the search is confined to that ball); `None` when no
    /// triangle lies within `upper`.
    ///
    /// `hint`, a point near where the nearest point is expected, only speeds the search: the
    /// triangles round it are tried first, so the rest is pruned to a thin cap.
    pub fn nearest(
        &self,
        p: [f64; 3],
        upper: f64,
        hint: Option<[f64; 3]>,
    ) -> Option<(f64, [f64; 3])> {
        if !(upper.is_finite() && upper >= 0.0) {
            return None;
        }
        let mut best: Option<(f64, [f64; 3])> = None;
        if let Some(h) = hint {
            let c = self.bin_of(h);
            for z in c[2].saturating_sub(1)..(c[2] + 2).min(self.dims[2]) {
                for y in c[1].saturating_sub(1)..(c[1] + 2).min(self.dims[1]) {
                    for x in c[0].saturating_sub(1)..(c[0] + 2).min(self.dims[0]) {
                        let b = x + self.dims[0] * (y + self.dims[1] * z);
                        for &id in &self.members[self.start[b] as usize..self.start[b + 1] as usize]
                        {
                            let q = closest_on_triangle(p, &self.corners[id as usize]);
                            let d = distance(p, q);
                            if d <= upper && best.is_none_or(|(bd, _)| d < bd) {
                                best = Some((d, q));
                            }
                        }
                    }
                }
            }
        }
        let bound = |best: &Option<(f64, [f64; 3])>| best.map_or(upper, |(d, _)| d.min(upper));
        // Coarse blocks nearest first, pruned by their box distance.
        let block = self.side * BLOCK as f64;
        let range = |a: usize, r: f64| -> (usize, usize) {
            let lo = ((p[a] - r - self.origin[a]) / block).floor().max(0.0) as usize;
            let hi = ((p[a] + r - self.origin[a]) / block).floor();
            let hi = hi.clamp(0.0, (self.blocks[a] - 1) as f64) as usize;
            (lo, hi)
        };
        let (rx, ry, rz) = (range(0, upper), range(1, upper), range(2, upper));
        let mut near: Vec<(f64, [usize; 3])> = Vec::new();
        for z in rz.0..=rz.1 {
            for y in ry.0..=ry.1 {
                for x in rx.0..=rx.1 {
                    let b = x + self.blocks[0] * (y + self.blocks[1] * z);
                    if !self.occupied[b] {
                        continue;
                    }
                    let d = self.box_distance(p, [x, y, z], block);
                    if d <= upper {
                        near.push((d, [x, y, z]));
                    }
                }
            }
        }
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (d, c) in near {
            if d > bound(&best) {
                break;
            }
            // Only the block's bins within the cube of the best distance so far.
            let r = bound(&best);
            let span = |a: usize| {
                let lo = ((p[a] - r - self.origin[a]) / self.side).floor().max(0.0) as usize;
                let hi = ((p[a] + r - self.origin[a]) / self.side).floor().max(0.0) as usize;
                (
                    lo.max(c[a] * BLOCK),
                    (hi + 1).min((c[a] + 1) * BLOCK).min(self.dims[a]),
                )
            };
            let (sx, sy, sz) = (span(0), span(1), span(2));
            for z in sz.0..sz.1 {
                for y in sy.0..sy.1 {
                    for x in sx.0..sx.1 {
                        let b = x + self.dims[0] * (y + self.dims[1] * z);
                        let ids = &self.members[self.start[b] as usize..self.start[b + 1] as usize];
                        if ids.is_empty()
                            || self.box_distance(p, [x, y, z], self.side) > bound(&best)
                        {
                            continue;
                        }
                        for &id in ids {
                            let (n, off) = self.planes[id as usize];
                            if (dot(n, p) - off).abs() >= bound(&best) {
                                continue;
                            }
                            let q = closest_on_triangle(p, &self.corners[id as usize]);
                            let d = distance(p, q);
                            if best.is_none_or(|(bd, _)| d < bd) {
                                best = Some((d, q));
                            }
                        }
                    }
                }
            }
        }
        best
    }

    /// The distance from `p` to the box of cell `c` of side `side`.
    fn box_distance(&self, p: [f64; 3], c: [usize; 3], side: f64) -> f64 {
        (0..3)
            .map(|a| {
                let lo = self.origin[a] + c[a] as f64 * side;
                let gap = (lo - p[a]).max(p[a] - (lo + side)).max(0.0);
                gap * gap
            })
            .sum::<f64>()
            .sqrt()
    }
}

impl Surface {
    /// The least `t > min_t` at which the ray `origin + t·dir` meets a triangle in the bins
    /// around `near`; `None` when none there does.
    pub fn hit_near(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        near: [f64; 3],
        min_t: f64,
    ) -> Option<f64> {
        let centre = self.bin_of(near);
        let mut best: Option<f64> = None;
        for z in centre[2].saturating_sub(1)..(centre[2] + 2).min(self.dims[2]) {
            for y in centre[1].saturating_sub(1)..(centre[1] + 2).min(self.dims[1]) {
                for x in centre[0].saturating_sub(1)..(centre[0] + 2).min(self.dims[0]) {
                    let b = x + self.dims[0] * (y + self.dims[1] * z);
                    for &id in &self.members[self.start[b] as usize..self.start[b + 1] as usize] {
                        if let Some(t) = ray_triangle(origin, dir, &self.corners[id as usize])
                            && t > min_t
                            && best.is_none_or(|b| t < b)
                        {
                            best = Some(t);
                        }
                    }
                }
            }
        }
        best
    }
}

/// Where the line `o + t·d` crosses triangle `p` (either side), by barycentric solve
/// (Möller and Trumbore's formulation); `None` when it misses or runs parallel.
fn ray_triangle(o: [f64; 3], d: [f64; 3], p: &[[f64; 3]; 3]) -> Option<f64> {
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let (e1, e2) = (sub(p[1], p[0]), sub(p[2], p[0]));
    let h = cross(d, e2);
    let det = dot(e1, h);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let s = sub(o, p[0]);
    let u = dot(s, h) / det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = cross(s, e1);
    let v = dot(d, q) / det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(dot(e2, q) / det)
}

/// A triangle's unit normal and offset; a zero normal (and offset) for a degenerate one,
/// which the plane test then never rejects.
fn plane(t: &[[f64; 3]; 3]) -> ([f64; 3], f64) {
    let (e1, e2) = (sub(t[1], t[0]), sub(t[2], t[0]));
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let l = dot(n, n).sqrt();
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
