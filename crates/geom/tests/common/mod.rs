//! Meshes shared by the geometry crate's integration tests.
#![allow(dead_code)]

use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::synthetic;

/// A torus with `n` segments around the axis and `m` around the tube, outward winding,
/// vertices at `((R + r cos φ) cos θ, (R + r cos φ) sin θ, r sin φ) + offset`, in `f32` (the
/// soup of [`synthetic::torus`], moved).
pub fn torus(n: u32, m: u32, big_r: f64, r: f64, offset: [f64; 3]) -> Mesh {
    let soup = synthetic::torus(n, m, big_r, r);
    Mesh {
        vertices: soup
            .positions
            .iter()
            .map(|p| std::array::from_fn(|a| (offset[a] + p[a]) as f32))
            .collect(),
        triangles: soup.triangles,
    }
}
pub mod sdf_sphere;
