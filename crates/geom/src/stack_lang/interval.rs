//! Interval arithmetic for deciding, block by block, that a field cannot change sign or that
//! one operand of a min/max cannot win.
//!
//! An [`Interval`] `[lo, hi]` with a `nan` flag stands for a set of values that the sampled
//! field may take: every non-NaN value lies in `[lo, hi]`, and `nan` says NaN may occur.
//!
//! Invariants:
//! - Enclosure: for any inputs in the argument intervals, the floating-point result of the
//!   operation lies in the result interval. Endpoints are computed in floating point and then
//!   widened by [`RELATIVE_SLACK`] of their magnitude (plus a tiny absolute amount), which
//!   covers the rounding of the evaluators (a few ulps of the intermediate magnitudes) many
//!   times over; intervals are only used to prove signs, so being wide costs speed, never
//!   correctness.
//! - Anything this module cannot bound tightly (division by an interval holding 0, powers of
//!   negative bases, infinite endpoints in arithmetic) becomes [`Interval::UNKNOWN`], which
//!   proves nothing.

use std::f64::consts::{PI, TAU};

use crate::expr::{BinOp, Expr, Func};

/// Relative widening applied to every computed endpoint.
pub const RELATIVE_SLACK: f64 = 1e-12;
/// Absolute widening, so that an exact 0 never proves a sign.
const ABSOLUTE_SLACK: f64 = 1e-300;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
    pub nan: bool,
}

impl Interval {
    pub const UNKNOWN: Interval = Interval {
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
        nan: true,
    };

    /// The exact value `v` (no widening: constants are exact).
    pub fn point(v: f64) -> Interval {
        if v.is_nan() {
            return Interval::UNKNOWN;
        }
        Interval {
            lo: v,
            hi: v,
            nan: false,
        }
    }

    /// `[lo, hi]` widened; NaN endpoints give UNKNOWN.
    pub fn new(lo: f64, hi: f64) -> Interval {
        if lo.is_nan() || hi.is_nan() {
            return Interval::UNKNOWN;
        }
        Interval {
            lo: lo - (lo.abs() * RELATIVE_SLACK + ABSOLUTE_SLACK),
            hi: hi + (hi.abs() * RELATIVE_SLACK + ABSOLUTE_SLACK),
            nan: false,
        }
    }

    fn finite(&self) -> bool {
        !self.nan && self.lo.is_finite() && self.hi.is_finite()
    }

    /// Every value is `≥ 0`, so every sample is outside (NaN counts as outside too, but an
    /// interval that may hold NaN is not trusted to prove anything).
    pub fn proves_outside(&self) -> bool {
        !self.nan && self.lo > 0.0
    }

    /// Every value is `< 0`: every sample is inside.
    pub fn proves_inside(&self) -> bool {
        !self.nan && self.hi < 0.0
    }

    pub fn hull(&self, other: &Interval) -> Interval {
        Interval {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
            nan: self.nan || other.nan,
        }
    }

    pub fn neg(self) -> Interval {
        Interval {
            lo: -self.hi,
            hi: -self.lo,
            nan: self.nan,
        }
    }

    pub fn add(self, b: Interval) -> Interval {
        if !self.finite() || !b.finite() {
            return Interval::UNKNOWN;
        }
        Interval::new(self.lo + b.lo, self.hi + b.hi)
    }

    pub fn sub(self, b: Interval) -> Interval {
        self.add(b.neg())
    }

