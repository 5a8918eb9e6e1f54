//! VTK unstructured grids: legacy `.vtk` (ASCII, and binary big-endian) and XML `.vtu`
//! (DataArrays ASCII, inline base64 binary raw or zlib-compressed with UInt32/UInt64
//! headers, and appended data, raw or base64).
//!
//! Invariants:
//! - Points keep their file order; node tags are 0-based point indices and element tags
//!   0-based cell indices (what VTK tools show).
//! - Cell types 5, 22, 9, 23, 28, 10, 24, 12, 25, 29 become tri3 … hex27 with VTK's local node
//!   order rewritten into Gmsh's (tet10: the last two edges swap; hex20/hex27: edges and faces
//!   reordered); other cell types are known by dimension only (named in errors, dropped when
//!   of lower dimension).
//! - `.vtu` point data arrays with one component become node data.
//! - zlib inflating never produces more than each block's declared size.

use super::assemble::{ElementType, RawMesh, RawNodeData};
use super::cursor::{Cursor, Locator, show};
use super::xml::{Tag, base64_decode, find, next_tag};
use super::{ElementKind, Scaffold, ScaffoldError};
use crate::scalar::Scalar;

const HEX20_FROM_VTK: [usize; 20] = [
    0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 16, 9, 17, 10, 18, 19, 12, 15, 13, 14,
];
const HEX27_FACES_FROM_VTK: [usize; 7] = [24, 22, 20, 21, 23, 25, 26];

/// The kind of a VTK cell type, with its dimension and name.
fn vtk_type(code: i64) -> Option<ElementType> {
    let kind = match code {
        5 => Some(ElementKind::Tri3),
        22 => Some(ElementKind::Tri6),
        9 => Some(ElementKind::Quad4),
        23 => Some(ElementKind::Quad8),
        28 => Some(ElementKind::Quad9),
        10 => Some(ElementKind::Tet4),
        24 => Some(ElementKind::Tet10),
        12 => Some(ElementKind::Hex8),
        25 => Some(ElementKind::Hex20),
        29 => Some(ElementKind::Hex27),
        _ => None,
    };
    if let Some(k) = kind {
        return Some(ElementType::of(k));
    }
    let (name, dimension) = match code {
        1 => ("vertex", 0),
        2 => ("poly-vertex", 0),
        3 => ("line", 1),
        4 => ("poly-line", 1),
        21 => ("quadratic edge", 1),
        35 => ("cubic line", 1),
        6 => ("triangle strip", 2),
        7 => ("polygon", 2),
        8 => ("pixel", 2),
        11 => ("voxel", 3),
        13 => ("wedge", 3),
        14 => ("pyramid", 3),
        26 => ("quadratic wedge", 3),
        27 => ("quadratic pyramid", 3),
        42 => ("polyhedron", 3),
        _ => return None,
    };
    Some(ElementType {
        name: format!("VTK {name} (cell type {code})"),
        dimension,
        kind: None,
    })
}

/// Gmsh's local node `i` is VTK's local node `vtk_local(kind, i)`.
fn vtk_local(kind: Option<ElementKind>, i: usize) -> usize {
    match kind {
        Some(ElementKind::Tet10) if i >= 8 => 17 - i,
        Some(ElementKind::Hex20) => HEX20_FROM_VTK[i],
        Some(ElementKind::Hex27) if i < 20 => HEX20_FROM_VTK[i],
        Some(ElementKind::Hex27) => HEX27_FACES_FROM_VTK[i - 20],
        _ => i,
    }
}

