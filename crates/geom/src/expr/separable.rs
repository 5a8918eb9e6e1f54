//! Recognising expressions that are finite sums of products of one-variable factors,
//! `f(x, y, z) = Σ_t c_t · X_t(x) · Y_t(y) · Z_t(z)`.
//!
//! Rules, applied top-down on a folded tree:
//! - a subtree of at most one variable is a single factor (or a constant);
//! - sums concatenate terms, negation and constant factors scale them, products distribute;
//! - division by a single term (a constant, or a product of one-variable factors) scales or
//!   multiplies by reciprocal factors; a non-negative integer power expands as a product, and
//!   any integer power of a single term distributes over its factors;
//! - `sin`/`cos` of a sum of one-variable parts expand by the angle-addition formulas, and
//!   `exp` of such a sum becomes a product;
//! - anything else with several variables (`sqrt(x^2+y^2)`, `min(x, y)`, `sin(x*y)`, division
//!   by a sum, more than [`MAX_TERMS`] terms) makes the whole expression non-separable.
//!
//! Invariants:
//! - The form equals the expression as a real function; in floating point the two differ
//!   only by rounding (expanded angle sums, distributed products, merged coefficients).
//! - Identical factors are stored once per axis (identity is structural, see `Expr::key`),
//!   and terms with the same three factors are merged, so a plane costs one multiply-add per
//!   sample for each distinct x factor.
//! - Analysis is deterministic: terms and factors keep their first-appearance order.

use std::collections::HashMap;

use super::ast::{BinOp, Expr, Func};

/// Most terms an expression (or any subexpression during expansion) may have and still be
/// treated as separable. Beyond this the tables cost more than evaluating point by point.
pub const MAX_TERMS: usize = 512;

/// One term `c · X(x) · Y(y) · Z(z)`; `None` is the factor 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Term {
    pub c: f64,
    pub f: [Option<usize>; 3],
}

/// A separable expression: distinct one-variable factors per axis and the terms using them.
#[derive(Clone, Debug)]
pub struct SeparableForm {
    /// `factors[axis][id]`: an expression in that axis's variable only.
    pub(crate) factors: [Vec<Expr>; 3],
    pub(crate) terms: Vec<Term>,
}

type Sum = Vec<Term>;

impl SeparableForm {
    /// The separable form of a (preferably folded) expression, if it has one.
    pub fn analyse(expr: &Expr) -> Option<SeparableForm> {
        let mut a = Analyser::default();
        let sum = a.sum(expr)?;
        // Merge terms with identical factors, keeping first-appearance order.
        let mut terms: Vec<Term> = Vec::new();
        let mut index: HashMap<[Option<usize>; 3], usize> = HashMap::new();
        for t in sum {
            match index.get(&t.f) {
                Some(&i) => terms[i].c += t.c,
                None => {
                    index.insert(t.f, terms.len());
                    terms.push(t);
                }
            }
        }
        // Keep only the factors the final terms use, renumbered in order of use.
        let mut factors: [Vec<Expr>; 3] = Default::default();
        let mut renumber: [HashMap<usize, usize>; 3] = Default::default();
        for t in &mut terms {
            for (axis, f) in t.f.iter_mut().enumerate() {
                if let Some(id) = f {
                    let next = factors[axis].len();
                    let new = *renumber[axis].entry(*id).or_insert(next);
                    if new == next {
                        factors[axis].push(a.factors[axis][*id].clone());
                    }
                    *id = new;
                }
            }
        }
        Some(SeparableForm { factors, terms })
    }

    /// Number of terms after merging.
    pub fn term_count(&self) -> usize {
        self.terms.len()
    }

    /// Number of distinct one-variable factors along `axis` (0 = x).
    pub fn factor_count(&self, axis: usize) -> usize {
        self.factors[axis].len()
    }

    /// `Σ |c_t|`: with factors bounded by 1 (trigonometric series), a bound on the value and
    /// the scale of the rounding difference between this form and the expression.
    pub fn coefficient_sum(&self) -> f64 {
        self.terms.iter().map(|t| t.c.abs()).sum()
    }

    /// Evaluates the form at one point by walking the factor trees (reference for tests).
    pub fn eval_tree(&self, p: [f64; 3]) -> f64 {
        self.terms
            .iter()
            .map(|t| {
                (0..3).fold(t.c, |acc, axis| match t.f[axis] {
                    Some(id) => acc * self.factors[axis][id].eval_tree(p),
                    None => acc,
                })
            })
            .sum()
    }
}

#[derive(Default)]
struct Analyser {
    factors: [Vec<Expr>; 3],
    index: [HashMap<String, usize>; 3],
}

fn constant(c: f64) -> Sum {
    vec![Term { c, f: [None; 3] }]
}

fn negate(mut s: Sum) -> Sum {
    for t in &mut s {
        t.c = -t.c;
    }
    s
}

