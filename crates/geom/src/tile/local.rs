//! The mesh of one element in reference coordinates, before it is welded to its neighbours.
//!
//! Invariants: every vertex lies on one lattice edge `(a, b)` (`a < b`, lattice point indices)
//! strictly between its ends, or — for cap corners, and inside corners of a 2D region — on one
//! lattice point `a` (`b == POINT`); triangles are counter-clockwise seen from outside the
//! solid in reference coordinates (2D: filled region triangles, counter-clockwise in ξ); `caps[f]` closes the solid on the element's face `f` and is used only where
//! that face is on the scaffold's boundary.

use std::collections::HashMap;

/// `LocalVertex::b` of a vertex that sits on a lattice point (a cap corner).
pub const POINT: u32 = u32::MAX;

/// Fraction of an edge kept between a crossing and the edge's ends, as in the contourer: no
/// two vertices share a position even where the field is exactly zero at a sample.
const EDGE_MARGIN: f64 = 1.0 / 256.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalVertex {
    pub a: u32,
    pub b: u32,
    /// Position along `a → b` (0 at `a`); 0 for a point vertex.
    pub t: f64,
}

#[derive(Clone, Debug, Default)]
pub struct LocalMesh {
    pub vertices: Vec<LocalVertex>,
    pub triangles: Vec<[u32; 3]>,
    pub caps: Vec<Vec<[u32; 3]>>,
}

/// Builds a [`LocalMesh`], giving each lattice edge or point one vertex.
pub struct LocalBuilder<'v> {
    values: &'v [f64],
    ids: HashMap<(u32, u32), u32>,
    pub mesh: LocalMesh,
}

impl<'v> LocalBuilder<'v> {
    pub fn new(values: &'v [f64], faces: usize) -> Self {
        LocalBuilder {
            values,
            ids: HashMap::new(),
            mesh: LocalMesh {
                caps: vec![Vec::new(); faces],
                ..LocalMesh::default()
            },
        }
    }

    /// The vertex where the surface crosses the lattice edge `p`–`q` (signs differ).
    pub fn crossing(&mut self, p: u32, q: u32) -> u32 {
        let (a, b) = (p.min(q), p.max(q));
        let values = self.values;
        let mesh = &mut self.mesh;
        *self.ids.entry((a, b)).or_insert_with(|| {
            let (va, vb) = (values[a as usize], values[b as usize]);
            let t = va / (va - vb);
            let t = if t.is_finite() {
                t.clamp(EDGE_MARGIN, 1.0 - EDGE_MARGIN)
            } else {
                0.5
            };
            mesh.vertices.push(LocalVertex { a, b, t });
            (mesh.vertices.len() - 1) as u32
        })
    }

    /// The vertex on lattice point `p` (an inside corner of a cap).
    pub fn point(&mut self, p: u32) -> u32 {
        let mesh = &mut self.mesh;
        *self.ids.entry((p, POINT)).or_insert_with(|| {
            mesh.vertices.push(LocalVertex {
                a: p,
                b: POINT,
                t: 0.0,
            });
            (mesh.vertices.len() - 1) as u32
        })
    }

    /// The sample at lattice point `p`.
    #[inline]
    pub fn value(&self, p: u32) -> f64 {
        self.values[p as usize]
    }

    pub fn finish(self) -> LocalMesh {
        self.mesh
    }
}

/// Inside means strictly negative; NaN is outside, as in the contourer.
#[inline]
pub fn inside(v: f64) -> bool {
    v < 0.0
}