/// Adds cells from VTK's arrays (types, offsets into `connectivity` ending each cell).
fn add_cells(
    raw: &mut RawMesh,
    loc: Locator<'_>,
    cell_at: &dyn Fn(usize) -> usize,
    types: &[i64],
    ends: &[u64],
    connectivity: &[u64],
) -> Result<(), ScaffoldError> {
    let mut type_ids: Vec<(i64, u16)> = Vec::new();
    let mut start = 0u64;
    for (c, (&code, &end)) in types.iter().zip(ends).enumerate() {
        let at = cell_at(c);
        if end < start || end > connectivity.len() as u64 {
            return Err(loc.error(
                at,
                format!(
                    "cell {c}: its connectivity ends at {end}, outside {start}..{}",
                    connectivity.len()
                ),
            ));
        }
        let nodes = &connectivity[start as usize..end as usize];
        start = end;
        let t = match type_ids.iter().find(|(k, _)| *k == code) {
            Some(&(_, t)) => t,
            None => {
                let ty = vtk_type(code).ok_or_else(|| {
                    loc.error(at, format!("cell {c}: unknown VTK cell type {code}"))
                })?;
                let t = raw.type_index(ty);
                type_ids.push((code, t));
                t
            }
        };
        let kind = raw.types[t as usize].kind;
        raw.begin_element(t, c as u64, 0, at);
        if let Some(k) = kind {
            if nodes.len() != k.node_count() {
                return Err(loc.error(
                    at,
                    format!(
                        "cell {c} ({k}, VTK cell type {code}) has {} points, expected {}",
                        nodes.len(),
                        k.node_count()
                    ),
                ));
            }
            for i in 0..nodes.len() {
                raw.element_nodes.push(nodes[vtk_local(kind, i)]);
            }
        } else {
            raw.element_nodes.extend_from_slice(nodes);
        }
    }
    Ok(())
}

fn to_index(v: f64, what: &str, loc: Locator<'_>, at: usize) -> Result<u64, ScaffoldError> {
    if v >= 0.0 && v.fract() == 0.0 && v < 9.0e15 {
        Ok(v as u64)
    } else {
        Err(loc.error(
            at,
            format!("expected {what} (a non-negative integer), found {v}"),
        ))
    }
}

// ----------------------------------------------------------------------------------------
// Legacy

pub(super) fn read_legacy(bytes: &[u8], name: &str) -> Result<Scaffold, ScaffoldError> {
    let mut cur = Cursor::new(bytes, name);
    let version_51 = legacy_header(&mut cur)?;
    let binary = cur.loc.binary;
    let mut grid = LegacyGrid {
        raw: RawMesh {
            indices_as_tags: true,
            ..RawMesh::default()
        },
        cells: None,
        cell_starts: Vec::new(),
        types: None,
        counts_51: (0, 0),
    };
    while let Some((at, keyword)) = cur.next_token() {
        let word = keyword.to_ascii_uppercase();
        match word.as_slice() {
            b"POINTS" => grid.points(&mut cur, binary)?,
            b"CELLS" => grid.cells(&mut cur, binary, version_51, at)?,
            b"OFFSETS" | b"CONNECTIVITY" => {
                grid.array_51(&mut cur, binary, word.as_slice() == b"OFFSETS", at)?
            }
            b"CELL_TYPES" => grid.cell_types(&mut cur, binary)?,
            b"CELL_DATA" | b"POINT_DATA" | b"FIELD" | b"METADATA" => break,
            _ => {
                return Err(cur.error(
                    at,
                    format!(
                        "expected POINTS, CELLS or CELL_TYPES, found `{}`",
                        show(keyword)
                    ),
                ));
            }
        }
    }
    grid.finish(cur.loc)
}

/// Reads a legacy file's header up to its `DATASET UNSTRUCTURED_GRID`, setting the cursor's
/// encoding; whether the file is version 5.1 (cells as OFFSETS and CONNECTIVITY arrays).
fn legacy_header(cur: &mut Cursor<'_>) -> Result<bool, ScaffoldError> {
    let bytes = cur.bytes();
    cur.skip_line(); // # vtk DataFile Version x.y
    let version_51 = {
        let first = &bytes[..cur.pos.min(bytes.len())];
        find(first, b"5.", 0).is_some()
    };
    cur.skip_line(); // title
    let (at, encoding) = cur.token("ASCII or BINARY")?;
    let binary = match encoding {
        e if e.eq_ignore_ascii_case(b"ASCII") => false,
        e if e.eq_ignore_ascii_case(b"BINARY") => true,
        e => return Err(cur.error(at, format!("expected ASCII or BINARY, found `{}`", show(e)))),
    };
    cur.big_endian = true;
    cur.loc.binary = binary;
    cur.expect("DATASET")?;
    let (at, dataset) = cur.token("a dataset type")?;
    if !dataset.eq_ignore_ascii_case(b"UNSTRUCTURED_GRID") {
        return Err(cur.error(
            at,
            format!(
                "expected DATASET UNSTRUCTURED_GRID, found `{}`",
                show(dataset)
            ),
        ));
    }
    Ok(version_51)
}

