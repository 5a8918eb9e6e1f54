//! The sigmoid blend `f g sigmoid-blend d x0 width`: a heterogeneous solid graded from `f` to
//! `g` along a direction, as MSLattice grades between two lattices (Al-Ketan & Abu Al-Rub
//! 2020, "MSLattice: A free software for generating uniform and graded lattices based on
//! triply periodic minimal surfaces"), which Cesogen's paper cites for heterogeneous solids.
//!
//! ```text
//! s = d̂·x − x0                      signed distance along d̂ from the transition plane
//! w = 1 / (1 + exp(−s / width))     0 far on the −d̂ side, ½ on the plane, 1 far on the +d̂ side
//! h = (1 − w)·f + w·g = f + w·(g − f)
//! ```
//!
//! `x` is the point in the blend's own frame (point transformations written after the word
//! move, scale or turn the blend as a whole), so `x0` and `width` are lengths in those model
//! units; 90 % of the transition lies within `±2.94·width` of the plane.
//!
//! Validity: `h` is a convex combination of `f` and `g` at every point, so `min(f, g) ≤ h ≤
//! max(f, g)`: where both solids agree (both inside or both outside) the blend agrees too,
//! and its surface lies where they disagree. It is not a distance even when `f` and `g` are:
//! `∇h = (1 − w)∇f + w∇g + (g − f)∇w` and `|∇w| ≤ 1/(4·width)`, so its Lipschitz constant is
//! at most `max(L_f, L_g) + sup|g − f| / (4·width)`. A narrow width over fields that differ
//! much makes a steep field (and, as any sharp transition, needs samples finer than the
//! width to be resolved); nothing in the language assumes a blend is a distance.
//!
//! Invariants:
//! - The weight is compiled as an ordinary formula leaf in world coordinates ([`weight`]), so
//!   every sampler and bound that handles formulas handles it; it evaluates within `[0, 1]`
//!   (`exp` overflowing to ∞ gives exactly 0).
//! - [`interval`] encloses `f + w·(g − f)` as the machine computes it, for any `f`, `g`, `w`
//!   in the argument intervals.

use super::affine::Affine;
use super::interval::{Interval, RELATIVE_SLACK};
use crate::expr::{BinOp, Expr, Func, Var};

/// The weight `1 / (1 + exp(−(d̂·(map x) − x0) / width))` as a formula in world x, y, z,
/// where `map` takes world coordinates to the blend's frame and `direction` is a unit vector.
pub fn weight(map: &Affine, direction: [f64; 3], x0: f64, width: f64) -> Expr {
    // d̂·(M x + t) − x0 = (Mᵀd̂)·x + (d̂·t − x0), divided by −width.
    let coefficient =
        |j: usize| -> f64 { (0..3).map(|i| direction[i] * map.m[i][j]).sum::<f64>() / -width };
    let constant = ((0..3).map(|i| direction[i] * map.t[i]).sum::<f64>() - x0) / -width;
    let mut exponent = Expr::Num(constant);
    for (j, var) in Var::ALL.into_iter().enumerate() {
        let c = coefficient(j);
        if c != 0.0 {
            let term = Expr::binary(BinOp::Mul, Expr::Num(c), Expr::Var(var));
            exponent = Expr::binary(BinOp::Add, exponent, term);
        }
    }
    let denominator = Expr::binary(BinOp::Add, Expr::Num(1.0), Expr::call(Func::Exp, exponent));
    Expr::binary(BinOp::Div, Expr::Num(1.0), denominator)
}

/// The blend's value `f + w·(g − f)` for one point.
#[inline]
pub fn value(f: f64, g: f64, w: f64) -> f64 {
    f + w * (g - f)
}

