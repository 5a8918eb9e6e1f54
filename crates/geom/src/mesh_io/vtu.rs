//! VTK XML unstructured grid (`.vtu`), the VTK-family format every reader takes (ParaView,
//! VTK, meshio, PyVista): the triangles as cells of type `VTK_TRIANGLE` (5).
//!
//! Layout: an XML head whose four `DataArray`s are `format="appended"`, then
//! `<AppendedData encoding="raw">`, `_` and the raw little-endian arrays, each behind a `UInt64`
//! byte count (`header_type="UInt64"`): points (`Float32` × 3), connectivity (`Int64`), offsets
//! (`Int64`, 3, 6, 9, …) and types (`UInt8`, all 5). Every array's size follows from the
//! counts, so the head is written first with every `offset`, and the arrays stream after it.
//! Always binary: the manifest's `ascii` does not apply.
//!
//! The stamp's generator and unit go in an XML comment after the declaration.
//! Offsets and types depend on the triangle count alone, so a chunked mesh writes points,
//! then connectivity, chunk by chunk, and the same tail: the bytes of the whole mesh.

use super::encode::{ByteOrder, Workers, records_per_block, write_encoded_by, write_points};
use super::stamp::Stamp;
use crate::mesh::Mesh;
use std::io::{self, Write};

/// `VTK_TRIANGLE`.
const TRIANGLE: u8 = 5;

pub(super) fn write(mesh: &Mesh, stamp: &Stamp, out: &mut dyn Write) -> io::Result<()> {
    let (nv, nt) = (mesh.vertices.len() as u64, mesh.triangles.len() as u64);
    header(nv, nt, stamp, out)?;
    points(&mesh.vertices, out)?;
    connectivity_header(nt, out)?;
    connectivity(&mesh.triangles, out)?;
    tail(nt, out)
}

/// The XML head, the appended data's `_` and the points' byte count.
pub(super) fn header(nv: u64, nt: u64, stamp: &Stamp, out: &mut dyn Write) -> io::Result<()> {
    let points = 8 + 12 * nv;
    let connectivity = 8 + 24 * nt;
    let offsets = 8 + 8 * nt;
    let comment = stamp.summary().replace("--", "- -");
    write!(
        out,
        "<?xml version=\"1.0\"?>\n<!-- {comment} -->\n\
         <VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\">\n<UnstructuredGrid>\n\
         <Piece NumberOfPoints=\"{nv}\" NumberOfCells=\"{nt}\">\n<Points>\n\
         <DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/>\n\
         </Points>\n<Cells>\n\
         <DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"{points}\"/>\n\
         <DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"{}\"/>\n\
         <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"{}\"/>\n\
         </Cells>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_",
        points + connectivity,
        points + connectivity + offsets,
    )?;
    out.write_all(&(12 * nv).to_le_bytes())
}

/// The points, little-endian `f32`.
pub(super) fn points(vertices: &[[f32; 3]], out: &mut dyn Write) -> io::Result<()> {
    write_points(out, vertices, super::Encoding::Binary, ByteOrder::Little)
}

/// The connectivity's byte count.
pub(super) fn connectivity_header(nt: u64, out: &mut dyn Write) -> io::Result<()> {
    out.write_all(&(24 * nt).to_le_bytes())
}

/// Connectivity records: three `Int64` indices per triangle.
pub(super) fn connectivity(triangles: &[[u32; 3]], out: &mut dyn Write) -> io::Result<()> {
    write_encoded_by(
        Workers::Pool,
        out,
        triangles,
        records_per_block(24),
        |buf, t| {
            for &i in t {
                buf.extend_from_slice(&i64::from(i).to_le_bytes());
            }
        },
    )
}

/// Offsets and types, which follow from `nt` alone, and the closing tags.
pub(super) fn tail(nt: u64, out: &mut dyn Write) -> io::Result<()> {
    const BLOCK: u64 = 1 << 16;
    let mut buf = Vec::with_capacity(8 * BLOCK as usize);
    out.write_all(&(8 * nt).to_le_bytes())?;
    let mut start = 0;
    while start < nt {
        let end = (start + BLOCK).min(nt);
        buf.clear();
        for cell in start..end {
            buf.extend_from_slice(&(3 * (cell as i64 + 1)).to_le_bytes());
        }
        out.write_all(&buf)?;
        start = end;
    }
    out.write_all(&nt.to_le_bytes())?;
    let types = vec![TRIANGLE; BLOCK as usize];
    let mut left = nt;
    while left > 0 {
        let n = left.min(BLOCK);
        out.write_all(&types[..n as usize])?;
        left -= n;
    }
    out.write_all(b"\n</AppendedData>\n</VTKFile>\n")
}