/// What a legacy file's sections have given so far.
struct LegacyGrid {
    raw: RawMesh,
    /// Where CELLS starts, each cell's end in the connectivity, and the connectivity.
    cells: Option<(usize, Vec<u64>, Vec<u64>)>,
    /// Where each cell starts (before 5.1).
    cell_starts: Vec<usize>,
    types: Option<Vec<i64>>,
    /// 5.1: the declared lengths of the OFFSETS and CONNECTIVITY arrays.
    counts_51: (usize, usize),
}

impl LegacyGrid {
    /// `POINTS n type` and the coordinates.
    fn points(&mut self, cur: &mut Cursor<'_>, binary: bool) -> Result<(), ScaffoldError> {
        let n = cur.count("the number of points", if binary { 12 } else { 6 })?;
        let ty = array_type(cur, "the point data type")?;
        if binary {
            cur.skip_line();
        }
        self.raw.nodes.reserve(n);
        for i in 0..n {
            let at = cur.mark();
            let mut p = [0.0; 3];
            for c in &mut p {
                *c = legacy_number(cur, binary, ty, "a point coordinate")?;
                super::cursor::finite(*c, "a point coordinate").map_err(|m| cur.error(at, m))?;
            }
            self.raw.push_node(i as u64, p, at);
        }
        Ok(())
    }

    /// `CELLS n size` (keyword at `at`) and, before 5.1, the cell list.
    fn cells(
        &mut self,
        cur: &mut Cursor<'_>,
        binary: bool,
        version_51: bool,
        at: usize,
    ) -> Result<(), ScaffoldError> {
        let n = cur.count("the number of cells", 4)?;
        let size = cur.count("the size of the cell list", if binary { 4 } else { 2 })?;
        if binary {
            cur.skip_line();
        }
        if version_51 {
            // 5.1: CELLS <offsets> <connectivity>, then OFFSETS and CONNECTIVITY arrays.
            self.counts_51 = (n, size);
            self.cells = Some((at, Vec::new(), Vec::new()));
            return Ok(());
        }
        let mut ends = Vec::with_capacity(n);
        let mut connectivity = Vec::with_capacity(size);
        for c in 0..n {
            let cat = cur.mark();
            self.cell_starts.push(cat);
            let k = legacy_index(cur, binary, Scalar::I32, "a cell's point count")?;
            let k = cur.check_count(cat, k, "a cell's point count", 2)?;
            if connectivity.len() + k + c + 1 > size {
                return Err(cur.error(
                    cat,
                    format!("the cell list is longer than its declared size {size}"),
                ));
            }
            for _ in 0..k {
                connectivity.push(legacy_index(cur, binary, Scalar::I32, "a point index")?);
            }
            ends.push(connectivity.len() as u64);
        }
        self.cells = Some((at, ends, connectivity));
        Ok(())
    }

    /// 5.1's `OFFSETS type` or `CONNECTIVITY type` (keyword at `at`) and its values.
    fn array_51(
        &mut self,
        cur: &mut Cursor<'_>,
        binary: bool,
        is_offsets: bool,
        at: usize,
    ) -> Result<(), ScaffoldError> {
        let ty = array_type(cur, "the array's data type")?;
        if binary {
            cur.skip_line();
        }
        let declared = if is_offsets {
            self.counts_51.0
        } else {
            self.counts_51.1
        };
        let declared = cur.check_count(
            at,
            declared as u64,
            "the array length",
            if binary { ty.size() } else { 2 },
        )?;
        let mut values = Vec::with_capacity(declared);
        for _ in 0..declared {
            values.push(legacy_index(cur, binary, ty, "an index")?);
        }
        let Some((_, ends, conn)) = self.cells.as_mut() else {
            return Err(cur.error(at, "OFFSETS or CONNECTIVITY before CELLS"));
        };
        if is_offsets {
            *ends = values.into_iter().skip(1).collect();
        } else {
            *conn = values;
        }
        Ok(())
    }

    /// `CELL_TYPES n` and the types.
    fn cell_types(&mut self, cur: &mut Cursor<'_>, binary: bool) -> Result<(), ScaffoldError> {
        let n = cur.count("the number of cell types", if binary { 4 } else { 2 })?;
        if binary {
            cur.skip_line();
        }
        let mut t = Vec::with_capacity(n);
        for _ in 0..n {
            let at = cur.mark();
            let v = legacy_index(cur, binary, Scalar::I32, "a cell type")?;
            t.push(i64::try_from(v).map_err(|_| cur.error(at, "cell type out of range"))?);
        }
        self.types = Some(t);
        Ok(())
    }

