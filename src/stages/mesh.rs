//! Triangle-mesh inputs: the `file` node that brings a file's bytes into the graph, and the
//! `cell` stage of a mesh cell, which reads, places and packs the mesh for every stage that
//! samples a cell.
//!
//! Invariants:
//! - A `file` node's hash is the blake3 hash of the file's bytes, so every stage reading it is
//!   keyed on the content, never on the path or the time (renaming or touching a mesh rebuilds
//!   nothing). The builder reads the file; this module never opens paths.
//! - A mesh cell's payload is the placed soup, little-endian `f64` positions and `u32` indices
//!   behind a magic and the sampling mode: a pure function of the file's bytes and the cell's
//!   keys. Reading errors name the file and the line, byte offset or face of the problem.

use latticebuild_geom::field::ScalarField;
use latticebuild_geom::mesh_read::{self, Format, TriangleSoup};
use latticebuild_geom::mesh_sdf::{MeshSdf, Mode, SdfOptions};

use crate::cache::KeyBuilder;
use crate::manifest::{MeshCell, MeshSampling};

pub const VERSION: u32 = 1;

const MESH_CELL_MAGIC: &[u8; 8] = b"LBMCEL01";

/// `file`: the bytes of a mesh file named in the manifest.
#[derive(Clone, Debug, PartialEq)]
pub struct FileStage {
    /// As written in the manifest, for messages.
    pub given: String,
    pub path: std::path::PathBuf,
}

/// The reader format of a file name (validated by the manifest: one of the known extensions).
fn format_of(given: &str) -> Result<Format, String> {
    std::path::Path::new(given)
        .extension()
        .and_then(|e| e.to_str())
        .and_then(Format::from_extension)
        .ok_or_else(|| format!("`{given}` has no mesh file extension"))
}

/// Reads the soup of a mesh file's bytes, in the format its content shows (its extension
/// when the content does not tell); errors name the file.
pub fn read_soup(given: &str, bytes: &[u8]) -> Result<TriangleSoup, String> {
    let extension = format_of(given)?.extension();
    mesh_read::read_auto(bytes, Some(extension)).map_err(|e| format!("cannot read `{given}`: {e}"))
}

/// `cell` of a mesh cell: the soup in the cell's reference frame, with its sampling mode.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshCellStage {
    pub cell: MeshCell,
}

impl MeshCellStage {
    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        // The file's content enters as the input hash; its extension picks the reader.
        let format = format_of(&self.cell.file.given)
            .map(|f| f.extension())
            .unwrap_or("");
        key.param("format", format)
            .param(
                "placement",
                if self.cell.fit_placement {
                    "fit"
                } else {
                    "reference"
                },
            )
            .param(
                "sample",
                match self.cell.sampling {
                    MeshSampling::SignedDistance => "sdf",
                    MeshSampling::Containment => "containment",
                },
            )
    }

    pub fn run(&self, file: &[u8]) -> Result<Vec<u8>, String> {
        let mut soup = read_soup(&self.cell.file.given, file)?;
        if self.cell.fit_placement {
            place_in_unit_cell(&mut soup);
        }
        Ok(encode(&soup, self.cell.sampling))
    }
}

/// Scales the soup uniformly and centres it so that its bounding box fits the reference cell
/// `[-½, ½]³` (the largest extent becomes 1), which also holds the tetrahedron's bounding box.
fn place_in_unit_cell(soup: &mut TriangleSoup) {
    let Some((lo, hi)) = soup.bounds() else {
        return;
    };
    let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    if extent <= 0.0 {
        return;
    }
    let centre: [f64; 3] = std::array::from_fn(|a| 0.5 * (lo[a] + hi[a]));
    for p in &mut soup.positions {
        *p = std::array::from_fn(|a| (p[a] - centre[a]) / extent);
    }
}

