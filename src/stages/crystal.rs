//! Periodic-surface cells: the `crystal` stage, which reads a crystal file's bytes (the
//! `file:` node) and reconstructs the loci surface through its atoms, and the payload of a
//! PS model, shared with explicit `ps = { terms = … }` cells.
//!
//! Invariants:
//! - The crystal file enters by content hash (its `file:` node), so renaming or touching it
//!   rebuilds nothing; every reconstruction option is in the key.
//! - A PS payload is the model's terms, little-endian `f64`s behind a magic: a pure function
//!   of the file's bytes and the options (or of the manifest's terms), reloaded bit for bit.
//! - A reconstruction that does not reach its tolerance by `max_scale` is an error naming the
//!   file and the error reached, never a surface that misses the atoms.

use latticebuild_geom::field::ScalarField;
use latticebuild_geom::periodic::reconstruct::{ReconstructOptions, Reconstruction, reconstruct};
use latticebuild_geom::periodic::{ExpandOptions, PsModel, PsTerm, positions_of, read_crystal};

use super::StageError;
use crate::cache::KeyBuilder;
use crate::manifest::CrystalCell;

pub const VERSION: u32 = 1;

const PS_MAGIC: &[u8; 8] = b"LBPSCEL1";

/// `crystal`: the reconstructed PS model of a crystal cell.
#[derive(Clone, Debug, PartialEq)]
pub struct CrystalStage {
    pub cell: CrystalCell,
}

impl CrystalStage {
    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        // The file's content enters as the input hash; its extension picks the reader.
        let extension = std::path::Path::new(&self.cell.file.given)
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        key.param("format", extension)
            .param("species", self.cell.species.clone().unwrap_or_default())
            .param("tolerance", self.cell.tolerance)
            .param("max_scale", self.cell.max_scale)
            .param("include_images", self.cell.include_images)
            .param("optimize", self.cell.optimize)
    }

    pub fn run(&self, file: &[u8]) -> Result<Vec<u8>, StageError> {
        let options = ReconstructOptions {
            tolerance: self.cell.tolerance,
            max_scale: self.cell.max_scale,
            optimize: self.cell.optimize,
            ..ReconstructOptions::default()
        };
        let found = reconstruct_crystal(
            &self.cell.file.given,
            file,
            self.cell.species.as_deref(),
            self.cell.include_images,
            &options,
        )?;
        let r = &found.reconstruction;
        if !r.converged {
            return Err(StageError::NotConverged(format!(
                "the surface through `{}` reaches a relative error of {:.3e} at scale {}, \
                 above the tolerance {:e}: raise `reconstruct.max_scale` or `tolerance`",
                self.cell.file.given, r.metrics.max_error, self.cell.max_scale, options.tolerance
            )));
        }
        Ok(encode(&r.model))
    }
}

/// A crystal file's atoms and the surface through them.
pub struct FoundSurface {
    pub name: String,
    /// The species of the structure, in order of first appearance.
    pub species: Vec<String>,
    pub reconstruction: Reconstruction,
}

/// Reads a crystal file's bytes, expands its sites and reconstructs the surface through the
/// atoms of `species` (all atoms with `None`). Errors name the file.
pub fn reconstruct_crystal(
    given: &str,
    bytes: &[u8],
    species: Option<&str>,
    include_images: bool,
    options: &ReconstructOptions,
) -> Result<FoundSurface, StageError> {
    let crystal = read_crystal(given, bytes)?;
    let atoms = crystal.atoms(&ExpandOptions {
        include_images,
        ..ExpandOptions::default()
    });
    let points = positions_of(&atoms, species);
    let present = crystal.species();
    if points.is_empty() {
        let what = species.map_or("atoms".to_string(), |s| format!("`{s}` atoms"));
        return Err(StageError::DoesNotFit(format!(
            "`{given}` has no {what}; its species are {}",
            present.join(", ")
        )));
    }
    let reconstruction = reconstruct(&points, options)
        .map_err(|e| StageError::geometry_of(format!("the surface through `{given}`"), e))?;
    Ok(FoundSurface {
        name: crystal.name,
        species: present,
        reconstruction,
    })
}

/// The payload of a PS model.
pub fn encode(model: &PsModel) -> Vec<u8> {
    let mut out = Vec::with_capacity(16 + model.terms.len() * 48);
    out.extend_from_slice(PS_MAGIC);
    out.extend_from_slice(&(model.terms.len() as u64).to_le_bytes());
    for t in &model.terms {
        for v in [t.moment, t.scale]
            .into_iter()
            .chain(t.vector.iter().copied())
        {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// Whether a cell payload is a PS model's.
pub fn is_ps_cell(payload: &[u8]) -> bool {
    payload.starts_with(PS_MAGIC)
}

pub fn decode(payload: &[u8]) -> Result<PsModel, StageError> {
    let bad = || StageError::malformed("periodic-surface cell");
    let rest = payload.strip_prefix(PS_MAGIC).ok_or_else(bad)?;
    let count = rest
        .get(..8)
        .and_then(|b| b.try_into().ok())
        .map(u64::from_le_bytes)
        .ok_or_else(bad)?;
    let body = &rest[8..];
    if body.len() as u64 != count.saturating_mul(48) {
        return Err(bad());
    }
    let value = |c: &[u8]| f64::from_le_bytes(c.try_into().unwrap_or([0; 8]));
    let terms = body
        .chunks_exact(48)
        .map(|c| {
            let v: Vec<f64> = c.chunks_exact(8).map(value).collect();
            PsTerm {
                moment: v[0],
                scale: v[1],
                vector: [v[2], v[3], v[4], v[5]],
            }
        })
        .collect();
    Ok(PsModel::new(terms))
}

/// The field of a PS payload (cell coordinates, period 1 for integer basis vectors).
pub fn ps_cell_field(payload: &[u8]) -> Result<Box<dyn ScalarField>, StageError> {
    Ok(Box::new(decode(payload)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn payload_reloads_bit_for_bit() {
        let model = PsModel::new(vec![
            PsTerm {
                moment: 0.1 + 0.2,
                scale: 4.0,
                vector: [1.0, -1.0, 0.0, 1.0 / 3.0],
            },
            PsTerm {
                moment: -1e-300,
                scale: 1.0,
                vector: [0.0; 4],
            },
        ]);
        let bytes = encode(&model);
        assert!(is_ps_cell(&bytes));
        assert_eq!(decode(&bytes).unwrap(), model);
        assert!(decode(&bytes[..bytes.len() - 1]).is_err());
    }
}