    /// The scaffold, once every section is read.
    fn finish(mut self, loc: Locator<'_>) -> Result<Scaffold, ScaffoldError> {
        let (cells_at, ends, connectivity) = self.cells.ok_or_else(|| {
            loc.file_error("no CELLS section: expected the cells of an unstructured grid")
        })?;
        let types = self
            .types
            .ok_or_else(|| loc.file_error("no CELL_TYPES section: expected one type per cell"))?;
        if types.len() != ends.len() {
            return Err(loc.error(
                cells_at,
                format!("{} cells but {} cell types", ends.len(), types.len()),
            ));
        }
        let cell_starts = self.cell_starts;
        let cell_at = |c: usize| cell_starts.get(c).copied().unwrap_or(cells_at);
        add_cells(&mut self.raw, loc, &cell_at, &types, &ends, &connectivity)?;
        self.raw.finish(loc)
    }
}

/// A legacy data type name (`what` the token is, for messages).
fn array_type(cur: &mut Cursor<'_>, what: &str) -> Result<Scalar, ScaffoldError> {
    let (at, ty) = cur.token(what)?;
    scalar_type(ty).ok_or_else(|| cur.error(at, format!("unknown VTK data type `{}`", show(ty))))
}

/// Legacy (`float`, `vtktypeint64`, …) and XML (`Float64`, `Int32`, …) type names.
fn scalar_type(name: &[u8]) -> Option<Scalar> {
    let lower = name.to_ascii_lowercase();
    Some(match lower.as_slice() {
        b"int8" | b"char" | b"vtktypeint8" => Scalar::I8,
        b"uint8" | b"unsigned_char" | b"vtktypeuint8" => Scalar::U8,
        b"int16" | b"short" | b"vtktypeint16" => Scalar::I16,
        b"uint16" | b"unsigned_short" | b"vtktypeuint16" => Scalar::U16,
        b"int32" | b"int" | b"vtktypeint32" => Scalar::I32,
        b"uint32" | b"unsigned_int" | b"vtktypeuint32" => Scalar::U32,
        b"int64" | b"long" | b"vtktypeint64" | b"vtkidtype" => Scalar::I64,
        b"uint64" | b"unsigned_long" | b"vtktypeuint64" => Scalar::U64,
        b"float32" | b"float" => Scalar::F32,
        b"float64" | b"double" => Scalar::F64,
        _ => return None,
    })
}

fn legacy_number(
    cur: &mut Cursor<'_>,
    binary: bool,
    ty: Scalar,
    what: &str,
) -> Result<f64, ScaffoldError> {
    if binary {
        let b = cur.take(ty.size(), what)?;
        Ok(ty.decode(b, true))
    } else {
        cur.float(what)
    }
}

fn legacy_index(
    cur: &mut Cursor<'_>,
    binary: bool,
    ty: Scalar,
    what: &str,
) -> Result<u64, ScaffoldError> {
    let at = cur.mark();
    let v = legacy_number(cur, binary, ty, what)?;
    to_index(v, what, cur.loc, at)
}

// ----------------------------------------------------------------------------------------
// XML

struct DataArray {
    name: String,
    section: Section,
    ty: Scalar,
    components: usize,
    format: Vec<u8>,
    /// The tag's start (for messages) and its text content.
    at: usize,
    content: (usize, usize),
    offset: Option<usize>,
}

#[derive(Clone, Copy, PartialEq)]
enum Section {
    Points,
    Cells,
    PointData,
    Other,
}

struct XmlFile<'a> {
    loc: Locator<'a>,
    big_endian: bool,
    header64: bool,
    zlib: bool,
    /// (encoding is base64, offset of the first byte after `_`).
    appended: Option<(bool, usize)>,
}

pub(super) fn read_xml(bytes: &[u8], name: &str) -> Result<Scaffold, ScaffoldError> {
    let loc = Locator {
        bytes,
        name,
        binary: false,
    };
    let (file, arrays, piece) = scan_xml(loc)?;
    let (piece_at, n_points, n_cells) = piece;
    // zlib shrinks data by at most about 1000:1, so no honest file declares more than this.
    let most = bytes.len().saturating_mul(1100);
    if n_points.saturating_mul(3) > most || n_cells > most {
        return Err(loc.error(
            piece_at,
            format!("Piece declares {n_points} points and {n_cells} cells, more than a file of {} bytes can hold", bytes.len()),
        ));
    }
    let grid = XmlGrid {
        file: &file,
        arrays: &arrays,
        piece_at,
        appended_offsets: {
            let mut offsets: Vec<usize> = arrays.iter().filter_map(|a| a.offset).collect();
            offsets.sort_unstable();
            offsets
        },
    };
    let mut raw = RawMesh {
        indices_as_tags: true,
        ..RawMesh::default()
    };
    grid.points(&mut raw, n_points)?;
    grid.cells(&mut raw, n_cells)?;
    grid.point_data(&mut raw, n_points)?;
    raw.finish(loc)
}

