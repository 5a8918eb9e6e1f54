//! A field's level set measured in lengths: `h = (f − c) / |∇f|`, the distance-like field
//! that makes walls and offsets model units (`wall`, `grow`) instead of field values.
//!
//! Invariants:
//! - `h` has the sign of `f − c` and the zero set of `f = c`; near it, `|h|` is the distance
//!   to the level set to first order. Lengths are in model units: `scale[a]` model units per
//!   cell unit along axis `a`, so `∂f/∂x_a = (∂f/∂ξ_a) / scale[a]`.
//! - Where `|∇f|` vanishes `h` is `±`[`FAR`] (the sign of `f − c`), or 0 on the level itself:
//!   never NaN from a finite `f`.
//! - Gradients are central differences. The grid sampler steps one grid spacing, reusing the
//!   neighbouring samples (`O(Δ²)`: 0.2 % of `|∇f|` for a sinusoid sampled 64 times a
//!   period), so a grid costs three planes of the field per plane: it gives the first-order
//!   `h`. Point evaluation (the tiler's reference lattice, the tetrahedron and planar
//!   contourers) steps [`STEP`] cell units and refines `h` by Newton's projection onto the
//!   level set, `x ← x − (f/|∇f|²) ∇f` up to [`NEWTON_STEPS`] times: `|h|` is how far the
//!   point moved to where it lands, or [`FAR`] where it lands nowhere. Fitted cells ring (small
//!   ripples of the field away from its surface, largest for Td), and the first-order `h` of
//!   a ripple that nearly touches zero is small: grown or walled, it made loose islands (25
//!   in a tiled strut lattice grown by 0.5 mm); projected, a ripple lands nowhere. The grid
//!   and point values therefore agree near the surface (to the first-order error below), not
//!   bitwise; the sampler is still a pure function of its plane.
//!
//! Why first order, and its error: for a sheet `|h| < W/2` around a smooth level set the
//! second-order terms of the two sides cancel in the wall (both sides move by
//! `¼ (f_nn/|∇f|) (W/2)²` the same way), so the wall is `W` to third order while the sheet's
//! middle shifts by that amount; `tests/model_units.rs` measures both on spheres and TPMS.

use std::ops::Range;

use crate::field::{Grid, PlaneSampler, ScalarField};

/// `|h|` where the gradient vanishes (finite, so contourers interpolate without NaN).
pub const FAR: f64 = 1e30;

/// The central-difference step of point evaluation, in cell units.
pub const STEP: f64 = 1e-4;

/// Newton steps of point evaluation's projection onto the level set.
pub const NEWTON_STEPS: usize = 6;

/// A projection has landed when its residual distance is this share of its path (or less).
const LANDED: f64 = 1e-7;

/// `(f − level) / |∇f|` in model units.
pub struct DistanceField<F> {
    pub inner: F,
    pub level: f64,
    /// Model units per cell unit, per axis.
    pub scale: [f64; 3],
}

/// `(f − level) / |g|`, finite: ±[`FAR`] where the gradient vanishes, 0 on the level.
#[inline]
fn distance(f: f64, level: f64, gradient: [f64; 3]) -> f64 {
    let v = f - level;
    let h = v
        / (gradient[0] * gradient[0] + gradient[1] * gradient[1] + gradient[2] * gradient[2])
            .sqrt();
    if h.is_finite() {
        h
    } else if v > 0.0 {
        FAR
    } else if v < 0.0 {
        -FAR
    } else {
        // 0/0 on the level, or a NaN field value: NaN stays NaN (the field's own problem).
        if v.is_nan() { v } else { 0.0 }
    }
}

