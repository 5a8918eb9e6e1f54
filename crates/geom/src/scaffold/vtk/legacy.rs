//! Legacy VTK `.vtk` unstructured grids, ASCII and BINARY (big-endian), versions before 5.1
//! (CELLS as counted lists) and 5.1 (OFFSETS and CONNECTIVITY arrays), as VTK 9, PyVista and
//! meshio write them.
//!
//! Invariants:
//! - Every section VTK's reader knows is read or read past: dataset `FIELD` data (before
//!   POINTS too), the `METADATA` block VTK 9 writes after any array (COMPONENT_NAMES,
//!   INFORMATION; it ends at an empty line, as VTK's reader has it), `CELL_DATA` and
//!   `POINT_DATA` with their attributes (SCALARS, VECTORS, NORMALS, TENSORS, FIELD arrays,
//!   …), string and bit arrays included. An unknown keyword is an error at its line or byte.
//! - Point data becomes node data when it has one component and one value per point: a
//!   `SCALARS` attribute (what PyVista and VTK write for the active scalars) or an array of a
//!   `FIELD` (what meshio and VTK write for the others). Its values must be finite.
//! - Skipped arrays are never parsed as numbers (a NaN in an unused array is fine), but their
//!   declared sizes must fit in the bytes that follow, as every count here must.

use super::legacy_arrays::{ArrayType, array_type, skip_metadata, skip_values};
use super::{add_cells, decode_name, scalar_type, to_index};
use crate::scaffold::assemble::{RawMesh, RawNodeData};
use crate::scaffold::cursor::{Cursor, Locator, finite, show};
use crate::scaffold::xml::find;
use crate::scaffold::{Scaffold, ScaffoldError};
use crate::scalar::Scalar;

