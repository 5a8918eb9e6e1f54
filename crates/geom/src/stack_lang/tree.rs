//! The parsed program: a tree of operations stored in post-order, and its canonical text.
//!
//! The words of a program are the post-order walk of its tree (paper, Figure 1), so the parser
//! appends each node as its word is read and the root is the last node. Every later pass
//! (bounds, compilation) walks this array forwards (children before parents) or backwards
//! (parents before children), never recursively, so no program is too deep to handle.
//!
//! Invariants:
//! - `nodes[i].children` hold indices smaller than `i`; the last node is the root; every node
//!   but the root is the child of exactly one node.
//! - Arguments are stored as the values they evaluate to, already checked (finite, non-zero
//!   scale factors, non-negative shell thickness, non-zero rotation axis, orientation axis off
//!   the negative z half-axis, a unit blend direction, a positive blend width).
//! - [`Tree::canonical`] is itself a program that parses back to a tree with the same
//!   canonical text; two programs with equal canonical text compute the same function.

use std::fmt::Write;

use super::words::{At, quote};
use crate::expr::Expr;
use crate::tpms::Surface;

/// One operation of the language.
#[derive(Clone, Debug, PartialEq)]
pub enum Op {
    /// The unit ball `|x| − 1`.
    Ball,
    /// The unit cylinder along z, infinitely long: `√(x² + y²) − 1`.
    Cylinder,
    /// The box of half-width 1, with its exact Euclidean distance.
    Box,
    /// A surface of the TPMS library, period 1.
    Tpms(&'static Surface),
    /// A user formula in x, y, z: the text as written and its parsed tree.
    Expression { text: String, expr: Expr },
    /// A mesh's signed distance; the path is resolved by the caller
    /// ([`ExternalSolids`](super::ExternalSolids)).
    File(String),
    /// `−f` (eq. 8).
    Complement,
    /// `f − ξ` (eq. 6).
    Offset(f64),
    /// `|f| − Ξ/2` (eq. 7, the shell of eq. 14).
    Shell(f64),
    /// `f(x − δ)` (eq. 2).
    Move([f64; 3]),
    /// `|κ| f(x/κ)` (eq. 3).
    Scale(f64),
    /// `min_i |κ_i| f(x/κ)`, componentwise division (eq. 4).
    ScaleAxes([f64; 3]),
    /// `f(R x)` with R the Rodrigues matrix of the unit axis and the angle (eq. 5).
    Rotate { axis: [f64; 3], angle: f64 },
    /// The solid turned so that its z axis points along the vector (§2, after eq. 5).
    Orient([f64; 3]),
    /// `min(f, g)` (eq. 9).
    Union,
    /// `max(f, g)` (eq. 10).
    Intersection,
    /// `max(f, −g)` (eq. 11).
    Difference,
    /// `(1 − w) f + w g` with the sigmoid weight `w = 1/(1 + exp(−(d̂·x − x0)/width))` along
    /// the unit direction d̂ (a heterogeneous solid, graded from f to g; `blend.rs`).
    SigmoidBlend {
        direction: [f64; 3],
        x0: f64,
        width: f64,
    },
}

impl Op {
    /// How many solids the operation takes from the stack.
    pub fn arity(&self) -> usize {
        match self {
            Op::Ball
            | Op::Cylinder
            | Op::Box
            | Op::Tpms(_)
            | Op::Expression { .. }
            | Op::File(_) => 0,
            Op::Union | Op::Intersection | Op::Difference | Op::SigmoidBlend { .. } => 2,
            _ => 1,
        }
    }
}

/// A node of the tree: its operation, its children (the first `arity` entries) and the word
/// that made it.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    pub op: Op,
    pub children: [usize; 2],
    pub at: At,
}

/// A parsed program.
#[derive(Clone, Debug, PartialEq)]
pub struct Tree {
    pub(crate) nodes: Vec<Node>,
}

impl Tree {
    /// The nodes in post-order; the last one is the root.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    pub fn root(&self) -> usize {
        self.nodes.len() - 1
    }

    /// The paths of the `file` words, in program order.
    pub fn files(&self) -> Vec<&str> {
        self.nodes
            .iter()
            .filter_map(|n| match &n.op {
                Op::File(path) => Some(path.as_str()),
                _ => None,
            })
            .collect()
    }

    /// The program in canonical words: numbers as the shortest text that reads back to the
    /// same `f64`, TPMS by canonical name, words lower case, one space between words,
    /// formulas without whitespace.
    pub fn canonical(&self) -> String {
        self.canonical_with(&|path| path.to_string())
    }

    /// [`canonical`](Self::canonical) with each `file` path replaced by `file_key(path)`, e.g.
    /// a hash of the file's content, for cache keys that must not depend on where a file is.
    pub fn canonical_with(&self, file_key: &dyn Fn(&str) -> String) -> String {
        let mut out = String::new();
        for node in &self.nodes {
            if !out.is_empty() {
                out.push(' ');
            }
            // `write!` to a String cannot fail.
            let _ = match &node.op {
                Op::Ball => write!(out, "ball"),
                Op::Cylinder => write!(out, "cylinder"),
                Op::Box => write!(out, "box"),
                Op::Tpms(s) => write!(out, "tpms.{}", s.name),
                // Whitespace never separates two tokens of a valid formula that would otherwise
                // merge, so dropping it keeps the meaning and normalizes the spelling.
                Op::Expression { text, .. } => {
                    let compact: String = text.chars().filter(|c| !c.is_whitespace()).collect();
                    write!(out, "expression {}", quote(&compact))
                }
                Op::File(path) => write!(out, "file {}", quote(&file_key(path))),
                Op::Complement => write!(out, "complement"),
                Op::Offset(v) => write!(out, "offset {}", number(*v)),
                Op::Shell(v) => write!(out, "shell {}", number(*v)),
                Op::Move(v) => write!(out, "move {}", vector(v)),
                Op::Scale(v) => write!(out, "scale {}", number(*v)),
                Op::ScaleAxes(v) => write!(out, "scale {}", vector(v)),
                Op::Rotate { axis, angle } => {
                    write!(out, "rotate {} {}", vector(axis), number(*angle))
                }
                Op::Orient(v) => write!(out, "orient {}", vector(v)),
                Op::Union => write!(out, "union"),
                Op::Intersection => write!(out, "intersection"),
                Op::Difference => write!(out, "difference"),
                Op::SigmoidBlend {
                    direction,
                    x0,
                    width,
                } => write!(
                    out,
                    "sigmoid-blend {} {} {}",
                    vector(direction),
                    number(*x0),
                    number(*width)
                ),
            };
        }
        out
    }
}

/// The shortest decimal that parses back to `v` (Rust's `Debug` for `f64`), which the
/// expression language reads (`1e-7`, `0.5`, `-0.0`).
fn number(v: f64) -> String {
    format!("{v:?}")
}

fn vector(v: &[f64; 3]) -> String {
    format!("{},{},{}", number(v[0]), number(v[1]), number(v[2]))
}
