//! Mesh readers: STL (ASCII and binary), OBJ, PLY (ASCII, binary little and big endian), OFF
//! and 3MF packages, from bytes to a [`TriangleSoup`].
//!
//! Invariants:
//! - Readers take bytes, never paths; the caller names the file in its own messages.
//! - No input makes a reader panic or allocate more than a small multiple of its input size:
//!   counts declared in headers are trusted only as far as the bytes that follow can hold them.
//! - A soup that is returned is usable as is: at least one triangle, every index in range, every
//!   coordinate finite. Anything else is a [`MeshReadError`] naming where it was found: a line
//!   (text formats, counted from 1), a byte offset (binary formats, from 0) and, for faces,
//!   the face's position in the file (counted from 0).
//! - Polygons are fan-triangulated from their first corner (`a b c d` gives `a b c`, `a c d`),
//!   which keeps their winding; for convex polygons, the only kind CAD exporters write, the fan
//!   is exact.
//! - Positions are kept as written: STL repeats each position per facet, and nothing is welded
//!   here (consumers that need shared vertices weld by exact position themselves).
//!
//! 3MF is the one format with a unit: [`read`] keeps its coordinates as written, and
//! [`read_auto_in`] converts them to the caller's unit.
//!
//! Format detection ([`detect`]) looks at the content only: a zip archive's magic (3MF), `ply` magic, an `OFF` keyword, a
//! binary STL whose size is exactly `84 + 50 n` for the count `n` in its header (many binary
//! STLs begin with `solid` too, so that word alone decides nothing), an ASCII STL beginning
//! with `solid` and holding only text, or OBJ keywords.
//!
//! We parse OBJ ourselves rather than through tobj: tobj's errors carry no line number, it reads
//! positions as `f32`, and only `v` and `f` records matter here. tobj stays a dev-dependency
//! that cross-checks this reader.

mod obj;
mod off;
mod ply;
mod soup;
mod stl;
mod text;
mod threemf;
mod unzip;

use std::fmt;
use thiserror::Error;

pub use soup::TriangleSoup;
pub use threemf::{ThreeMf, read as read_3mf};

use crate::mesh_io::Units;

/// A mesh file format this module reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Format {
    Stl,
    Obj,
    Ply,
    Off,
    ThreeMf,
}

impl Format {
    pub const ALL: [Format; 5] = [
        Format::Stl,
        Format::Obj,
        Format::Ply,
        Format::Off,
        Format::ThreeMf,
    ];

    /// The format a file extension names (`stl`, `obj`, `ply`, `off`, `3mf`, any case, with or
    /// without the leading dot).
    pub fn from_extension(extension: &str) -> Option<Format> {
        let ext = extension.trim_start_matches('.');
        Format::ALL
            .into_iter()
            .find(|f| f.extension().eq_ignore_ascii_case(ext))
    }

    pub fn extension(self) -> &'static str {
        match self {
            Format::Stl => "stl",
            Format::Obj => "obj",
            Format::Ply => "ply",
            Format::Off => "off",
            Format::ThreeMf => "3mf",
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Format::Stl => "STL",
            Format::Obj => "OBJ",
            Format::Ply => "PLY",
            Format::Off => "OFF",
            Format::ThreeMf => "3MF",
        })
    }
}

/// Where in a file a problem was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// A line of a text file, counted from 1.
    Line(usize),
    /// A byte offset in a binary file, counted from 0.
    Byte(usize),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(n) => write!(f, "line {n}"),
            Location::Byte(n) => write!(f, "byte {n}"),
        }
    }
}

