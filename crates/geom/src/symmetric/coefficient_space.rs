//! The coefficient vector space `optimize` walks in: coefficients by frequency, sorted, with
//! the real inner product `Re Σ conj(a_f) b_f` (the L² product of the fields, the `φ_f`
//! being orthonormal).
//!
//! Invariant: entries stay sorted by frequency, so every operation is one merge pass in a
//! fixed order (the same bits however it was reached).

use rustfft::num_complex::Complex64;

use super::fit::{Coefficient, FittedCell};

/// Coefficients by frequency, sorted; the vector space the optimisation walks in.
#[derive(Clone, Debug, Default)]
pub(super) struct Vector(pub(super) Vec<([i32; 3], Complex64)>);

impl Vector {
    pub(super) fn of(cell: &FittedCell) -> Vector {
        Vector(cell.coefficients.iter().map(|c| (c.f, c.c)).collect())
    }

    /// `a·self + b·other`, over the union of frequencies.
    pub(super) fn combine(&self, a: f64, other: &Vector, b: f64) -> Vector {
        let (x, y) = (&self.0, &other.0);
        let (mut i, mut j) = (0, 0);
        let mut out = Vec::with_capacity(x.len().max(y.len()));
        while i < x.len() || j < y.len() {
            let take_x = j == y.len() || (i < x.len() && x[i].0 <= y[j].0);
            let take_y = i == x.len() || (j < y.len() && y[j].0 <= x[i].0);
            let f = if take_x { x[i].0 } else { y[j].0 };
            let mut v = Complex64::new(0.0, 0.0);
            if take_x {
                v += x[i].1 * a;
                i += 1;
            }
            if take_y {
                v += y[j].1 * b;
                j += 1;
            }
            out.push((f, v));
        }
        Vector(out)
    }

    /// The real inner product `Re Σ conj(a_f) b_f`.
    pub(super) fn dot(&self, other: &Vector) -> f64 {
        let (x, y) = (&self.0, &other.0);
        let (mut i, mut j, mut sum) = (0, 0, 0.0);
        while i < x.len() && j < y.len() {
            match x[i].0.cmp(&y[j].0) {
                std::cmp::Ordering::Less => i += 1,
                std::cmp::Ordering::Greater => j += 1,
                std::cmp::Ordering::Equal => {
                    sum += (x[i].1.conj() * y[j].1).re;
                    i += 1;
                    j += 1;
                }
            }
        }
        sum
    }

    pub(super) fn norm(&self) -> f64 {
        self.0.iter().map(|e| e.1.norm_sqr()).sum::<f64>().sqrt()
    }

    pub(super) fn cell(&self, like: &FittedCell, n: usize) -> FittedCell {
        let group = &like.group;
        let cs = self
            .0
            .iter()
            .map(|&(f, c)| Coefficient {
                f,
                c,
                k_f: group.normalization(f),
            })
            .collect();
        FittedCell::new_unchecked(group.clone(), n, cs)
    }
}