pub(in crate::scaffold) fn read_legacy(
    bytes: &[u8],
    name: &str,
) -> Result<Scaffold, ScaffoldError> {
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
        binary,
        data: Data::Dataset,
    };
    while let Some((at, keyword)) = cur.next_token() {
        let word = keyword.to_ascii_uppercase();
        match word.as_slice() {
            b"POINTS" => grid.points(&mut cur)?,
            b"CELLS" => grid.cells(&mut cur, version_51, at)?,
            b"OFFSETS" | b"CONNECTIVITY" => {
                grid.array_51(&mut cur, word.as_slice() == b"OFFSETS", at)?
            }
            b"CELL_TYPES" => grid.cell_types(&mut cur)?,
            b"METADATA" => {
                cur.pos = at;
                skip_metadata(&mut cur, 0);
            }
            b"POINT_DATA" | b"CELL_DATA" => grid.data_section(&mut cur, &word, at)?,
            b"FIELD" => grid.field(&mut cur)?,
            b"SCALARS"
            | b"COLOR_SCALARS"
            | b"LOOKUP_TABLE"
            | b"VECTORS"
            | b"NORMALS"
            | b"TEXTURE_COORDINATES"
            | b"TENSORS"
            | b"TENSORS6"
            | b"GLOBAL_IDS"
            | b"PEDIGREE_IDS"
            | b"EDGE_FLAGS" => grid.attribute(&mut cur, &word, at)?,
            _ => {
                return Err(cur.error(
                    at,
                    format!(
                        "expected a section (POINTS, CELLS, CELL_TYPES, POINT_DATA, CELL_DATA, \
                         FIELD, …), found `{}`",
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

/// Which data the attributes and field arrays that follow belong to.
#[derive(Clone, Copy, PartialEq)]
enum Data {
    /// The dataset's own FIELD data (before POINT_DATA or CELL_DATA).
    Dataset,
    /// POINT_DATA of that many points.
    Points(usize),
    /// CELL_DATA of that many cells.
    Cells(usize),
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
    binary: bool,
    data: Data,
}

impl LegacyGrid {
    /// `POINTS n type` and the coordinates.
    fn points(&mut self, cur: &mut Cursor<'_>) -> Result<(), ScaffoldError> {
        let binary = self.binary;
        let n = cur.count("the number of points", if binary { 12 } else { 6 })?;
        let ty = number_type(cur, "the point data type")?;
        if binary {
            cur.skip_line();
        }
        self.raw.nodes.reserve(n);
        for i in 0..n {
            let at = cur.mark();
            let mut p = [0.0; 3];
            for c in &mut p {
                *c = legacy_number(cur, binary, ty, "a point coordinate")?;
            }
            self.raw.push_node(i as u64, p, at);
        }
        skip_metadata(cur, 3);
        Ok(())
    }

    /// `CELLS n size` (keyword at `at`) and, before 5.1, the cell list.
    fn cells(
        &mut self,
        cur: &mut Cursor<'_>,
        version_51: bool,
        at: usize,
    ) -> Result<(), ScaffoldError> {
        let binary = self.binary;
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
        skip_metadata(cur, 1);
        Ok(())
    }

    /// 5.1's `OFFSETS type` or `CONNECTIVITY type` (keyword at `at`) and its values.
    fn array_51(
        &mut self,
        cur: &mut Cursor<'_>,
        is_offsets: bool,
        at: usize,
    ) -> Result<(), ScaffoldError> {
        let binary = self.binary;
        let ty = number_type(cur, "the array's data type")?;
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
        skip_metadata(cur, 1);
        Ok(())
    }

    /// `CELL_TYPES n` and the types.
    fn cell_types(&mut self, cur: &mut Cursor<'_>) -> Result<(), ScaffoldError> {
        let binary = self.binary;
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
        skip_metadata(cur, 1);
        Ok(())
    }

    /// `POINT_DATA n` or `CELL_DATA n` (keyword `word` at `at`): the attributes that follow
    /// belong to the points (there must be `n` of them) or to the cells.
    fn data_section(
        &mut self,
        cur: &mut Cursor<'_>,
        word: &[u8],
        at: usize,
    ) -> Result<(), ScaffoldError> {
        let n = cur.uint("the number of values")?;
        if word == b"POINT_DATA" {
            let points = self.raw.nodes.len();
            if n != points as u64 {
                return Err(cur.error(
                    at,
                    format!("POINT_DATA has {n} values, but the file has {points} points"),
                ));
            }
            self.data = Data::Points(points);
        } else {
            // Cell data is never read, only read past: its count is checked as it is used.
            let n = usize::try_from(n).map_err(|_| cur.error(at, "CELL_DATA count too large"))?;
            self.data = Data::Cells(n);
        }
        Ok(())
    }

    /// How many tuples an attribute of the current section has (`word` at `at`).
    fn tuples(&self, cur: &Cursor<'_>, word: &[u8], at: usize) -> Result<usize, ScaffoldError> {
        match self.data {
            Data::Points(n) | Data::Cells(n) => Ok(n),
            Data::Dataset => Err(cur.error(
                at,
                format!(
                    "{} before POINT_DATA or CELL_DATA: expected an attribute of the points or \
                     cells",
                    show(word)
                ),
            )),
        }
    }

    /// One attribute of POINT_DATA or CELL_DATA (keyword `word` at `at`): a one-component
    /// SCALARS of the points is kept as node data, everything else read past.
    fn attribute(
        &mut self,
        cur: &mut Cursor<'_>,
        word: &[u8],
        at: usize,
    ) -> Result<(), ScaffoldError> {
        let binary = self.binary;
        let n = self.tuples(cur, word, at)?;
        let (_, name) = cur.token("the attribute's name")?;
        let name = decode_name(name);
        let (ty, components) = match word {
            b"SCALARS" => {
                let ty = array_type(cur, "the data type")?;
                let mut components = 1;
                let mut next = cur.token("LOOKUP_TABLE")?;
                if let Some(c) = std::str::from_utf8(next.1)
                    .ok()
                    .and_then(|s| s.parse::<usize>().ok())
                {
                    components = c;
                    next = cur.token("LOOKUP_TABLE")?;
                }
                // VTK's reader insists on the table line too: without it, the number of
                // components could not be told from a first value.
                if !next.1.eq_ignore_ascii_case(b"LOOKUP_TABLE") {
                    return Err(cur.error(
                        next.0,
                        format!("expected LOOKUP_TABLE, found `{}`", show(next.1)),
                    ));
                }
                cur.token("the lookup table's name")?;
                (ty, components)
            }
            b"COLOR_SCALARS" => {
                let c = cur.count("the number of color components", 1)?;
                let ty = if binary { Scalar::U8 } else { Scalar::F32 };
                (ArrayType::Number(ty), c)
            }
            b"LOOKUP_TABLE" => {
                // A table of its own: `n` RGBA colors, not one per point.
                let size = cur.count("the table size", 4)?;
                if binary {
                    cur.skip_line();
                }
                let ty = if binary { Scalar::U8 } else { Scalar::F32 };
                skip_values(
                    cur,
                    binary,
                    ArrayType::Number(ty),
                    size.saturating_mul(4),
                    at,
                )?;
                return Ok(());
            }
            b"TEXTURE_COORDINATES" => {
                let dim = cur.count("the texture dimension", 1)?;
                (array_type(cur, "the data type")?, dim)
            }
            b"VECTORS" | b"NORMALS" => (array_type(cur, "the data type")?, 3),
            b"TENSORS" => (array_type(cur, "the data type")?, 9),
            b"TENSORS6" => (array_type(cur, "the data type")?, 6),
            _ => (array_type(cur, "the data type")?, 1), // ids and edge flags
        };
        if binary {
            cur.skip_line();
        }
        let keep = word == b"SCALARS" && components == 1 && matches!(self.data, Data::Points(_));
        self.array(cur, &name, ty, n, components, keep, at)
    }

    /// `FIELD name n` and its `n` arrays (`name components tuples type`, values).
    fn field(&mut self, cur: &mut Cursor<'_>) -> Result<(), ScaffoldError> {
        cur.token("the field's name")?;
        let arrays = cur.count("the number of field arrays", 2)?;
        for _ in 0..arrays {
            let (at, name) = cur.token("a field array's name")?;
            if name.eq_ignore_ascii_case(b"NULL_ARRAY") {
                continue;
            }
            let name = decode_name(name);
            let components = cur.count("the number of components", 1)?;
            let tuples = cur.count("the number of tuples", 1)?;
            let ty = array_type(cur, "the data type")?;
            if self.binary {
                cur.skip_line();
            }
            let keep = components == 1 && self.data == Data::Points(tuples);
            self.array(cur, &name, ty, tuples, components, keep, at)?;
        }
        Ok(())
    }

    /// The values of an array (`tuples` × `components` of type `ty`, header at `at`): kept as
    /// node data `name` if `keep` (and numeric), else read past; then any METADATA.
    #[allow(clippy::too_many_arguments)]
    fn array(
        &mut self,
        cur: &mut Cursor<'_>,
        name: &str,
        ty: ArrayType,
        tuples: usize,
        components: usize,
        keep: bool,
        at: usize,
    ) -> Result<(), ScaffoldError> {
        let binary = self.binary;
        let count = tuples.checked_mul(components).ok_or_else(|| {
            cur.error(
                at,
                format!("array \"{name}\": {tuples} × {components} values"),
            )
        })?;
        match ty {
            ArrayType::Number(scalar) if keep => {
                cur.check_count(
                    at,
                    count as u64,
                    "the number of values",
                    if binary { scalar.size() } else { 2 },
                )?;
                let mut values = Vec::with_capacity(count);
                for i in 0..count {
                    let value_at = cur.mark();
                    let v = legacy_number(cur, binary, scalar, "a point data value")?;
                    values.push((i as u64, v, value_at));
                }
                self.raw.node_data.push(RawNodeData {
                    name: name.to_string(),
                    at,
                    values,
                });
            }
            _ => skip_values(cur, binary, ty, count, at)?,
        }
        skip_metadata(cur, components);
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

/// A number type name (points, cells).
fn number_type(cur: &mut Cursor<'_>, what: &str) -> Result<Scalar, ScaffoldError> {
    let (at, ty) = cur.token(what)?;
    scalar_type(ty).ok_or_else(|| cur.error(at, format!("unknown VTK data type `{}`", show(ty))))
}

/// One finite number, binary (big-endian `ty`) or text.
fn legacy_number(
    cur: &mut Cursor<'_>,
    binary: bool,
    ty: Scalar,
    what: &str,
) -> Result<f64, ScaffoldError> {
    if binary {
        let at = cur.pos;
        let b = cur.take(ty.size(), what)?;
        finite(ty.decode(b, true), what).map_err(|m| cur.error(at, m))
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
