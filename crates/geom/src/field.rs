//! Scalar fields sampled on regular grids, one z-plane (or a few rows of one) at a time.
//!
//! Invariants:
//! - A [`Grid`] point `(i, j, k)` sits at `origin + (i, j, k) ∘ spacing`; planes are stored x
//!   fastest, then y (`index = i + nx * j`).
//! - [`PlaneSampler::sample_plane`] is a pure function of `k`: two calls for the same plane give
//!   bit-identical values, whichever thread makes them. Contouring relies on this to let two
//!   chunks evaluate their shared plane independently and still agree on every sign.
//! - Fields never see model units or solids: [`SolidSampler`] turns a field into the implicit
//!   function of a solid (negative inside) on the same grid. A shell sampled that way,
//!   `|f| − w/2`, loses every wall that passes between two samples (both are positive), so
//!   the box contourer takes a shell as its [`Band`] of `f` instead; the implicit function
//!   remains for the contourers that combine it with other solids (a part, an element's clip).

use std::ops::Range;

/// A regular grid of sample points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub origin: [f64; 3],
    pub spacing: [f64; 3],
    pub counts: [usize; 3],
}

impl Grid {
    /// The grid with `counts` points per axis spanning `min..=max` exactly.
    /// Every count must be at least 2.
    pub fn spanning(min: [f64; 3], max: [f64; 3], counts: [usize; 3]) -> Grid {
        let spacing = std::array::from_fn(|a| (max[a] - min[a]) / (counts[a] - 1) as f64);
        Grid {
            origin: min,
            spacing,
            counts,
        }
    }

    /// Coordinate of sample `i` along axis `axis`.
    #[inline]
    pub fn coord(&self, axis: usize, i: usize) -> f64 {
        self.origin[axis] + i as f64 * self.spacing[axis]
    }

    /// All sample coordinates along one axis.
    pub fn axis(&self, axis: usize) -> Vec<f64> {
        (0..self.counts[axis])
            .map(|i| self.coord(axis, i))
            .collect()
    }

    /// Number of samples in one z-plane.
    #[inline]
    pub fn plane_len(&self) -> usize {
        self.counts[0] * self.counts[1]
    }

    /// The same index grid with coordinates divided by `cell_size` per axis
    /// (model units to cell units).
    pub fn scaled_down(&self, cell_size: [f64; 3]) -> Grid {
        Grid {
            origin: std::array::from_fn(|a| self.origin[a] / cell_size[a]),
            spacing: std::array::from_fn(|a| self.spacing[a] / cell_size[a]),
            counts: self.counts,
        }
    }
}

/// Samples one field on the z-planes of one grid.
pub trait PlaneSampler: Sync {
    /// The grid this sampler was prepared for.
    fn grid(&self) -> &Grid;

    /// Writes the field's values on rows `rows` (y indices) of plane `k` into `out`
    /// (`out.len() == rows.len() * nx`). Callers sample a plane a few rows at a time so
    /// that what they do next with the values happens while the rows are still in cache.
    fn sample_rows(&self, k: usize, rows: Range<usize>, out: &mut [f64]);

    /// Writes the field's values on plane `k` into `out` (`out.len() == grid.plane_len()`).
    fn sample_plane(&self, k: usize, out: &mut [f64]) {
        self.sample_rows(k, 0..self.grid().counts[1], out);
    }
}

/// A scalar field that can be evaluated at arbitrary points and prepared for a grid.
pub trait ScalarField: Sync + Send {
    /// Evaluates the field at the points `(xs[n], ys[n], zs[n])` into `out[n]`.
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]);

    /// A sampler for `grid`. The default evaluates point by point in blocks; fields with
    /// structure (separable trigonometric series) override it with something faster.
    fn sampler<'a>(&'a self, grid: &Grid) -> Box<dyn PlaneSampler + 'a> {
        Box::new(PointwiseSampler {
            field: self,
            grid: *grid,
        })
    }
}

