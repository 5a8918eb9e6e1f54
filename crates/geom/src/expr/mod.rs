//! Expressions in x, y, z: parsing, constant folding, compiled evaluation and separable
//! analysis. (Interface fixed here; the implementation lands with the expression work.)

use std::ops::Range;

/// A syntax or name error in an expression, located by a byte span in its text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseError {
    pub span: Range<usize>,
    pub message: String,
    pub help: Option<String>,
}