/// Why a file could not be read. Face numbers count from 0 in file order.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum MeshReadError {
    #[error("{format} {at}: expected {expected}, found {found}")]
    Unexpected {
        format: Format,
        at: Location,
        expected: String,
        found: String,
    },
    #[error("{format} ends at {at} where {expected} was expected: the file is truncated")]
    Truncated {
        format: Format,
        at: Location,
        expected: String,
    },
    #[error(
        "binary STL: the header declares {declared} facets, which take {needed} bytes, but the \
         file has {actual} bytes (truncated, or not an STL file)"
    )]
    StlSize {
        declared: u64,
        needed: u64,
        actual: u64,
    },
    #[error("{format} {at}: vertex {vertex} has a non-finite coordinate ({value})")]
    NonFinite {
        format: Format,
        at: Location,
        vertex: usize,
        value: f64,
    },
    #[error(
        "{format} {at}: face {face} refers to vertex {index}, but the file has {count} vertices"
    )]
    IndexOutOfRange {
        format: Format,
        at: Location,
        face: usize,
        /// The index as written in the file (1-based or negative for OBJ).
        index: i64,
        count: usize,
    },
    #[error("{format}: the file holds no triangles")]
    Empty { format: Format },
    #[error("{format} {at}: {what} is not supported")]
    Unsupported {
        format: Format,
        at: Location,
        what: String,
    },
    #[error(
        "cannot tell the mesh format: the content is none of binary STL, ASCII STL (`solid`), \
         PLY (`ply`), OFF (`OFF`), OBJ (`v`/`f` lines) or 3MF (a zip package)"
    )]
    UnknownFormat,
}

/// Reads `bytes` as `format`. STL covers both encodings (told apart by content).
pub fn read(bytes: &[u8], format: Format) -> Result<TriangleSoup, MeshReadError> {
    let soup = match format {
        Format::Stl => stl::read(bytes)?,
        Format::Obj => obj::read(bytes)?,
        Format::Ply => ply::read(bytes)?,
        Format::Off => off::read(bytes)?,
        Format::ThreeMf => threemf::read(bytes)?.soup,
    };
    if soup.triangles.is_empty() {
        return Err(MeshReadError::Empty { format });
    }
    Ok(soup)
}

/// Vertex positions and their normals (empty when the vertices have none).
pub type PlyVertices = (Vec<[f64; 3]>, Vec<[f64; 3]>);

/// The vertices of a PLY file with their normals (`nx`, `ny`, `nz`), for point clouds: faces
/// are read but not needed.
pub fn read_ply_vertices(bytes: &[u8]) -> Result<PlyVertices, MeshReadError> {
    ply::read_with_normals(bytes).map(|(soup, normals)| (soup.positions, normals))
}

/// Reads `bytes` in the format its content shows ([`detect`]), or, when the content is not
/// conclusive, the format `extension` names.
pub fn read_auto(bytes: &[u8], extension: Option<&str>) -> Result<TriangleSoup, MeshReadError> {
    let format = detect(bytes)
        .or_else(|| extension.and_then(Format::from_extension))
        .ok_or(MeshReadError::UnknownFormat)?;
    read(bytes, format)
}

/// [`read_auto`], with a 3MF package's coordinates converted from its unit to `units`.
pub fn read_auto_in(
    bytes: &[u8],
    extension: Option<&str>,
    units: Units,
) -> Result<TriangleSoup, MeshReadError> {
    let format = detect(bytes)
        .or_else(|| extension.and_then(Format::from_extension))
        .ok_or(MeshReadError::UnknownFormat)?;
    if format != Format::ThreeMf {
        return read(bytes, format);
    }
    let model = threemf::read(bytes)?;
    let mut soup = model.soup;
    if soup.triangles.is_empty() {
        return Err(MeshReadError::Empty { format });
    }
    let scale = model.unit_mm / units.millimeters();
    if scale != 1.0 {
        for p in &mut soup.positions {
            *p = p.map(|c| c * scale);
        }
    }
    Ok(soup)
}

/// The format of `bytes` judged by content alone, or `None` when nothing is conclusive.
pub fn detect(bytes: &[u8]) -> Option<Format> {
    if bytes.starts_with(b"PK\x03\x04") {
        return Some(Format::ThreeMf);
    }
    if bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n") {
        return Some(Format::Ply);
    }
    if stl::is_binary(bytes) || stl::is_ascii(bytes) {
        return Some(Format::Stl);
    }
    let first = text::first_keyword(bytes)?;
    if off::is_keyword(first) {
        return Some(Format::Off);
    }
    const OBJ_KEYWORDS: [&[u8]; 9] = [
        b"v", b"vt", b"vn", b"f", b"o", b"g", b"s", b"mtllib", b"usemtl",
    ];
    OBJ_KEYWORDS.contains(&first).then_some(Format::Obj)
}
