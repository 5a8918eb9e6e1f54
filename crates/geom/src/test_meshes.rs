//! Small meshes for the crate's unit tests.

use crate::mesh::Mesh;

/// An axis-aligned box's 12 triangles, outward (inward with `inward`), ids from `base`.
pub(crate) fn cube(min: [f32; 3], size: f32, base: u32, inward: bool) -> Mesh {
    let vertices: Vec<[f32; 3]> = (0..8)
        .map(|c| [0, 1, 2].map(|a| min[a] + if c >> a & 1 == 1 { size } else { 0.0 }))
        .collect();
    let faces: [[u32; 4]; 6] = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let triangles = faces
        .iter()
        .flat_map(|f| [[f[0], f[1], f[2]], [f[0], f[2], f[3]]])
        .map(|t| if inward { [t[0], t[2], t[1]] } else { t })
        .map(|t| t.map(|v| v + base))
        .collect();
    Mesh {
        vertices,
        triangles,
    }
}