impl<F: ScalarField> DistanceField<F> {
    /// `f − level` and its gradient in model units at the points.
    fn value_and_gradient(&self, at: &[Vec<f64>; 3]) -> (Vec<f64>, Vec<[f64; 3]>) {
        let n = at[0].len();
        let mut value = vec![0.0; n];
        self.inner.eval_points(&at[0], &at[1], &at[2], &mut value);
        for v in &mut value {
            *v -= self.level;
        }
        let mut gradient = vec![[0.0f64; 3]; n];
        let (mut plus, mut minus) = (vec![0.0; n], vec![0.0; n]);
        let mut shifted = at.clone();
        for axis in 0..3 {
            for (s, &b) in shifted[axis].iter_mut().zip(&at[axis]) {
                *s = b + STEP;
            }
            self.inner
                .eval_points(&shifted[0], &shifted[1], &shifted[2], &mut plus);
            for (s, &b) in shifted[axis].iter_mut().zip(&at[axis]) {
                *s = b - STEP;
            }
            self.inner
                .eval_points(&shifted[0], &shifted[1], &shifted[2], &mut minus);
            shifted[axis].copy_from_slice(&at[axis]);
            let denominator = 2.0 * STEP * self.scale[axis];
            for ((g, p), m) in gradient.iter_mut().zip(&plus).zip(&minus) {
                g[axis] = (p - m) / denominator;
            }
        }
        (value, gradient)
    }
}

impl<F: ScalarField> ScalarField for DistanceField<F> {
    /// Point by point the first-order distance is refined by Newton's projection onto the
    /// level set (see the module docs): how far the point moved to where it lands, or ±[`FAR`]
    /// where it lands nowhere within [`NEWTON_STEPS`].
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        let n = xs.len();
        let mut at = [xs.to_vec(), ys.to_vec(), zs.to_vec()];
        let (start, mut gradient) = self.value_and_gradient(&at);
        let mut value = start.clone();
        let mut path = vec![0.0; n];
        let residual =
            |f: f64, g: [f64; 3]| f.abs() / (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        let landed = |f: f64, g: [f64; 3], path: f64| {
            let r = residual(f, g);
            f == 0.0 || r <= LANDED * path || r <= f64::EPSILON
        };
        for _ in 0..NEWTON_STEPS {
            let mut moved = false;
            for i in 0..n {
                let (f, g) = (value[i], gradient[i]);
                let g2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
                if g2.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
                    || !f.is_finite()
                    || landed(f, g, path[i])
                {
                    continue;
                }
                // The Newton step in model units, taken in cell units; `path` is how far the
                // point has moved from where it started (not the steps' total: an overshoot
                // and its return cancel).
                let step = g.map(|c| -f * c / g2);
                for a in 0..3 {
                    at[a][i] += step[a] / self.scale[a];
                }
                let moved_by: [f64; 3] =
                    std::array::from_fn(|a| (at[a][i] - [xs, ys, zs][a][i]) * self.scale[a]);
                path[i] = (moved_by[0] * moved_by[0]
                    + moved_by[1] * moved_by[1]
                    + moved_by[2] * moved_by[2])
                    .sqrt();
                moved = true;
            }
            if !moved {
                break;
            }
            (value, gradient) = self.value_and_gradient(&at);
        }
        for i in 0..n {
            let (f, g) = (value[i], gradient[i]);
            out[i] = if start[i] == 0.0 {
                0.0
            } else if start[i].is_nan() {
                start[i]
            } else if landed(f, g, path[i]) {
                start[i].signum() * (path[i] + residual(f, g))
            } else {
                start[i].signum() * FAR
            };
        }
    }

