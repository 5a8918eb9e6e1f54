//! Evaluating a fitted cell: direct summation (value and gradient at any point) and grids by
//! inverse FFT.
//!
//! Conventions:
//! - Points and gradients are in the Cartesian REFERENCE frame (cell size 1, centroid at the
//!   origin). For D3 a point is converted to skew coordinates `s = B⁻¹x` and the gradient
//!   back by `∇x = B⁻ᵀ ∇s`; the field is periodic with the domain's lattice.
//! - Direct summation uses the plane-wave expansion `Φ(s) = Re Σ_k w_k exp(2πi k·s)`,
//!   `w_k = c_f K_f m_k`, with `k` and `−k` merged (`Re(w e) + Re(w' ē) = Re((w + w̄') e)`).
//!   Terms are pruned: coefficients are dropped smallest first while the sum of their bounds
//!   `|c_f| K_f |S|` (each `|c_f φ_f| ≤` its bound) stays within [`PRUNE_TOLERANCE`] times the
//!   sum of all bounds, so the pruned sum differs from the full one by at most that.
//! - [`FittedCell::grid`] uses the full coefficient set (no pruning), by inverse real FFT, on
//!   the domain grid `s_i = x_0 + i/N`, x fastest. A smaller `N` than the fit's folds
//!   frequencies modulo `N`, which still gives the exact values at the grid points.

use rustfft::num_complex::Complex64;

use super::basis::cis_turns;
use super::domain::{OriginPhase, check_n};
use super::fft::{Spectrum, wrap};
use super::fit::{FitError, FittedCell};
use super::frequency::FrequencyIndex;
use super::group::Frame;
use super::sampler::SeparableSampler;
use crate::field::{Grid, PlaneSampler, ScalarField};

/// Relative bound on what pruning may change in direct evaluation (see the module docs).
pub const PRUNE_TOLERANCE: f64 = 1e-12;

/// The pruned plane-wave expansion, grouped in rows of equal `(ky, kz)` sorted by `kx`.
#[derive(Clone, Debug)]
pub(crate) struct Terms {
    frame: Frame,
    kmax: [usize; 3],
    rows: Vec<Row>,
    kx: Vec<i32>,
    w: Vec<Complex64>,
}

#[derive(Clone, Copy, Debug)]
struct Row {
    ky: i32,
    kz: i32,
    start: usize,
    end: usize,
}

/// `exp(2πi m t)` for `m = 0..len`, by recurrence with an exact reseed every 32 steps so the
/// error stays at rounding level for large `m`.
fn fill_table(t: f64, len: usize, out: &mut Vec<Complex64>) {
    out.clear();
    let step = cis_turns(t);
    let mut z = Complex64::new(1.0, 0.0);
    for m in 0..len {
        if m % 32 == 0 {
            z = cis_turns(m as f64 * t);
        }
        out.push(z);
        z *= step;
    }
}

#[inline]
fn lookup(t: &[Complex64], k: i32) -> Complex64 {
    if k >= 0 {
        t[k as usize]
    } else {
        t[(-k) as usize].conj()
    }
}

/// Reusable per-point tables.
#[derive(Default)]
pub(crate) struct Tables {
    x: Vec<Complex64>,
    y: Vec<Complex64>,
    z: Vec<Complex64>,
}

