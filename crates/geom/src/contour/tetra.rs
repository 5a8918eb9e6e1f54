//! Marching tetrahedra: the other contouring of a sampled solid, with the solid capped on the
//! domain box like marching cubes ([`super::contour`]).
//!
//! Each cube of the grid is cut into six tetrahedra around its diagonal from corner 0 to
//! corner 7 (the Kuhn triangulation: one tetrahedron per order of the axes, each a monotone
//! path 0 → e_a → e_a + e_b → 7). Every face of a cube is then cut by its diagonal from its
//! lowest to its highest corner, whichever cube it is seen from, so neighbouring cubes'
//! tetrahedra meet face to face. In a tetrahedron the surface is the zero set of the linear
//! interpolant of its four samples: one triangle (one corner inside or one outside) or a quad
//! (two and two), with no ambiguous case, so no table is needed and the mesh is closed by
//! construction: a triangle's edge lies in a face of its tetrahedron, where the two
//! tetrahedra sharing that face draw the same segment from the same three samples.
//!
//! Compared with marching cubes on the same samples it makes about two to three times as many
//! triangles (the cube's diagonals cut the surface too), some of them thin; its volume
//! converges at the same rate.
//!
//! Caps: on the domain's faces, each boundary cube face is cut into its two triangles (the
//! same diagonal as the tetrahedra's) and the inside part of each triangle (a triangle or a
//! quad of inside nodes and crossings) is added, facing out of the box. Its cut edges are the
//! segments the boundary tetrahedra draw on that face, so the caps close the surface.
//!
//! Invariants:
//! - Inside is `g < 0`; NaN counts as outside. Every vertex is either a crossing on an edge
//!   from a grid node `n` to `n + e` (`e` one of the seven nonzero 0/1 offsets) or an inside
//!   node on the domain's boundary, created once and shared by every triangle using it; a
//!   crossing is interpolated from the edge's lower node (`n`), whichever tetrahedron asks,
//!   kept [`super::chunk`]'s margin from the ends and rounded strictly inside its edge on the
//!   axes it spans, so no two vertices share an `f32` position.
//! - Triangles face the outside: towards the outside corners of their tetrahedron, or out of
//!   the box for caps.
//! - Memory: two planes of samples and two planes of vertex ids (plus a small batch of
//!   planes sampled ahead in parallel), so it grows with N², not N³. Extraction runs on one
//!   thread in a fixed order, so the mesh is the same for any number of threads.

use rayon::prelude::*;

use super::{ContourError, check_grids, crossing_fraction};
use crate::field::{Grid, PlaneSampler};
use crate::mesh::{Mesh, round_inside};

/// The six tetrahedra of a cube, by corner number (bit 0: +x, bit 1: +y, bit 2: +z), each the
/// monotone path from corner 0 to corner 7 along one order of the axes.
const TETRAHEDRA: [[usize; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 5, 7],
    [0, 2, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 6, 7],
];

/// Planes sampled ahead at once, in parallel.
const SAMPLE_AHEAD: usize = 8;

/// No vertex yet in a slot of a plane's id table.
const NONE: u32 = u32::MAX;

/// Contours the solid `{g < 0}` sampled by `sampler` on `model` with marching tetrahedra.
/// `progress(n)` is called as cube layers complete (total `nz − 1`).
pub fn contour_tetrahedra(
    sampler: &dyn PlaneSampler,
    model: &Grid,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Mesh, ContourError> {
    check_grids(sampler, None, model)?;
    let [nx, ny, nz] = model.counts;
    let len = nx * ny;
    let sample = |k: usize| {
        let mut plane = vec![0.0; len];
        sampler.sample_plane(k, &mut plane);
        plane
    };
    let mut march = March {
        model,
        mesh: Mesh::default(),
        ids: [vec![NONE; len * 8], vec![NONE; len * 8]],
        k: 0,
    };
    let mut lower = sample(0);
    let mut k = 0;
    while k + 1 < nz {
        let ahead: Vec<Vec<f64>> = (k + 1..(k + 1 + SAMPLE_AHEAD).min(nz))
            .into_par_iter()
            .map(sample)
            .collect();
        for upper in ahead {
            march.k = k;
            march.layer([&lower, &upper])?;
            progress(1);
            lower = upper;
            // The upper plane's vertices become the lower plane's; the new upper has none.
            march.ids.swap(0, 1);
            march.ids[1].fill(NONE);
            k += 1;
        }
    }
    Ok(march.mesh)
}

struct March<'g> {
    model: &'g Grid,
    mesh: Mesh,
    /// Vertex ids of the lower and upper plane of the current layer: 8 slots per node, slot 0
    /// the node itself (a cap vertex), slot `e` the crossing on the edge from it to `n + e`.
    ids: [Vec<u32>; 2],
    /// The layer: cubes between planes `k` and `k + 1`.
    k: usize,
}