/// A Piece tag's start, and its numbers of points and cells.
type PieceCounts = (usize, usize, usize);

/// Reads a `.vtu` file's tags: its encoding, its DataArrays (where their data is, not yet
/// decoded) and its one Piece.
fn scan_xml(loc: Locator<'_>) -> Result<(XmlFile<'_>, Vec<DataArray>, PieceCounts), ScaffoldError> {
    let bytes = loc.bytes;
    let mut file = XmlFile {
        loc,
        big_endian: false,
        header64: false,
        zlib: false,
        appended: None,
    };
    let mut arrays = Vec::new();
    let mut section = Section::Other;
    let mut piece: Option<PieceCounts> = None;
    let mut saw_vtk = false;
    let mut pos = 0;
    while let Some(tag) = next_tag(bytes, pos) {
        let tag: Tag<'_> = tag.map_err(|at| loc.error(at, "unterminated XML tag: expected `>`"))?;
        pos = tag.end;
        match (tag.name, tag.closing) {
            (b"VTKFile", false) => {
                saw_vtk = true;
                file.read_attributes(&tag)?;
            }
            (b"Piece", false) => {
                if piece.is_some() {
                    return Err(loc.error(
                        tag.start,
                        "more than one Piece: expected a single unstructured grid piece",
                    ));
                }
                piece = Some(piece_counts(&tag, loc)?);
            }
            (b"Points", closing) => {
                section = if closing {
                    Section::Other
                } else {
                    Section::Points
                }
            }
            (b"Cells", closing) => {
                section = if closing {
                    Section::Other
                } else {
                    Section::Cells
                }
            }
            (b"PointData", closing) => {
                section = if closing || tag.empty {
                    Section::Other
                } else {
                    Section::PointData
                }
            }
            (b"DataArray", false) => arrays.push(DataArray::new(&tag, loc, section)?),
            (b"AppendedData", false) => {
                let base64 = tag.attribute("encoding") != Some(b"raw");
                let underscore = bytes[tag.end..]
                    .iter()
                    .position(|&b| b == b'_')
                    .map(|k| tag.end + k + 1);
                let start = underscore
                    .ok_or_else(|| loc.error(tag.start, "AppendedData without its `_` marker"))?;
                file.appended = Some((base64, start));
                break; // raw appended bytes may contain anything, '<' included
            }
            _ => {}
        }
    }
    if !saw_vtk {
        return Err(loc.file_error("no <VTKFile> element: expected a VTK XML unstructured grid"));
    }
    let piece =
        piece.ok_or_else(|| loc.file_error("no <Piece>: expected one unstructured grid piece"))?;
    Ok((file, arrays, piece))
}

/// A Piece tag's start, NumberOfPoints and NumberOfCells.
fn piece_counts(tag: &Tag<'_>, loc: Locator<'_>) -> Result<PieceCounts, ScaffoldError> {
    let number = |key: &str| {
        tag.attribute(key)
            .and_then(|v| std::str::from_utf8(v).ok()?.trim().parse::<usize>().ok())
            .ok_or_else(|| {
                loc.error(
                    tag.start,
                    format!("Piece needs a {key} attribute (a non-negative integer)"),
                )
            })
    };
    Ok((
        tag.start,
        number("NumberOfPoints")?,
        number("NumberOfCells")?,
    ))
}

