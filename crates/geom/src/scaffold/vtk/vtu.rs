//! XML `.vtu` unstructured grids: DataArrays ASCII, inline base64, or appended (raw or
//! base64), uncompressed or in zlib or LZ4 blocks (`blocks.rs`), UInt32 or UInt64 headers.
//!
//! Invariants:
//! - One Piece; its Points, the Cells arrays connectivity, offsets and types, and its
//!   one-component PointData arrays are read; everything else (FieldData, CellData, `Array`
//!   string arrays, InformationKey elements) is passed over.
//! - An appended base64 array ends where the next array's offset starts (any element's
//!   `offset`, string arrays included) or at `</AppendedData>`.
//! - No array is decoded to more than the Piece's counts ask for, and those counts must fit
//!   in what a file of its size can hold.

use super::blocks::{Compressor, Encoding};
use super::{add_cells, scalar_type, to_index};
use crate::scaffold::assemble::{RawMesh, RawNodeData};
use crate::scaffold::cursor::{Cursor, Locator, show};
use crate::scaffold::xml::{Tag, base64_decode, find, next_tag};
use crate::scaffold::{Scaffold, ScaffoldError};
use crate::scalar::Scalar;

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
    encoding: Encoding,
    /// (encoding is base64, offset of the first byte after `_`).
    appended: Option<(bool, usize)>,
    /// Every appended array's offset (DataArray and string Array elements), in order: where
    /// each base64 array ends.
    offsets: Vec<usize>,
}

pub(in crate::scaffold) fn read_xml(bytes: &[u8], name: &str) -> Result<Scaffold, ScaffoldError> {
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
        appended_offsets: file.offsets.clone(),
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
        encoding: Encoding {
            big_endian: false,
            header64: false,
            compressor: Compressor::None,
        },
        appended: None,
        offsets: Vec::new(),
    };
    let mut arrays = Vec::new();
    let mut section = Section::Other;
    let mut piece: Option<PieceCounts> = None;
    let mut saw_vtk = false;
    let mut pos = 0;
    while let Some(tag) = next_tag(bytes, pos) {
        let tag: Tag<'_> = tag.map_err(|at| loc.error(at, "unterminated XML tag: expected `>`"))?;
        pos = tag.end;
        if let Some(offset) = tag
            .attribute("offset")
            .and_then(|v| std::str::from_utf8(v).ok()?.trim().parse::<usize>().ok())
        {
            file.offsets.push(offset);
        }
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
    file.offsets.sort_unstable();
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
        self.encoding = Encoding {
            big_endian: tag.attribute("byte_order") == Some(b"BigEndian"),
            header64: tag.attribute("header_type") == Some(b"UInt64"),
            compressor: Compressor::from_attribute(tag.attribute("compressor"))
                .map_err(|m| loc.error(tag.start, m))?,
        };
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

    /// Header(s) + data of a binary array (raw or compressed blocks) to `count` values.
    fn unpack(&self, a: &DataArray, data: &[u8], count: usize) -> Result<Vec<f64>, ScaffoldError> {
        let loc = self.loc;
        let size = a.ty.size();
        let expected = count.saturating_mul(size);
        let body = self
            .encoding
            .unpack(loc.name, data, expected)
            .map_err(|m| loc.error(a.at, format!("DataArray \"{}\": {m}", a.name)))?;
        if body.len() < expected {
            return Err(loc.error(
                a.at,
                format!(
                    "DataArray \"{}\" holds {} bytes, expected {expected} ({count} values)",
                    a.name,
                    body.len(),
                ),
            ));
        }
        Ok(body[..expected]
            .chunks_exact(size)
            .map(|c| a.ty.decode(c, self.encoding.big_endian))
            .collect())
    }
}