/// An interval holding `value(f, g, w)` for every `f ∈ a`, `g ∈ b`, `w ∈ weight`.
///
/// For a fixed `w ∈ [0, 1]` the value `(1 − w)f + wg` grows with `f` and with `g`, so its
/// least value is `(1 − w)a.lo + w·b.lo`, linear in `w`: the least over the weights is at one
/// of their ends (and likewise the greatest). The weight is clamped to `[0, 1]`, where the
/// evaluator keeps it, and taken as all of `[0, 1]` when its interval proves nothing (its
/// `exp` overflowed). Rounding of `f + w·(g − f)` is a few ulps of `max(|f|, |g|)`, so the
/// ends are widened by [`RELATIVE_SLACK`] of that magnitude, not of the (possibly small) ends.
pub fn interval(a: Interval, b: Interval, weight: Interval) -> Interval {
    let finite = |i: &Interval| !i.nan && i.lo.is_finite() && i.hi.is_finite();
    if !finite(&a) || !finite(&b) {
        return Interval::UNKNOWN;
    }
    let (w0, w1) = if weight.nan || weight.lo.is_nan() || weight.hi.is_nan() {
        (0.0, 1.0)
    } else {
        (weight.lo.clamp(0.0, 1.0), weight.hi.clamp(0.0, 1.0))
    };
    let at = |w: f64, f: f64, g: f64| (1.0 - w) * f + w * g;
    let lo = at(w0, a.lo, b.lo).min(at(w1, a.lo, b.lo));
    let hi = at(w0, a.hi, b.hi).max(at(w1, a.hi, b.hi));
    let magnitude = [a.lo, a.hi, b.lo, b.hi]
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let slack = 4.0 * RELATIVE_SLACK * magnitude;
    Interval::new(lo - slack, hi + slack)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (xorshift), so the test needs no crate.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, lo: f64, hi: f64) -> Interval {
            let (x, y) = (lo + (hi - lo) * self.next(), lo + (hi - lo) * self.next());
            Interval::new(x.min(y), x.max(y))
        }
    }

    #[test]
    fn interval_encloses_sampled_blends() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for _ in 0..2000 {
            let (a, b) = (rng.range(-3.0, 3.0), rng.range(-50.0, 2.0));
            let w = rng.range(-0.2, 1.2);
            let r = interval(a, b, w);
            for _ in 0..20 {
                let pick = |i: Interval, t: f64| i.lo + t * (i.hi - i.lo);
                let wv = pick(w, rng.next()).clamp(0.0, 1.0);
                let v = value(pick(a, rng.next()), pick(b, rng.next()), wv);
                assert!(
                    r.lo <= v && v <= r.hi,
                    "{v} not in {r:?} ({a:?} {b:?} {w:?})"
                );
            }
            // The ends of the boxes themselves, where the bound is tight.
            for (f, g, wv) in [(a.lo, b.lo, w.lo), (a.hi, b.hi, w.hi), (a.lo, b.hi, w.hi)] {
                let v = value(f, g, wv.clamp(0.0, 1.0));
                assert!(r.lo <= v && v <= r.hi);
            }
        }
        let unknown_weight = interval(
            Interval::point(1.0),
            Interval::point(3.0),
            Interval::UNKNOWN,
        );
        assert!(unknown_weight.lo <= 1.0 && unknown_weight.hi >= 3.0 && !unknown_weight.nan);
        assert_eq!(
            interval(
                Interval::UNKNOWN,
                Interval::point(1.0),
                Interval::point(0.5)
            ),
            Interval::UNKNOWN
        );
    }

    #[test]
    fn weight_is_the_logistic_of_the_distance_along_the_direction() {
        // Blend frame = world moved by (1, 0, 0): the plane x0 = 0.5 there is world x = 1.5.
        let map = Affine::translation([-1.0, 0.0, 0.0]);
        let e = weight(&map, [1.0, 0.0, 0.0], 0.5, 0.25);
        for x in [-3.0, 0.0, 1.5, 1.7, 4.0] {
            let expected = 1.0 / (1.0 + (-((x - 1.0) - 0.5) / 0.25f64).exp());
            let got = e.eval_tree([x, 7.0, -2.0]);
            assert!((got - expected).abs() < 1e-15, "{x}: {got} vs {expected}");
        }
        // Far on either side: exactly 0 (exp overflows) and 1.
        assert_eq!(e.eval_tree([-1e3, 0.0, 0.0]), 0.0);
        assert_eq!(e.eval_tree([1e3, 0.0, 0.0]), 1.0);
    }
}
