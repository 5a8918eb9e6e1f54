//! The expression tree and the scalar meaning of every operation.
//!
//! Invariants:
//! - Every [`Expr`] is well formed by construction: functions of one argument hold exactly one,
//!   and `min`/`max` of several arguments are nested binary nodes, so no later stage has an
//!   arity to check.
//! - [`Func::apply`] and [`BinOp::apply`] are the only definitions of what an operation
//!   computes. Constant folding, the compiled program and the separable tables all call them,
//!   so a folded constant is bit-identical to what evaluation would have produced.

use std::f64::consts::{E, PI, TAU};

/// A coordinate variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Var {
    X,
    Y,
    Z,
}

impl Var {
    pub const ALL: [Var; 3] = [Var::X, Var::Y, Var::Z];

    /// Axis index: 0 for x, 1 for y, 2 for z.
    pub fn index(self) -> usize {
        self as usize
    }

    pub fn name(self) -> &'static str {
        match self {
            Var::X => "x",
            Var::Y => "y",
            Var::Z => "z",
        }
    }
}

/// A function of one argument.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Func {
    Sin,
    Cos,
    Tan,
    Exp,
    /// Natural logarithm.
    Log,
    Sqrt,
    Abs,
}

impl Func {
    pub const ALL: [Func; 7] = [
        Func::Sin,
        Func::Cos,
        Func::Tan,
        Func::Exp,
        Func::Log,
        Func::Sqrt,
        Func::Abs,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Exp => "exp",
            Func::Log => "log",
            Func::Sqrt => "sqrt",
            Func::Abs => "abs",
        }
    }

    #[inline]
    pub fn apply(self, a: f64) -> f64 {
        match self {
            Func::Sin => a.sin(),
            Func::Cos => a.cos(),
            Func::Tan => a.tan(),
            Func::Exp => a.exp(),
            Func::Log => a.ln(),
            Func::Sqrt => a.sqrt(),
            Func::Abs => a.abs(),
        }
    }
}

/// A binary operation. `Min` and `Max` are the binary forms of the n-ary functions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    Min,
    Max,
}

impl BinOp {
    #[inline]
    pub fn apply(self, a: f64, b: f64) -> f64 {
        match self {
            BinOp::Add => a + b,
            BinOp::Sub => a - b,
            BinOp::Mul => a * b,
            BinOp::Div => a / b,
            BinOp::Pow => pow(a, b),
            BinOp::Min => a.min(b),
            BinOp::Max => a.max(b),
        }
    }
}

/// `a ^ b`. Squares are by far the most common power and `a * a` is correctly rounded and
/// several times faster than `powf`, so `^ 2` is defined as that product everywhere.
#[inline]
pub fn pow(a: f64, b: f64) -> f64 {
    if b == 2.0 { a * a } else { a.powf(b) }
}

/// An expression in x, y and z.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    Num(f64),
    Var(Var),
    Neg(Box<Expr>),
    Call(Func, Box<Expr>),
    Binary(BinOp, Box<Expr>, Box<Expr>),
}

/// Named constants of the language and their values.
pub const CONSTANTS: [(&str, f64); 3] = [("pi", PI), ("tau", TAU), ("e", E)];

impl Expr {
    pub fn binary(op: BinOp, a: Expr, b: Expr) -> Expr {
        Expr::Binary(op, Box::new(a), Box::new(b))
    }

    pub fn call(f: Func, a: Expr) -> Expr {
        Expr::Call(f, Box::new(a))
    }

    /// The variables the expression depends on, as a bit set (bit 0 = x, 1 = y, 2 = z).
    pub fn var_mask(&self) -> u8 {
        match self {
            Expr::Num(_) => 0,
            Expr::Var(v) => 1 << v.index(),
            Expr::Neg(a) | Expr::Call(_, a) => a.var_mask(),
            Expr::Binary(_, a, b) => a.var_mask() | b.var_mask(),
        }
    }

    /// The value of an expression without variables, evaluated with the language's semantics.
    pub fn const_value(&self) -> Option<f64> {
        match self {
            Expr::Num(v) => Some(*v),
            Expr::Var(_) => None,
            Expr::Neg(a) => a.const_value().map(|v| -v),
            Expr::Call(f, a) => a.const_value().map(|v| f.apply(v)),
            Expr::Binary(op, a, b) => Some(op.apply(a.const_value()?, b.const_value()?)),
        }
    }

    /// Evaluates the tree directly at one point. Slow (it walks the tree); it exists as the
    /// reference the compiled forms are tested against.
    pub fn eval_tree(&self, p: [f64; 3]) -> f64 {
        match self {
            Expr::Num(v) => *v,
            Expr::Var(v) => p[v.index()],
            Expr::Neg(a) => -a.eval_tree(p),
            Expr::Call(f, a) => f.apply(a.eval_tree(p)),
            Expr::Binary(op, a, b) => op.apply(a.eval_tree(p), b.eval_tree(p)),
        }
    }

    /// A structural identity key: equal keys mean the same computation, bit for bit
    /// (`-0.0` and `0.0` differ; `Debug` prints floats so they round-trip exactly).
    pub(crate) fn key(&self) -> String {
        format!("{self:?}")
    }
}
