//! Voxel-image cells: the `cell` stage of a `voxels` cell, which reads the image (a `file`
//! node's bytes, see [`super::file`]) and turns its values into the samples of a periodic
//! field for every stage that samples a cell.
//!
//! Invariants:
//! - This module never opens paths: the image arrives as the bytes of its `file` node.
//! - The payload is a magic, the shape and the field's samples (little-endian `f64`, negative
//!   inside, x fastest): a pure function of the file's bytes and the cell's keys, all of which
//!   are in the key. Reading errors name the file and what was wrong (a shape, a byte count,
//!   a voxel).
//! - The field is the geometry crate's `VoxelField`: trilinear between voxel centres, period 1.

use latticebuild_geom::field::ScalarField;
use latticebuild_geom::voxels::{self, VoxelField, VoxelValues};

use super::StageError;
use crate::cache::KeyBuilder;
use crate::manifest::VoxelCell;

pub const VERSION: u32 = 1;

const VOXEL_CELL_MAGIC: &[u8; 8] = b"LBVOXC01";

/// `cell` of a voxel cell: the image's field samples.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelCellStage {
    pub cell: VoxelCell,
}

impl VoxelCellStage {
    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        // The file's content enters as the input hash; the layout says how to read it.
        let key = match &self.cell.raw {
            None => key.param("format", "npy"),
            Some(raw) => key
                .param("format", "raw")
                .param("shape", raw.shape)
                .param("dtype", raw.dtype.name())
                .param("big_endian", raw.big_endian),
        };
        match self.cell.values {
            VoxelValues::Distance => key.param("values", "distance"),
            VoxelValues::Occupancy { threshold } => {
                let key = key.param("values", "occupancy");
                match threshold {
                    Some(t) => key.param("threshold", t),
                    None => key,
                }
            }
        }
    }

    pub fn run(&self, file: &[u8]) -> Result<Vec<u8>, StageError> {
        let given = &self.cell.file.given;
        let what = || format!("cannot read `{given}`");
        let image = match &self.cell.raw {
            None => voxels::read_npy(file),
            Some(raw) => voxels::read_raw(file, raw.shape, raw.dtype, raw.big_endian),
        }
        .map_err(|e| StageError::geometry_of(what(), e))?;
        let field = image
            .field(self.cell.values)
            .map_err(|e| StageError::geometry_of(format!("the voxel image `{given}`"), e))?;
        Ok(encode(&field))
    }
}

fn encode(field: &VoxelField) -> Vec<u8> {
    let shape = field.shape();
    let count: usize = shape.iter().product();
    let mut out = Vec::with_capacity(8 + 24 + 8 * count);
    out.extend_from_slice(VOXEL_CELL_MAGIC);
    for n in shape {
        out.extend_from_slice(&(n as u64).to_le_bytes());
    }
    for k in 0..shape[2] {
        for j in 0..shape[1] {
            for i in 0..shape[0] {
                out.extend_from_slice(&field.sample([i, j, k]).to_le_bytes());
            }
        }
    }
    out
}

/// Whether a cell payload is a voxel cell's.
pub fn is_voxel_cell(payload: &[u8]) -> bool {
    payload.starts_with(VOXEL_CELL_MAGIC)
}

/// The field of a voxel cell's payload (see the module's invariants).
pub fn voxel_cell_field(payload: &[u8]) -> Result<Box<dyn ScalarField>, StageError> {
    let bad = || StageError::malformed("voxel cell");
    let rest = payload.strip_prefix(VOXEL_CELL_MAGIC).ok_or_else(bad)?;
    let (head, body) = rest.split_at_checked(24).ok_or_else(bad)?;
    let mut shape = [0usize; 3];
    for (n, bytes) in shape.iter_mut().zip(head.chunks_exact(8)) {
        let value = u64::from_le_bytes(bytes.try_into().map_err(|_| bad())?);
        *n = usize::try_from(value).map_err(|_| bad())?;
    }
    let count = shape
        .iter()
        .try_fold(1usize, |acc, &n| acc.checked_mul(n))
        .filter(|&c| c > 0 && Some(body.len()) == c.checked_mul(8))
        .ok_or_else(bad)?;
    let values: Vec<f64> = body
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
        .collect();
    debug_assert_eq!(values.len(), count);
    Ok(Box::new(VoxelField::new(shape, values)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::manifest::{InputFile, RawLayout};
    use latticebuild_geom::voxels::VoxelType;

    fn stage(raw: Option<RawLayout>, values: VoxelValues) -> VoxelCellStage {
        VoxelCellStage {
            cell: VoxelCell {
                file: InputFile {
                    given: "part.raw".into(),
                    path: "part.raw".into(),
                    span: 0..0,
                },
                raw,
                values,
            },
        }
    }

    /// The payload decodes to the field the image gives: an occupancy step from 0 to 1 along
    /// x is (½ − v)·h, h = ¼, at the voxel centres.
    #[test]
    fn the_payload_is_the_images_field() {
        let data: Vec<u8> = (0..4 * 2 * 2).map(|n| u8::from(n % 4 >= 2)).collect();
        let raw = RawLayout {
            shape: [4, 2, 2],
            dtype: VoxelType::U8,
            big_endian: false,
        };
        let payload = stage(Some(raw), VoxelValues::Occupancy { threshold: None })
            .run(&data)
            .expect("run");
        assert!(is_voxel_cell(&payload));
        let field = voxel_cell_field(&payload).expect("field");
        let xs = [-0.375, -0.125, 0.125, 0.375];
        let mut out = [0.0; 4];
        field.eval_points(&xs, &[0.25; 4], &[0.25; 4], &mut out);
        assert_eq!(out, [0.125, 0.125, -0.125, -0.125]);
        assert!(voxel_cell_field(&payload[..payload.len() - 1]).is_err());
    }

    /// Every option that changes the payload changes the key.
    #[test]
    fn every_option_is_in_the_key() {
        let raw = RawLayout {
            shape: [4, 2, 2],
            dtype: VoxelType::U8,
            big_endian: false,
        };
        let variants = [
            stage(None, VoxelValues::Distance),
            stage(Some(raw), VoxelValues::Distance),
            stage(
                Some(RawLayout {
                    shape: [2, 4, 2],
                    ..raw
                }),
                VoxelValues::Distance,
            ),
            stage(
                Some(RawLayout {
                    dtype: VoxelType::I16,
                    ..raw
                }),
                VoxelValues::Distance,
            ),
            stage(
                Some(RawLayout {
                    big_endian: true,
                    ..raw
                }),
                VoxelValues::Distance,
            ),
            stage(None, VoxelValues::Occupancy { threshold: None }),
            stage(
                None,
                VoxelValues::Occupancy {
                    threshold: Some(0.3),
                },
            ),
        ];
        let keys: std::collections::BTreeSet<String> = variants
            .iter()
            .map(|s| {
                let stage = super::super::Stage::VoxelCell(s.clone());
                let (key, _) = stage.key(&[]).expect("key");
                format!("{key:?}")
            })
            .collect();
        assert_eq!(keys.len(), variants.len());
    }
}
