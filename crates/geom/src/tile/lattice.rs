//! Reference lattices: the sample points of one element in reference coordinates.
//!
//! A lattice is invariant under the symmetry group of its element (Oh for the cube, Td — acting
//! on the vertices as S4 — for the tetrahedron), and knows, for each point, an orbit
//! representative and its intrinsic weights: the point as a combination of the element's
//! corners with integer weights (multilinear for the cube, barycentric for the tetrahedron).
//! The weights of a point on a face involve only that face's corners and do not depend on
//! which element, in which orientation, looks at the face, so `(global corner id, weight)`
//! lists name boundary points across elements exactly.
//!
//! Invariants: `representative(p)` is the same for every point of an orbit; weights are
//! positive and listed in increasing corner order; the face masks are the element's faces in
//! the order its contourer numbers its caps.

use super::local::{LocalMesh, Samples};

/// Most corners an element has (the cube's eight).
pub const MAX_CORNERS: usize = 8;

pub trait Lattice: Sync {
    /// Size of the dense point index range (some indices may be unused).
    fn index_len(&self) -> usize;
    /// Whether index `p` is a lattice point.
    fn is_point(&self, p: u32) -> bool;
    /// Reference coordinates of point `p` (docs/method.md §Reference elements).
    fn xi(&self, p: u32) -> [f64; 3];
    /// One fixed member of `p`'s orbit under the element's group.
    fn representative(&self, p: u32) -> u32;
    /// The intrinsic corner weights of `p`.
    fn weights(&self, p: u32) -> Weights;
    /// Corner bit masks of the element's faces, in cap order.
    fn face_masks(&self) -> &[u8];
    /// Contours `samples` (one per index; negative inside, or a band between two levels) into a
    /// local mesh with caps per face. The 2D lattices take one level only.
    fn contour(&self, samples: Samples) -> LocalMesh;
    /// Whether [`Lattice::contour`] takes a band (the 3D lattices do).
    fn takes_bands(&self) -> bool;
}

/// A point's corner weights: `(local corner, weight)` pairs with weight > 0, in increasing
/// corner order (a fixed-capacity list: no allocation per point).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Weights {
    len: u8,
    items: [(u8, u32); MAX_CORNERS],
}

impl Weights {
    pub fn push(&mut self, corner: u8, weight: u32) {
        self.items[self.len as usize] = (corner, weight);
        self.len += 1;
    }

    pub fn as_slice(&self) -> &[(u8, u32)] {
        &self.items[..self.len as usize]
    }

    /// Bit mask of the corners with a weight.
    pub fn mask(&self) -> u8 {
        self.as_slice().iter().fold(0, |m, &(c, _)| m | 1 << c)
    }

    /// The weights of a simplex lattice point with barycentric integers `a` (one per corner):
    /// the nonzero ones.
    pub fn barycentric(a: &[u32]) -> Weights {
        let mut out = Weights::default();
        for (corner, &w) in a.iter().enumerate() {
            if w > 0 {
                out.push(corner as u8, w);
            }
        }
        out
    }

    /// The weights of grid point `c` (each coordinate in `0..=m`) on a square's or cube's
    /// `corners` (0 or 1 per axis): per corner, the product over the axes of `m − c` (corner
    /// at 0) or `c` (corner at 1); corners of weight 0 are left out.
    pub fn grid<const D: usize>(c: [u32; D], m: u32, corners: &[[u32; D]]) -> Weights {
        let mut out = Weights::default();
        for (corner, at) in corners.iter().enumerate() {
            let w = (0..D).fold(1u32, |w, a| w * if at[a] == 0 { m - c[a] } else { c[a] });
            if w > 0 {
                out.push(corner as u8, w);
            }
        }
        out
    }
}

/// The orbit representative of grid point `c` (each coordinate in `0..=m`) under a square's
/// or cube's symmetries: each coordinate folded to `min(c, m − c)`, then sorted.
pub fn grid_representative<const D: usize>(c: [u32; D], m: u32) -> [u32; D] {
    let mut c = c.map(|c| c.min(m - c));
    c.sort_unstable();
    c
}
