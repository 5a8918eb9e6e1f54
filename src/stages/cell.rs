//! The `cell` stage: resolves a cell's source to the canonical formula every later stage
//! evaluates. Library surfaces and expressions meet here, so `tpms = "schwarz-p"` and
//! `tpms = "p"` give the same payload and nothing downstream rebuilds between them.

use latticebuild_geom::field::ScalarField;
use latticebuild_geom::periodic::{PsModel, PsTerm};
use latticebuild_geom::{expr, tpms};

use super::StageError;
use crate::cache::KeyBuilder;
use crate::manifest::{Cell, CellSource, PsTransform};

pub const VERSION: u32 = 1;

#[derive(Clone, Debug, PartialEq)]
pub struct CellStage {
    pub source: CellSource,
}

impl CellStage {
    pub fn new(cell: &Cell) -> CellStage {
        CellStage {
            source: cell.source.clone(),
        }
    }

    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        match &self.source {
            CellSource::Tpms(name) => key.param("tpms", name.as_str()),
            CellSource::Expr(text) => key.param("expr", text.as_str()),
            // The transform only when given: a cell without one keeps its key.
            CellSource::Ps { terms, transform } => {
                let key = key.param("ps", super::crystal::encode(&PsModel::new(terms.to_vec())));
                match transform {
                    Some(t) => key.param("transform", t.numbers()),
                    None => key,
                }
            }
            CellSource::Blend { .. }
            | CellSource::Minkowski { .. }
            | CellSource::Mesh(_)
            | CellSource::Voxels(_)
            | CellSource::Points(_)
            | CellSource::Crystal(_) => key.param("combined", true),
        }
    }

    /// The payload: the formula's text, UTF-8. Validation guarantees library names exist.
    pub fn run(&self) -> Result<Vec<u8>, StageError> {
        let formula = match &self.source {
            CellSource::Tpms(name) => tpms::lookup(name)
                .ok_or_else(|| {
                    StageError::Internal(format!(
                        "unknown TPMS `{name}` (manifest validation missed it)"
                    ))
                })?
                .formula
                .to_string(),
            CellSource::Expr(text) => text.clone(),
            CellSource::Ps { terms, transform } => {
                return ps_payload(terms, transform.as_ref());
            }
            CellSource::Blend { .. }
            | CellSource::Minkowski { .. }
            | CellSource::Mesh(_)
            | CellSource::Voxels(_)
            | CellSource::Points(_)
            | CellSource::Crystal(_) => {
                return Err(StageError::Internal(
                    "blends, Minkowski combinations, meshes, voxel images, point clouds and crystals have no formula".into(),
                ));
            }
        };
        Ok(formula.into_bytes())
    }
}

/// The payload of an explicit PS model, moved by its transform: the same as a crystal cell's.
pub fn ps_payload(
    terms: &[PsTerm],
    transform: Option<&PsTransform>,
) -> Result<Vec<u8>, StageError> {
    let model = PsModel::new(terms.to_vec());
    let model = match transform {
        None => model,
        Some(t) => super::crystal::transform(&model, t)?,
    };
    Ok(super::crystal::encode(&model))
}

/// The field of a cell payload: a mesh cell's (see [`super::mesh`]), a PS model's (see
/// [`super::crystal`]) or a formula's.
pub fn cell_field(payload: &[u8]) -> Result<Box<dyn ScalarField>, StageError> {
    if super::mesh::is_mesh_cell(payload) {
        return super::mesh::mesh_cell_field(payload);
    }
    if super::voxels::is_voxel_cell(payload) {
        return super::voxels::voxel_cell_field(payload);
    }
    if super::points::is_point_cell(payload) {
        return super::points::point_cell_field(payload);
    }
    if super::crystal::is_ps_cell(payload) {
        return super::crystal::ps_cell_field(payload);
    }
    let text = std::str::from_utf8(payload)
        .map_err(|_| StageError::Internal("cell formula is not UTF-8".into()))?;
    let compiled = expr::compile(text)
        .map_err(|e| StageError::geometry_of("cell formula does not compile", e))?;
    Ok(Box::new(compiled))
}
