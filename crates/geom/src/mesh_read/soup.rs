//! The readers' output: positions and index triples, nothing else.
//!
//! Invariant (for soups the readers return): at least one triangle, every index below
//! `positions.len()`, every coordinate finite. Soups built by hand may break it; consumers such
//! as `mesh_sdf::MeshSdf::new` check again.

use crate::mesh::Mesh;

/// Triangles over `f64` positions, counter-clockwise seen from outside when the file says so.
///
/// Not [`Mesh`]: input files may hold `double` coordinates (PLY, text formats) that `Mesh`'s
/// `f32` would round, and a soup makes no promise about sharing, orientation or closedness.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleSoup {
    pub positions: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

impl TriangleSoup {
    /// The axis-aligned bounding box of the positions the triangles use, or `None` without
    /// triangles. Indices must be in range.
    pub fn bounds(&self) -> Option<([f64; 3], [f64; 3])> {
        let mut corners = self
            .triangles
            .iter()
            .flatten()
            .map(|&i| self.positions[i as usize]);
        let first = corners.next()?;
        Some(corners.fold((first, first), |(lo, hi), p| {
            (
                std::array::from_fn(|a| lo[a].min(p[a])),
                std::array::from_fn(|a| hi[a].max(p[a])),
            )
        }))
    }
}

impl From<&Mesh> for TriangleSoup {
    fn from(mesh: &Mesh) -> TriangleSoup {
        TriangleSoup {
            positions: mesh.vertices.iter().map(|p| p.map(f64::from)).collect(),
            triangles: mesh.triangles.clone(),
        }
    }
}
