//! A closed, outward-oriented triangle mesh sampled onto a regular grid: which voxel centres
//! lie inside the solid.
//!
//! Invariants:
//! - [`Grid`]: cubic voxels of side `spacing`; voxel `(i, j, k)` is centred at
//!   `origin + (i, j, k)·spacing`; layout as in [`super::edt`]. [`Grid::covering`] puts
//!   `pad` voxels of margin round a box, so the solid never touches the grid's faces.
//! - A centre is inside when the winding number of the mesh about it is positive (for a
//!   closed outward mesh: inside the solid; nested shells and cavities count right).
//! - Robust to rays through vertices and edges: every column's ray is perturbed
//!   symbolically by `(ε, ε²)` in (x, y), and each edge's side test is evaluated with its
//!   ends in one canonical order, so the two triangles of a shared edge always agree and a
//!   ray meets a closed surface an even number of times. Triangles that project to a segment
//!   or a point (vertical ones) are never met by the perturbed ray.
//!
//! Method: each triangle is binned to the grid rows (y) its shadow covers; rows run in
//! parallel; per column the crossings `(z, ±1)` are sorted and swept upward with the centres.

use rayon::prelude::*;

use crate::mesh::Mesh;

/// A regular grid of cubic voxels (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub origin: [f64; 3],
    pub spacing: f64,
    pub dims: [usize; 3],
}

/// The most voxels a measuring grid may hold (feature indices are `u32`).
pub const MAX_VOXELS: usize = 1 << 31;

impl Grid {
    /// The grid of voxels of side `spacing` whose centres cover `[min, max]`, with `pad`
    /// voxels more on each side; `None` for a non-finite or empty box, a spacing that is not
    /// finite and positive, or more than [`MAX_VOXELS`] voxels.
    pub fn covering(min: [f64; 3], max: [f64; 3], spacing: f64, pad: usize) -> Option<Grid> {
        if !(spacing.is_finite() && spacing > 0.0) {
            return None;
        }
        let mut dims = [0usize; 3];
        let mut origin = [0.0; 3];
        for a in 0..3 {
            let extent = max[a] - min[a];
            if !(extent.is_finite() && extent >= 0.0 && min[a].is_finite()) {
                return None;
            }
            // A side of a whole number of spacings (up to rounding) gets that many voxels,
            // whose centres then sit half a spacing inside its faces, off the mesh's caps.
            let cells = (extent / spacing * (1.0 - 1e-9)).ceil().max(1.0);
            if cells > MAX_VOXELS as f64 {
                return None;
            }
            let cells = cells as usize;
            // Centred on the box: the inner voxels' centres span it symmetrically.
            let centre = 0.5 * (min[a] + max[a]);
            origin[a] = centre - (cells as f64 - 1.0) * 0.5 * spacing - pad as f64 * spacing;
            dims[a] = cells + 2 * pad;
        }
        let total = dims
            .iter()
            .try_fold(1usize, |acc, &d| acc.checked_mul(d))
            .filter(|&t| t <= MAX_VOXELS)?;
        (total > 0).then_some(Grid {
            origin,
            spacing,
            dims,
        })
    }

    pub fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The centre of voxel `index`.
    pub fn centre(&self, index: usize) -> [f64; 3] {
        let c = super::edt::coords(self.dims, index);
        std::array::from_fn(|a| self.origin[a] + c[a] as f64 * self.spacing)
    }
}

