//! VTK legacy polydata, ASCII or BINARY.
//!
//! ```text
//! # vtk DataFile Version 3.0
//! latticebuild mesh
//! ASCII | BINARY
//! DATASET POLYDATA
//! POINTS N float
//! <3N floats>
//! POLYGONS M 4M
//! <M records: 3 a b c>
//! ```
//! Binary legacy VTK is big-endian: points are big-endian `f32`, polygon records big-endian
//! `i32`. Each binary section is followed by a newline, as VTK's own writer does. Indices and
//! the `4M` size are 32-bit signed, which bounds vertex and triangle counts.

use super::Encoding;
use super::encode::{records_per_block, write_encoded, write_text_faces, write_text_points};
use crate::mesh::Mesh;
use std::io::{self, Write};

const POINT_BYTES: usize = 12;
const POLYGON_BYTES: usize = 16;

pub(super) fn write(mesh: &Mesh, encoding: Encoding, out: &mut dyn Write) -> io::Result<()> {
    let limit = i32::MAX as usize;
    let polygon_ints = mesh.triangles.len().saturating_mul(4);
    if mesh.vertices.len() > limit + 1 || polygon_ints > limit {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "legacy VTK counts and indices are 32-bit signed: \
                 mesh has {} vertices, {} triangles",
                mesh.vertices.len(),
                mesh.triangles.len()
            ),
        ));
    }
    let name = match encoding {
        Encoding::Binary => "BINARY",
        Encoding::Ascii => "ASCII",
    };
    write!(
        out,
        "# vtk DataFile Version 3.0\nlatticebuild mesh\n{name}\nDATASET POLYDATA\n\
         POINTS {} float\n",
        mesh.vertices.len()
    )?;
    match encoding {
        Encoding::Binary => {
            write_encoded(
                out,
                &mesh.vertices,
                records_per_block(POINT_BYTES),
                |buf, p| {
                    let mut record = [0u8; POINT_BYTES];
                    for (slot, value) in record.chunks_exact_mut(4).zip(p) {
                        slot.copy_from_slice(&value.to_be_bytes());
                    }
                    buf.extend_from_slice(&record);
                },
            )?;
            write!(
                out,
                "\nPOLYGONS {} {}\n",
                mesh.triangles.len(),
                polygon_ints
            )?;
            write_encoded(
                out,
                &mesh.triangles,
                records_per_block(POLYGON_BYTES),
                |buf, tri| {
                    let mut record = [0u8; POLYGON_BYTES];
                    record[..4].copy_from_slice(&3i32.to_be_bytes());
                    for (slot, index) in record[4..].chunks_exact_mut(4).zip(tri) {
                        // In range for i32 by the vertex-count check above, so the bits are equal.
                        slot.copy_from_slice(&index.to_be_bytes());
                    }
                    buf.extend_from_slice(&record);
                },
            )?;
            out.write_all(b"\n")
        }
        Encoding::Ascii => {
            write_text_points(out, &mesh.vertices, b"")?;
            writeln!(out, "POLYGONS {} {}", mesh.triangles.len(), polygon_ints)?;
            write_text_faces(out, &mesh.triangles, b"3 ", 0)
        }
    }
}
