//! VTK unstructured grids: legacy `.vtk` ([`legacy`], arrays read past in [`legacy_arrays`])
//! and XML `.vtu` ([`vtu`], its binary blocks in [`blocks`]), as VTK 9, PyVista and meshio
//! write them; what both share is here: cell types, VTK's local node order, type names.
//!
//! Invariants:
//! - Points keep their file order; node tags are 0-based point indices and element tags
//!   0-based cell indices (what VTK tools show).
//! - Cell types 5, 22, 9, 23, 28, 10, 24, 12, 25, 29 become tri3 … hex27 with VTK's local node
//!   order rewritten into Gmsh's (tet10: the last two edges swap; hex20/hex27: edges and faces
//!   reordered); other cell types are known by dimension only (named in errors, dropped when
//!   of lower dimension).
//! - Point data arrays with one component and one value per point become node data, under
//!   the name the tools show (legacy names have VTK's `%XX` escapes decoded); every other
//!   array (cell data, field data, vectors, strings) is read past, never interpreted.

mod blocks;
mod legacy;
mod legacy_arrays;
mod vtu;

pub(super) use legacy::read_legacy;
pub(super) use vtu::read_xml;

use super::assemble::{ElementType, RawMesh};
use super::cursor::Locator;
use super::{ElementKind, ScaffoldError};
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
pub(super) fn add_cells(
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

pub(super) fn to_index(
    v: f64,
    what: &str,
    loc: Locator<'_>,
    at: usize,
) -> Result<u64, ScaffoldError> {
    if v >= 0.0 && v.fract() == 0.0 && v < 9.0e15 {
        Ok(v as u64)
    } else {
        Err(loc.error(
            at,
            format!("expected {what} (a non-negative integer), found {v}"),
        ))
    }
}

/// Legacy (`float`, `vtktypeint64`, …) and XML (`Float64`, `Int32`, …) type names.
pub(super) fn scalar_type(name: &[u8]) -> Option<Scalar> {
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

/// A name as VTK's legacy writer escapes it (`wall%20thickness`), decoded (`wall thickness`):
/// `%` and two hex digits stand for that byte; anything else is kept as is.
pub(super) fn decode_name(raw: &[u8]) -> String {
    let mut out = Vec::with_capacity(raw.len());
    let mut i = 0;
    while i < raw.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (raw[i], raw.get(i + 1).copied(), raw.get(i + 2).copied()) {
            (b'%', Some(h), Some(l)) if hex(h).is_some() && hex(l).is_some() => {
                out.push((hex(h).unwrap_or(0) * 16 + hex(l).unwrap_or(0)) as u8);
                i += 3;
            }
            (b, _, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}