/// `c · f` as an expression, without a multiplication when `c` is ±1.
fn scaled(c: f64, f: Expr) -> Expr {
    if c == 1.0 {
        f
    } else if c == -1.0 {
        Expr::Neg(Box::new(f))
    } else {
        Expr::binary(BinOp::Mul, Expr::Num(c), f)
    }
}

impl Analyser {
    fn intern(&mut self, axis: usize, e: Expr) -> usize {
        let key = e.key();
        if let Some(&id) = self.index[axis].get(&key) {
            return id;
        }
        self.factors[axis].push(e);
        self.index[axis].insert(key, self.factors[axis].len() - 1);
        self.factors[axis].len() - 1
    }

    fn factor(&mut self, axis: usize, e: Expr) -> Term {
        let mut f = [None; 3];
        f[axis] = Some(self.intern(axis, e));
        Term { c: 1.0, f }
    }

    /// A one-variable subtree as a term, with constant scale factors moved out into the
    /// coefficient so that `cos(tau*x)` and `2*cos(tau*x)` share one table.
    fn scaled_factor(&mut self, axis: usize, e: &Expr) -> Term {
        let mut c = 1.0;
        let mut e = e;
        loop {
            match e {
                Expr::Neg(a) => {
                    c = -c;
                    e = a;
                }
                Expr::Binary(BinOp::Mul, k, a) | Expr::Binary(BinOp::Mul, a, k)
                    if matches!(**k, Expr::Num(_)) =>
                {
                    c *= k.const_value().unwrap_or(1.0);
                    e = a;
                }
                Expr::Binary(BinOp::Div, a, k) if matches!(**k, Expr::Num(_)) => {
                    c /= k.const_value().unwrap_or(1.0);
                    e = a;
                }
                _ => break,
            }
        }
        let mut term = self.factor(axis, e.clone());
        term.c = c;
        term
    }

    fn sum(&mut self, e: &Expr) -> Option<Sum> {
        let mask = e.var_mask();
        if mask == 0 {
            return Some(constant(e.const_value()?));
        }
        if mask.count_ones() == 1 {
            return Some(vec![self.scaled_factor(mask.trailing_zeros() as usize, e)]);
        }
        let s = match e {
            Expr::Num(_) | Expr::Var(_) => return None, // covered by the mask cases
            Expr::Neg(a) => negate(self.sum(a)?),
            Expr::Binary(op, a, b) => {
                let a_sum = self.sum(a)?;
                match op {
                    BinOp::Add => [a_sum, self.sum(b)?].concat(),
                    BinOp::Sub => [a_sum, negate(self.sum(b)?)].concat(),
                    BinOp::Mul => {
                        let b_sum = self.sum(b)?;
                        self.product(&a_sum, &b_sum)?
                    }
                    BinOp::Div => {
                        let b_sum = self.sum(b)?;
                        self.quotient(&a_sum, &b_sum)?
                    }
                    BinOp::Pow => self.power(a_sum, b.const_value()?)?,
                    BinOp::Min | BinOp::Max => return None,
                }
            }
            Expr::Call(f, a) => {
                let arg = self.sum(a)?;
                let (k, parts) = self.parts(&arg)?;
                match f {
                    Func::Sin => self.angle_sum(true, &parts, k),
                    Func::Cos => self.angle_sum(false, &parts, k),
                    Func::Exp => {
                        let mut term = Term {
                            c: k.exp(),
                            f: [None; 3],
                        };
                        for (axis, p) in parts {
                            term.f[axis] = Some(self.intern(axis, Expr::call(Func::Exp, p)));
                        }
                        vec![term]
                    }
                    _ => return None,
                }
            }
        };
        (s.len() <= MAX_TERMS).then_some(s)
    }

    /// The factor `a · b` along `axis` (either may be 1).
    fn times(&mut self, axis: usize, a: Option<usize>, b: Option<usize>) -> Option<usize> {
        match (a, b) {
            (None, f) | (f, None) => f,
            (Some(a), Some(b)) => {
                let e = Expr::binary(
                    BinOp::Mul,
                    self.factors[axis][a].clone(),
                    self.factors[axis][b].clone(),
                );
                Some(self.intern(axis, e))
            }
        }
    }

    fn product(&mut self, a: &Sum, b: &Sum) -> Option<Sum> {
        if a.len().saturating_mul(b.len()) > MAX_TERMS {
            return None;
        }
        let mut out = Vec::with_capacity(a.len() * b.len());
        for s in a {
            for t in b {
                let mut f = [None; 3];
                for (axis, slot) in f.iter_mut().enumerate() {
                    *slot = self.times(axis, s.f[axis], t.f[axis]);
                }
                out.push(Term { c: s.c * t.c, f });
            }
        }
        Some(out)
    }

