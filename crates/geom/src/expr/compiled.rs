//! The compiled form of an expression: what the rest of the crate evaluates.
//!
//! Invariants:
//! - A [`CompiledExpr`] is immutable after construction and holds no interior mutability, so
//!   it is `Send + Sync` and every evaluation is a pure function of its inputs.
//! - Its tree is folded once; the program and the separable form are both built from that
//!   same folded tree, so they compute the same function.
//! - [`ScalarField::sampler`] takes the separable path whenever the analysis found a form,
//!   and the pointwise path otherwise; both agree to rounding.

use super::ParseError;
use super::ast::Expr;
use super::fold::fold;
use super::parse::parse;
use super::plane::SeparableSampler;
use super::program::Program;
use super::separable::SeparableForm;
use crate::field::{Grid, PlaneSampler, PointwiseSampler, ScalarField};

/// An expression ready for evaluation: folded, compiled to bytecode, and analysed for
/// separability.
#[derive(Clone, Debug)]
pub struct CompiledExpr {
    expr: Expr,
    program: Program,
    separable: Option<SeparableForm>,
}

/// Parses, folds and compiles `text`.
pub fn compile(text: &str) -> Result<CompiledExpr, ParseError> {
    Ok(CompiledExpr::from_expr(&parse(text)?))
}

impl CompiledExpr {
    /// Compiles a tree. Trees from [`parse`] are always accepted; a hand-built tree should not
    /// be taller than [`MAX_HEIGHT`](super::MAX_HEIGHT), or the recursive passes may exhaust
    /// the stack.
    pub fn from_expr(expr: &Expr) -> CompiledExpr {
        let expr = fold(expr);
        let program = Program::new(&expr);
        let separable = SeparableForm::analyse(&expr);
        CompiledExpr {
            expr,
            program,
            separable,
        }
    }

    /// The folded tree.
    pub fn expr(&self) -> &Expr {
        &self.expr
    }

    /// The value at one point.
    pub fn eval(&self, p: [f64; 3]) -> f64 {
        let mut out = [0.0];
        self.program.eval(&[p[0]], &[p[1]], &[p[2]], &mut out);
        out[0]
    }

    /// Whether grids are sampled from per-axis tables rather than point by point.
    pub fn is_separable(&self) -> bool {
        self.separable.is_some()
    }

    /// The separable form, if the expression has one.
    pub fn separable_form(&self) -> Option<&SeparableForm> {
        self.separable.as_ref()
    }
}

impl ScalarField for CompiledExpr {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        self.program.eval(xs, ys, zs, out);
    }

    fn sampler<'a>(&'a self, grid: &Grid) -> Box<dyn PlaneSampler + 'a> {
        match &self.separable {
            Some(form) => Box::new(SeparableSampler::new(form, grid)),
            None => Box::new(PointwiseSampler {
                field: self,
                grid: *grid,
            }),
        }
    }
}
