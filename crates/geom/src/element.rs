//! A field clipped to a 3D reference element, contoured as one closed mesh.
//!
//! Reference elements are those of `docs/method.md` §Reference elements: the cube `[-½, ½]³` and
//! the
//! regular tetrahedron inscribed in it with vertices `p0 = (-½,-½,-½)`, `p1 = (½,½,-½)`,
//! `p2 = (-½,½,½)`, `p3 = (½,-½,½)`.
//!
//! [`contour_clipped`] returns the solid `{Φ ≤ 0} ∩ element` (negative inside, as everywhere in
//! this crate) as one closed, manifold, outward-oriented [`Mesh`]. It contours a function with
//! the sign of `max(Φ, c)`, where `c` is a clipping function of the element (negative inside),
//! with the streaming contourer, which caps the solid on its grid's box. How the grid is chosen
//! is what makes the element's faces exact:
//!
//! - **Cube**: the grid spans the cube exactly, so the element's faces are the box faces and the
//!   contourer's caps are exact planar faces. Inside the box `c ≤ 0`, so `g = Φ` there: `c` is
//!   never sampled (it is zero on the faces, and a zero sample would count as outside).
//! - **Tetrahedron**: an axis-aligned grid cannot reproduce it: its edges are diagonals of the
//!   cube's faces, which run through grid nodes, so every cell along them bevels the edge and the
//!   volume error is O(h²). Instead the grid is laid on the tetrahedron's own affine lattice,
//!   `x = p0 + u (p1 − p0) + v (p2 − p0) + w (p3 − p0)`: three faces are `u = 0`, `v = 0`,
//!   `w = 0`, i.e. box faces with exact caps, and the fourth is the zero set of the linear clip
//!   `c = u + v + w − 1`. The spacing is `h = 1 / (N + ⅓)` for `N` cells along an edge, so at
//!   node `(i, j, k)` `c = h·m − 1` with `m = i + j + k`, never zero: every grid edge crossing
//!   the face runs from layer `m = N` (`c = −h/3`) to `m = N + 1` (`c = 2h/3`), a third of the
//!   way along. The box ends one layer past the face, where every node is outside, so those box
//!   faces get no caps. The map has determinant 2 > 0, so it keeps the outward winding.
//!
//! Only the signs of the samples decide the topology; the values decide where crossings go,
//! and each node's value serves the edges it touches. So the sampled function has the sign of
//! `max(Φ, c)` everywhere, with these values (`lattice_clip`): deeper than layer `N` it is
//! `Φ` (plain `max(Φ, c)` would replace `Φ` by `c` wherever `c > Φ`, a thick layer near the face,
//! and drag the field's own crossings towards inside nodes: −1.1 % of volume at 40 samples for a
//! gyroid); on layers `N` and `N + 1`, where `Φ < 0` it is `c`, so every crossing of the face is
//! exactly on it, and elsewhere `max(Φ, c)`. The clipped solid is therefore reproduced exactly
//! except in the cells where the field's surface meets the face (the crease, O(h²) in volume); a
//! constant-inside field gives the tetrahedron itself up to `f32` rounding.
//!
//! NaN samples of `Φ` count as outside, as in the contourer (the clip never hides them).
//!
//! A shell over the cube is a band of the field clipped by the box alone, so
//! [`contour_cube_band`] contours it with the two-level contourer (a wall between two samples
//! is kept). Over the tetrahedron the clip is a third surface the band cannot combine with:
//! a shell there is `|f − c| − w/2` through [`contour_clipped`], which can lose walls thinner
//! than a sample spacing.

use crate::contour::{BandMesh, ContourError, contour, contour_band};
use crate::field::{Band, Grid, ScalarField};
use crate::mesh::Mesh;
use crate::simplex_contour::contour_tetrahedron;

/// A 3D reference element (docs/method.md §Reference elements).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Element3 {
    /// `[-½, ½]³`.
    Cube,
    /// The regular tetrahedron with vertices [`TETRAHEDRON_VERTICES`].
    Tetrahedron,
}

/// The tetrahedron's vertices `p0..p3`: the cube corners whose coordinates multiply to a
/// negative number. Face `i` is opposite `p_i`.
pub const TETRAHEDRON_VERTICES: [[f64; 3]; 4] = [
    [-0.5, -0.5, -0.5],
    [0.5, 0.5, -0.5],
    [-0.5, 0.5, 0.5],
    [0.5, -0.5, 0.5],
];

/// Outward normals (unnormalised) of the tetrahedron's faces: face `i` is `n_i · x = ½`.
const TETRAHEDRON_NORMALS: [[f64; 3]; 4] = [
    [1.0, 1.0, 1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, -1.0],
    [-1.0, 1.0, -1.0],
];

