//! Real-input FFTs on the `N^d` domain grid: forward (samples → spectrum) and inverse
//! (Hermitian half-spectrum → samples).
//!
//! Layout and conventions:
//! - Real grids are stored x fastest (`i + N·j + N²·k`), as everywhere in the crate. The
//!   real-to-complex transform (realfft) runs along x, the contiguous axis, so only
//!   `kx ∈ [0, N/2]` is stored (`H = N/2 + 1` values); rustfft transforms y and z.
//! - A negative x-frequency is read through the conjugate: for real samples,
//!   `DFT[k] = conj(DFT[−k])`. [`Spectrum::raw`] does this for any integer `k` (mod N).
//! - Spectrum storage: 2D `kx + H·ky`; 3D `kx + H·(kz + N·ky)` — y-major blocks, so the z
//!   pass works on one contiguous block per `ky` and the passes parallelise (rayon) over
//!   blocks or planes without sharing mutable memory.
//! - Forward is the unnormalised DFT `Σ g_i exp(−2πi k·i/N)`; inverse is the unnormalised
//!   `Σ H_k exp(+2πi k·i/N)`. Phases for the domain corner and `1/N^d` are applied by the
//!   callers.
//! - Samples are produced plane by plane inside the forward pass, so the full real grid is
//!   never held in memory during a fit.

use std::sync::Arc;

use rayon::prelude::*;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::num_complex::Complex64;
use rustfft::{Fft, FftPlanner};

use super::domain::PlaneSource;
use super::fit::FitError;

const ZERO: Complex64 = Complex64::new(0.0, 0.0);

/// How many ranges of `ky` [`Spectrum::par_fold_entries`] folds separately: a constant, so
/// that the order of its floating-point sums is one for every thread count; 16 keeps a
/// 16-thread pool busy while each task's accumulator stays small next to the spectrum.
const FOLD_TASKS: usize = 16;

/// `v mod n` in `[0, n)`, without a division in the usual case `|v| < n`.
#[inline]
pub(crate) fn wrap(v: i32, n: usize) -> usize {
    let n = n as i64;
    let v = v as i64;
    let r = if v >= 0 && v < n {
        v
    } else if v < 0 && v >= -n {
        v + n
    } else {
        v.rem_euclid(n)
    };
    r as usize
}

/// Produces the real samples of plane `z` (`N²`, x fastest).
type PlaneFn<'a> = dyn Fn(usize, &mut [f64]) -> Result<(), FitError> + Sync + 'a;

/// The DFT of a real `N^d` grid, half-spectrum along x.
#[derive(Clone, Debug)]
pub(crate) struct Spectrum {
    pub(crate) n: usize,
    pub(crate) dim: usize,
    pub(crate) data: Vec<Complex64>,
}

/// Plans for one grid size.
struct Plans {
    r2c: Arc<dyn RealToComplex<f64>>,
    c2r: Arc<dyn ComplexToReal<f64>>,
    fwd: Arc<dyn Fft<f64>>,
    inv: Arc<dyn Fft<f64>>,
}

impl Plans {
    fn new(n: usize) -> Plans {
        let mut rp = RealFftPlanner::<f64>::new();
        let mut cp = FftPlanner::<f64>::new();
        Plans {
            r2c: rp.plan_fft_forward(n),
            c2r: rp.plan_fft_inverse(n),
            fwd: cp.plan_fft_forward(n),
            inv: cp.plan_fft_inverse(n),
        }
    }
}

/// Per-thread buffers.
struct Work {
    real: Vec<f64>,
    t: Vec<Complex64>,
    row: Vec<Complex64>,
    rscratch: Vec<Complex64>,
    cscratch: Vec<Complex64>,
}

impl Work {
    fn new(n: usize, p: &Plans) -> Work {
        let h = n / 2 + 1;
        let clen = p
            .fwd
            .get_inplace_scratch_len()
            .max(p.inv.get_inplace_scratch_len());
        let rlen = p.r2c.get_scratch_len().max(p.c2r.get_scratch_len());
        Work {
            real: vec![0.0; n * n],
            t: vec![ZERO; h * n],
            row: vec![ZERO; h],
            rscratch: vec![ZERO; rlen],
            cscratch: vec![ZERO; clen],
        }
    }
}