impl Terms {
    pub(crate) fn build(cell: &FittedCell) -> Terms {
        let group = &cell.group;
        let order = group.order() as f64;
        let bound = |c: &super::fit::Coefficient| c.c.norm() * c.k_f * order;
        let total: f64 = cell.coefficients.iter().map(bound).sum();
        let mut by_size: Vec<(f64, usize)> = cell
            .coefficients
            .iter()
            .enumerate()
            .map(|(i, c)| (bound(c), i))
            .collect();
        by_size.sort_by(|a, b| a.0.total_cmp(&b.0));
        let budget = PRUNE_TOLERANCE * total;
        let mut dropped = 0.0;
        let mut keep = vec![true; cell.coefficients.len()];
        for &(b, i) in &by_size {
            if dropped + b > budget {
                break;
            }
            dropped += b;
            keep[i] = false;
        }
        let mut list: Vec<([i32; 3], Complex64)> = Vec::new();
        for (c, _) in cell.coefficients.iter().zip(&keep).filter(|(_, k)| **k) {
            let w = c.c * (c.k_f * group.stabilizer_order(c.f) as f64);
            for k in group.orbit(c.f) {
                let neg = [-k[0], -k[1], -k[2]];
                if neg > k {
                    list.push((neg, w.conj()));
                } else {
                    list.push((k, w));
                }
            }
        }
        list.sort_by_key(|(k, _)| (k[2], k[1], k[0]));
        let mut terms = Terms {
            frame: group.frame(),
            kmax: [0; 3],
            rows: Vec::new(),
            kx: Vec::new(),
            w: Vec::new(),
        };
        for (k, w) in list {
            for (m, c) in terms.kmax.iter_mut().zip(k) {
                *m = (*m).max(c.unsigned_abs() as usize);
            }
            if terms.kx.last() == Some(&k[0])
                && let Some(row) = terms.rows.last()
                && row.ky == k[1]
                && row.kz == k[2]
            {
                if let Some(last) = terms.w.last_mut() {
                    *last += w;
                }
                continue;
            }
            match terms.rows.last_mut() {
                Some(row) if row.ky == k[1] && row.kz == k[2] => row.end += 1,
                _ => {
                    let start = terms.kx.len();
                    terms.rows.push(Row {
                        ky: k[1],
                        kz: k[2],
                        start,
                        end: start + 1,
                    });
                }
            }
            terms.kx.push(k[0]);
            terms.w.push(w);
        }
        terms
    }

    /// The frame and every plane wave `(k, w)` of `Re Σ w·exp(2πi k·s)`.
    pub(crate) fn plane_waves(&self) -> (Frame, impl Iterator<Item = ([i32; 3], Complex64)> + '_) {
        let waves = self.rows.iter().flat_map(move |row| {
            (row.start..row.end).map(move |i| ([self.kx[i], row.ky, row.kz], self.w[i]))
        });
        (self.frame, waves)
    }

    /// Number of plane waves after pruning and merging.
    pub(crate) fn len(&self) -> usize {
        self.kx.len()
    }

    /// Value and (if `gradient`) Cartesian gradient at Cartesian `x`.
    pub(crate) fn eval(&self, x: [f64; 3], gradient: bool, t: &mut Tables) -> (f64, [f64; 3]) {
        let s = self.frame.from_cartesian(x);
        fill_table(s[0], self.kmax[0] + 1, &mut t.x);
        fill_table(s[1], self.kmax[1] + 1, &mut t.y);
        fill_table(s[2], self.kmax[2] + 1, &mut t.z);
        let mut value = 0.0;
        let mut g = [0.0; 3];
        for row in &self.rows {
            let kx = &self.kx[row.start..row.end];
            let w = &self.w[row.start..row.end];
            let e = lookup(&t.y, row.ky) * lookup(&t.z, row.kz);
            let mut s0 = Complex64::new(0.0, 0.0);
            if gradient {
                let mut s1 = Complex64::new(0.0, 0.0);
                for (&k, &w) in kx.iter().zip(w) {
                    let term = w * lookup(&t.x, k);
                    s0 += term;
                    s1 += term * k as f64;
                }
                // d/ds Re(a·exp(2πi k s)) = Re(2πi k a exp(..)) = −2π k Im(a exp(..)).
                let es0 = e * s0;
                g[0] -= (e * s1).im;
                g[1] -= row.ky as f64 * es0.im;
                g[2] -= row.kz as f64 * es0.im;
                value += es0.re;
            } else {
                for (&k, &w) in kx.iter().zip(w) {
                    s0 += w * lookup(&t.x, k);
                }
                value += (e * s0).re;
            }
        }
        let tau = std::f64::consts::TAU;
        let gs = [g[0] * tau, g[1] * tau, g[2] * tau];
        (value, self.frame.gradient_to_cartesian(gs))
    }
}

