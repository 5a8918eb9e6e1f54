//! An indexed triangle mesh, the one mesh type every stage passes around.
//!
//! Invariants: vertex positions are `f32` (what every writer stores, so what is validated is
//! what is written); triangles index `vertices`; winding is counter-clockwise seen from
//! outside, so the right-hand normal points out of the solid.

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub vertices: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }
}