    pub fn mul(self, b: Interval) -> Interval {
        if !self.finite() || !b.finite() {
            return Interval::UNKNOWN;
        }
        let p = [
            self.lo * b.lo,
            self.lo * b.hi,
            self.hi * b.lo,
            self.hi * b.hi,
        ];
        Interval::new(
            p.iter().fold(f64::INFINITY, |m, &v| m.min(v)),
            p.iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v)),
        )
    }

    /// `k · self` for an exact constant `k`.
    pub fn scale(self, k: f64) -> Interval {
        self.mul(Interval::point(k))
    }

    pub fn div(self, b: Interval) -> Interval {
        if !b.finite() || b.lo <= 0.0 && b.hi >= 0.0 {
            return Interval::UNKNOWN;
        }
        let inv = Interval::new(1.0 / b.hi, 1.0 / b.lo);
        self.mul(inv)
    }

    pub fn abs(self) -> Interval {
        let (lo, hi) = if self.lo >= 0.0 {
            (self.lo, self.hi)
        } else if self.hi <= 0.0 {
            (-self.hi, -self.lo)
        } else {
            (0.0, self.hi.max(-self.lo))
        };
        Interval {
            lo,
            hi,
            nan: self.nan,
        }
    }

    pub fn square(self) -> Interval {
        let a = self.abs();
        if !a.finite() {
            return Interval::UNKNOWN;
        }
        Interval::new(a.lo * a.lo, a.hi * a.hi)
    }

    /// `f64::min` of two values: NaN loses to a number, so a side that may be NaN lets the
    /// other side's values through unchanged.
    pub fn min(self, b: Interval) -> Interval {
        let mut r = Interval {
            lo: self.lo.min(b.lo),
            hi: self.hi.min(b.hi),
            nan: self.nan && b.nan,
        };
        if self.nan {
            r = Interval {
                nan: r.nan,
                ..r.hull(&b)
            };
        }
        if b.nan {
            r = Interval {
                nan: r.nan,
                ..r.hull(&self)
            };
        }
        r
    }

    pub fn max(self, b: Interval) -> Interval {
        self.neg().min(b.neg()).neg()
    }

    pub fn sqrt(self) -> Interval {
        if self.nan || self.hi < 0.0 {
            return Interval::UNKNOWN;
        }
        let mut r = Interval::new(self.lo.max(0.0).sqrt(), self.hi.sqrt());
        r.lo = r.lo.max(0.0);
        // sqrt of a negative value is NaN.
        r.nan = self.lo < 0.0;
        r
    }

    /// `cos` over the interval, including the extrema at multiples of π it contains.
    pub fn cos(self) -> Interval {
        if !self.finite() {
            return Interval::UNKNOWN;
        }
        if self.hi - self.lo >= TAU {
            return Interval::new(-1.0, 1.0);
        }
        let (a, b) = (self.lo.cos(), self.hi.cos());
        let (mut lo, mut hi) = (a.min(b), a.max(b));
        // Extrema at kπ: a maximum for even k, a minimum for odd k. Look a little beyond the
        // ends so that rounding of the interval never hides one.
        let slack = 1e-9 * (1.0 + self.lo.abs().max(self.hi.abs()));
        let first = ((self.lo - slack) / PI).ceil();
        let mut k = first;
        while k * PI <= self.hi + slack && k < first + 3.0 {
            if (k as i64).rem_euclid(2) == 0 {
                hi = 1.0;
            } else {
                lo = -1.0;
            }
            k += 1.0;
        }
        Interval::new(lo, hi).clamp_unit()
    }

    pub fn sin(self) -> Interval {
        self.sub(Interval::point(PI / 2.0)).cos()
    }

    fn clamp_unit(self) -> Interval {
        Interval {
            lo: self.lo.max(-1.0),
            hi: self.hi.min(1.0),
            nan: self.nan,
        }
    }

    pub fn exp(self) -> Interval {
        if !self.finite() {
            return Interval::UNKNOWN;
        }
        let mut r = Interval::new(self.lo.exp(), self.hi.exp());
        r.lo = r.lo.max(0.0);
        r
    }

    pub fn ln(self) -> Interval {
        if !self.finite() || self.lo <= 0.0 {
            return Interval::UNKNOWN;
        }
        Interval::new(self.lo.ln(), self.hi.ln())
    }

    pub fn tan(self) -> Interval {
        if !self.finite() {
            return Interval::UNKNOWN;
        }
        // A pole at π/2 + kπ inside the interval makes it unbounded.
        let pole = ((self.lo - PI / 2.0) / PI).ceil() * PI + PI / 2.0;
        if pole <= self.hi + 1e-9 * (1.0 + self.hi.abs()) {
            return Interval::UNKNOWN;
        }
        Interval::new(self.lo.tan(), self.hi.tan())
    }

    /// `a ^ b` with the language's meaning (`powf`, and `a * a` for `b = 2`).
    pub fn pow(self, b: Interval) -> Interval {
        if !self.finite() || !b.finite() {
            return Interval::UNKNOWN;
        }
        if b.lo == b.hi {
            let e = b.lo;
            if e == 2.0 {
                return self.square();
            }
            if e == e.trunc() && e.abs() < 1e9 {
                let n = e as i64;
                if n == 0 {
                    return Interval::point(1.0);
                }
                if n < 0 {
                    return Interval::point(1.0).div(self.pow(Interval::point(-e)));
                }
                if n % 2 == 0 {
                    let a = self.abs();
                    return Interval::new(a.lo.powf(e), a.hi.powf(e));
                }
                return Interval::new(self.lo.powf(e), self.hi.powf(e));
            }
            if self.lo >= 0.0 {
                let (x, y) = (self.lo.powf(e), self.hi.powf(e));
                return Interval::new(x.min(y), x.max(y));
            }
            return Interval::UNKNOWN;
        }
        if self.lo > 0.0 {
            // a^b = exp(b ln a), monotone in each argument on a > 0.
            return b.mul(self.ln()).exp();
        }
        Interval::UNKNOWN
    }
}

