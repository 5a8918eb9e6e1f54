//! Geometry and math for latticebuild.
//!
//! Invariant: nothing in this crate knows about manifests, stages, caches or files. Everything
//! here is a pure function of its arguments; the writers in [`mesh_io`] write to any
//! `std::io::Write` and never open a path themselves.
//!
//! Conventions shared by every module:
//! - A scalar field is negative inside the solid, positive outside; the surface is its zero set.
//! - Triangles wind counter-clockwise seen from outside the solid, so normals point outward.
//! - Cell coordinates have period 1 for the TPMS library: `cos(2πx)`, not `cos(x)`.

pub mod contour;
pub mod contour2d;
pub mod density;
pub mod distance;
pub mod element;
pub mod expr;
pub mod field;
pub mod floor;
pub mod graded;
pub mod islands;
pub mod measure;
pub mod mesh;
pub mod mesh_io;
pub mod mesh_read;
pub mod mesh_sdf;
pub mod periodic;
pub mod point_cloud;
pub mod render;
pub mod scaffold;
mod scalar;
mod simplex_contour;
pub mod spelling;
pub mod stack_lang;
pub mod symmetric;
pub mod synthetic;
#[cfg(test)]
mod test_meshes;
pub mod tile;
pub mod tpms;
pub mod validate;
pub(crate) mod vec3;
pub mod voxels;
pub mod within;
