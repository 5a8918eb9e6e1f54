//! Point-cloud cells: the `cell` stage of a `points` cell, which reads the oriented points (a
//! `file` node's bytes, see [`super::file`]) for every stage that samples a cell.
//!
//! Invariants:
//! - This module never opens paths: the points arrive as the bytes of their `file` node.
//! - The payload is a magic, the count, then each point's position and unit normal as
//!   little-endian `f64`: a pure function of the file's bytes and its format (in the key).
//!   Reading errors name the file and the point's index or line.
//! - The field is the geometry crate's `PointCloudField`: the weighted vote of the nearest
//!   points' tangent planes, period 1.

use latticebuild_geom::field::ScalarField;
use latticebuild_geom::point_cloud::{PointCloud, PointCloudField};

use super::StageError;
use crate::cache::KeyBuilder;
use crate::manifest::InputFile;

pub const VERSION: u32 = 1;

const POINT_CELL_MAGIC: &[u8; 8] = b"LBPTSC01";

/// `cell` of a point cell: its points and normals.
#[derive(Clone, Debug, PartialEq)]
pub struct PointCellStage {
    pub file: InputFile,
}

impl PointCellStage {
    fn is_ply(&self) -> bool {
        self.file.given.to_ascii_lowercase().ends_with(".ply")
    }

    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        // The file's content enters as the input hash; its extension picks the reader.
        key.param("format", if self.is_ply() { "ply" } else { "xyz" })
    }

    pub fn run(&self, file: &[u8]) -> Result<Vec<u8>, StageError> {
        let cloud = if self.is_ply() {
            PointCloud::read_ply(file)
        } else {
            PointCloud::read_xyz(file)
        }
        .map_err(|e| StageError::geometry_of(format!("cannot read `{}`", self.file.given), e))?;
        let mut out = Vec::with_capacity(16 + 48 * cloud.positions.len());
        out.extend_from_slice(POINT_CELL_MAGIC);
        out.extend_from_slice(&(cloud.positions.len() as u64).to_le_bytes());
        for (p, n) in cloud.positions.iter().zip(&cloud.normals) {
            for c in p.iter().chain(n) {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        Ok(out)
    }
}

/// Whether a cell payload is a point cell's.
pub fn is_point_cell(payload: &[u8]) -> bool {
    payload.starts_with(POINT_CELL_MAGIC)
}

/// The field of a point cell's payload (see the module's invariants).
pub fn point_cell_field(payload: &[u8]) -> Result<Box<dyn ScalarField>, StageError> {
    let bad = || StageError::malformed("point cell");
    let rest = payload.strip_prefix(POINT_CELL_MAGIC).ok_or_else(bad)?;
    let (count, body) = rest.split_at_checked(8).ok_or_else(bad)?;
    let count = u64::from_le_bytes(count.try_into().map_err(|_| bad())?);
    if Some(body.len() as u64) != count.checked_mul(48) {
        return Err(bad());
    }
    let f = |c: &[u8]| f64::from_le_bytes(c.try_into().unwrap_or([0; 8]));
    let (mut positions, mut normals) = (Vec::new(), Vec::new());
    for point in body.chunks_exact(48) {
        let v: Vec<f64> = point.chunks_exact(8).map(f).collect();
        positions.push([v[0], v[1], v[2]]);
        normals.push([v[3], v[4], v[5]]);
    }
    let cloud = PointCloud::new(positions, normals).map_err(|_| bad())?;
    Ok(Box::new(PointCloudField::new(&cloud)))
}
