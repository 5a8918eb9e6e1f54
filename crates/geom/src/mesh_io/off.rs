//! Object File Format: `OFF`, a `V F 0` counts line, `x y z` vertex lines, `3 a b c` face
//! lines (0-based). Always text. Every vertex is written, referenced or not.

use super::encode::{write_text_faces, write_text_points};
use crate::mesh::Mesh;
use std::io::{self, Write};

pub(super) fn write(mesh: &Mesh, out: &mut dyn Write) -> io::Result<()> {
    write!(
        out,
        "OFF\n{} {} 0\n",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    write_text_points(out, &mesh.vertices, b"")?;
    write_text_faces(out, &mesh.triangles, b"3 ", 0)
}