impl Element3 {
    /// A clipping function of the element: negative inside, zero on the boundary, positive
    /// outside. For the cube it is the exact signed distance. For the tetrahedron it is the
    /// largest signed distance to a face plane: exact inside and wherever the nearest boundary
    /// point lies inside a face, a lower bound of the distance elsewhere outside (near edges
    /// and vertices). Only its zero set matters for clipping.
    pub fn signed_distance(&self, p: [f64; 3]) -> f64 {
        match self {
            Element3::Cube => {
                let q = p.map(|c| c.abs() - 0.5);
                let outside = q.iter().map(|c| c.max(0.0).powi(2)).sum::<f64>().sqrt();
                let inside = q[0].max(q[1]).max(q[2]).min(0.0);
                outside + inside
            }
            Element3::Tetrahedron => {
                let inv_norm = 1.0 / 3f64.sqrt();
                TETRAHEDRON_NORMALS
                    .iter()
                    .map(|n| (n[0] * p[0] + n[1] * p[1] + n[2] * p[2] - 0.5) * inv_norm)
                    .fold(f64::NEG_INFINITY, f64::max)
            }
        }
    }

    /// Axis-aligned bounding box `(min, max)`: the cube `[-½, ½]³` for both elements.
    pub fn bbox(&self) -> ([f64; 3], [f64; 3]) {
        ([-0.5; 3], [0.5; 3])
    }

    /// Volume of the element: 1 for the cube, ⅓ for the tetrahedron.
    pub fn volume(&self) -> f64 {
        match self {
            Element3::Cube => 1.0,
            Element3::Tetrahedron => 1.0 / 3.0,
        }
    }
}

/// Largest number of samples per plane accepted: beyond it the vertices of a single cap could
/// overflow the contourer's 32-bit indices, and plane buffers would not fit in memory anyway.
const MAX_PLANE_SAMPLES: u64 = u32::MAX as u64;

/// Contours `{Φ ≤ 0} ∩ element` as one closed, manifold, outward mesh (see the module docs for
/// the grid). `samples` is the number of samples along each edge direction of the element
/// (at least 2): per axis of the cube; per edge `p0 p_i` of the tetrahedron, whose grid adds
/// one layer of outside samples. `progress(n)` reports completed cube layers, as in
/// [`contour`].
pub fn contour_clipped(
    field: &dyn ScalarField,
    element: Element3,
    samples: usize,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Mesh, ContourError> {
    if samples < 2 {
        return Err(ContourError::TooFewSamples([samples; 3]));
    }
    // The tetrahedron's grid has one more sample per axis than `samples`.
    let per_axis = (samples as u64).saturating_add(1);
    if per_axis.saturating_mul(per_axis) > MAX_PLANE_SAMPLES {
        return Err(ContourError::TooManyVertices(
            per_axis.saturating_mul(per_axis),
        ));
    }
    match element {
        Element3::Cube => {
            let (min, max) = element.bbox();
            let grid = Grid::spanning(min, max, [samples; 3]);
            // Inside the box the clipping function is ≤ 0, so `max(Φ, c) = Φ`: the box itself
            // clips, and the field's own (possibly separable, fast) sampler can be used.
            let sampler = field.sampler(&grid);
            contour(sampler.as_ref(), &grid, progress)
        }
        Element3::Tetrahedron => Ok(contour_tetrahedron(field, samples - 1, progress).mesh),
    }
}

/// The band `lo < f < hi` of `field` (a shell) over the cube `[-½, ½]³`, `samples` per axis:
/// the grid [`contour_clipped`] uses for the cube, whose box clips exactly.
pub fn contour_cube_band(
    field: &dyn ScalarField,
    band: Band,
    samples: usize,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<BandMesh, ContourError> {
    if samples < 2 {
        return Err(ContourError::TooFewSamples([samples; 3]));
    }
    if (samples as u64).saturating_mul(samples as u64) > MAX_PLANE_SAMPLES {
        return Err(ContourError::TooManyVertices(
            (samples as u64).saturating_mul(samples as u64),
        ));
    }
    let (min, max) = Element3::Cube.bbox();
    let grid = Grid::spanning(min, max, [samples; 3]);
    contour_band(field.sampler(&grid).as_ref(), band, &grid, progress)
}

/// The affine map from lattice coordinates `(u, v, w)` to the tetrahedron:
/// `p0 + u (p1 − p0) + v (p2 − p0) + w (p3 − p0)`, with `p1 − p0 = (1,1,0)`,
/// `p2 − p0 = (0,1,1)`, `p3 − p0 = (1,0,1)` (determinant 2).
#[inline]
pub(crate) fn tetrahedron_point([u, v, w]: [f64; 3]) -> [f64; 3] {
    [-0.5 + u + w, -0.5 + u + v, -0.5 + v + w]
}
