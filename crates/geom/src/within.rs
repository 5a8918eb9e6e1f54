//! A lattice confined to a part: the solid `{L ≤ 0} ∩ {d ≤ 0}`, optionally with a skin
//! `{−t ≤ d ≤ 0}` along the part's surface, where `L` is the lattice's field and `d` the part's
//! signed distance. As fields: `max(L, d)`, and with a skin `min(max(L, d), max(d, −d − t))`.
//!
//! Narrow band. The part's distance is only needed near its surface, so it may be clamped to
//! `±band` (which makes it far cheaper to sample). Where `d ≤ −band` the sample takes `L`
//! itself: deep inside the part `max(L, d)` has the sign of `L`, and `L` is also the right value
//! for placing the lattice's vertices (a clamped `d` would pull them). Where `d ≥ band` the
//! sample is `band` (outside). With `band` at least the grid's cell diagonal plus `t`, every
//! grid edge crossing the part's surface or the skin's inner surface has exact values at both
//! ends, so the contour is that of the exact field there.
//!
//! Invariant: the combination is pointwise, so the result depends only on the two samplers'
//! values (deterministic, any thread count), and its sign is exactly that of the exact field
//! wherever the part's sign is exact.

use std::ops::Range;

use crate::field::{Grid, PlaneSampler};

/// The lattice sampler confined to the part sampler (module docs). Both sample the same grid.
pub struct WithinSampler<'a> {
    pub lattice: Box<dyn PlaneSampler + 'a>,
    /// The part's signed distance, exact within `band` and clamped to `±band` beyond.
    pub part: Box<dyn PlaneSampler + 'a>,
    pub band: f64,
    /// Skin thickness `t` (`t < band`), or none.
    pub skin: Option<f64>,
}

impl WithinSampler<'_> {
    /// The narrow band needed on `grid` for a skin of thickness `skin` (module docs), with a
    /// factor 2 of margin.
    pub fn band_for(grid: &Grid, skin: Option<f64>) -> f64 {
        let diagonal = grid.spacing.iter().map(|h| h * h).sum::<f64>().sqrt();
        skin.unwrap_or(0.0) + 2.0 * diagonal
    }
}

/// One sample of the confined field from the lattice's value `l` and the part's `d`.
#[inline]
pub fn combine(l: f64, d: f64, band: f64, skin: Option<f64>) -> f64 {
    if d >= band {
        return band;
    }
    if d <= -band {
        return l;
    }
    let inside_part = l.max(d);
    match skin {
        Some(t) => inside_part.min(d.max(-d - t)),
        None => inside_part,
    }
}

impl PlaneSampler for WithinSampler<'_> {
    fn grid(&self) -> &Grid {
        self.lattice.grid()
    }

    fn sample_rows(&self, k: usize, rows: Range<usize>, out: &mut [f64]) {
        self.lattice.sample_rows(k, rows.clone(), out);
        let mut part = vec![0.0; out.len()];
        self.part.sample_rows(k, rows, &mut part);
        for (v, &d) in out.iter_mut().zip(&part) {
            *v = combine(*v, d, self.band, self.skin);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_band_keeps_the_sign_of_the_exact_field() {
        let (band, t) = (0.3, 0.1);
        for i in 0..200 {
            let l = -1.0 + 0.01 * i as f64;
            for j in 0..200 {
                let d = -1.0 + 0.01 * j as f64;
                let exact = l.max(d).min(d.max(-d - t));
                let clamped = d.clamp(-band, band);
                let got = combine(l, clamped, band, Some(t));
                // Zero counts as outside in both (the contourer's inside test is `< 0`).
                assert_eq!(got < 0.0, exact < 0.0, "l {l}, d {d}: {got} vs {exact}");
                if d.abs() < band {
                    assert_eq!(got, exact);
                }
            }
        }
    }

    #[test]
    fn without_skin_it_is_the_intersection() {
        assert_eq!(combine(-0.5, -0.1, 1.0, None), -0.1);
        assert_eq!(combine(0.2, -0.1, 1.0, None), 0.2);
        assert_eq!(combine(-0.5, 0.3, 1.0, None), 0.3);
        // Deep inside the part: the lattice's own value.
        assert_eq!(combine(-0.5, -1.0, 1.0, None), -0.5);
        assert_eq!(combine(0.7, -1.0, 1.0, None), 0.7);
        // Far outside: the band.
        assert_eq!(combine(-0.5, 1.0, 1.0, None), 1.0);
    }
}