impl FittedCell {
    pub(crate) fn terms(&self) -> &Terms {
        self.terms.get_or_init(|| Terms::build(self))
    }

    /// Number of plane waves direct evaluation sums (after pruning and merging ±k).
    pub fn term_count(&self) -> usize {
        self.terms().len()
    }

    /// `Φ(x)` at a Cartesian point of the reference frame, by direct summation.
    pub fn value(&self, x: [f64; 3]) -> f64 {
        self.terms().eval(x, false, &mut Tables::default()).0
    }

    /// `Φ(x)` and its Cartesian gradient `∇Φ(x)`, by direct summation.
    pub fn value_gradient(&self, x: [f64; 3]) -> (f64, [f64; 3]) {
        self.terms().eval(x, true, &mut Tables::default())
    }

    /// `Φ` on the `N^d` grid `s_i = x_0 + i/N` of the group's domain (domain coordinates,
    /// x fastest), by inverse FFT of the full coefficient set. `N` must be even and ≥ 4.
    pub fn grid(&self, n: usize) -> Result<Vec<f64>, FitError> {
        self.spectral_grid(n, None)
    }

    /// `∂Φ/∂s_axis` (domain coordinates; [`Frame::gradient_to_cartesian`] turns the `d` of
    /// them into a Cartesian gradient) on the grid of [`grid`](Self::grid), exact at its
    /// points like it: the term of frequency `k` gains the factor `2πi k_axis`, with `k` the
    /// true frequency, not the folded one.
    pub fn derivative_grid(&self, n: usize, axis: usize) -> Result<Vec<f64>, FitError> {
        self.spectral_grid(n, Some(axis.min(2)))
    }

    fn spectral_grid(&self, n: usize, derivative: Option<usize>) -> Result<Vec<f64>, FitError> {
        let d = self.group.dimension();
        check_n(n, d)?;
        let phase = OriginPhase::new(self.group.domain());
        let mut spectrum = Spectrum::zeros(n, d);
        let factor = |k: [i32; 3]| match derivative {
            Some(a) => Complex64::new(0.0, std::f64::consts::TAU * f64::from(k[a])),
            None => Complex64::new(1.0, 0.0),
        };
        if n >= self.n {
            self.fill_spectrum_by_gather(&mut spectrum, &phase);
            // In band, every stored k is the true frequency (|k_a| < N_fit/2 ≤ N/2).
            if derivative.is_some() {
                spectrum.map_with_frequency(factor);
            }
            return Ok(spectrum.inverse());
        }
        // A coarser grid than the fit's folds frequencies: scatter every term instead.
        let transposes = self.group.transposes();
        let coefficients = &self.coefficients;
        let half = n / 2;
        let (dim, sn) = (d, spectrum.n);
        let offset = |kx: usize, kz: usize| kx + (sn / 2 + 1) * kz;
        let row = spectrum.row_len();
        // Each task owns a range of ky rows and replays all terms, computing the y-component
        // first to skip the ones it does not own. Summing over every element (not the
        // distinct orbit) gives each k its multiplicity m_k = |Stab f|. The term
        // Re(w·exp(2πi k·(x_0 + i/N))) has corner phase exp(+2πi k·x_0); it is stored as ½ of
        // it at k and ½ of its conjugate at −k (each where the half-spectrum stores it).
        spectrum.par_ky_ranges(|lo, hi, block| {
            let owns = |ky: usize| ky >= lo && ky < hi;
            for c in coefficients {
                let w = c.c * (0.5 * c.k_f);
                let f = c.f;
                for t in transposes {
                    let k1 = t[1][0] * f[0] + t[1][1] * f[1] + t[1][2] * f[2];
                    let (yp, yn) = (wrap(k1, n), wrap(-k1, n));
                    if !owns(yp) && !owns(yn) {
                        continue;
                    }
                    let k0 = t[0][0] * f[0] + t[0][1] * f[1] + t[0][2] * f[2];
                    let k2 = t[2][0] * f[0] + t[2][1] * f[1] + t[2][2] * f[2];
                    let mut v = w * phase.at([k0, k1, k2]).conj();
                    if derivative.is_some() {
                        v *= factor([k0, k1, k2]);
                    }
                    let z = |k: i32| if dim == 3 { wrap(k, n) } else { 0 };
                    let xp = wrap(k0, n);
                    if owns(yp) && xp <= half {
                        block[(yp - lo) * row + offset(xp, z(k2))] += v;
                    }
                    let xn = wrap(-k0, n);
                    if owns(yn) && xn <= half {
                        block[(yn - lo) * row + offset(xn, z(-k2))] += v.conj();
                    }
                }
            }
        });
        Ok(spectrum.inverse())
    }
}

