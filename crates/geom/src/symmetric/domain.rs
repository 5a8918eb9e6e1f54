//! Sampling a source on the periodic domain, with the simplex extensions of docs/method.md
//! §Mirroring.
//!
//! Conventions:
//! - Sources are evaluated in the REFERENCE frame: Cartesian coordinates in which the cell has
//!   size 1 and its centroid at the origin (2D sources see `z = 0`). Negative inside.
//! - The grid is `s_i = x_0 + i/N` per axis in the domain's coordinates (skew for the
//!   rhombus), stored x fastest: `index = i + N·j (+ N²·k)`. The upper end is not sampled.
//! - `Extend::Mirror` (default): the tetrahedron's cube corners beyond face `i`
//!   (`n_i·x > ½`) take `g(R_i x)`, `R_i x = x − ⅔ (n_i·x − ½) n_i`; the rhombus half beyond
//!   `s1 + s2 = ⅓` takes `g(⅓ − s2, ⅓ − s1)`. Both region tests are done on grid indices, so
//!   points on a face or edge count as inside the element exactly (no rounding). For the
//!   rhombus the mirror of a grid point is a grid point, `(i, j) ↦ (N − j, N − i)`, so the
//!   mirrored half is copied rather than evaluated.
//! - `Extend::None` samples the source as it is on the whole domain.
//! - Symmetrization replaces `g` by `min_Q g(Q x)` (the union of the images) before the
//!   extension is applied.
//! - Known limitation (docs/method.md §Mirroring), not hidden: the mirrored cube of a Td cell is
//!   continuous inside the cube but its periodic extension jumps across the cube faces, which
//!   hold the tetrahedron's edges, so Td fits ring near the edges and vertices of T. The
//!   mirrored rhombus of a D3-symmetric cell has no such jump.

use rustfft::num_complex::Complex64;

use super::basis::cis_fraction;
use super::fit::FitError;
use super::group::{Domain, Frame, Group, ReferenceElement, TETRAHEDRON_FACE_NORMALS, mat_vec_f64};
use crate::field::{Grid, PlaneSampler, ScalarField};

/// Something that can be sampled: a [`ScalarField`] (any type implementing it) or a closure
/// wrapped by [`from_fn`].
pub trait Source: Sync {
    /// Values at the Cartesian points `(xs[i], ys[i], zs[i])`.
    fn sample_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]);

    /// A fast sampler for a regular Cartesian grid, if the source has one.
    fn grid_sampler<'a>(&'a self, _grid: &Grid) -> Option<Box<dyn PlaneSampler + 'a>> {
        None
    }
}

impl<T: ScalarField + ?Sized> Source for T {
    fn sample_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        ScalarField::eval_points(self, xs, ys, zs, out);
    }

    fn grid_sampler<'a>(&'a self, grid: &Grid) -> Option<Box<dyn PlaneSampler + 'a>> {
        Some(self.sampler(grid))
    }
}

/// A closure `[x, y, z] -> value` as a [`Source`].
#[derive(Clone, Copy, Debug)]
pub struct FnSource<F>(pub F);

/// Wraps a closure as a [`Source`].
pub fn from_fn<F: Fn([f64; 3]) -> f64 + Sync>(f: F) -> FnSource<F> {
    FnSource(f)
}

impl<F: Fn([f64; 3]) -> f64 + Sync> Source for FnSource<F> {
    fn sample_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = (self.0)([xs[i], ys[i], zs[i]]);
        }
    }
}

/// How a simplex cell (Td, D3) fills the rest of its sampling domain.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Extend {
    /// Mirror the cell across its faces (edges) — docs/method.md §Mirroring.
    #[default]
    Mirror,
    /// Sample the source as it is on the whole domain.
    None,
}

/// How to sample a source.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SampleOptions {
    /// Extension of simplex cells; ignored for the square and cube.
    pub extend: Extend,
    /// Replace the source by the minimum over its images under the group first.
    pub symmetrize: bool,
}

/// `exp(−2πi k·x_0)` for the domain's lower corner `x_0`, from exact fractions.
pub(crate) fn origin_phase(domain: Domain, k: [i32; 3]) -> Complex64 {
    OriginPhase::new(domain).at(k)
}

/// Table lookup of `exp(−2πi k·x_0)`: per axis, `x_0 = p/q` with `q ≤ 3`, so the factor
/// depends only on `k_a mod q`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct OriginPhase {
    den: [i64; 3],
    table: [[Complex64; 3]; 3],
    dim: usize,
}