/// Running minimum and maximum of the samples.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SampleRange {
    pub(crate) min: f64,
    pub(crate) max: f64,
}

impl SampleRange {
    fn of(v: &[f64]) -> SampleRange {
        v.iter().fold(
            SampleRange {
                min: f64::INFINITY,
                max: f64::NEG_INFINITY,
            },
            |r, &x| SampleRange {
                min: r.min.min(x),
                max: r.max.max(x),
            },
        )
    }

    fn join(self, o: SampleRange) -> SampleRange {
        SampleRange {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
}

/// Forward transform of one real plane (`N²`, x fastest) into `out` (`N·H`, layout
/// `kx + H·ky`): realfft along x, then rustfft along y.
fn forward_plane(n: usize, p: &Plans, w: &mut Work, out: &mut [Complex64]) {
    let h = n / 2 + 1;
    for (row, spec) in w.real.chunks_exact_mut(n).zip(out.chunks_exact_mut(h)) {
        // Only fails on length mismatches, which the layout rules out.
        let _ = p.r2c.process_with_scratch(row, spec, &mut w.rscratch);
    }
    y_pass(n, &*p.fwd, w, out);
}

/// Transforms every column (fixed kx) of an `N·H` plane along y, in place.
fn y_pass(n: usize, fft: &dyn Fft<f64>, w: &mut Work, plane: &mut [Complex64]) {
    let h = n / 2 + 1;
    for (j, row) in plane.chunks_exact(h).enumerate() {
        for (kx, &v) in row.iter().enumerate() {
            w.t[kx * n + j] = v;
        }
    }
    fft.process_with_scratch(&mut w.t, &mut w.cscratch);
    for (j, row) in plane.chunks_exact_mut(h).enumerate() {
        for (kx, v) in row.iter_mut().enumerate() {
            *v = w.t[kx * n + j];
        }
    }
}

/// Inverse of [`forward_plane`] without normalisation: rustfft along y, realfft (c2r) along
/// x. The plane is consumed as scratch; the real result goes to `out` (`N²`).
fn inverse_plane(n: usize, p: &Plans, w: &mut Work, plane: &mut [Complex64], out: &mut [f64]) {
    let h = n / 2 + 1;
    y_pass(n, &*p.inv, w, plane);
    for (spec, row) in plane.chunks_exact(h).zip(out.chunks_exact_mut(n)) {
        w.row.copy_from_slice(spec);
        // The DC and Nyquist terms of a Hermitian row are real; drop rounding residue so that
        // realfft accepts the row.
        w.row[0].im = 0.0;
        w.row[h - 1].im = 0.0;
        let _ = p.c2r.process_with_scratch(&mut w.row, row, &mut w.rscratch);
    }
}

impl Spectrum {
    /// Samples `source` plane by plane and transforms it. Returns the spectrum and the range
    /// of the samples.
    pub(crate) fn forward(
        n: usize,
        source: &PlaneSource<'_>,
    ) -> Result<(Spectrum, SampleRange), FitError> {
        let dim = if source.planes() == 1 { 2 } else { 3 };
        Spectrum::forward_with(n, dim, &|z, out| source.sample_plane(z, out))
    }

    /// The forward transform of an in-memory grid (`N^d`, x fastest).
    pub(crate) fn forward_grid(n: usize, dim: usize, grid: &[f64]) -> Spectrum {
        let r: Result<_, FitError> = Spectrum::forward_with(n, dim, &|z, out| {
            out.copy_from_slice(&grid[z * n * n..][..n * n]);
            Ok(())
        });
        match r {
            Ok((s, _)) => s,
            // The copying sampler cannot fail.
            Err(_) => Spectrum::zeros(n, dim),
        }
    }

    /// Forward transform of the planes produced by `plane(z, out)`.
    fn forward_with(
        n: usize,
        dim: usize,
        plane: &PlaneFn<'_>,
    ) -> Result<(Spectrum, SampleRange), FitError> {
        let h = n / 2 + 1;
        let plans = Plans::new(n);
        if dim == 2 {
            let mut w = Work::new(n, &plans);
            let mut data = vec![ZERO; n * h];
            plane(0, &mut w.real)?;
            let range = SampleRange::of(&w.real);
            forward_plane(n, &plans, &mut w, &mut data);
            return Ok((Spectrum { n, dim, data }, range));
        }
        let mut planes = vec![ZERO; n * n * h];
        let ranges = planes
            .par_chunks_mut(n * h)
            .enumerate()
            .map_init(
                || Work::new(n, &plans),
                |w, (z, out)| {
                    plane(z, &mut w.real)?;
                    let r = SampleRange::of(&w.real);
                    forward_plane(n, &plans, w, out);
                    Ok(r)
                },
            )
            .collect::<Result<Vec<SampleRange>, FitError>>()?;
        let range = ranges.into_iter().fold(
            SampleRange {
                min: f64::INFINITY,
                max: f64::NEG_INFINITY,
            },
            SampleRange::join,
        );
        let mut data = vec![ZERO; n * n * h];
        data.par_chunks_mut(n * h).enumerate().for_each_init(
            || Work::new(n, &plans),
            |w, (ky, block)| {
                for z in 0..n {
                    let row = &planes[(z * n + ky) * h..][..h];
                    for (kx, &v) in row.iter().enumerate() {
                        w.t[kx * n + z] = v;
                    }
                }
                plans.fwd.process_with_scratch(&mut w.t, &mut w.cscratch);
                for (kz, row) in block.chunks_exact_mut(h).enumerate() {
                    for (kx, v) in row.iter_mut().enumerate() {
                        *v = w.t[kx * n + kz];
                    }
                }
            },
        );
        Ok((Spectrum { n, dim, data }, range))
    }

    /// An all-zero spectrum to be filled with [`add`](Self::add) and inverted.
    pub(crate) fn zeros(n: usize, dim: usize) -> Spectrum {
        let h = n / 2 + 1;
        let len = if dim == 3 { n * n * h } else { n * h };
        Spectrum {
            n,
            dim,
            data: vec![ZERO; len],
        }
    }

    /// Runs `fill(lo, hi, block)` in parallel over disjoint ranges `lo..hi` of `ky`, each
    /// with the storage of those rows (`kx + H·kz` within a row of `ky`, rows of
    /// [`row_len`](Self::row_len)). Lets a filler write without locks. The ranges follow the
    /// thread count, so `fill` must compute each entry the same way whatever range holds it
    /// (the coarse-grid scatter of `eval.rs` replays every term, in order, in every range).
    pub(crate) fn par_ky_ranges(&mut self, fill: impl Fn(usize, usize, &mut [Complex64]) + Sync) {
        let n = self.n;
        let row = self.row_len();
        let tasks = rayon::current_num_threads().clamp(1, n);
        let per = n.div_ceil(tasks);
        self.data
            .par_chunks_mut(row * per)
            .enumerate()
            .for_each(|(t, chunk)| {
                let lo = t * per;
                fill(lo, lo + chunk.len() / row, chunk);
            });
    }

    /// Calls `visit(k, value)` for every stored entry, `k` taken in `(−N/2, N/2]` per axis,
    /// in parallel over ranges of `ky`; each task folds into its own accumulator made by
    /// `init`, and the accumulators are returned in `ky` order.
    ///
    /// The ranges depend only on `N` ([`FOLD_TASKS`] of them at most), never on the thread
    /// count: a caller that adds the accumulators in order gets the same bits on any pool.
    /// (With one range per thread, a fitted cell's coefficients differed in their last bits
    /// between `-j 1` and `-j 3`, and so did every mesh made from it.)
    pub(crate) fn par_fold_entries<A: Send>(
        &self,
        init: impl Fn() -> A + Sync,
        visit: impl Fn(&mut A, [i32; 3], Complex64) + Sync,
    ) -> Vec<A> {
        let n = self.n;
        let h = n / 2 + 1;
        let row = self.row_len();
        let dim = self.dim;
        let signed = |i: usize| {
            if i > n / 2 {
                i as i32 - n as i32
            } else {
                i as i32
            }
        };
        let per = n.div_ceil(FOLD_TASKS.clamp(1, n.max(1)));
        self.data
            .par_chunks(row * per)
            .enumerate()
            .map(|(t, chunk)| {
                let mut acc = init();
                for (r, entries) in chunk.chunks_exact(row).enumerate() {
                    let ky = signed(t * per + r);
                    for (i, &v) in entries.iter().enumerate() {
                        let kz = if dim == 3 { signed(i / h) } else { 0 };
                        visit(&mut acc, [(i % h) as i32, ky, kz], v);
                    }
                }
                acc
            })
            .collect()
    }

    /// Sets every stored entry to `value(k)`, `k` taken in `(−N/2, N/2]` per axis, in
    /// parallel over rows of `ky`.
    pub(crate) fn par_set_entries(&mut self, value: impl Fn([i32; 3]) -> Complex64 + Sync) {
        let n = self.n;
        let h = n / 2 + 1;
        let row = self.row_len();
        let dim = self.dim;
        let signed = |i: usize| {
            if i > n / 2 {
                i as i32 - n as i32
            } else {
                i as i32
            }
        };
        self.data
            .par_chunks_mut(row)
            .enumerate()
            .for_each(|(ky, entries)| {
                let ky = signed(ky);
                for (i, v) in entries.iter_mut().enumerate() {
                    let kz = if dim == 3 { signed(i / h) } else { 0 };
                    *v = value([(i % h) as i32, ky, kz]);
                }
            });
    }

    /// Length of the storage of one `ky`.
    #[inline]
    pub(crate) fn row_len(&self) -> usize {
        let h = self.n / 2 + 1;
        if self.dim == 3 { self.n * h } else { h }
    }

    /// Multiplies every stored value by `f(k)`, `k` the stored frequency taken in
    /// `(−N/2, N/2]` per axis. For the result to stay the spectrum of a real grid, `f` should
    /// satisfy `f(−k) = conj f(k)` (at Nyquist the inverse keeps only the Hermitian part).
    pub(crate) fn map_with_frequency(&mut self, f: impl Fn([i32; 3]) -> Complex64 + Sync) {
        let n = self.n;
        let h = n / 2 + 1;
        let signed = |i: usize| {
            if i > n / 2 {
                i as i32 - n as i32
            } else {
                i as i32
            }
        };
        let dim = self.dim;
        self.data
            .par_chunks_mut(n * h)
            .enumerate()
            .for_each(|(b, chunk)| {
                for (i, v) in chunk.iter_mut().enumerate() {
                    let kx = (i % h) as i32;
                    let k = if dim == 3 {
                        [kx, signed(b), signed(i / h)]
                    } else {
                        [kx, signed(i / h), 0]
                    };
                    *v *= f(k);
                }
            });
    }

    /// The unnormalised inverse transform: the real grid `Σ_k H_k exp(+2πi k·i/N)`.
    pub(crate) fn inverse(mut self) -> Vec<f64> {
        let n = self.n;
        let h = n / 2 + 1;
        let plans = Plans::new(n);
        if self.dim == 2 {
            let mut w = Work::new(n, &plans);
            let mut out = vec![0.0; n * n];
            inverse_plane(n, &plans, &mut w, &mut self.data, &mut out);
            return out;
        }
        // z pass in place: block ky goes from [kz][kx] to [z][kx].
        self.data.par_chunks_mut(n * h).for_each_init(
            || Work::new(n, &plans),
            |w, block| {
                for (kz, row) in block.chunks_exact(h).enumerate() {
                    for (kx, &v) in row.iter().enumerate() {
                        w.t[kx * n + kz] = v;
                    }
                }
                plans.inv.process_with_scratch(&mut w.t, &mut w.cscratch);
                for (z, row) in block.chunks_exact_mut(h).enumerate() {
                    for (kx, v) in row.iter_mut().enumerate() {
                        *v = w.t[kx * n + z];
                    }
                }
            },
        );
        let data = &self.data;
        let mut out = vec![0.0; n * n * n];
        out.par_chunks_mut(n * n).enumerate().for_each_init(
            || (Work::new(n, &plans), vec![ZERO; n * h]),
            |(w, plane), (z, out_plane)| {
                for (ky, row) in plane.chunks_exact_mut(h).enumerate() {
                    row.copy_from_slice(&data[(ky * n + z) * h..][..h]);
                }
                inverse_plane(n, &plans, w, plane, out_plane);
            },
        );
        out
    }
}
