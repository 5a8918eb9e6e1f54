//! A field clipped to a 3D reference element, contoured as one closed mesh.
//!
//! Reference elements are those of `docs/method.md` §Reference elements: the cube `[-½, ½]³` and
//! the regular tetrahedron inscribed in it with vertices `p0 = (-½,-½,-½)`, `p1 = (½,½,-½)`,
//! `p2 = (-½,½,½)`, `p3 = (½,-½,½)`.
//!
//! [`contour_clipped`] returns the solid `{Φ ≤ 0} ∩ element` (negative inside, as everywhere in
//! this crate) as one closed, manifold, outward-oriented [`Mesh`]. How the samples are laid out
//! is what makes the element's faces exact:
//!
//! - **Cube**: the streaming contourer's grid spans the cube exactly, so the element's faces are
//!   the box faces and the contourer's caps (it caps the solid on its grid's box) are exact
//!   planar faces; `Φ` is contoured as it is.
//! - **Tetrahedron**: an axis-aligned grid cannot reproduce it (its edges are diagonals of the
//!   cube's faces, beveled by every cell along them), and a lattice laid from one vertex treats
//!   the far face differently from the other three. It is contoured on its own symmetric
//!   subdivision instead, by marching tetrahedra with caps on its faces
//!   (`simplex_contour`): every face exact, the result symmetric under Td to rounding.
//!
//! NaN samples of `Φ` count as outside, as in the contourer.
//!
//! A shell over the cube is a band of the field clipped by the box alone, so
//! [`contour_cube_band`] contours it with the two-level contourer (a wall between two samples
//! is kept). Over the tetrahedron the two-level rule is not implemented: a shell there is `|f − c| − w/2` through [`contour_clipped`], which can lose walls thinner
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
/// (at least 2): per axis of the cube; per edge of the tetrahedron. `progress(n)` reports
/// completed layers (`samples − 1` in all), as in [`contour`].
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