impl OriginPhase {
    pub(crate) fn new(domain: Domain) -> OriginPhase {
        let o = domain.origin_fraction();
        let mut table = [[Complex64::new(1.0, 0.0); 3]; 3];
        for a in 0..3 {
            for (r, t) in table[a].iter_mut().enumerate().take(o[a].1 as usize) {
                *t = cis_fraction(-(r as i64) * o[a].0, o[a].1);
            }
        }
        OriginPhase {
            den: o.map(|f| f.1),
            table,
            dim: domain.dimension(),
        }
    }

    #[inline]
    pub(crate) fn at(&self, k: [i32; 3]) -> Complex64 {
        // Constant divisors: no hardware division on this hot path.
        let r = |a: usize| -> usize {
            match self.den[a] {
                1 => 0,
                2 => (k[a] & 1) as usize,
                3 => k[a].rem_euclid(3) as usize,
                q => (k[a] as i64).rem_euclid(q) as usize,
            }
        };
        let mut z = self.table[0][r(0)];
        for a in 1..self.dim {
            z *= self.table[a][r(a)];
        }
        z
    }
}

/// The largest `N` a group of dimension `d` is fitted on. Memory: the half-spectrum alone is
/// 8·N^d bytes (1 GiB at 512³, 512 MiB at 8192²).
pub fn max_grid_n(dimension: usize) -> usize {
    if dimension == 3 { 512 } else { 8192 }
}

/// Checks a grid size: even and at least 4, and not absurdly large.
pub(crate) fn check_n(n: usize, dimension: usize) -> Result<(), FitError> {
    if n < 4 {
        return Err(FitError::TooSmall(n));
    }
    if !n.is_multiple_of(2) {
        return Err(FitError::Odd(n));
    }
    let limit = max_grid_n(dimension);
    if n > limit {
        return Err(FitError::TooLarge { n, limit });
    }
    Ok(())
}

/// Samples one plane of the domain grid at a time (all of it in 2D).
pub(crate) struct PlaneSource<'a> {
    group: &'a Group,
    n: usize,
    source: &'a dyn Source,
    options: SampleOptions,
    sampler: Option<Box<dyn PlaneSampler + 'a>>,
    mirror_tet: bool,
    mirror_tri: bool,
}