/// An interval containing the values of `e` at every point of the box `x × y × z`.
pub fn eval_expr(e: &Expr, vars: &[Interval; 3]) -> Interval {
    match e {
        Expr::Num(v) => Interval::point(*v),
        Expr::Var(v) => vars[v.index()],
        Expr::Neg(a) => eval_expr(a, vars).neg(),
        Expr::Call(f, a) => {
            let a = eval_expr(a, vars);
            match f {
                Func::Sin => a.sin(),
                Func::Cos => a.cos(),
                Func::Tan => a.tan(),
                Func::Exp => a.exp(),
                Func::Log => a.ln(),
                Func::Sqrt => a.sqrt(),
                Func::Abs => a.abs(),
            }
        }
        Expr::Binary(op, a, b) => {
            let (a, b) = (eval_expr(a, vars), eval_expr(b, vars));
            match op {
                BinOp::Add => a.add(b),
                BinOp::Sub => a.sub(b),
                BinOp::Mul => a.mul(b),
                BinOp::Div => a.div(b),
                BinOp::Pow => a.pow(b),
                BinOp::Min => a.min(b),
                BinOp::Max => a.max(b),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::{fold, parse};

    /// Samples the interval's operation densely and checks that every value is enclosed.
    fn encloses(text: &str, lo: [f64; 3], hi: [f64; 3]) {
        let e = fold(&parse(text).expect(text));
        let vars = std::array::from_fn(|a| Interval::new(lo[a], hi[a]));
        let r = eval_expr(&e, &vars);
        let n = 12;
        for i in 0..=n {
            for j in 0..=n {
                for k in 0..=n {
                    let t = [i, j, k].map(|v| v as f64 / n as f64);
                    let p = std::array::from_fn(|a| lo[a] + t[a] * (hi[a] - lo[a]));
                    let v = e.eval_tree(p);
                    if v.is_nan() {
                        assert!(r.nan, "{text}: NaN at {p:?} not flagged");
                    } else {
                        assert!(r.lo <= v && v <= r.hi, "{text}: {v} at {p:?} not in {r:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn intervals_enclose_sampled_values() {
        let boxes = [
            ([0.1, 0.2, 0.3], [0.2, 0.25, 0.5]),
            ([-0.3, -1.0, 0.0], [0.4, 0.5, 2.0]),
            ([-3.0, 2.0, -7.5], [-2.9, 2.01, -7.4]),
        ];
        let texts = [
            "cos(tau*x)*sin(tau*y) + cos(tau*y)*sin(tau*z) + cos(tau*z)*sin(tau*x)",
            "sqrt(x^2 + y^2 + z^2) - 1",
            "sqrt(x) + log(y) - exp(z)",
            "x / (y - 0.3) + tan(z)",
            "min(x, y, abs(z)) - max(x^3, y^-2, 2^z)",
            "x^0.5 * y^2.5 + (x*y)^y",
        ];
        for text in texts {
            for (lo, hi) in boxes {
                encloses(text, lo, hi);
            }
        }
    }

    #[test]
    fn cos_finds_its_extrema() {
        let r = Interval::new(-0.1, 0.1).cos();
        assert!(r.hi >= 1.0 && r.lo > 0.99);
        let r = Interval::new(3.0, 3.3).cos();
        assert!(r.lo <= -1.0 && r.hi < -0.98);
        let r = Interval::new(0.2, 0.4).sin();
        assert!((r.lo - 0.2f64.sin()).abs() < 1e-9 && (r.hi - 0.4f64.sin()).abs() < 1e-9);
    }

    #[test]
    fn nan_and_min_max() {
        let maybe_nan = Interval::new(-1.0, 4.0).sqrt();
        assert!(maybe_nan.nan && maybe_nan.lo == 0.0);
        // max(NaN, 5) is 5, so the result may not be NaN and is at least min(0, 5).
        let m = maybe_nan.max(Interval::point(5.0));
        assert!(!m.nan && m.lo >= 5.0 - 1e-9 && m.hi >= 5.0);
        assert!(Interval::new(1.0, 2.0).div(Interval::new(-1.0, 1.0)) == Interval::UNKNOWN);
        assert!(
            !Interval::point(0.0)
                .add(Interval::point(0.0))
                .proves_outside()
        );
    }
}