/// A boxed field is the field it holds (its grid sampler included).
impl<F: ScalarField + ?Sized> ScalarField for Box<F> {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        (**self).eval_points(xs, ys, zs, out);
    }

    fn sampler<'a>(&'a self, grid: &Grid) -> Box<dyn PlaneSampler + 'a> {
        (**self).sampler(grid)
    }
}

/// Evaluates a field at every grid point, a row of the plane at a time.
pub struct PointwiseSampler<'a, F: ScalarField + ?Sized> {
    pub field: &'a F,
    pub grid: Grid,
}

impl<F: ScalarField + ?Sized> PlaneSampler for PointwiseSampler<'_, F> {
    fn grid(&self) -> &Grid {
        &self.grid
    }

    fn sample_rows(&self, k: usize, rows: Range<usize>, out: &mut [f64]) {
        let nx = self.grid.counts[0];
        let xs = self.grid.axis(0);
        let z = vec![self.grid.coord(2, k); nx];
        let mut y = vec![0.0; nx];
        for (j, row) in rows.zip(out.chunks_mut(nx)) {
            y.fill(self.grid.coord(1, j));
            self.field.eval_points(&xs, &y, &z, row);
        }
    }
}

/// Which side of a field's level sets is solid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Solid {
    /// Endoskeleton: `f ≤ offset`.
    Inside { offset: f64 },
    /// Exoskeleton: `−f ≤ −offset`, i.e. `f ≥ offset`.
    Outside { offset: f64 },
    /// Shell: `|f| ≤ thickness / 2`.
    Shell { thickness: f64 },
    /// Eccentric shell: `|f − offset| ≤ thickness / 2`.
    EccentricShell { offset: f64, thickness: f64 },
}

/// The solid between two levels of a field, `lo < f < hi` (a shell), contoured from `f`
/// itself (see `contour::contour_band`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Band {
    pub lo: f64,
    pub hi: f64,
}

impl Solid {
    /// For a shell, the band of field values it spans; `None` for one-sided solids.
    pub fn band(&self) -> Option<Band> {
        let (middle, thickness) = match *self {
            Solid::Shell { thickness } => (0.0, thickness),
            Solid::EccentricShell { offset, thickness } => (offset, thickness),
            Solid::Inside { .. } | Solid::Outside { .. } => return None,
        };
        Some(Band {
            lo: middle - 0.5 * thickness,
            hi: middle + 0.5 * thickness,
        })
    }

    /// The implicit function of the solid (negative inside) from the field value.
    #[inline]
    pub fn apply(&self, f: f64) -> f64 {
        match *self {
            Solid::Inside { offset } => f - offset,
            Solid::Outside { offset } => offset - f,
            Solid::Shell { thickness } => f.abs() - 0.5 * thickness,
            Solid::EccentricShell { offset, thickness } => (f - offset).abs() - 0.5 * thickness,
        }
    }
}

/// A sampler of the solid's implicit function, built on a field's sampler.
pub struct SolidSampler<'a> {
    pub inner: Box<dyn PlaneSampler + 'a>,
    pub solid: Solid,
}

impl PlaneSampler for SolidSampler<'_> {
    fn grid(&self) -> &Grid {
        self.inner.grid()
    }

    fn sample_rows(&self, k: usize, rows: Range<usize>, out: &mut [f64]) {
        self.inner.sample_rows(k, rows, out);
        let solid = self.solid;
        for v in out.iter_mut() {
            *v = solid.apply(*v);
        }
    }
}

/// A field seen through a [`Solid`]: the solid's implicit function, negative inside, for the
/// contourers that take a [`ScalarField`] (element clipping).
pub struct SolidField<'a> {
    pub inner: &'a dyn ScalarField,
    pub solid: Solid,
}

impl ScalarField for SolidField<'_> {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        self.inner.eval_points(xs, ys, zs, out);
        for v in out.iter_mut() {
            *v = self.solid.apply(*v);
        }
    }

    fn sampler<'b>(&'b self, grid: &Grid) -> Box<dyn PlaneSampler + 'b> {
        Box::new(SolidSampler {
            inner: self.inner.sampler(grid),
            solid: self.solid,
        })
    }
}