impl<'a> PlaneSource<'a> {
    pub(crate) fn new(
        group: &'a Group,
        n: usize,
        source: &'a dyn Source,
        options: SampleOptions,
    ) -> PlaneSource<'a> {
        let mirror = options.extend == Extend::Mirror;
        let reference = group.reference_element();
        let mirror_tet = mirror && reference == Some(ReferenceElement::Tetrahedron);
        let mirror_tri = mirror && reference == Some(ReferenceElement::Triangle);
        let domain = group.domain();
        // The source's own grid sampler only helps on a Cartesian grid without symmetrization.
        let sampler = if domain.frame() == Frame::Cartesian && !options.symmetrize {
            let h = 1.0 / n as f64;
            let grid = if domain.dimension() == 3 {
                Grid {
                    origin: [-0.5; 3],
                    spacing: [h; 3],
                    counts: [n; 3],
                }
            } else {
                Grid {
                    origin: [-0.5, -0.5, 0.0],
                    spacing: [h, h, 1.0],
                    counts: [n, n, 1],
                }
            };
            source.grid_sampler(&grid)
        } else {
            None
        };
        PlaneSource {
            group,
            n,
            source,
            options,
            sampler,
            mirror_tet,
            mirror_tri,
        }
    }

    /// Number of planes: `N` in 3D, 1 in 2D.
    pub(crate) fn planes(&self) -> usize {
        if self.group.dimension() == 3 {
            self.n
        } else {
            1
        }
    }

    /// Domain coordinate of grid index `i` on `axis`.
    #[inline]
    fn coord(&self, axis: usize, i: usize) -> f64 {
        self.group.domain().origin()[axis] + i as f64 / self.n as f64
    }

    /// The Cartesian point where the source is evaluated for grid point `(i, j, k)`, after the
    /// tetrahedron's mirror (the triangle's mirror is handled by copying).
    fn eval_point(&self, i: usize, j: usize, k: usize) -> [f64; 3] {
        let frame = self.group.domain().frame();
        let z = if self.group.dimension() == 3 {
            self.coord(2, k)
        } else {
            0.0
        };
        let x = frame.to_cartesian([self.coord(0, i), self.coord(1, j), z]);
        if self.mirror_tet
            && let Some(face) = tet_corner(i, j, k, self.n)
        {
            return tet_reflect(x, face);
        }
        x
    }

    /// Writes the samples of plane `k` (`N²` values, x fastest) into `out`.
    pub(crate) fn sample_plane(&self, k: usize, out: &mut [f64]) -> Result<(), FitError> {
        let n = self.n;
        debug_assert_eq!(out.len(), n * n);
        let is_tri_mirror = |i: usize, j: usize| self.mirror_tri && i + j > n;
        if let Some(sampler) = &self.sampler {
            sampler.sample_plane(k, out);
            if self.mirror_tet {
                let mut idx = Vec::new();
                let mut pts = Points::default();
                for j in 0..n {
                    for i in 0..n {
                        if tet_corner(i, j, k, n).is_some() {
                            idx.push(i + n * j);
                            pts.push(self.eval_point(i, j, k));
                        }
                    }
                }
                let mut vals = vec![0.0; idx.len()];
                self.evaluate(&pts, &mut vals);
                for (p, v) in idx.into_iter().zip(vals) {
                    out[p] = v;
                }
            }
        } else {
            // One row at a time keeps the batches cache-sized.
            let mut pts = Points::default();
            let mut idx = Vec::with_capacity(n);
            let mut vals = Vec::with_capacity(n);
            for j in 0..n {
                pts.clear();
                idx.clear();
                for i in 0..n {
                    if !is_tri_mirror(i, j) {
                        idx.push(i);
                        pts.push(self.eval_point(i, j, k));
                    }
                }
                vals.clear();
                vals.resize(idx.len(), 0.0);
                self.evaluate(&pts, &mut vals);
                for (&i, &v) in idx.iter().zip(&vals) {
                    out[i + n * j] = v;
                }
            }
            if self.mirror_tri {
                for j in 0..n {
                    for i in 0..n {
                        if is_tri_mirror(i, j) {
                            out[i + n * j] = out[(n - j) + n * (n - i)];
                        }
                    }
                }
            }
        }
        self.check_finite(k, out)
    }

    /// Writes plane `k` (even) of this grid into `out`, taking the points it shares with the
    /// half-size grid (both indices even) from that grid's plane `k/2` (`coarse`) and
    /// evaluating only the others: rows of odd `j` whole (by the grid sampler when there is
    /// one), odd `i` of the even rows point by point. The values are those
    /// [`sample_plane`](Self::sample_plane) gives, as the nested grid's coordinates are the
    /// same numbers (`2i/2N = i/N` exactly) and the mirror regions are decided on integers
    /// that scale with the grid.
    pub(crate) fn refine_plane(
        &self,
        k: usize,
        coarse: &[f64],
        out: &mut [f64],
    ) -> Result<(), FitError> {
        let n = self.n;
        let half = n / 2;
        debug_assert!(k.is_multiple_of(2) && coarse.len() == half * half && out.len() == n * n);
        let is_tri_mirror = |i: usize, j: usize| self.mirror_tri && i + j > n;
        let mut pts = Points::default();
        let mut idx = Vec::new();
        for j in 0..n {
            let row = j * n..(j + 1) * n;
            if j % 2 == 0 {
                for i in 0..n {
                    if i % 2 == 0 {
                        out[i + n * j] = coarse[i / 2 + half * (j / 2)];
                    } else if !is_tri_mirror(i, j) {
                        idx.push(i + n * j);
                        pts.push(self.eval_point(i, j, k));
                    }
                }
            } else if let Some(sampler) = &self.sampler {
                sampler.sample_rows(k, j..j + 1, &mut out[row]);
                // The sampler saw the tetrahedron's corners unmirrored.
                for i in (0..n).filter(|&i| self.mirror_tet && tet_corner(i, j, k, n).is_some()) {
                    idx.push(i + n * j);
                    pts.push(self.eval_point(i, j, k));
                }
            } else {
                for i in (0..n).filter(|&i| !is_tri_mirror(i, j)) {
                    idx.push(i + n * j);
                    pts.push(self.eval_point(i, j, k));
                }
            }
        }
        let mut vals = vec![0.0; idx.len()];
        self.evaluate(&pts, &mut vals);
        for (p, v) in idx.into_iter().zip(vals) {
            out[p] = v;
        }
        if self.mirror_tri {
            for j in 0..n {
                for i in 0..n {
                    if is_tri_mirror(i, j) {
                        out[i + n * j] = out[(n - j) + n * (n - i)];
                    }
                }
            }
        }
        self.check_finite(k, out)
    }

    /// Fails with [`FitError::NonFinite`] at the first non-finite value of plane `k`.
    fn check_finite(&self, k: usize, out: &[f64]) -> Result<(), FitError> {
        let n = self.n;
        if let Some(p) = out.iter().position(|v| !v.is_finite()) {
            let (i, j) = (p % n, p / n);
            let frame = self.group.domain().frame();
            let z = if self.group.dimension() == 3 {
                self.coord(2, k)
            } else {
                0.0
            };
            return Err(FitError::NonFinite {
                point: frame.to_cartesian([self.coord(0, i), self.coord(1, j), z]),
                value: out[p],
            });
        }
        Ok(())
    }

    /// The source (or its symmetrization) at Cartesian points.
    fn evaluate(&self, pts: &Points, out: &mut [f64]) {
        if !self.options.symmetrize {
            self.source.sample_points(&pts.x, &pts.y, &pts.z, out);
            return;
        }
        out.fill(f64::INFINITY);
        let frame = self.group.domain().frame();
        let mut img = Points::default();
        let mut vals = vec![0.0; out.len()];
        for q in self.group.elements() {
            img.clear();
            for p in 0..pts.x.len() {
                let s = frame.from_cartesian([pts.x[p], pts.y[p], pts.z[p]]);
                img.push(frame.to_cartesian(mat_vec_f64(q, s)));
            }
            self.source.sample_points(&img.x, &img.y, &img.z, &mut vals);
            for (o, &v) in out.iter_mut().zip(&vals) {
                // NaN propagates so that a bad source is reported, not hidden by `min`.
                *o = if v.is_nan() || o.is_nan() {
                    f64::NAN
                } else {
                    o.min(v)
                };
            }
        }
    }
}