impl DataArray {
    /// A DataArray tag in `section`, its content up to the next tag.
    fn new(tag: &Tag<'_>, loc: Locator<'_>, section: Section) -> Result<DataArray, ScaffoldError> {
        let bytes = loc.bytes;
        let ty_name = tag.attribute("type").unwrap_or(b"");
        let ty = scalar_type(ty_name).ok_or_else(|| {
            loc.error(
                tag.start,
                format!("DataArray has unknown type \"{}\"", show(ty_name)),
            )
        })?;
        let components = match tag.attribute("NumberOfComponents") {
            None => 1,
            Some(v) => std::str::from_utf8(v)
                .ok()
                .and_then(|s| s.trim().parse::<usize>().ok())
                .filter(|&c| (1..=64).contains(&c))
                .ok_or_else(|| {
                    loc.error(tag.start, format!("bad NumberOfComponents \"{}\"", show(v)))
                })?,
        };
        let content_end = if tag.empty {
            tag.end
        } else {
            bytes[tag.end..]
                .iter()
                .position(|&b| b == b'<')
                .map_or(bytes.len(), |k| tag.end + k)
        };
        let offset = tag
            .attribute("offset")
            .and_then(|v| std::str::from_utf8(v).ok()?.trim().parse::<usize>().ok());
        Ok(DataArray {
            name: tag.attribute_str("Name").unwrap_or_default(),
            section,
            ty,
            components,
            format: tag.attribute("format").unwrap_or(b"ascii").to_vec(),
            at: tag.start,
            content: (tag.end, content_end),
            offset,
        })
    }
}

/// A `.vtu` file's arrays, to be decoded into a mesh.
struct XmlGrid<'g> {
    file: &'g XmlFile<'g>,
    arrays: &'g [DataArray],
    /// Where the Piece tag starts (for messages).
    piece_at: usize,
    /// The appended arrays' offsets, in order (where each base64 array ends).
    appended_offsets: Vec<usize>,
}

impl XmlGrid<'_> {
    fn find(&self, section: Section, name: Option<&str>) -> Option<&DataArray> {
        self.arrays
            .iter()
            .find(|a| a.section == section && name.is_none_or(|n| a.name.eq_ignore_ascii_case(n)))
    }

    fn values(&self, a: &DataArray, count: usize) -> Result<Vec<f64>, ScaffoldError> {
        self.file.values(a, count, &self.appended_offsets)
    }

    /// The Points array's `n_points` points, as nodes.
    fn points(&self, raw: &mut RawMesh, n_points: usize) -> Result<(), ScaffoldError> {
        let loc = self.file.loc;
        let points = self.find(Section::Points, None).ok_or_else(|| {
            loc.error(
                self.piece_at,
                "no Points DataArray: expected the point coordinates",
            )
        })?;
        if points.components != 3 {
            return Err(loc.error(
                points.at,
                format!("Points has {} components, expected 3", points.components),
            ));
        }
        let coordinates = self.values(points, n_points * 3)?;
        for i in 0..n_points {
            let p = [
                coordinates[3 * i],
                coordinates[3 * i + 1],
                coordinates[3 * i + 2],
            ];
            if let Some(bad) = p.iter().find(|v| !v.is_finite()) {
                return Err(loc.error(
                    points.at,
                    format!("point {i}: expected a finite coordinate, found {bad}"),
                ));
            }
            raw.push_node(i as u64, p, points.at);
        }
        Ok(())
    }

    /// The `n_cells` cells of the Cells arrays connectivity, offsets and types.
    fn cells(&self, raw: &mut RawMesh, n_cells: usize) -> Result<(), ScaffoldError> {
        let loc = self.file.loc;
        let cell_array = |name: &str| {
            self.find(Section::Cells, Some(name))
                .ok_or_else(|| loc.error(self.piece_at, format!("no Cells DataArray \"{name}\"")))
        };
        let conn_array = cell_array("connectivity")?;
        let offsets_array = cell_array("offsets")?;
        let types_array = cell_array("types")?;
        let offsets = self.values(offsets_array, n_cells)?;
        let types = self.values(types_array, n_cells)?;
        let ends: Vec<u64> = offsets
            .iter()
            .map(|&v| to_index(v, "a cell offset", loc, offsets_array.at))
            .collect::<Result<_, _>>()?;
        let conn_len = ends.last().copied().unwrap_or(0) as usize;
        let connectivity: Vec<u64> = self
            .values(conn_array, conn_len)?
            .iter()
            .map(|&v| to_index(v, "a point index", loc, conn_array.at))
            .collect::<Result<_, _>>()?;
        let types: Vec<i64> = types
            .iter()
            .map(|&v| to_index(v, "a cell type", loc, types_array.at).map(|t| t as i64))
            .collect::<Result<_, _>>()?;
        add_cells(raw, loc, &|_| conn_array.at, &types, &ends, &connectivity)
    }

    /// The one-component PointData arrays, as node data.
    fn point_data(&self, raw: &mut RawMesh, n_points: usize) -> Result<(), ScaffoldError> {
        for a in self
            .arrays
            .iter()
            .filter(|a| a.section == Section::PointData && a.components == 1)
        {
            let values = self.values(a, n_points)?;
            raw.node_data.push(RawNodeData {
                name: a.name.clone(),
                at: a.at,
                values: values
                    .iter()
                    .enumerate()
                    .map(|(i, &v)| (i as u64, v, a.at))
                    .collect(),
            });
        }
        Ok(())
    }
}

