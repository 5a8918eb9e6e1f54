//! Sampling along paths of nearby points: grid rows and batches of points.
//!
//! A [`Walker`] evaluates points in order and carries two things from one to the next:
//! - the previous nearest triangle, whose distance bounds the next search before it starts;
//! - on closed surfaces, the previous side. The winding number of a closed surface only
//!   changes across the surface, so when the step from the previous point is shorter than the
//!   sum of the distances to the surface at its two ends (the two surface-free open balls then
//!   cover it; signed distance), or no triangle's bounding box meets the step (containment),
//!   the side carries over and no winding number is evaluated.
//!   A margin of 1e-9 relative plus [`MeshSdf::tolerance`] absolute keeps rounding on the
//!   safe side; points too near the surface always evaluate.
//!
//! Invariant: a row of a [`MeshSampler`] starts a fresh walker, so its values depend on the row
//! alone and every thread computes the same bits for it. Rows of a band search together, but
//! a search's distance is the exact minimum over the triangles whatever it shares, and the
//! side depends only on the row's own points and distances.

use super::nearest::LANES;
use super::{MeshSdf, Mode, nearest, winding};
use crate::field::{Grid, PlaneSampler};
use crate::vec3::{V3, add, dot, max, min, sub};
use rayon::prelude::*;
use std::ops::Range;

/// Far-field threshold of the sign-only winding numbers.
pub(super) const SIGN_BETA: f64 = 1.25;
/// How far from ½ a coarse winding number must be to decide the side by itself.
pub(super) const SIGN_MARGIN: f64 = 0.2;

struct Previous {
    p: V3,
    /// Distance within which there is no surface around `p` (0 when unknown).
    clear: f64,
    inside: bool,
    triangle: Option<u32>,
}

pub(super) struct Walker<'a> {
    sdf: &'a MeshSdf,
    previous: Option<Previous>,
    search: nearest::Search,
}

impl<'a> Walker<'a> {
    pub(super) fn new(sdf: &'a MeshSdf) -> Walker<'a> {
        Walker {
            sdf,
            previous: None,
            search: nearest::Search::default(),
        }
    }

    /// Whether `q` is inside. A coarse winding number (β = [`SIGN_BETA`], errors below 0.1 in
    /// our tests) decides when it is clearly away from ½; only near ½ (holes, open sheets,
    /// coarse-estimate trouble) does the configured β decide.
    fn inside_by_winding(&self, q: V3) -> bool {
        let sdf = self.sdf;
        let coarse = winding::fast(&sdf.bvh, &sdf.moments, q, SIGN_BETA * SIGN_BETA);
        if (coarse - 0.5).abs() > SIGN_MARGIN {
            return coarse > 0.5;
        }
        sdf.winding_number(q) > 0.5
    }

    /// The triangle nearest the previous point, a good start for the next search.
    pub(super) fn hint(&self) -> Option<u32> {
        self.previous.as_ref().and_then(|p| p.triangle)
    }

    /// The signed distance at `q`, given its nearest triangle search: `(d2, triangle)` as
    /// [`nearest::nearest`] returns it with the bound `band²`.
    pub(super) fn signed(&mut self, q: V3, d2: f64, triangle: Option<u32>) -> f64 {
        if q.iter().any(|c| c.is_nan()) {
            self.previous = None;
            return f64::NAN;
        }
        let sdf = self.sdf;
        let band = sdf.options.band.unwrap_or(f64::INFINITY);
        let dist = if triangle.is_some() { d2.sqrt() } else { band };
        let inside = match &self.previous {
            Some(prev)
                if sdf.report.closed && {
                    let step = dot(sub(q, prev.p), sub(q, prev.p)).sqrt();
                    step < (prev.clear + dist) * (1.0 - 1e-9) - sdf.tolerance
                } =>
            {
                prev.inside
            }
            _ => self.inside_by_winding(q),
        };
        let hint = self.hint();
        self.previous = Some(Previous {
            p: q,
            clear: dist,
            inside,
            triangle: triangle.or(hint),
        });
        if inside { -dist } else { dist }
    }

    /// The field value at `q` (NaN for a NaN point).
    pub(super) fn value(&mut self, q: V3) -> f64 {
        if q.iter().any(|c| c.is_nan()) {
            self.previous = None;
            return f64::NAN;
        }
        let sdf = self.sdf;
        let closed = sdf.report.closed;
        match sdf.options.mode {
            Mode::SignedDistance => {
                let band = sdf.options.band.unwrap_or(f64::INFINITY);
                let hint = self.hint();
                let (d2, triangle) =
                    nearest::nearest(&sdf.bvh, q, hint, band * band, &mut self.search);
                self.signed(q, d2, triangle)
            }
            Mode::Containment => {
                let inside = match &self.previous {
                    Some(prev)
                        if closed && {
                            let pad = [sdf.tolerance; 3];
                            let lo = sub(min(prev.p, q), pad);
                            let hi = add(max(prev.p, q), pad);
                            !nearest::any_box_overlap(&sdf.bvh, lo, hi)
                        } =>
                    {
                        prev.inside
                    }
                    _ => self.inside_by_winding(q),
                };
                self.previous = Some(Previous {
                    p: q,
                    clear: 0.0,
                    inside,
                    triangle: None,
                });
                if inside { -1.0 } else { 1.0 }
            }
        }
    }
}

/// Samples a [`MeshSdf`] on the z-planes of a grid, in bands of [`BAND`] rows (bands in
/// parallel). At each `x`, the band's nearest-triangle searches run together: [`LANES`]
/// neighbouring rows per search, the searches interleaved (`nearest.rs`). Each row keeps its
/// own walker, so its values are those of walking the row alone.
pub struct MeshSampler<'a> {
    sdf: &'a MeshSdf,
    grid: Grid,
    xs: Vec<f64>,
}

