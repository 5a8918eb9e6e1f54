//! Object File Format: `OFF`, a `V F 0` counts line, `x y z` vertex lines, `3 a b c` face
//! lines (0-based). Always text. Every vertex is written, referenced or not.

use super::encode::{push_indices, push_point, records_per_block, write_encoded};
use crate::mesh::Mesh;
use std::io::{self, Write};

const VERTEX_BYTES: usize = 48;
const FACE_BYTES: usize = 36;

pub(super) fn write(mesh: &Mesh, out: &mut dyn Write) -> io::Result<()> {
    write!(
        out,
        "OFF\n{} {} 0\n",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    write_encoded(
        out,
        &mesh.vertices,
        records_per_block(VERTEX_BYTES),
        |buf, p| {
            push_point(buf, p);
            buf.push(b'\n');
        },
    )?;
    write_encoded(
        out,
        &mesh.triangles,
        records_per_block(FACE_BYTES),
        |buf, tri| {
            buf.extend_from_slice(b"3 ");
            push_indices(buf, tri, 0);
            buf.push(b'\n');
        },
    )
}