impl XmlFile<'_> {
    /// The VTKFile tag's type, byte order, header type and compressor.
    fn read_attributes(&mut self, tag: &Tag<'_>) -> Result<(), ScaffoldError> {
        let loc = self.loc;
        if tag
            .attribute("type")
            .is_some_and(|t| t != b"UnstructuredGrid")
        {
            return Err(loc.error(
                tag.start,
                format!(
                    "expected a VTK UnstructuredGrid file, found type \"{}\"",
                    tag.attribute_str("type").unwrap_or_default()
                ),
            ));
        }
        self.big_endian = tag.attribute("byte_order") == Some(b"BigEndian");
        self.header64 = tag.attribute("header_type") == Some(b"UInt64");
        match tag.attribute("compressor") {
            None | Some(b"") => {}
            Some(b"vtkZLibDataCompressor") => self.zlib = true,
            Some(other) => {
                return Err(loc.error(
                    tag.start,
                    format!(
                        "unsupported compressor \"{}\": expected vtkZLibDataCompressor or none",
                        show(other)
                    ),
                ));
            }
        }
        Ok(())
    }
    /// Exactly `count` values of an array (components included), as f64.
    fn values(
        &self,
        a: &DataArray,
        count: usize,
        offsets: &[usize],
    ) -> Result<Vec<f64>, ScaffoldError> {
        let loc = self.loc;
        let bytes = loc.bytes;
        let values = match a.format.as_slice() {
            b"ascii" => {
                let mut cur = Cursor::new(&bytes[..a.content.1], loc.name);
                cur.pos = a.content.0;
                let mut v = Vec::with_capacity(count.min(bytes.len()));
                for _ in 0..count {
                    v.push(cur.float(&format!("a value of DataArray \"{}\"", a.name))?);
                }
                if cur.next_token().is_some() {
                    return Err(loc.error(
                        a.at,
                        format!("DataArray \"{}\" has more than {count} values", a.name),
                    ));
                }
                v
            }
            b"binary" => {
                let text = &bytes[a.content.0..a.content.1];
                let decoded = base64_decode(text, a.content.0).map_err(|at| {
                    loc.error(at, format!("bad base64 in DataArray \"{}\"", a.name))
                })?;
                self.unpack(a, &decoded, count)?
            }
            b"appended" => {
                let (base64, start) = self.appended.ok_or_else(|| {
                    loc.error(
                        a.at,
                        format!(
                            "DataArray \"{}\" is appended, but there is no AppendedData",
                            a.name
                        ),
                    )
                })?;
                let offset = a.offset.ok_or_else(|| {
                    loc.error(
                        a.at,
                        format!("appended DataArray \"{}\" has no offset", a.name),
                    )
                })?;
                let from = start
                    .checked_add(offset)
                    .filter(|&f| f <= bytes.len())
                    .ok_or_else(|| {
                        loc.error(
                            a.at,
                            format!(
                                "DataArray \"{}\": offset {offset} is past the end of the file",
                                a.name
                            ),
                        )
                    })?;
                if base64 {
                    let next = offsets.iter().find(|&&o| o > offset).map(|&o| start + o);
                    let end = next
                        .or_else(|| find(bytes, b"</AppendedData>", from))
                        .unwrap_or(bytes.len())
                        .min(bytes.len());
                    let decoded = base64_decode(&bytes[from..end], from).map_err(|at| {
                        loc.error(at, format!("bad base64 in DataArray \"{}\"", a.name))
                    })?;
                    self.unpack(a, &decoded, count)?
                } else {
                    self.unpack(a, &bytes[from..], count)?
                }
            }
            other => {
                return Err(loc.error(
                    a.at,
                    format!(
                        "unknown DataArray format \"{}\": expected ascii, binary or appended",
                        show(other)
                    ),
                ));
            }
        };
        if values.len() != count {
            return Err(loc.error(
                a.at,
                format!(
                    "DataArray \"{}\" has {} values, expected {count}",
                    a.name,
                    values.len()
                ),
            ));
        }
        Ok(values)
    }

    /// Header(s) + data of a binary array (raw or zlib blocks) to `count` values.
    fn unpack(&self, a: &DataArray, data: &[u8], count: usize) -> Result<Vec<f64>, ScaffoldError> {
        let loc = self.loc;
        let mut cur = Cursor::new(data, loc.name);
        cur.big_endian = self.big_endian;
        let payload: Vec<u8>;
        let body: &[u8] = if self.zlib {
            payload = self.inflate(a, &mut cur, count)?;
            &payload
        } else {
            let n = self.header(a, &mut cur)?;
            let n = usize::try_from(n).map_err(|_| truncated(loc, a, "data"))?;
            cur.take(n, "data").map_err(|_| truncated(loc, a, "data"))?
        };
        let size = a.ty.size();
        if body.len() < count * size {
            return Err(loc.error(
                a.at,
                format!(
                    "DataArray \"{}\" holds {} bytes, expected {} ({count} values)",
                    a.name,
                    body.len(),
                    count * size
                ),
            ));
        }
        Ok(body[..count * size]
            .chunks_exact(size)
            .map(|c| a.ty.decode(c, self.big_endian))
            .collect())
    }

    /// One header number (UInt32 or UInt64) of array `a`'s binary data.
    fn header(&self, a: &DataArray, cur: &mut Cursor<'_>) -> Result<u64, ScaffoldError> {
        let trunc = || truncated(self.loc, a, "header");
        if self.header64 {
            cur.u64("a header").map_err(|_| trunc())
        } else {
            cur.i32("a header")
                .map(|v| v as u32 as u64)
                .map_err(|_| trunc())
        }
    }

    /// The zlib blocks of array `a` (block list at `cur`), inflated: the bytes of `count`
    /// values.
    fn inflate(
        &self,
        a: &DataArray,
        cur: &mut Cursor<'_>,
        count: usize,
    ) -> Result<Vec<u8>, ScaffoldError> {
        let loc = self.loc;
        let h = if self.header64 { 8 } else { 4 };
        let trunc = |what: &str| truncated(loc, a, what);
        let blocks = self.header(a, cur)?;
        let block_size = self.header(a, cur)?;
        let last_size = self.header(a, cur)?;
        let blocks = cur
            .check_count(0, blocks, "the number of compressed blocks", h)
            .map_err(|_| trunc("block list"))?;
        let mut sizes = Vec::with_capacity(blocks);
        for _ in 0..blocks {
            sizes.push(self.header(a, cur)?);
        }
        let expected = (count * a.ty.size()) as u64;
        if blocks > 0
            && block_size
                .saturating_mul(blocks as u64 - 1)
                .saturating_add(last_size)
                != expected
        {
            return Err(loc.error(
                a.at,
                format!(
                    "DataArray \"{}\": compressed blocks hold {} bytes, expected {expected}",
                    a.name,
                    block_size
                        .saturating_mul(blocks as u64 - 1)
                        .saturating_add(last_size)
                ),
            ));
        }
        let data_len = cur.bytes().len() as u64;
        let mut out = Vec::with_capacity(expected.min(data_len * 1100) as usize);
        for (b, &size) in sizes.iter().enumerate() {
            let size = usize::try_from(size).map_err(|_| trunc("block"))?;
            let block = cur
                .take(size, "a compressed block")
                .map_err(|_| trunc("compressed block"))?;
            let limit = if b + 1 == blocks {
                last_size
            } else {
                block_size
            } as usize;
            let inflated = miniz_oxide::inflate::decompress_to_vec_zlib_with_limit(block, limit)
                .map_err(|e| {
                    loc.error(
                        a.at,
                        format!(
                            "DataArray \"{}\": bad zlib data in block {b} ({:?})",
                            a.name, e.status
                        ),
                    )
                })?;
            if inflated.len() != limit {
                return Err(loc.error(
                    a.at,
                    format!(
                        "DataArray \"{}\": block {b} inflates to {} bytes, expected {limit}",
                        a.name,
                        inflated.len()
                    ),
                ));
            }
            out.extend_from_slice(&inflated);
        }
        Ok(out)
    }
}

/// "truncated `what`" in array `a`.
fn truncated(loc: Locator<'_>, a: &DataArray, what: &str) -> ScaffoldError {
    loc.error(a.at, format!("DataArray \"{}\": truncated {what}", a.name))
}
