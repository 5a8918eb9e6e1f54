//! Mesh writers: STL, PLY, OBJ, OFF, VTK legacy polydata, VTK XML unstructured grid (`vtu`) and
//! 3MF, streamed to any `io::Write`.
//!
//! Invariant: writers never open files; the caller hands them a buffered writer (the CLI
//! writes to a temporary file and renames it into place).
//!
//! Further invariants of [`write_mesh`]:
//! - The input is checked before the first byte is written: every triangle index must be in
//!   range and every coordinate finite, or the call fails with `InvalidInput` and writes nothing.
//!   Format limits (32-bit counts and indices) are checked the same way.
//! - Text and binary encodings hold the same values: text prints each `f32` with the shortest
//!   decimal that parses back to it bit for bit.
//! - A [`Stamp`] (generator and version, unit, title, parameters) changes headers, comments
//!   and metadata only; [`write_mesh`] writes the anonymous [`Stamp::default`].
//! - Every vertex is written by the indexed formats (all but STL), so indices in the file
//!   are the mesh's own (plus one for OBJ). STL has no indices and repeats positions per facet.
//! - [`write_chunked`] writes a mesh held as [`crate::mesh::MeshChunk`]s, a chunk at a time,
//!   with exactly the bytes `write_mesh` writes for the concatenated mesh. Chunks are checked
//!   (as above, and against the chunk invariants) as they come, so a bad chunk fails the call
//!   midway: the caller discards the partial output (the CLI's files are temporary until
//!   renamed).
//! - Output is produced in blocks of about 1 MiB, encoded in parallel and written in order with
//!   `write_all`; any error of `out` is returned as is, and the writer is flushed at the end.

mod chunked;
mod encode;
mod obj;
mod off;
mod ply;
mod stamp;
mod stl;
pub mod svg;
pub mod threemf;
mod vtk;
mod vtu;
mod zip;

use crate::mesh::Mesh;
use rayon::prelude::*;
use std::io::{self, Write};

pub use chunked::{ChunkSource, Pass, StlStream, write_chunked, write_chunked_stamped};
pub use encode::Workers;
pub use stamp::{Stamp, Units};
pub use svg::{scaffold_svg, with_physical_size, write_svg};

/// Writes `mesh` to `out` in `format`, anonymously ([`Stamp::default`]). `encoding` chooses
/// binary or text for STL, PLY and VTK and is ignored by the others (OBJ and OFF are always
/// text, VTU and 3MF always binary).
pub fn write_mesh(
    mesh: &Mesh,
    format: Format,
    encoding: Encoding,
    out: &mut dyn Write,
) -> io::Result<()> {
    write_mesh_stamped(mesh, format, encoding, &Stamp::default(), out)
}

/// [`write_mesh`] with the headers and metadata of `stamp`.
pub fn write_mesh_stamped(
    mesh: &Mesh,
    format: Format,
    encoding: Encoding,
    stamp: &Stamp,
    out: &mut dyn Write,
) -> io::Result<()> {
    check_input(mesh)?;
    match format {
        Format::Stl => stl::write(mesh, encoding, stamp, out)?,
        Format::Ply => ply::write(mesh, encoding, stamp, out)?,
        Format::Obj => obj::write(mesh, stamp, out)?,
        Format::Off => off::write(mesh, out)?,
        Format::Vtk => vtk::write(mesh, encoding, stamp, out)?,
        Format::Vtu => vtu::write(mesh, stamp, out)?,
        Format::ThreeMf => threemf::write(mesh, stamp, out)?,
    }
    out.flush()
}

/// Rejects meshes that no format can represent faithfully: an out-of-range index would make
/// the writers fail halfway (STL) or write a corrupt file (the others), and a non-finite
/// coordinate is not a point (most readers reject `NaN`/`inf`).
fn check_input(mesh: &Mesh) -> io::Result<()> {
    check_indices(&mesh.triangles, mesh.vertices.len() as u64, 0)?;
    check_finite(&mesh.vertices, 0)
}

/// Branch-free folds over fixed blocks vectorize; the slow search for the culprit only runs
/// once a block is known to hold one.
const CHECK_BLOCK: usize = 1 << 16;

/// Every index of `triangles` (numbered from `first`) is below `n`.
fn check_indices(triangles: &[[u32; 3]], n: u64, first: u64) -> io::Result<()> {
    let indices_ok = triangles.par_chunks(CHECK_BLOCK).all(|chunk| {
        let largest = chunk.iter().flatten().fold(0, |m: u32, &i| m.max(i));
        u64::from(largest) < n
    });
    let in_range = |tri: &[u32; 3]| tri.iter().all(|&i| u64::from(i) < n);
    if !indices_ok && let Some(t) = triangles.iter().position(|tri| !in_range(tri)) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "triangle {} {:?} indexes past the {n} vertices",
                first + t as u64,
                triangles[t]
            ),
        ));
    }
    Ok(())
}

/// Every coordinate of `vertices` (numbered from `first`) is finite.
fn check_finite(vertices: &[[f32; 3]], first: u64) -> io::Result<()> {
    check_finite_by(Workers::Pool, vertices, first)
}

/// [`check_finite`] by `workers`.
fn check_finite_by(workers: Workers, vertices: &[[f32; 3]], first: u64) -> io::Result<()> {
    let finite = |p: &[f32; 3]| p.iter().all(|c| c.is_finite());
    let block_ok = |chunk: &[[f32; 3]]| {
        chunk
            .iter()
            .flatten()
            .fold(true, |ok, c| ok & c.is_finite())
    };
    let coordinates_ok = match workers {
        Workers::Pool => vertices.par_chunks(CHECK_BLOCK).all(block_ok),
        Workers::Caller => block_ok(vertices),
    };
    if !coordinates_ok && let Some(v) = vertices.iter().position(|p| !finite(p)) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "vertex {} {:?} has a non-finite coordinate",
                first + v as u64,
                vertices[v]
            ),
        ));
    }
    Ok(())
}

/// A mesh file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Format {
    Stl,
    Ply,
    Obj,
    Off,
    Vtk,
    Vtu,
    ThreeMf,
}

/// Binary or text, for the formats that have both (STL, PLY, VTK). OBJ and OFF are always
/// text, VTU and 3MF always binary.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Encoding {
    #[default]
    Binary,
    Ascii,
}

impl Format {
    pub const ALL: [Format; 7] = [
        Format::Stl,
        Format::Ply,
        Format::Obj,
        Format::Off,
        Format::Vtk,
        Format::Vtu,
        Format::ThreeMf,
    ];

    /// The manifest name of the format, which is also its file extension.
    pub fn name(self) -> &'static str {
        match self {
            Format::Stl => "stl",
            Format::Ply => "ply",
            Format::Obj => "obj",
            Format::Off => "off",
            Format::Vtk => "vtk",
            Format::Vtu => "vtu",
            Format::ThreeMf => "3mf",
        }
    }

    pub fn from_name(name: &str) -> Option<Format> {
        Format::ALL.into_iter().find(|f| f.name() == name)
    }
}

/// The CRC-32 of `bytes` (zip's), for readers that check a package's parts.
pub(crate) fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = zip::Crc32::new();
    crc.update(bytes);
    crc.value()
}