    fn sampler<'a>(&'a self, grid: &Grid) -> Box<dyn PlaneSampler + 'a> {
        // One more sample on each side of every axis with extent, so that every point of
        // `grid` has both neighbours.
        let pad: [usize; 3] = std::array::from_fn(|a| {
            usize::from(grid.counts[a] > 1 && grid.spacing[a] != 0.0 && grid.spacing[a].is_finite())
        });
        let padded = Grid {
            origin: std::array::from_fn(|a| grid.origin[a] - pad[a] as f64 * grid.spacing[a]),
            spacing: grid.spacing,
            counts: std::array::from_fn(|a| grid.counts[a] + 2 * pad[a]),
        };
        let inverse = std::array::from_fn(|a| match pad[a] {
            0 => 0.0,
            _ => 1.0 / (2.0 * grid.spacing[a] * self.scale[a]),
        });
        Box::new(DistanceSampler {
            inner: self.inner.sampler(&padded),
            grid: *grid,
            padded,
            pad,
            inverse,
            level: self.level,
        })
    }
}

struct DistanceSampler<'a> {
    inner: Box<dyn PlaneSampler + 'a>,
    grid: Grid,
    padded: Grid,
    pad: [usize; 3],
    /// `1 / (2 Δ_a scale_a)`, or 0 along an axis without extent.
    inverse: [f64; 3],
    level: f64,
}