#[derive(Default)]
struct Points {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
}

impl Points {
    fn push(&mut self, p: [f64; 3]) {
        self.x.push(p[0]);
        self.y.push(p[1]);
        self.z.push(p[2]);
    }

    fn clear(&mut self) {
        self.x.clear();
        self.y.clear();
        self.z.clear();
    }
}

/// The tetrahedron face `r` whose corner region `n_r·x > ½` holds cube grid point
/// `(i, j, k)` (x = −½ + i/N), decided on integers. The four regions do not overlap.
#[inline]
fn tet_corner(i: usize, j: usize, k: usize, n: usize) -> Option<usize> {
    let (i, j, k, n) = (i as i64, j as i64, k as i64, n as i64);
    // n·x − ½ in units of 1/N for each face normal of TETRAHEDRON_FACE_NORMALS.
    if i + j + k > 2 * n {
        Some(0)
    } else if k > i + j {
        Some(1)
    } else if i > j + k {
        Some(2)
    } else if j > i + k {
        Some(3)
    } else {
        None
    }
}

/// `R_r x = x − ⅔ (n_r·x − ½) n_r`: the mirror image of `x` across tetrahedron face `r`.
#[inline]
fn tet_reflect(x: [f64; 3], r: usize) -> [f64; 3] {
    let nr = TETRAHEDRON_FACE_NORMALS[r];
    let t = (2.0 / 3.0) * (nr[0] * x[0] + nr[1] * x[1] + nr[2] * x[2] - 0.5);
    [x[0] - t * nr[0], x[1] - t * nr[1], x[2] - t * nr[2]]
}

/// Samples `source` on the `N^d` grid of the group's domain (x fastest), with the extension
/// and symmetrization of `options`. Errors on a bad `N` or a non-finite sample.
pub fn sample(
    group: &Group,
    n: usize,
    source: &dyn Source,
    options: SampleOptions,
) -> Result<Vec<f64>, FitError> {
    use rayon::prelude::*;
    check_n(n, group.dimension())?;
    let ps = PlaneSource::new(group, n, source, options);
    let mut out = vec![0.0; n * n * ps.planes()];
    out.par_chunks_mut(n * n)
        .enumerate()
        .try_for_each(|(k, plane)| ps.sample_plane(k, plane))?;
    Ok(out)
}
