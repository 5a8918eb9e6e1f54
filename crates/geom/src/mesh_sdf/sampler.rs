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
//! alone and every thread computes the same bits for it.

use super::vec3::{V3, add, dot, max, min, sub};
use super::{MeshSdf, Mode, nearest, winding};
use crate::field::{Grid, PlaneSampler};
use rayon::prelude::*;
use std::ops::Range;

/// Far-field threshold of the sign-only winding numbers.
const SIGN_BETA: f64 = 1.25;
/// How far from ½ a coarse winding number must be to decide the side by itself.
const SIGN_MARGIN: f64 = 0.2;

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
    stack: Vec<(u32, f64)>,
}

impl<'a> Walker<'a> {
    pub(super) fn new(sdf: &'a MeshSdf) -> Walker<'a> {
        Walker {
            sdf,
            previous: None,
            stack: Vec::with_capacity(64),
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
                let hint = self.previous.as_ref().and_then(|p| p.triangle);
                let (d2, triangle) =
                    nearest::nearest(&sdf.bvh, q, hint, band * band, &mut self.stack);
                let dist = if triangle.is_some() { d2.sqrt() } else { band };
                let inside = match &self.previous {
                    Some(prev)
                        if closed && {
                            let step = dot(sub(q, prev.p), sub(q, prev.p)).sqrt();
                            step < (prev.clear + dist) * (1.0 - 1e-9) - sdf.tolerance
                        } =>
                    {
                        prev.inside
                    }
                    _ => self.inside_by_winding(q),
                };
                self.previous = Some(Previous {
                    p: q,
                    clear: dist,
                    inside,
                    triangle: triangle.or(hint),
                });
                if inside { -dist } else { dist }
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

/// Samples a [`MeshSdf`] on the z-planes of a grid, row by row (rows in parallel).
pub struct MeshSampler<'a> {
    sdf: &'a MeshSdf,
    grid: Grid,
    xs: Vec<f64>,
}

impl<'a> MeshSampler<'a> {
    pub fn new(sdf: &'a MeshSdf, grid: &Grid) -> MeshSampler<'a> {
        MeshSampler {
            sdf,
            grid: *grid,
            xs: grid.axis(0),
        }
    }
}

impl PlaneSampler for MeshSampler<'_> {
    fn grid(&self) -> &Grid {
        &self.grid
    }

    fn sample_rows(&self, k: usize, rows: Range<usize>, out: &mut [f64]) {
        let nx = self.grid.counts[0];
        let z = self.grid.coord(2, k);
        let sample_row = |(j, row): (usize, &mut [f64])| {
            let y = self.grid.coord(1, j);
            let mut walker = Walker::new(self.sdf);
            for (v, &x) in row.iter_mut().zip(&self.xs) {
                *v = walker.value([x, y, z]);
            }
        };
        if nx == 0 {
            return;
        }
        out.par_chunks_mut(nx)
            .enumerate()
            .map(|(r, row)| (rows.start + r, row))
            .for_each(sample_row);
    }
}
