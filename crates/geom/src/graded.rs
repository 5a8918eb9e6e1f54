//! A field whose level, or scale, varies in space: `g = (f − shift(x)) / divide(x)`, so that a
//! solid graded over a block (`wall = "expr"`, `grow = "expr"`, a graded volume fraction) is
//! the constant solid `g ≤ 0` or `|g| ≤ 1` of `g` and every contourer stays as it is.
//!
//! Invariants:
//! - `shift` and `divide` are functions of the model position `x = ξ ∘ scale` (`ξ` the cell
//!   coordinates the field is sampled at), evaluated at exactly the points `f` is.
//! - `divide` is positive wherever it is used: [`Spatial::evaluate`] clamps it to
//!   [`MIN_DIVIDE`], so a graded wall that reaches 0 thins the sheet to nothing there instead
//!   of flipping it inside out (callers check the range and report it first).
//! - The grid sampler samples `f` with the inner field's own sampler and the spatial terms
//!   point by point on the same rows: a pure function of its plane, like every sampler.

use std::ops::Range;
use std::sync::Arc;

use crate::field::{Grid, PlaneSampler, ScalarField};

/// The smallest divisor used (a wall of a billionth of the unit is no wall).
pub const MIN_DIVIDE: f64 = 1e-9;

/// A value in space, in model coordinates.
#[derive(Clone)]
pub enum Spatial {
    Constant(f64),
    /// A field of the model position, its values passed through `map` (a table lookup, a
    /// halving), or as they are.
    Field {
        field: Arc<dyn ScalarField>,
        map: Option<Arc<dyn Fn(f64) -> f64 + Send + Sync>>,
    },
}

impl Spatial {
    fn evaluate(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64], divisor: bool) {
        match self {
            Spatial::Constant(v) => out.fill(*v),
            Spatial::Field { field, map } => {
                field.eval_points(xs, ys, zs, out);
                if let Some(map) = map {
                    for v in out.iter_mut() {
                        *v = map(*v);
                    }
                }
            }
        }
        if divisor {
            for v in out.iter_mut() {
                // NaN is kept: the field's own problem, reported as such.
                if *v < MIN_DIVIDE {
                    *v = MIN_DIVIDE;
                }
            }
        }
    }
}

/// `(f − shift(x)) / divide(x)`.
pub struct GradedField<F> {
    pub inner: F,
    /// Model units per cell unit, per axis.
    pub scale: [f64; 3],
    pub shift: Spatial,
    pub divide: Spatial,
}

impl<F: ScalarField> GradedField<F> {
    /// `out[n] ← (out[n] − shift) / divide` at the cell points given.
    fn grade(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        let model = |c: &[f64], a: usize| c.iter().map(|v| v * self.scale[a]).collect::<Vec<_>>();
        let (mx, my, mz) = (model(xs, 0), model(ys, 1), model(zs, 2));
        let mut shift = vec![0.0; out.len()];
        let mut divide = vec![0.0; out.len()];
        self.shift.evaluate(&mx, &my, &mz, &mut shift, false);
        self.divide.evaluate(&mx, &my, &mz, &mut divide, true);
        for ((v, s), d) in out.iter_mut().zip(&shift).zip(&divide) {
            *v = (*v - s) / d;
        }
    }
}

impl<F: ScalarField> ScalarField for GradedField<F> {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        self.inner.eval_points(xs, ys, zs, out);
        self.grade(xs, ys, zs, out);
    }

    fn sampler<'a>(&'a self, grid: &Grid) -> Box<dyn PlaneSampler + 'a> {
        Box::new(GradedSampler {
            field: self,
            inner: self.inner.sampler(grid),
            grid: *grid,
        })
    }
}

struct GradedSampler<'a, F> {
    field: &'a GradedField<F>,
    inner: Box<dyn PlaneSampler + 'a>,
    grid: Grid,
}

impl<F: ScalarField> PlaneSampler for GradedSampler<'_, F> {
    fn grid(&self) -> &Grid {
        &self.grid
    }

    fn sample_rows(&self, k: usize, rows: Range<usize>, out: &mut [f64]) {
        self.inner.sample_rows(k, rows.clone(), out);
        let nx = self.grid.counts[0];
        let xs = self.grid.axis(0);
        let zs = vec![self.grid.coord(2, k); nx];
        let mut ys = vec![0.0; nx];
        for (j, row) in rows.zip(out.chunks_mut(nx)) {
            ys.fill(self.grid.coord(1, j));
            self.field.grade(&xs, &ys, &zs, row);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `f = x` in cell units.
    struct X;

    impl ScalarField for X {
        fn eval_points(&self, xs: &[f64], _ys: &[f64], _zs: &[f64], out: &mut [f64]) {
            out.copy_from_slice(xs);
        }
    }

    /// `y` in model units.
    struct Y;

    impl ScalarField for Y {
        fn eval_points(&self, _xs: &[f64], ys: &[f64], _zs: &[f64], out: &mut [f64]) {
            out.copy_from_slice(ys);
        }
    }

    #[test]
    fn the_shift_and_divisor_are_taken_at_the_model_position_on_grids_and_points() {
        let graded = GradedField {
            inner: X,
            scale: [2.0, 4.0, 1.0],
            shift: Spatial::Field {
                field: Arc::new(Y),
                map: Some(Arc::new(|v| 0.5 * v)),
            },
            divide: Spatial::Constant(0.25),
        };
        let grid = Grid::spanning([0.0; 3], [1.0; 3], [5, 3, 2]);
        let sampler = graded.sampler(&grid);
        let mut plane = vec![0.0; 15];
        sampler.sample_plane(1, &mut plane);
        for j in 0..3 {
            for i in 0..5 {
                let (x, y) = (grid.coord(0, i), grid.coord(1, j));
                // Model y = 4 y; shift = 2 y.
                let expected = (x - 2.0 * y) / 0.25;
                assert!((plane[i + 5 * j] - expected).abs() < 1e-12);
                let mut point = [0.0];
                graded.eval_points(&[x], &[y], &[1.0], &mut point);
                assert_eq!(point[0], plane[i + 5 * j]);
            }
        }
    }

    #[test]
    fn a_divisor_that_reaches_zero_is_clamped_not_flipped() {
        let graded = GradedField {
            inner: X,
            scale: [1.0; 3],
            shift: Spatial::Constant(0.0),
            divide: Spatial::Field {
                field: Arc::new(Y),
                map: None,
            },
        };
        let mut out = [0.0; 2];
        graded.eval_points(&[0.5, 0.5], &[-1.0, 2.0], &[0.0, 0.0], &mut out);
        assert_eq!(out, [0.5 / MIN_DIVIDE, 0.25]);
    }
}
