//! The `cell` stage: resolves a cell's source to the canonical formula every later stage
//! evaluates. Library surfaces and expressions meet here, so `tpms = "schwarz-p"` and
//! `tpms = "p"` give the same payload and nothing downstream rebuilds between them.

use latticebuild_geom::tpms;

use crate::cache::KeyBuilder;
use crate::manifest::{Cell, CellSource};

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
            CellSource::Blend { .. } | CellSource::Minkowski { .. } => key.param("combined", true),
        }
    }

    /// The payload: the formula's text, UTF-8. Validation guarantees library names exist.
    pub fn run(&self) -> Result<Vec<u8>, String> {
        let formula = match &self.source {
            CellSource::Tpms(name) => tpms::lookup(name)
                .ok_or_else(|| format!("unknown TPMS `{name}` (manifest validation missed it)"))?
                .formula
                .to_string(),
            CellSource::Expr(text) => text.clone(),
            CellSource::Blend { .. } | CellSource::Minkowski { .. } => {
                return Err("blends and Minkowski combinations have no formula".into());
            }
        };
        Ok(formula.into_bytes())
    }
}
