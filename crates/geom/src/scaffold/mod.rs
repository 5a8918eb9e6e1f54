//! Scaffold meshes: the unstructured meshes a lattice is tiled into (docs/method.md §Element maps,
//! §Tiling and continuity).
//!
//! A [`Scaffold`] is a mesh of one [`ElementKind`] (tri3/tri6, quad4/quad8/quad9, tet4/tet10,
//! hex8/hex20/hex27) in Gmsh's local node order, read from bytes ([`read_scaffold`]: Gmsh
//! `.msh` 2.2/4.1 ASCII and binary, VTK legacy and `.vtu`, Abaqus `.inp`, OBJ/OFF surfaces) or
//! generated from a box ([`grid`]).
//!
//! Invariants of a returned scaffold:
//! - `connectivity` holds `kind.node_count()` indices per element, each < `nodes.len()`; every
//!   coordinate is finite and within single precision (`|c| ≤ f32::MAX`, as tiled meshes
//!   store vertices); there is at least one element. `node_tags`, `element_tags`,
//!   `physical` and every `node_data[..].values` are parallel to `nodes` or to the elements.
//! - Only elements of the highest dimension in the file are kept (boundary triangles, lines and
//!   points of a volume mesh are dropped), and they are all of one kind: anything else is an
//!   error naming the types found with their counts. Nodes are kept as the file lists them
//!   (including any that only dropped elements used), in file order.
//! - Readers take bytes and a display name, never paths, and never panic: every error names
//!   the file and a line (text), byte offset (binary) or element tag, and what was expected.
//!   Counts in headers are trusted only as far as the bytes that follow can hold them.
//! - Nothing here checks element quality: [`check`] does (inverted or degenerate elements).

mod assemble;
mod check;
mod cursor;
mod element;
mod facets;
mod grid;
mod inp;
mod map;
mod msh;
mod smooth;
mod surface;
mod vtk;
mod xml;

use std::fmt;

pub use check::check;
pub use element::{ElementKind, HEX_CORNERS};
pub use facets::{Facet, FacetSide, Facets};
pub use grid::grid;
pub use map::{Quadrature, gauss_legendre};
pub use smooth::SmoothMap;

/// A mesh of one element kind, with the file's tags, physical groups and nodal data.
#[derive(Clone, Debug, PartialEq)]
pub struct Scaffold {
    pub kind: ElementKind,
    /// Node positions; 2D meshes keep z (z = 0 in the plane, or surfaces in 3D).
    pub nodes: Vec<[f64; 3]>,
    /// `kind.node_count()` node indices per element, in Gmsh's local order.
    pub connectivity: Vec<u32>,
    /// The file's tag of each node (for messages): Gmsh/Abaqus/OBJ tags as written, the
    /// 0-based point index for VTK and OFF.
    pub node_tags: Vec<u64>,
    /// The file's tag (id) of each element, like `node_tags`.
    pub element_tags: Vec<u64>,
    /// Physical group per element where the file has one, else 0.
    pub physical: Vec<i64>,
    /// (tag, dimension, name) of the file's physical groups (Abaqus: element sets, numbered
    /// from 1 in order of appearance).
    pub physical_names: Vec<(i64, u32, String)>,
    /// Gmsh `$NodeData` views with one component (VTK: point data with one component).
    pub node_data: Vec<NodeData>,
    /// The display name given to the reader (`grid` for generated scaffolds), for messages.
    pub source: String,
    /// C¹ maps replacing the isoparametric ones ([`Scaffold::make_c1`]); `None` as read.
    pub smooth: Option<std::sync::Arc<SmoothMap>>,
}

/// One nodal scalar field, by name.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeData {
    pub name: String,
    /// One value per node, in `nodes` order.
    pub values: Vec<f64>,
}

impl Scaffold {
    pub fn element_count(&self) -> usize {
        self.element_tags.len()
    }

    /// The node indices of element `e`.
    pub fn element(&self, e: usize) -> &[u32] {
        let n = self.kind.node_count();
        &self.connectivity[e * n..(e + 1) * n]
    }

    /// The node data view called `name`, if any.
    pub fn node_data(&self, name: &str) -> Option<&NodeData> {
        self.node_data.iter().find(|d| d.name == name)
    }
}

/// Where in a file an error was found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Location {
    /// Nowhere in particular (the file as a whole).
    File,
    /// A line of a text file, counted from 1.
    Line(u64),
    /// A byte offset in a binary file, counted from 0.
    Byte(u64),
}