    fn quotient(&mut self, a: &Sum, b: &Sum) -> Option<Sum> {
        let [d] = b.as_slice() else {
            return None; // dividing by a sum does not separate
        };
        let mut out = Vec::with_capacity(a.len());
        for t in a {
            let mut f = t.f;
            for (axis, slot) in f.iter_mut().enumerate() {
                let Some(den) = d.f[axis] else { continue };
                let num = match *slot {
                    Some(id) => self.factors[axis][id].clone(),
                    None => Expr::Num(1.0),
                };
                let e = Expr::binary(BinOp::Div, num, self.factors[axis][den].clone());
                *slot = Some(self.intern(axis, e));
            }
            out.push(Term { c: t.c / d.c, f });
        }
        Some(out)
    }

    fn power(&mut self, base: Sum, n: f64) -> Option<Sum> {
        if n.fract() != 0.0 || n.abs() > 64.0 {
            return None;
        }
        if let [t] = base.as_slice() {
            // (c·X·Y·Z)^n = c^n · X^n · Y^n · Z^n for integer n.
            let mut f = t.f;
            for (axis, slot) in f.iter_mut().enumerate() {
                if let Some(id) = *slot {
                    let e = Expr::binary(BinOp::Pow, self.factors[axis][id].clone(), Expr::Num(n));
                    *slot = Some(self.intern(axis, e));
                }
            }
            return Some(vec![Term {
                c: super::ast::pow(t.c, n),
                f,
            }]);
        }
        if n < 0.0 {
            return None;
        }
        let mut acc = constant(1.0);
        for _ in 0..n as usize {
            acc = self.product(&acc, &base)?;
        }
        Some(acc)
    }

    /// `sin` or `cos` of `Σ parts + k` by the angle-addition formulas.
    fn angle_sum(&mut self, sine: bool, parts: &[(usize, Expr)], k: f64) -> Sum {
        let Some(((axis, p), rest)) = parts.split_first() else {
            return match (sine, k == 0.0) {
                (true, true) => vec![], // sin 0 = 0: no term at all
                (true, false) => constant(k.sin()),
                (false, _) => constant(k.cos()),
            };
        };
        let s = self.factor(*axis, Expr::call(Func::Sin, p.clone()));
        let c = self.factor(*axis, Expr::call(Func::Cos, p.clone()));
        let cos_rest = self.angle_sum(false, rest, k);
        let sin_rest = self.angle_sum(true, rest, k);
        // Factors along different axes: these products never synthesise new factors, and the
        // sizes are bounded by 2^3 · 2 terms.
        let scale = |t: Term, rest: &Sum, sign: f64| -> Sum {
            rest.iter()
                .map(|r| {
                    let mut f = r.f;
                    f[*axis] = t.f[*axis];
                    Term { c: sign * r.c, f }
                })
                .collect()
        };
        if sine {
            // sin(p + r) = sin p cos r + cos p sin r
            [scale(s, &cos_rest, 1.0), scale(c, &sin_rest, 1.0)].concat()
        } else {
            // cos(p + r) = cos p cos r − sin p sin r
            [scale(c, &cos_rest, 1.0), scale(s, &sin_rest, -1.0)].concat()
        }
    }
}

