//! Constant folding.
//!
//! Invariant: folding never changes a value, bit for bit, at any point (NaN payloads aside).
//! Only subtrees without variables are replaced, by the value [`Func::apply`] /
//! [`BinOp::apply`] compute for them at run time; nothing is reassociated or simplified
//! algebraically (`x*0` is not `0` when `x` is infinite, `(x+1)-1` is not `x`).
//!
//! [`Func::apply`]: super::ast::Func::apply
//! [`BinOp::apply`]: super::ast::BinOp::apply

use super::ast::Expr;

/// `expr` with every variable-free subtree replaced by its value.
pub fn fold(expr: &Expr) -> Expr {
    match expr {
        Expr::Num(_) | Expr::Var(_) => expr.clone(),
        Expr::Neg(a) => match fold(a) {
            Expr::Num(v) => Expr::Num(-v),
            a => Expr::Neg(Box::new(a)),
        },
        Expr::Call(f, a) => match fold(a) {
            Expr::Num(v) => Expr::Num(f.apply(v)),
            a => Expr::call(*f, a),
        },
        Expr::Binary(op, a, b) => match (fold(a), fold(b)) {
            (Expr::Num(a), Expr::Num(b)) => Expr::Num(op.apply(a, b)),
            (a, b) => Expr::binary(*op, a, b),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::ast::{BinOp, Var};
    use crate::expr::parse;
    use std::f64::consts::{PI, TAU};

    fn folded(text: &str) -> Expr {
        fold(&parse(text).expect(text))
    }

    #[test]
    fn constant_subtrees_fold() {
        assert_eq!(folded("pi*2"), Expr::Num(TAU));
        assert_eq!(folded("sqrt(3)"), Expr::Num(3f64.sqrt()));
        assert_eq!(folded("-(1)"), Expr::Num(-1.0));
        assert_eq!(folded("2^3^2"), Expr::Num(512.0));
        assert_eq!(folded("min(3, 1, 2)"), Expr::Num(1.0));
        assert_eq!(
            folded("cos(2*pi*x)"),
            Expr::call(
                crate::expr::ast::Func::Cos,
                Expr::binary(BinOp::Mul, Expr::Num(2.0 * PI), Expr::Var(Var::X))
            )
        );
    }

    #[test]
    fn ieee_semantics_are_kept() {
        assert!(matches!(folded("1/0"), Expr::Num(v) if v == f64::INFINITY));
        assert!(matches!(folded("-1/0"), Expr::Num(v) if v == f64::NEG_INFINITY));
        assert!(matches!(folded("0/0"), Expr::Num(v) if v.is_nan()));
        assert!(matches!(folded("sqrt(-1)"), Expr::Num(v) if v.is_nan()));
        assert!(matches!(folded("-0"), Expr::Num(v) if v == 0.0 && v.is_sign_negative()));
        // Not constant as a whole, so not touched: x*0 is NaN for infinite x.
        assert_eq!(
            folded("x*0"),
            Expr::binary(BinOp::Mul, Expr::Var(Var::X), Expr::Num(0.0))
        );
        // No reassociation: (x + 1) - 1 keeps both constants.
        assert_eq!(folded("x + 1 - 1"), parse("x + 1 - 1").expect("valid"));
        // 2*x*3 is (2*x)*3: the constants are not adjacent in the tree.
        assert_eq!(folded("2*x*3"), parse("2*x*3").expect("valid"));
    }
}