/// A scaffold that could not be read, generated or accepted.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScaffoldError {
    /// The display name of the file (or `grid`).
    pub file: String,
    pub at: Location,
    /// What was found and what was expected.
    pub message: String,
}

impl ScaffoldError {
    pub fn new(file: &str, at: Location, message: impl Into<String>) -> ScaffoldError {
        ScaffoldError {
            file: file.to_string(),
            at,
            message: message.into(),
        }
    }
}

impl fmt::Display for ScaffoldError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.at {
            Location::File => write!(f, "{}: {}", self.file, self.message),
            Location::Line(line) => write!(f, "{}:{}: {}", self.file, line, self.message),
            Location::Byte(byte) => write!(f, "{}: byte {}: {}", self.file, byte, self.message),
        }
    }
}

impl std::error::Error for ScaffoldError {}

/// A scaffold file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScaffoldFormat {
    Msh,
    VtkLegacy,
    Vtu,
    Inp,
    Obj,
    Off,
}

impl ScaffoldFormat {
    /// The format an extension names (`msh`, `vtk`, `vtu`, `inp`, `obj`, `off`; any case, with
    /// or without the dot).
    pub fn from_extension(ext: &str) -> Option<ScaffoldFormat> {
        match ext.trim_start_matches('.').to_ascii_lowercase().as_str() {
            "msh" => Some(ScaffoldFormat::Msh),
            "vtk" => Some(ScaffoldFormat::VtkLegacy),
            "vtu" => Some(ScaffoldFormat::Vtu),
            "inp" => Some(ScaffoldFormat::Inp),
            "obj" => Some(ScaffoldFormat::Obj),
            "off" => Some(ScaffoldFormat::Off),
            _ => None,
        }
    }

    /// The format the content shows (leading keywords), if it shows one.
    pub fn detect(bytes: &[u8]) -> Option<ScaffoldFormat> {
        let start = bytes
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(bytes.len());
        let head = &bytes[start..];
        let starts =
            |s: &str| head.len() >= s.len() && head[..s.len()].eq_ignore_ascii_case(s.as_bytes());
        if starts("$MeshFormat") {
            Some(ScaffoldFormat::Msh)
        } else if starts("# vtk DataFile") {
            Some(ScaffoldFormat::VtkLegacy)
        } else if starts("<?xml") || starts("<VTKFile") {
            Some(ScaffoldFormat::Vtu)
        } else if starts("*") {
            Some(ScaffoldFormat::Inp)
        } else if starts("OFF") || starts("COFF") || starts("NOFF") {
            Some(ScaffoldFormat::Off)
        } else {
            // OBJ: the first keyword line is a comment or one of OBJ's records.
            let line = head.split(|&b| b == b'\n').next().unwrap_or(&[]);
            let word = line
                .split(|b| b.is_ascii_whitespace())
                .next()
                .unwrap_or(&[]);
            matches!(
                word,
                b"#" | b"v" | b"vn" | b"vt" | b"f" | b"o" | b"g" | b"s" | b"mtllib" | b"usemtl"
            )
            .then_some(ScaffoldFormat::Obj)
        }
    }
}

/// Reads a scaffold from a file's bytes. The format is decided by content; `format_hint` (an
/// extension such as `"msh"` or `".vtu"`) decides only when the content shows none.
pub fn read_scaffold(
    bytes: &[u8],
    name: &str,
    format_hint: Option<&str>,
) -> Result<Scaffold, ScaffoldError> {
    let format = ScaffoldFormat::detect(bytes)
        .or_else(|| format_hint.and_then(ScaffoldFormat::from_extension))
        .ok_or_else(|| {
            ScaffoldError::new(
                name,
                Location::File,
                "not a scaffold mesh: expected Gmsh .msh ($MeshFormat), VTK legacy (# vtk DataFile), \
VTK XML (<VTKFile), Abaqus .inp (*NODE), OBJ or OFF",
            )
        })?;
    match format {
        ScaffoldFormat::Msh => msh::read(bytes, name),
        ScaffoldFormat::VtkLegacy => vtk::read_legacy(bytes, name),
        ScaffoldFormat::Vtu => vtk::read_xml(bytes, name),
        ScaffoldFormat::Inp => inp::read(bytes, name),
        ScaffoldFormat::Obj => surface::read_obj(bytes, name),
        ScaffoldFormat::Off => surface::read_off(bytes, name),
    }
}