/// Which voxel centres of `grid` lie inside `mesh` (see the module docs). Triangles with
/// non-finite corners or out-of-range indices are skipped.
pub fn voxelise(mesh: &Mesh, grid: &Grid) -> Vec<bool> {
    let [nx, ny, nz] = grid.dims;
    let h = grid.spacing;
    let column = |v: f64, a: usize| (v - grid.origin[a]) / h;
    // Triangles by the rows their shadow covers.
    let mut rows: Vec<Vec<u32>> = vec![Vec::new(); ny];
    let mut corners: Vec<[[f64; 3]; 3]> = Vec::with_capacity(mesh.triangles.len());
    for t in &mesh.triangles {
        let Some(p) = triangle(mesh, t) else { continue };
        let lo = p.iter().map(|v| v[1]).fold(f64::INFINITY, f64::min);
        let hi = p.iter().map(|v| v[1]).fold(f64::NEG_INFINITY, f64::max);
        let (j0, j1) = (column(lo, 1).ceil(), column(hi, 1).floor());
        if j1 < 0.0 || j0 > (ny - 1) as f64 {
            continue;
        }
        let id = corners.len() as u32;
        corners.push(p);
        for row in rows
            .iter_mut()
            .take(j1.min((ny - 1) as f64) as usize + 1)
            .skip(j0.max(0.0) as usize)
        {
            row.push(id);
        }
    }
    // Per row: the inside flags of its columns, x-major (`x·nz + z`).
    let slabs: Vec<Vec<bool>> = rows
        .par_iter()
        .enumerate()
        .map(|(j, ids)| {
            let y = grid.origin[1] + j as f64 * h;
            let mut crossings: Vec<Vec<(f64, i32)>> = vec![Vec::new(); nx];
            for &id in ids {
                let p = &corners[id as usize];
                let lo = p.iter().map(|v| v[0]).fold(f64::INFINITY, f64::min);
                let hi = p.iter().map(|v| v[0]).fold(f64::NEG_INFINITY, f64::max);
                let (i0, i1) = (column(lo, 0).ceil(), column(hi, 0).floor());
                if i1 < 0.0 || i0 > (nx - 1) as f64 {
                    continue;
                }
                let first = i0.max(0.0) as usize;
                let last = i1.min((nx - 1) as f64) as usize;
                for (i, list) in crossings.iter_mut().enumerate().take(last + 1).skip(first) {
                    let x = grid.origin[0] + i as f64 * h;
                    if let Some(hit) = ray_hit(p, x, y) {
                        list.push(hit);
                    }
                }
            }
            let mut out = vec![false; nx * nz];
            for (i, list) in crossings.iter_mut().enumerate() {
                list.sort_by(|a, b| a.0.total_cmp(&b.0));
                let mut winding = 0;
                let mut next = 0;
                for k in 0..nz {
                    let z = grid.origin[2] + k as f64 * h;
                    while next < list.len() && list[next].0 < z {
                        winding += list[next].1;
                        next += 1;
                    }
                    out[i * nz + k] = winding > 0;
                }
            }
            out
        })
        .collect();
    let mut inside = vec![false; grid.len()];
    for (j, slab) in slabs.iter().enumerate() {
        for i in 0..nx {
            for k in 0..nz {
                inside[i + nx * (j + ny * k)] = slab[i * nz + k];
            }
        }
    }
    inside
}

/// A triangle's corners in `f64`, or `None` for bad indices or non-finite positions.
pub(crate) fn triangle(mesh: &Mesh, t: &[u32; 3]) -> Option<[[f64; 3]; 3]> {
    let mut p = [[0.0; 3]; 3];
    for (slot, &v) in p.iter_mut().zip(t) {
        let q = mesh.vertices.get(v as usize)?;
        if !q.iter().all(|c| c.is_finite()) {
            return None;
        }
        *slot = q.map(f64::from);
    }
    Some(p)
}

/// The sign (±1) of the side of the edge `a → b` that the perturbed point `(x + ε, y + ε²)`
/// lies on: positive to the left. Evaluated with the ends in lexicographic order, so the
/// edge `b → a` of the neighbouring triangle gets exactly the opposite sign. 0 only for an
/// edge whose ends project to one point.
fn side(a: [f64; 3], b: [f64; 3], x: f64, y: f64) -> i32 {
    let forward = (a[0], a[1]) <= (b[0], b[1]);
    let (u, v) = if forward { (a, b) } else { (b, a) };
    let e = (v[0] - u[0]) * (y - u[1]) - (v[1] - u[1]) * (x - u[0]);
    let s = if e != 0.0 {
        e.signum() as i32
    } else if v[1] != u[1] {
        // d/dε of the perturbed test: −(v_y − u_y).
        -((v[1] - u[1]).signum() as i32)
    } else {
        (v[0] - u[0]).signum() as i32
    };
    if forward { s } else { -s }
}

/// Where the upward ray from `(x, y)` (perturbed) crosses triangle `p`: its height and the
/// change of winding number (+1 entering the solid through a face seen from below, −1
/// leaving through one seen from above).
fn ray_hit(p: &[[f64; 3]; 3], x: f64, y: f64) -> Option<(f64, i32)> {
    let s = [
        side(p[1], p[2], x, y),
        side(p[2], p[0], x, y),
        side(p[0], p[1], x, y),
    ];
    if s[0] == 0 || s[0] != s[1] || s[1] != s[2] {
        return None;
    }
    // Barycentric weights from the unperturbed areas (clamped: the point may sit on an edge).
    let area =
        |a: [f64; 3], b: [f64; 3]| ((b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0])).abs();
    let w = [area(p[1], p[2]), area(p[2], p[0]), area(p[0], p[1])];
    let total = w[0] + w[1] + w[2];
    let z = if total > 0.0 {
        (w[0] * p[0][2] + w[1] * p[1][2] + w[2] * p[2][2]) / total
    } else {
        (p[0][2] + p[1][2] + p[2][2]) / 3.0
    };
    // Counter-clockwise from above (all left): the normal points up, so the ray leaves.
    Some((z, -s[0]))
}
