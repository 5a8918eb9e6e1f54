//! Expressions in x, y, z: parsing, constant folding, compiled evaluation and separable
//! analysis.
//!
//! Pipeline: [`parse`] text into an [`Expr`], [`fold`] its constant subtrees, then
//! [`CompiledExpr::from_expr`] builds a block-evaluated register program and, when the
//! expression is a finite sum of products of one-variable factors, a [`SeparableForm`] whose
//! grid sampler needs no transcendental function per sample. [`compile`] does all three.
//!
//! Invariants of the module:
//! - Nothing here panics or overflows the stack on any input text; every problem with the
//!   text is a [`ParseError`] with a byte span into it.
//! - Every stage computes the same function: folding is exact, the program agrees with the
//!   tree bit for bit, and the separable sampler agrees with them up to rounding.
//! - Samplers are pure functions of the plane index.

use std::ops::Range;

mod ast;
mod compiled;
mod error;
mod fold;
mod lex;
mod parse;
mod plane;
mod program;
mod separable;

pub use ast::{BinOp, CONSTANTS, Expr, Func, Var};
pub use compiled::{CompiledExpr, compile};
pub use fold::fold;
pub use parse::{MAX_HEIGHT, MAX_NESTING, parse};
pub use separable::{MAX_TERMS, SeparableForm};

/// A syntax or name error in an expression, located by a byte span in its text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseError {
    pub span: Range<usize>,
    pub message: String,
    pub help: Option<String>,
}
