//! The stages: what each node of the graph computes, and what goes into its cache key.
//!
//! Invariants:
//! - A stage is a pure function of its parameters and its inputs' payloads. Only the write
//!   stage has an effect, and it reaches files solely through the [`OutputSink`] the CLI gives
//!   it; stages never open paths themselves.
//! - Everything a stage's result depends on is in its key: kind, version (bump it whenever the
//!   algorithm changes what it produces), parameters, and its inputs' payload hashes.
//!
//! | stage     | parameters in the key                                   | input          | payload |
//! |-----------|---------------------------------------------------------|----------------|---------|
//! | `cell`    | source kind, TPMS name or expression text               | —              | canonical formula text |
//! | `contour` | domain, cell size, solid, offset, thickness, samples   | cell payload   | mesh + its check ([`artifact`]) |
//! | `write`   | formats, encoding, path stem                            | contour payload| files written and the mesh summary (JSON) |

pub mod artifact;
pub mod cell;
pub mod contour;
pub mod write;

use crate::cache::{ContentHash, Key, KeyBuilder, KeyDescription, KeyError};
use crate::manifest::{Cell, Output};

pub use artifact::{MeshArtifact, MeshSummary, WrittenFile, WrittenOutput};
pub use write::OutputSink;

/// One node's computation, with its parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum Stage {
    Cell(cell::CellStage),
    Contour(contour::ContourStage),
    Write(write::WriteStage),
}

impl Stage {
    pub fn cell(cell: &Cell) -> Stage {
        Stage::Cell(cell::CellStage::new(cell))
    }

    pub fn contour(output: &Output) -> Stage {
        Stage::Contour(contour::ContourStage::new(output))
    }

    pub fn write(output: &Output) -> Stage {
        Stage::Write(write::WriteStage::new(output))
    }

    pub fn kind(&self) -> &'static str {
        match self {
            Stage::Cell(_) => "cell",
            Stage::Contour(_) => "contour",
            Stage::Write(_) => "write",
        }
    }

    /// Bumped whenever the stage's algorithm changes what it produces.
    pub fn version(&self) -> u32 {
        match self {
            Stage::Cell(_) => cell::VERSION,
            Stage::Contour(_) => contour::VERSION,
            Stage::Write(_) => write::VERSION,
        }
    }

    /// The cache key from the parameters and the payload hashes of the inputs, in order.
    pub fn key(&self, inputs: &[ContentHash]) -> Result<(Key, KeyDescription), KeyError> {
        let builder = KeyBuilder::new(self.kind(), self.version());
        let builder = match self {
            Stage::Cell(s) => s.key_params(builder),
            Stage::Contour(s) => s.key_params(builder),
            Stage::Write(s) => s.key_params(builder),
        };
        debug_assert_eq!(inputs.len(), self.input_names().len());
        let builder = self
            .input_names()
            .iter()
            .zip(inputs)
            .fold(builder, |b, (name, hash)| b.input(name, *hash));
        builder.build()
    }

    /// Names of the inputs, in order, as they appear in keys and `-v` explanations.
    pub fn input_names(&self) -> &'static [&'static str] {
        match self {
            Stage::Cell(_) => &[],
            Stage::Contour(_) => &["cell"],
            Stage::Write(_) => &["mesh"],
        }
    }
}
