//! A section of a solid by the plane `z = z0`, drawn as its filled 2D region.
//!
//! Invariants:
//! - The cut is exact for a closed mesh: a corner with `z ≥ z0` counts as above, so every
//!   edge is crossed or not, consistently for both triangles sharing it, and each crossing
//!   point is computed from the edge's endpoints in a fixed order (below, then above): the
//!   two triangles of an edge give the same bits. The segments therefore form closed loops,
//!   and filling by even-odd crossings of each pixel row gives the region inside the solid
//!   (pores, holes and the outside empty) without ever assembling the loops.
//! - Rows are filled at pixel centres with a half-open rule (an endpoint exactly on a row
//!   counts on the side above it), so a loop's vertex on a row is crossed once, not twice.
//! - Order-independent: a row's crossings are sorted before filling, so triangles may come in
//!   any order, from any thread, and the image is the same.

use rayon::prelude::*;

/// A triangle's cut by the plane, in pixels.
pub type Segment = [[f64; 2]; 2];

/// The cut of a mesh streamed in, as crossings per pixel row of a `width × height` panel.
pub struct Section {
    pub z0: f64,
    /// Model `(x, y)` to pixel: `x_px = origin[0] + x · scale`, `y_px = origin[1] − y · scale`.
    pub scale: f64,
    pub origin: [f64; 2],
    width: usize,
    /// The x (in pixels) of each crossing of each row's centre line.
    rows: Vec<Vec<f64>>,
}

impl Section {
    /// The section at `z0` of a mesh in box `bbox`, its `x, y` extent centred in the panel
    /// and filling `fill` of it.
    pub fn new(z0: f64, bbox: [[f64; 3]; 2], (width, height): (usize, usize), fill: f64) -> Self {
        let extent = [bbox[1][0] - bbox[0][0], bbox[1][1] - bbox[0][1]];
        let scale = [width as f64 / extent[0], height as f64 / extent[1]]
            .into_iter()
            .filter(|s| s.is_finite() && *s > 0.0)
            .fold(f64::INFINITY, f64::min);
        let scale = if scale.is_finite() { scale * fill } else { 1.0 };
        let centre = [
            (bbox[0][0] + bbox[1][0]) / 2.0,
            (bbox[0][1] + bbox[1][1]) / 2.0,
        ];
        Section {
            z0,
            scale,
            origin: [
                width as f64 / 2.0 - centre[0] * scale,
                height as f64 / 2.0 + centre[1] * scale,
            ],
            width,
            rows: vec![Vec::new(); height],
        }
    }

    /// Whether the plane meets a triangle of corner heights `z` (as [`Section::segment`]
    /// decides), so that only those triangles need their corners looked up.
    pub fn meets(&self, z: [f32; 3]) -> bool {
        let ups = z.iter().filter(|&&z| self.above(z)).count();
        ups == 1 || ups == 2
    }

    /// Whether a corner at height `z` counts as above the plane.
    pub fn above(&self, z: f32) -> bool {
        f64::from(z) >= self.z0
    }

    /// The cut segment of one triangle, in pixels: `None` when the plane misses it.
    pub fn segment(&self, c: [[f32; 3]; 3]) -> Option<Segment> {
        let p = c.map(|v| v.map(f64::from));
        let above = p.map(|v| v[2] >= self.z0);
        let ups = above.iter().filter(|&&a| a).count();
        if ups == 0 || ups == 3 {
            return None;
        }
        let mut ends = [[0.0; 2]; 2];
        let mut n = 0;
        for k in 0..3 {
            let (a, b) = (p[k], p[(k + 1) % 3]);
            if above[k] == above[(k + 1) % 3] {
                continue;
            }
            // From the corner below to the one above, whichever way the triangle runs.
            let (lo, hi) = if above[k] { (b, a) } else { (a, b) };
            let t = (self.z0 - lo[2]) / (hi[2] - lo[2]);
            let x = lo[0] + t * (hi[0] - lo[0]);
            let y = lo[1] + t * (hi[1] - lo[1]);
            ends[n] = [
                self.origin[0] + x * self.scale,
                self.origin[1] - y * self.scale,
            ];
            n += 1;
        }
        (n == 2).then_some(ends)
    }

    /// Records where segment `a–b` crosses the rows' centre lines.
    pub fn cross(&mut self, [a, b]: Segment) {
        let (a, b) = if a[1] <= b[1] { (a, b) } else { (b, a) };
        // Rows whose centre `r + 0.5` lies in [a.y, b.y): half-open, so a vertex on a
        // centre line is counted by exactly one of its two segments (or none, at a tip).
        let first = (a[1] - 0.5).ceil().max(0.0);
        let last = ((b[1] - 0.5).ceil() - 1.0).min(self.rows.len() as f64 - 1.0);
        // Also nothing to do when a coordinate is NaN (every comparison false).
        let some_rows = first <= last;
        if !some_rows {
            return;
        }
        for r in first as usize..=last as usize {
            let yc = r as f64 + 0.5;
            if yc < a[1] || yc >= b[1] {
                continue;
            }
            let t = (yc - a[1]) / (b[1] - a[1]);
            self.rows[r].push(a[0] + t * (b[0] - a[0]));
        }
    }

    /// Whether each pixel (row by row) is inside the solid's section.
    pub fn inside(&mut self) -> Vec<bool> {
        let width = self.width;
        self.rows
            .par_iter_mut()
            .flat_map_iter(|xs| {
                xs.sort_by(f64::total_cmp);
                let mut row = vec![false; width];
                for pair in xs.chunks_exact(2) {
                    // Pixels whose centre lies in [x0, x1).
                    let first = (pair[0] - 0.5).ceil().max(0.0);
                    let last = ((pair[1] - 0.5).ceil() - 1.0).min(width as f64 - 1.0);
                    if first <= last {
                        row[first as usize..=last as usize].fill(true);
                    }
                }
                row
            })
            .collect()
    }
}
