//! VTK legacy polydata, ASCII or BINARY.
//!
//! ```text
//! # vtk DataFile Version 3.0
//! latticebuild mesh (the stamp: latticebuild 0.1.0 mesh, units: mm)
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
use super::encode::{ByteOrder, write_points, write_polygons};
use super::stamp::Stamp;
use crate::mesh::Mesh;
use std::io::{self, Write};

pub(super) fn write(
    mesh: &Mesh,
    encoding: Encoding,
    stamp: &Stamp,
    out: &mut dyn Write,
) -> io::Result<()> {
    let (nv, nt) = (mesh.vertices.len() as u64, mesh.triangles.len() as u64);
    header(nv, nt, encoding, stamp, out)?;
    points(&mesh.vertices, encoding, out)?;
    polygons_header(nt, encoding, out)?;
    polygons(&mesh.triangles, encoding, out)?;
    end(encoding, out)
}

/// Everything before the points, after checking the 32-bit limits.
pub(super) fn header(
    nv: u64,
    nt: u64,
    encoding: Encoding,
    stamp: &Stamp,
    out: &mut dyn Write,
) -> io::Result<()> {
    let limit = i32::MAX as u64;
    if nv > limit + 1 || nt.saturating_mul(4) > limit {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "legacy VTK counts and indices are 32-bit signed: \
                 mesh has {nv} vertices, {nt} triangles"
            ),
        ));
    }
    let name = match encoding {
        Encoding::Binary => "BINARY",
        Encoding::Ascii => "ASCII",
    };
    // The title line: at most 256 characters.
    let mut title = format!("{} mesh", stamp.generator());
    if let Some(units) = stamp.units {
        title.push_str(", units: ");
        title.push_str(units.name());
    }
    let title: String = title.chars().take(255).collect();
    write!(
        out,
        "# vtk DataFile Version 3.0\n{title}\n{name}\nDATASET POLYDATA\n\
         POINTS {nv} float\n"
    )
}

/// Point records, in order.
pub(super) fn points(
    vertices: &[[f32; 3]],
    encoding: Encoding,
    out: &mut dyn Write,
) -> io::Result<()> {
    write_points(out, vertices, encoding, ByteOrder::Big)
}

/// The `POLYGONS` line between the sections (a binary section ends with its own newline).
pub(super) fn polygons_header(nt: u64, encoding: Encoding, out: &mut dyn Write) -> io::Result<()> {
    let ints = nt * 4;
    match encoding {
        Encoding::Binary => write!(out, "\nPOLYGONS {nt} {ints}\n"),
        Encoding::Ascii => writeln!(out, "POLYGONS {nt} {ints}"),
    }
}

/// Polygon records, in order: the corner count and three indices, each an `int`.
pub(super) fn polygons(
    triangles: &[[u32; 3]],
    encoding: Encoding,
    out: &mut dyn Write,
) -> io::Result<()> {
    write_polygons(
        out,
        triangles,
        encoding,
        &3i32.to_be_bytes(),
        ByteOrder::Big,
    )
}

/// What follows the polygons: the binary section's newline.
pub(super) fn end(encoding: Encoding, out: &mut dyn Write) -> io::Result<()> {
    match encoding {
        Encoding::Binary => out.write_all(b"\n"),
        Encoding::Ascii => Ok(()),
    }
}