impl Analyser {
    /// Splits a sum whose terms each depend on at most one variable into its constant and one
    /// expression per variable (in axis order). `None` if some term mixes variables.
    fn parts(&self, arg: &Sum) -> Option<(f64, Vec<(usize, Expr)>)> {
        let mut k = 0.0;
        let mut per_axis: [Option<Expr>; 3] = Default::default();
        for t in arg {
            let mut axes = (0..3).filter_map(|a| t.f[a].map(|id| (a, id)));
            match (axes.next(), axes.next()) {
                (None, _) => k += t.c,
                (Some((axis, id)), None) => {
                    let term = scaled(t.c, self.factors[axis][id].clone());
                    per_axis[axis] = Some(match per_axis[axis].take() {
                        None => term,
                        Some(acc) => Expr::binary(BinOp::Add, acc, term),
                    });
                }
                _ => return None,
            }
        }
        let parts = per_axis
            .into_iter()
            .enumerate()
            .filter_map(|(a, p)| p.map(|p| (a, p)));
        Some((k, parts.collect()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::{fold, parse};

    fn form(text: &str) -> Option<SeparableForm> {
        SeparableForm::analyse(&fold(&parse(text).expect(text)))
    }

    /// `Σ_t |c_t · X_t · Y_t · Z_t|` at `p`: the scale of the rounding difference between the
    /// form and the expression.
    fn magnitude(f: &SeparableForm, p: [f64; 3]) -> f64 {
        f.terms
            .iter()
            .map(|t| {
                (0..3).fold(t.c.abs(), |acc, a| match t.f[a] {
                    Some(id) => acc * f.factors[a][id].eval_tree(p).abs(),
                    None => acc,
                })
            })
            .sum()
    }

    #[test]
    fn shapes_of_known_forms() {
        let g = form("cos(tau*x)*sin(tau*y) + cos(tau*y)*sin(tau*z) + cos(tau*z)*sin(tau*x)")
            .expect("gyroid separates");
        assert_eq!(
            (
                g.term_count(),
                g.factor_count(0),
                g.factor_count(1),
                g.factor_count(2)
            ),
            (3, 2, 2, 2)
        );
        assert_eq!(g.coefficient_sum(), 3.0);
        // cos(a + b) = cos a cos b − sin a sin b.
        let c = form("cos(tau*(3*x + y))").expect("angle sum separates");
        assert_eq!(
            (c.term_count(), c.factor_count(0), c.factor_count(1)),
            (2, 2, 2)
        );
        // cos(x + y + z + 1) expands to 8 products, each scaled by cos 1 or sin 1.
        assert_eq!(form("cos(x + y + z + 1)").map(|f| f.term_count()), Some(8));
        assert_eq!(form("sin(x - y)").map(|f| f.term_count()), Some(2));
        assert_eq!(form("exp(x + 2*y - 1)").map(|f| f.term_count()), Some(1));
        // (x + y)^3: the products x·y·x and x·x·y are one term.
        assert_eq!(form("(x + y)^3").map(|f| f.term_count()), Some(4));
        assert_eq!(form("x*y/(2*z)").map(|f| f.term_count()), Some(1));
        assert_eq!(form("(x*y)^-2").map(|f| f.term_count()), Some(1));
        assert_eq!(form("3").map(|f| f.term_count()), Some(1));
        // A repeated factor is one table.
        let d = form("cos(tau*x)*sin(tau*y) + cos(tau*x)*cos(tau*z) + 2*cos(tau*x)*sin(tau*y)")
            .expect("separates");
        assert_eq!((d.term_count(), d.factor_count(0)), (2, 1));
        assert_eq!(d.coefficient_sum(), 4.0);
    }

    #[test]
    fn mixed_expressions_are_refused() {
        for text in [
            "sqrt(x^2 + y^2) - 0.3",
            "min(x, y)",
            "max(x, y) + z",
            "abs(x*y)",
            "sin(x*y)",
            "x/(x + y)",
            "x^y",
            "tan(x + y)",
            "log(x*y)",
            "(x + y)^0.5",
            "(x + y)^-1",
            "(x + y + z)^20",
        ] {
            assert!(form(text).is_none(), "{text} should not separate");
        }
    }

    /// A random expression built only from separable constructs.
    fn random_separable(rng: &mut u64, depth: u32) -> String {
        let mut next = |n: u64| {
            *rng ^= *rng << 13;
            *rng ^= *rng >> 7;
            *rng ^= *rng << 17;
            *rng % n
        };
        let leaf = [
            "x",
            "y",
            "z",
            "0.5",
            "2",
            "cos(tau*x)",
            "sin(3*y)",
            "exp(z/2)",
            "x^2",
        ];
        if depth == 0 {
            return leaf[next(leaf.len() as u64) as usize].to_string();
        }
        let choice = next(9);
        let mut sub = || random_separable(rng, depth - 1);
        match choice {
            0 => format!("({} + {})", sub(), sub()),
            1 => format!("({} - {})", sub(), sub()),
            2 => format!("{} * {}", sub(), sub()),
            3 => format!("-{}", sub()),
            4 => format!("cos({} + {})", sub(), sub()),
            5 => format!("sin({} - 2*{})", sub(), sub()),
            6 => format!("({})^2", sub()),
            7 => format!("{} / 3", sub()),
            _ => format!("exp(({} + {})/4)", sub(), sub()),
        }
    }

    #[test]
    fn random_forms_equal_their_expressions() {
        let mut rng = 0x9e37_79b9_7f4a_7c15u64;
        let mut separable = 0;
        for _ in 0..400 {
            let text = random_separable(&mut rng, 3);
            let expr = fold(&parse(&text).expect(&text));
            let Some(f) = SeparableForm::analyse(&expr) else {
                continue;
            };
            separable += 1;
            for i in 0..5 {
                let t = i as f64;
                let p = [(t * 0.71).sin(), (t * 1.3 + 0.2).cos(), 0.37 * t - 0.8];
                let want = expr.eval_tree(p);
                let got = f.eval_tree(p);
                let tol = 1e-12 * (1.0 + magnitude(&f, p));
                assert!(
                    (got - want).abs() <= tol,
                    "{text} at {p:?}: {got} vs {want}"
                );
            }
        }
        // Only sin/cos of products of several variables (not angle sums) may refuse.
        assert!(separable > 250, "only {separable} of 400 separated");
    }
}