fn encode(soup: &TriangleSoup, sampling: MeshSampling) -> Vec<u8> {
    let mut out =
        Vec::with_capacity(8 + 1 + 16 + soup.positions.len() * 24 + soup.triangles.len() * 12);
    out.extend_from_slice(MESH_CELL_MAGIC);
    out.push(match sampling {
        MeshSampling::SignedDistance => 0,
        MeshSampling::Containment => 1,
    });
    out.extend_from_slice(&(soup.positions.len() as u64).to_le_bytes());
    out.extend_from_slice(&(soup.triangles.len() as u64).to_le_bytes());
    for p in &soup.positions {
        for c in p {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for t in &soup.triangles {
        for i in t {
            out.extend_from_slice(&i.to_le_bytes());
        }
    }
    out
}

/// Whether a cell payload is a mesh cell's (the others are formula text).
pub fn is_mesh_cell(payload: &[u8]) -> bool {
    payload.starts_with(MESH_CELL_MAGIC)
}

fn decode(payload: &[u8]) -> Result<(TriangleSoup, MeshSampling), String> {
    let bad = || "malformed mesh cell payload".to_string();
    let rest = payload.strip_prefix(MESH_CELL_MAGIC).ok_or_else(bad)?;
    let (&mode, rest) = rest.split_first().ok_or_else(bad)?;
    let count = |b: &[u8]| -> Result<usize, String> {
        Ok(u64::from_le_bytes(b.try_into().map_err(|_| bad())?) as usize)
    };
    let (np, nt) = (
        count(rest.get(..8).ok_or_else(bad)?)?,
        count(rest.get(8..16).ok_or_else(bad)?)?,
    );
    let body = &rest[16..];
    if body.len() != np * 24 + nt * 12 {
        return Err(bad());
    }
    let (pos, tri) = body.split_at(np * 24);
    let f = |c: &[u8]| f64::from_le_bytes(c.try_into().unwrap_or([0; 8]));
    let u = |c: &[u8]| u32::from_le_bytes(c.try_into().unwrap_or([0; 4]));
    let positions = pos
        .chunks_exact(24)
        .map(|c| [f(&c[..8]), f(&c[8..16]), f(&c[16..])])
        .collect();
    let triangles = tri
        .chunks_exact(12)
        .map(|c| [u(&c[..4]), u(&c[4..8]), u(&c[8..])])
        .collect();
    let sampling = match mode {
        0 => MeshSampling::SignedDistance,
        _ => MeshSampling::Containment,
    };
    Ok((
        TriangleSoup {
            positions,
            triangles,
        },
        sampling,
    ))
}

/// The field of a mesh cell's payload, repeated with period 1 (the cell is the unit cube
/// centred at the origin, like every cell).
pub fn mesh_cell_field(payload: &[u8]) -> Result<Box<dyn ScalarField>, String> {
    let (soup, sampling) = decode(payload)?;
    let options = SdfOptions {
        mode: match sampling {
            MeshSampling::SignedDistance => Mode::SignedDistance,
            MeshSampling::Containment => Mode::Containment,
        },
        ..SdfOptions::default()
    };
    let sdf = MeshSdf::new(&soup, options).map_err(|e| format!("the cell's mesh: {e}"))?;
    Ok(Box::new(Periodic(sdf)))
}

/// A field repeated with period 1 on every axis around the cell `[-½, ½]³`.
struct Periodic<F>(F);

impl<F: ScalarField> ScalarField for Periodic<F> {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        let wrap = |v: &[f64]| -> Vec<f64> { v.iter().map(|c| c - c.round()).collect() };
        self.0.eval_points(&wrap(xs), &wrap(ys), &wrap(zs), out);
    }
}

/// The part of `within`: its signed distance in model units, exact within `band` of the
/// surface and clamped beyond (the sign stays exact everywhere).
pub fn part_sdf(given: &str, bytes: &[u8], band: f64) -> Result<MeshSdf, String> {
    let soup = read_soup(given, bytes)?;
    let options = SdfOptions {
        band: Some(band),
        ..SdfOptions::default()
    };
    MeshSdf::new(&soup, options).map_err(|e| format!("the part `{given}`: {e}"))
}
