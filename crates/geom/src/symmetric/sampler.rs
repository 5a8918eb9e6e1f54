//! A separable grid sampler for fitted cells, for contouring on arbitrary regular grids.
//!
//! Every plane wave factors over the Cartesian axes: `exp(2πi k·s)` with `s` the frame
//! coordinates of a Cartesian point `x` equals `Π_a exp(2πi σ_a m_a x_a)` with integer keys
//! `m = k` and scales `σ = 1` in the Cartesian frame, and `m = (k1, 2k2 − k1, k3)`,
//! `σ = (1, 1/√3, 1)` in the hexagonal one (`s1 = x − y/√3`, `s2 = 2y/√3`). So on a grid
//!
//! ```text
//! Φ(x_i, y_j, z_l) = Re Σ_{mx} Ex[i][mx] · Σ_{my} Ey[j][my] · Σ_{mz} w(mx,my,mz) · Ez[l][mz]
//! ```
//!
//! evaluated innermost first: per plane `A(mx,my) = Σ_mz w·Ez` (cached for a few planes,
//! since the contourer asks for a plane a few rows at a time), per row
//! `B(mx) = Σ_my A·Ey`, per point `Re Σ_mx B·Ex`. No transcendental function per sample, and
//! the cost per plane is `terms + rows·pairs + points·|mx|` instead of `points·terms`.
//!
//! Invariant: values are a pure function of the plane index (the cache only stores what the
//! same computation would produce again), so two calls for one plane agree bit for bit.

use std::ops::Range;
use std::sync::{Arc, Mutex};

use rustfft::num_complex::Complex64;

use super::basis::cis_turns;
use super::eval::Terms;
use super::group::Frame;
use crate::field::{Grid, PlaneSampler};

/// How many planes' partial sums are kept.
const CACHED_PLANES: usize = 8;

pub(crate) struct SeparableSampler {
    grid: Grid,
    /// Distinct x keys; `ex[i * kx_len + c]` is the table for grid column `i`, key index `c`.
    kx_len: usize,
    ex: Vec<Complex64>,
    ky_len: usize,
    ey: Vec<Complex64>,
    kz_len: usize,
    ez: Vec<Complex64>,
    /// (x key index, y key index) of each pair, sorted by y then x.
    pairs: Vec<(u32, u32)>,
    /// For pair `p`, its z terms are `starts[p]..starts[p + 1]` of `zs` / `ws`.
    starts: Vec<usize>,
    zs: Vec<u32>,
    ws: Vec<Complex64>,
    cache: Mutex<Vec<(usize, Arc<Vec<Complex64>>)>>,
}

/// Sorted distinct values and a lookup from value to index.
fn keys(values: impl Iterator<Item = i64>) -> Vec<i64> {
    let mut v: Vec<i64> = values.collect();
    v.sort_unstable();
    v.dedup();
    v
}

fn table(keys: &[i64], scale: f64, grid: &Grid, axis: usize) -> Vec<Complex64> {
    let mut t = Vec::with_capacity(keys.len() * grid.counts[axis]);
    for i in 0..grid.counts[axis] {
        let x = grid.coord(axis, i);
        for &m in keys {
            t.push(cis_turns(scale * m as f64 * x));
        }
    }
    t
}

impl SeparableSampler {
    pub(crate) fn new(terms: &Terms, grid: &Grid) -> SeparableSampler {
        let (frame, list) = terms.plane_waves();
        let key = |k: [i32; 3]| -> [i64; 3] {
            let k = k.map(i64::from);
            match frame {
                Frame::Cartesian => k,
                Frame::Hexagonal => [k[0], 2 * k[1] - k[0], k[2]],
            }
        };
        let scale = match frame {
            Frame::Cartesian => [1.0; 3],
            Frame::Hexagonal => [1.0, 1.0 / 3f64.sqrt(), 1.0],
        };
        let mut items: Vec<([i64; 3], Complex64)> = list.map(|(k, w)| (key(k), w)).collect();
        let kx = keys(items.iter().map(|t| t.0[0]));
        let ky = keys(items.iter().map(|t| t.0[1]));
        let kz = keys(items.iter().map(|t| t.0[2]));
        let index = |v: &[i64], m: i64| v.binary_search(&m).unwrap_or(0) as u32;
        items.sort_by_key(|t| (t.0[1], t.0[0], t.0[2]));
        let mut pairs = Vec::new();
        let mut starts = Vec::new();
        let mut zs = Vec::with_capacity(items.len());
        let mut ws = Vec::with_capacity(items.len());
        let mut last: Option<(i64, i64)> = None;
        for (m, w) in items {
            if last != Some((m[0], m[1])) {
                last = Some((m[0], m[1]));
                pairs.push((index(&kx, m[0]), index(&ky, m[1])));
                starts.push(zs.len());
            }
            zs.push(index(&kz, m[2]));
            ws.push(w);
        }
        starts.push(zs.len());
        SeparableSampler {
            grid: *grid,
            kx_len: kx.len(),
            ex: table(&kx, scale[0], grid, 0),
            ky_len: ky.len(),
            ey: table(&ky, scale[1], grid, 1),
            kz_len: kz.len(),
            ez: table(&kz, scale[2], grid, 2),
            pairs,
            starts,
            zs,
            ws,
            cache: Mutex::new(Vec::new()),
        }
    }

    /// `A(pair) = Σ_mz w·Ez[k][mz]` for plane `k`, from the cache when it is there.
    fn plane_sums(&self, k: usize) -> Arc<Vec<Complex64>> {
        if let Ok(cache) = self.cache.lock()
            && let Some((_, a)) = cache.iter().find(|(p, _)| *p == k)
        {
            return Arc::clone(a);
        }
        let ez = &self.ez[k * self.kz_len..(k + 1) * self.kz_len];
        let a: Vec<Complex64> = (0..self.pairs.len())
            .map(|p| {
                let r = self.starts[p]..self.starts[p + 1];
                self.zs[r.clone()]
                    .iter()
                    .zip(&self.ws[r])
                    .map(|(&z, &w)| w * ez[z as usize])
                    .sum()
            })
            .collect();
        let a = Arc::new(a);
        if let Ok(mut cache) = self.cache.lock() {
            if cache.len() >= CACHED_PLANES {
                cache.remove(0);
            }
            cache.push((k, Arc::clone(&a)));
        }
        a
    }
}

impl PlaneSampler for SeparableSampler {
    fn grid(&self) -> &Grid {
        &self.grid
    }

    fn sample_rows(&self, k: usize, rows: Range<usize>, out: &mut [f64]) {
        let nx = self.grid.counts[0];
        let a = self.plane_sums(k);
        let mut b = vec![Complex64::new(0.0, 0.0); self.kx_len];
        for (j, row) in rows.zip(out.chunks_mut(nx)) {
            b.fill(Complex64::new(0.0, 0.0));
            let ey = &self.ey[j * self.ky_len..(j + 1) * self.ky_len];
            for (&(x, y), &v) in self.pairs.iter().zip(a.iter()) {
                b[x as usize] += v * ey[y as usize];
            }
            for (i, o) in row.iter_mut().enumerate() {
                let ex = &self.ex[i * self.kx_len..(i + 1) * self.kx_len];
                *o = b.iter().zip(ex).map(|(b, e)| (b * e).re).sum();
            }
        }
    }
}
