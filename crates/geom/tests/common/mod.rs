//! Meshes shared by the geometry crate's integration tests.
#![allow(dead_code)]

use latticebuild_geom::mesh::Mesh;
use std::f64::consts::TAU;

/// A torus with `n` segments around the axis and `m` around the tube, outward winding,
/// vertices at `((R + r cos φ) cos θ, (R + r cos φ) sin θ, r sin φ) + offset`.
pub fn torus(n: u32, m: u32, big_r: f64, r: f64, offset: [f64; 3]) -> Mesh {
    let mut vertices = Vec::with_capacity((n * m) as usize);
    for i in 0..n {
        let theta = TAU * f64::from(i) / f64::from(n);
        for j in 0..m {
            let phi = TAU * f64::from(j) / f64::from(m);
            let rho = big_r + r * phi.cos();
            vertices.push([
                (offset[0] + rho * theta.cos()) as f32,
                (offset[1] + rho * theta.sin()) as f32,
                (offset[2] + r * phi.sin()) as f32,
            ]);
        }
    }
    let id = |i: u32, j: u32| (i % n) * m + (j % m);
    let mut triangles = Vec::with_capacity(2 * (n * m) as usize);
    for i in 0..n {
        for j in 0..m {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    Mesh {
        vertices,
        triangles,
    }
}
pub mod mesh_gen;
pub mod sdf_sphere;