/// Rows per band: eight interleaved searches of four lanes, enough independent memory loads
/// in flight to hide most of their latency (measured on the benchmark torus: 16 and 64 rows
/// were slower).
const BAND: usize = 32;

impl<'a> MeshSampler<'a> {
    pub fn new(sdf: &'a MeshSdf, grid: &Grid) -> MeshSampler<'a> {
        MeshSampler {
            sdf,
            grid: *grid,
            xs: grid.axis(0),
        }
    }

    /// One band: consecutive rows of plane `z` from row `first`, into `out`. The rows'
    /// searches at each `x` are interleaved ([`nearest::nearest_many`]).
    fn sample_band(&self, z: f64, first: usize, out: &mut [f64]) {
        let nx = self.grid.counts[0];
        let rows = out.len() / nx;
        let mut walkers: Vec<Walker> = (0..rows).map(|_| Walker::new(self.sdf)).collect();
        let ys: Vec<f64> = (0..rows).map(|r| self.grid.coord(1, first + r)).collect();
        if self.sdf.options.mode == Mode::Containment {
            for (r, walker) in walkers.iter_mut().enumerate() {
                for (v, &x) in out[r * nx..(r + 1) * nx].iter_mut().zip(&self.xs) {
                    *v = walker.value([x, ys[r], z]);
                }
            }
            return;
        }
        let band = self.sdf.options.band.unwrap_or(f64::INFINITY);
        let bvh = &self.sdf.bvh;
        let mut searches: Vec<nearest::Search> = (0..rows.div_ceil(LANES))
            .map(|_| nearest::Search::default())
            .collect();
        let mut hints = [None; LANES];
        let mut points = [[0.0; 3]; LANES];
        for (i, &x) in self.xs.iter().enumerate() {
            for (g, search) in searches.iter_mut().enumerate() {
                let lanes = (g * LANES..rows.min((g + 1) * LANES)).len();
                for l in 0..lanes {
                    let r = g * LANES + l;
                    points[l] = [x, ys[r], z];
                    hints[l] = walkers[r].hint();
                }
                search.start(bvh, &points[..lanes], &hints[..lanes], band * band);
            }
            nearest::nearest_many(bvh, &mut searches);
            for (r, walker) in walkers.iter_mut().enumerate() {
                let (d2, triangle) = searches[r / LANES].result(r % LANES);
                out[r * nx + i] = walker.signed([x, ys[r], z], d2, triangle);
            }
        }
    }
}

impl PlaneSampler for MeshSampler<'_> {
    fn grid(&self) -> &Grid {
        &self.grid
    }

    fn sample_rows(&self, k: usize, rows: Range<usize>, out: &mut [f64]) {
        let nx = self.grid.counts[0];
        if nx == 0 {
            return;
        }
        let z = self.grid.coord(2, k);
        out.par_chunks_mut(nx * BAND)
            .enumerate()
            .for_each(|(b, band)| self.sample_band(z, rows.start + b * BAND, band));
    }
}