impl PlaneSampler for DistanceSampler<'_> {
    fn grid(&self) -> &Grid {
        &self.grid
    }

    fn sample_rows(&self, k: usize, rows: Range<usize>, out: &mut [f64]) {
        let [px, py, pz] = self.pad;
        let nx = self.grid.counts[0];
        let wide = self.padded.counts[0];
        let tall = rows.len() + 2 * py;
        let padded_rows = rows.start..rows.start + tall;
        // Planes k − 1, k, k + 1 of the grid (or k alone without z extent), in padded indices.
        let planes: Vec<Vec<f64>> = (0..1 + 2 * pz)
            .map(|d| {
                let mut plane = vec![0.0; wide * tall];
                self.inner
                    .sample_rows(k + d, padded_rows.clone(), &mut plane);
                plane
            })
            .collect();
        let centre = &planes[pz];
        for (r, row) in out.chunks_mut(nx).enumerate().take(rows.len()) {
            let j = r + py;
            for (i, v) in row.iter_mut().enumerate() {
                let at = (i + px) + wide * j;
                let dx = centre[at + px] - centre[at - px];
                let dy = centre[at + py * wide] - centre[at - py * wide];
                let dz = planes[2 * pz][at] - planes[0][at];
                let gradient = [
                    dx * self.inverse[0],
                    dy * self.inverse[1],
                    dz * self.inverse[2],
                ];
                *v = distance(centre[at], self.level, gradient);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `f = |x|² − R²` in cell units.
    struct Sphere(f64);

    impl ScalarField for Sphere {
        fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
            for (((o, x), y), z) in out.iter_mut().zip(xs).zip(ys).zip(zs) {
                *o = x * x + y * y + z * z - self.0 * self.0;
            }
        }
    }

    /// `f = 3 (2x − y)`: a plane, whose distance field is exact.
    struct Plane;

    impl ScalarField for Plane {
        fn eval_points(&self, xs: &[f64], ys: &[f64], _zs: &[f64], out: &mut [f64]) {
            for ((o, x), y) in out.iter_mut().zip(xs).zip(ys) {
                *o = 3.0 * (2.0 * x - y);
            }
        }
    }

    #[test]
    fn a_plane_is_measured_exactly_in_model_units_by_points_and_on_a_grid() {
        // Scale 2 model units per cell unit: the distance doubles.
        let field = DistanceField {
            inner: Plane,
            level: 0.6,
            scale: [2.0; 3],
        };
        let grid = Grid::spanning([-1.0; 3], [1.0; 3], [9, 7, 5]);
        let sampler = field.sampler(&grid);
        let mut plane = vec![0.0; grid.plane_len()];
        for k in 0..5 {
            sampler.sample_plane(k, &mut plane);
            for j in 0..7 {
                for i in 0..9 {
                    let (x, y) = (grid.coord(0, i), grid.coord(1, j));
                    // Distance from (2x − y) = 0.2 in cell units, times 2.
                    let exact = 2.0 * (2.0 * x - y - 0.2) / 5f64.sqrt();
                    assert!((plane[i + 9 * j] - exact).abs() < 1e-12);
                    let mut point = [0.0];
                    field.eval_points(&[x], &[y], &[grid.coord(2, k)], &mut point);
                    assert!((point[0] - exact).abs() < 1e-9, "{} {exact}", point[0]);
                }
            }
        }
    }

    #[test]
    fn a_spheres_distance_is_first_order_near_it_and_a_partial_row_range_agrees() {
        let field = DistanceField {
            inner: Sphere(0.3),
            level: 0.0,
            scale: [1.0; 3],
        };
        let grid = Grid::spanning([-0.5; 3], [0.5; 3], [21; 3]);
        let sampler = field.sampler(&grid);
        let mut whole = vec![0.0; grid.plane_len()];
        let mut part = vec![0.0; 3 * 21];
        for k in [0, 10, 20] {
            sampler.sample_plane(k, &mut whole);
            sampler.sample_rows(k, 5..8, &mut part);
            assert_eq!(&whole[5 * 21..8 * 21], &part[..]);
            for j in 0..21 {
                for i in 0..21 {
                    let p = [grid.coord(0, i), grid.coord(1, j), grid.coord(2, k)];
                    let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                    // h = (r² − R²) / 2r = (r − R)(r + R) / 2r: within (r − R)²/2r of r − R.
                    let h = whole[i + 21 * j];
                    if r > 0.05 {
                        let bound = (r - 0.3).powi(2) / (2.0 * r) + 1e-9;
                        assert!((h - (r - 0.3)).abs() <= bound, "{h} at r = {r}");
                    }
                }
            }
        }
    }

    /// `f = x² + 0.01`: never zero, a ripple's bottom.
    struct Ripple;

    impl ScalarField for Ripple {
        fn eval_points(&self, xs: &[f64], _ys: &[f64], _zs: &[f64], out: &mut [f64]) {
            for (o, x) in out.iter_mut().zip(xs) {
                *o = x * x + 0.01;
            }
        }
    }

    #[test]
    fn points_are_projected_onto_the_surface_and_a_ripple_lands_nowhere() {
        let sphere = DistanceField {
            inner: Sphere(0.3),
            level: 0.0,
            scale: [10.0; 3],
        };
        let (xs, ys, zs) = (
            [0.45, 0.1, -0.2, 0.05],
            [0.1, 0.2, 0.1, 0.0],
            [0.0, -0.3, 0.15, 0.02],
        );
        let mut out = [0.0; 4];
        sphere.eval_points(&xs, &ys, &zs, &mut out);
        for i in 0..4 {
            let r = (xs[i] * xs[i] + ys[i] * ys[i] + zs[i] * zs[i]).sqrt();
            // The exact distance, in model units (10 per cell unit).
            assert!(
                (out[i] - 10.0 * (r - 0.3)).abs() < 1e-6,
                "{} vs {}",
                out[i],
                r
            );
        }
        let ripple = DistanceField {
            inner: Ripple,
            level: 0.0,
            scale: [1.0; 3],
        };
        let mut out = [0.0];
        ripple.eval_points(&[0.05], &[0.0], &[0.0], &mut out);
        // The first-order h would be 0.0125 / 0.1 = 0.125.
        assert_eq!(out[0], FAR);
    }

    #[test]
    fn a_vanishing_gradient_gives_a_finite_far_value_with_the_fields_sign() {
        let field = DistanceField {
            inner: Sphere(0.3),
            level: 0.0,
            scale: [1.0; 3],
        };
        let mut out = [0.0];
        field.eval_points(&[0.0], &[0.0], &[0.0], &mut out);
        assert_eq!(out[0], -FAR);
        assert_eq!(distance(0.0, 0.0, [0.0; 3]), 0.0);
        assert_eq!(distance(1.0, 0.0, [0.0; 3]), FAR);
    }
}
