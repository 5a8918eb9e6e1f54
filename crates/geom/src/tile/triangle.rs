//! The triangle's lattice: points with barycentric coordinates `a/m` (`a ∈ ℕ³`, `Σ a = m`),
//! i.e. `ξ = Σ a_i q_i / m` over the reference triangle's corners `q_i`
//! (docs/method.md §Reference elements: side 1,
//! centroid at 0, pointing to +y; Gmsh's corner order), contoured by marching triangles over
//! the standard subdivision into `m²` small triangles (upward and downward).
//!
//! Why barycentric: the lattice is invariant under all of D3 (S3 on the barycentric
//! coordinates), so the points on an edge, with their values, are the same whichever
//! neighbour looks at it; the orbit representative sorts `a` in decreasing order. Marching
//! triangles has no ambiguous case, and every edge is cut into the same `m` segments from both
//! sides.
//!
//! Indices are dense over `(u, v) = (a1, a2)` in `[0, m]²` (points with `u + v ≤ m` are used).
//! Edges are the triangle's facets (01, 12, 20).
//!
//! Invariants: as for the square ([`super::square`]): filled triangles counter-clockwise in ξ
//! (the map `(u, v) ↦ ξ` has positive determinant), no caps.

use super::lattice::{Lattice, Weights};
use super::local::{LocalBuilder, LocalMesh, Samples, band_state, band_triangle_walk, inside};
use crate::scaffold::ElementKind;

pub struct TriangleLattice {
    /// Segments per edge.
    m: u32,
    corners: [[f64; 3]; 3],
}

impl TriangleLattice {
    /// `n ≥ 2` points per edge.
    pub fn new(n: usize) -> TriangleLattice {
        TriangleLattice {
            m: n as u32 - 1,
            corners: std::array::from_fn(|i| ElementKind::Tri3.reference_node(i)),
        }
    }

    #[inline]
    fn index(&self, [u, v]: [u32; 2]) -> u32 {
        u + (self.m + 1) * v
    }

    #[inline]
    fn coords(&self, p: u32) -> [u32; 2] {
        let n = self.m + 1;
        [p % n, p / n]
    }

    /// Barycentric integers `(a0, a1, a2)` of a valid point.
    #[inline]
    fn barycentric(&self, p: u32) -> [u32; 3] {
        let [u, v] = self.coords(p);
        [self.m - u - v, u, v]
    }

    /// Marching triangles on the small triangle `q` (counter-clockwise): the inside corners
    /// and crossings in cyclic order, fanned. For a band, the corners between its levels and
    /// both levels' crossings, in the order the sides meet them: all on the triangle's
    /// perimeter, in order, so the polygon is convex.
    fn march(&self, builder: &mut LocalBuilder, q: [u32; 3]) {
        let samples = builder.samples();
        // At most the 3 corners and 2 crossings per side.
        let mut polygon: [u32; 9] = [0; 9];
        let mut len = 0;
        let mut push = |id: u32| {
            polygon[len] = id;
            len += 1;
        };
        match samples.upper {
            None => {
                let ins = q.map(|p| inside(builder.value(p)));
                for k in 0..3 {
                    if ins[k] {
                        push(builder.point(q[k]));
                    }
                    if ins[k] != ins[(k + 1) % 3] {
                        push(builder.crossing(q[k], q[(k + 1) % 3]));
                    }
                }
            }
            Some(upper) => {
                let state = q.map(|p| band_state(samples.lower, upper, p as usize));
                band_triangle_walk(state, |k, level| {
                    push(match level {
                        None => builder.point(q[k]),
                        Some(upper) => builder.level_crossing(q[k], q[(k + 1) % 3], upper),
                    })
                });
            }
        }
        for k in 1..len.saturating_sub(1) {
            builder
                .mesh
                .triangles
                .push([polygon[0], polygon[k], polygon[k + 1]]);
        }
    }
}

impl Lattice for TriangleLattice {
    fn index_len(&self) -> usize {
        (self.m as usize + 1).pow(2)
    }

    fn is_point(&self, p: u32) -> bool {
        (p as usize) < self.index_len() && self.coords(p).iter().sum::<u32>() <= self.m
    }

    fn xi(&self, p: u32) -> [f64; 3] {
        let m = f64::from(self.m);
        let a = self.barycentric(p).map(|a| f64::from(a) / m);
        std::array::from_fn(|k| (0..3).map(|i| a[i] * self.corners[i][k]).sum())
    }

    fn representative(&self, p: u32) -> u32 {
        let mut a = self.barycentric(p);
        a.sort_unstable_by(|x, y| y.cmp(x));
        self.index([a[1], a[2]])
    }

    fn weights(&self, p: u32) -> Weights {
        Weights::barycentric(&self.barycentric(p))
    }

    fn face_masks(&self) -> &[u8] {
        &[0b011, 0b110, 0b101]
    }

    fn takes_bands(&self) -> bool {
        true
    }

    fn contour(&self, samples: Samples) -> LocalMesh {
        let mut builder = LocalBuilder::new(samples, 0);
        let m = self.m;
        for v in 0..m {
            for u in 0..m - v {
                let at = |du: u32, dv: u32| self.index([u + du, v + dv]);
                self.march(&mut builder, [at(0, 0), at(1, 0), at(0, 1)]);
                if u + v + 2 <= m {
                    self.march(&mut builder, [at(1, 0), at(1, 1), at(0, 1)]);
                }
            }
        }
        builder.finish()
    }
}