impl FittedCell {
    /// The half-spectrum of `Φ` on a grid at least as fine as the fit's (no folding): each
    /// stored bin `k` reads its coefficient, `H(k) = (W_k + conj W_{−k})/2` with
    /// `W_k = c_f K_f m_k exp(2πi k·x_0)`, `f` the representative of `k`. Writes stream
    /// through memory; only the small coefficient table is read at random.
    fn fill_spectrum_by_gather(&self, spectrum: &mut Spectrum, phase: &OriginPhase) {
        let group = &self.group;
        let d = group.dimension();
        let fs: Vec<[i32; 3]> = self.coefficients.iter().map(|c| c.f).collect();
        // Coefficients are unique in-band representatives, so as many as the full set means
        // the full set.
        let index = FrequencyIndex::complete(group, &fs, self.n);
        let weights: Vec<Complex64> = self
            .coefficients
            .iter()
            .map(|c| c.c * (c.k_f * group.stabilizer_order(c.f) as f64))
            .collect();
        // The representative of −k is the partner of k's: one index look-up per bin.
        let partner: Vec<Option<usize>> = self
            .coefficients
            .iter()
            .map(|c| index.find(group.partner(c.f)))
            .collect();
        let half = (spectrum.n / 2) as i32;
        let zero = Complex64::new(0.0, 0.0);
        spectrum.par_set_entries(|k| {
            if (0..d).any(|a| k[a].abs() >= half) {
                return zero;
            }
            match index.find(group.representative_fast(k)) {
                Some(i) => {
                    // W_{−k} = w_partner·exp(−2πi k·x_0), so conj(W_{−k}) carries the same
                    // phase exp(+2πi k·x_0) as W_k.
                    let wm = partner[i].map_or(zero, |j| weights[j].conj());
                    (weights[i] + wm) * phase.at(k).conj() * 0.5
                }
                // No coefficient for k's orbit (explicit coefficient sets may hold f without
                // its partner): only −k's term remains.
                None => match index.find(group.representative_fast([-k[0], -k[1], -k[2]])) {
                    Some(j) => weights[j].conj() * phase.at(k).conj() * 0.5,
                    None => zero,
                },
            }
        });
    }
}

impl ScalarField for FittedCell {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        let terms = self.terms();
        let mut t = Tables::default();
        for (i, o) in out.iter_mut().enumerate() {
            *o = terms.eval([xs[i], ys[i], zs[i]], false, &mut t).0;
        }
    }

    /// Separable evaluation (module `symmetric::sampler`): per-axis tables instead of
    /// per-point sums over all terms, so big contour grids of rich fits stay affordable.
    fn sampler<'a>(&'a self, grid: &Grid) -> Box<dyn PlaneSampler + 'a> {
        Box::new(SeparableSampler::new(self.terms(), grid))
    }
}
