//! Object File Format: `OFF`, a `V F 0` counts line, `x y z` vertex lines, `3 a b c` face
//! lines (0-based). Always text. Every vertex is written, referenced or not.

use super::encode::{write_text_faces, write_text_points};
use crate::mesh::Mesh;
use std::io::{self, Write};

pub(super) fn write(mesh: &Mesh, out: &mut dyn Write) -> io::Result<()> {
    header(mesh.vertices.len() as u64, mesh.triangles.len() as u64, out)?;
    vertices(&mesh.vertices, out)?;
    faces(&mesh.triangles, out)
}

pub(super) fn header(nv: u64, nt: u64, out: &mut dyn Write) -> io::Result<()> {
    write!(out, "OFF\n{nv} {nt} 0\n")
}

pub(super) fn vertices(vertices: &[[f32; 3]], out: &mut dyn Write) -> io::Result<()> {
    write_text_points(out, vertices, b"")
}

pub(super) fn faces(triangles: &[[u32; 3]], out: &mut dyn Write) -> io::Result<()> {
    write_text_faces(out, triangles, b"3 ", 0)
}