/// The offset of a cube corner along each axis.
fn offset(corner: usize) -> [usize; 3] {
    [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1]
}

impl March<'_> {
    /// Contours the cubes of one layer, whose planes' samples are `planes`.
    fn layer(&mut self, planes: [&[f64]; 2]) -> Result<(), ContourError> {
        let [nx, ny, nz] = self.model.counts;
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let values: [f64; 8] = std::array::from_fn(|c| {
                    let o = offset(c);
                    planes[o[2]][(j + o[1]) * nx + i + o[0]]
                });
                let inside = values
                    .iter()
                    .enumerate()
                    .fold(0u8, |m, (c, v)| m | (u8::from(*v < 0.0) << c));
                if inside == 0 {
                    continue;
                }
                let on_box = [
                    i == 0,
                    i + 2 == nx,
                    j == 0,
                    j + 2 == ny,
                    self.k == 0,
                    self.k + 2 == nz,
                ];
                if inside == u8::MAX && !on_box.contains(&true) {
                    continue;
                }
                let cube = Cube {
                    at: [i, j, self.k],
                    values,
                    inside,
                };
                for tet in TETRAHEDRA {
                    self.tetrahedron(&cube, tet)?;
                }
                for (face, &on) in on_box.iter().enumerate() {
                    if on {
                        self.cap(&cube, face / 2, face % 2)?;
                    }
                }
            }
        }
        Ok(())
    }

    /// The surface in one tetrahedron of `cube`.
    fn tetrahedron(&mut self, cube: &Cube, tet: [usize; 4]) -> Result<(), ContourError> {
        let (ins, outs): (Vec<usize>, Vec<usize>) =
            tet.into_iter().partition(|&c| cube.is_inside(c));
        let polygon: Vec<(usize, usize)> = match (ins.as_slice(), outs.as_slice()) {
            ([a], [b, c, d]) | ([b, c, d], [a]) => vec![(*a, *b), (*a, *c), (*a, *d)],
            ([a, b], [c, d]) => vec![(*a, *c), (*a, *d), (*b, *d), (*b, *c)],
            _ => return Ok(()),
        };
        // Outward: from the inside corners towards the outside ones.
        let centroid = |corners: &[usize]| -> [f64; 3] {
            let mut s = [0.0; 3];
            for &c in corners {
                let p = self.corner_point(cube, c);
                (0..3).for_each(|a| s[a] += p[a] / corners.len() as f64);
            }
            s
        };
        let (cin, cout) = (centroid(&ins), centroid(&outs));
        let outward: [f64; 3] = std::array::from_fn(|a| cout[a] - cin[a]);
        let mut vertices = Vec::with_capacity(4);
        for &(a, b) in &polygon {
            vertices.push(self.crossing(cube, a, b)?);
        }
        self.fan(&vertices, outward);
        Ok(())
    }

    /// The inside part of the cube's face on the domain boundary: axis `axis`, side `side`
    /// (0 the lower, 1 the upper).
    fn cap(&mut self, cube: &Cube, axis: usize, side: usize) -> Result<(), ContourError> {
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        let base = side << axis;
        let (p10, p01) = (base | 1 << b, base | 1 << c);
        let p11 = base | 1 << b | 1 << c;
        let mut outward = [0.0; 3];
        outward[axis] = if side == 0 { -1.0 } else { 1.0 };
        for triangle in [[base, p10, p11], [base, p11, p01]] {
            if !triangle.iter().any(|&u| cube.is_inside(u)) {
                continue;
            }
            let mut polygon = Vec::with_capacity(4);
            for n in 0..3 {
                let (u, v) = (triangle[n], triangle[(n + 1) % 3]);
                if cube.is_inside(u) {
                    polygon.push(self.node(cube, u)?);
                }
                if cube.is_inside(u) != cube.is_inside(v) {
                    polygon.push(self.crossing(cube, u, v)?);
                }
            }
            self.fan(&polygon, outward);
        }
        Ok(())
    }

    /// Triangles fanned from the first of `polygon`'s (id, position) vertices, each turned to
    /// face `outward`.
    fn fan(&mut self, polygon: &[(u32, [f64; 3])], outward: [f64; 3]) {
        for n in 1..polygon.len().saturating_sub(1) {
            let (a, b, c) = (polygon[0], polygon[n], polygon[n + 1]);
            let normal = cross(sub(b.1, a.1), sub(c.1, a.1));
            let facing = dot(normal, outward);
            self.mesh.triangles.push(if facing >= 0.0 {
                [a.0, b.0, c.0]
            } else {
                [a.0, c.0, b.0]
            });
        }
    }

    fn corner_point(&self, cube: &Cube, corner: usize) -> [f64; 3] {
        let o = offset(corner);
        std::array::from_fn(|a| self.model.coord(a, cube.at[a] + o[a]))
    }

    /// The vertex of an inside node of the box's boundary.
    fn node(&mut self, cube: &Cube, corner: usize) -> Result<(u32, [f64; 3]), ContourError> {
        let p = self.corner_point(cube, corner);
        let slot = self.slot(cube, corner, 0);
        let id = self.vertex(slot, || p.map(|v| v as f32))?;
        Ok((id, p))
    }

    /// The crossing on the edge between corners `u` and `v` (one of them inside), measured
    /// from the edge's lower corner.
    fn crossing(
        &mut self,
        cube: &Cube,
        u: usize,
        v: usize,
    ) -> Result<(u32, [f64; 3]), ContourError> {
        // On a monotone path one corner's bits are a subset of the other's.
        let (low, high) = if u & v == u { (u, v) } else { (v, u) };
        let t = crossing_fraction(cube.values[low], cube.values[high]);
        let (a, b) = (self.corner_point(cube, low), self.corner_point(cube, high));
        let p: [f64; 3] = std::array::from_fn(|x| a[x] + t * (b[x] - a[x]));
        let slot = self.slot(cube, low, high & !low);
        let id = self.vertex(slot, || {
            std::array::from_fn(|x| {
                if a[x] == b[x] {
                    a[x] as f32
                } else {
                    round_inside(p[x], a[x], b[x])
                }
            })
        })?;
        Ok((id, p))
    }

    /// Plane and index of the id slot `dir` of `corner`'s node.
    fn slot(&self, cube: &Cube, corner: usize, dir: usize) -> (usize, usize) {
        let o = offset(corner);
        let nx = self.model.counts[0];
        let node = (cube.at[1] + o[1]) * nx + cube.at[0] + o[0];
        (o[2], node * 8 + dir)
    }

    /// The id in `slot`, creating its vertex at `position()` the first time.
    fn vertex(
        &mut self,
        (plane, index): (usize, usize),
        position: impl FnOnce() -> [f32; 3],
    ) -> Result<u32, ContourError> {
        let id = self.ids[plane][index];
        if id != NONE {
            return Ok(id);
        }
        let id = self.mesh.vertices.len() as u64;
        if id >= u64::from(NONE) {
            return Err(ContourError::TooManyVertices(id + 1));
        }
        self.mesh.vertices.push(position());
        self.ids[plane][index] = id as u32;
        Ok(id as u32)
    }
}

/// One cube: its lowest node, its corners' samples and which are inside (bit per corner).
struct Cube {
    at: [usize; 3],
    values: [f64; 8],
    inside: u8,
}

impl Cube {
    fn is_inside(&self, corner: usize) -> bool {
        self.inside & (1 << corner) != 0
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| a[i] - b[i])
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| a[i] * b[i]).sum()
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
