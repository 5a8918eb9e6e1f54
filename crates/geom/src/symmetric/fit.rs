//! Fitting a source onto the symmetric basis by FFT, and the fitted cell.
//!
//! Conventions (docs/method.md §Fitting by FFT, §Conjugation):
//! - `ĝ(k) = (1/N^d) · DFT[k mod N] · exp(−2πi k·x_0)`: the Fourier coefficient of the
//!   sampled field on the domain, corrected for the domain's lower corner `x_0` (a sign
//!   `(−1)^(kx+ky+kz)` on the cube, a cube root of unity on the rhombus).
//! - Projection WITH the conjugate: `c_f = ⟨g, φ_f⟩ = ∫ g·conj(φ_f) = K_f Σ_Q ĝ(Qᵀ f)`.
//!   (The paper's equation drops the conjugate; for Td and D3 that fits `g(−x)`, the inverted
//!   cell. Groups containing −I cannot show the difference.)
//! - `c_f` is complex in general and never forced real: for Td and D3, `f` and its conjugate
//!   partner carry `c_partner = conj(c_f)` for real input, and `Φ = Re Σ c_f φ_f`.
//! - Band: `f` is kept only if its whole orbit has `|k_i| < N/2` (no Nyquist), so every
//!   `ĝ(Qᵀ f)` read here is an unaliased DFT bin and a band-limited input inside the band is
//!   reproduced to rounding.
//! - Coefficients are stored sorted by `f`; `φ_0 ≡ 1`, so `c_0` is the mean of the field.

use std::sync::OnceLock;

use rayon::prelude::*;
use rustfft::num_complex::Complex64;

use super::domain::{OriginPhase, PlaneSource, SampleOptions, Source, check_n};
use super::eval::Terms;
use super::fft::Spectrum;
use super::frequency::FrequencyIndex;
use super::group::Group;

/// One coefficient of a fitted cell: `c_f` for representative `f` (third component 0 in 2D)
/// with the basis normalisation `K_f`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coefficient {
    pub f: [i32; 3],
    pub c: Complex64,
    pub k_f: f64,
}

/// Which side of the surface a one-signed field lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Every value ≤ 0: all solid.
    Inside,
    /// Every value > 0: all void.
    Outside,
    /// The field is zero to rounding: the symmetric part of the input is zero.
    Zero,
}

impl std::fmt::Display for Side {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Side::Inside => "inside (≤ 0)",
            Side::Outside => "outside (> 0)",
            Side::Zero => "zero",
        })
    }
}

/// Errors of sampling, fitting, evaluating and blending cells.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FitError {
    #[error("grid size N = {0} is odd; the FFT grid needs an even N (e.g. 64, 128)")]
    Odd(usize),
    #[error("grid size N = {0} is too small; use N ≥ 4 (typically 64 or 128)")]
    TooSmall(usize),
    #[error("grid size N = {n} is too large; at most {limit} in this dimension")]
    TooLarge { n: usize, limit: usize },
    #[error("the source is not finite ({value}) at the point {point:?}")]
    NonFinite { point: [f64; 3], value: f64 },
    #[error("the input has no surface: every sample is {side}")]
    EmptyInput { side: Side },
    #[error(
        "the fit vanishes: every value of the fitted cell is {side}, so it has no surface (its symmetric part is one-signed); try symmetrizing the input or a larger N"
    )]
    Vanishes { side: Side },
    #[error("cells of different groups cannot be combined: {0} and {1}")]
    GroupMismatch(String, String),
    #[error("a blend needs at least one cell")]
    NoCells,
    #[error("blend weights must be finite and not sum to zero")]
    BadWeights,
    #[error("frequency {f:?} is not the representative of its orbit")]
    NotRepresentative { f: [i32; 3] },
    #[error("frequency {f:?} appears twice")]
    Duplicate { f: [i32; 3] },
    #[error("frequency {f:?} lies outside the band of an N = {n} grid")]
    OutOfBand { f: [i32; 3], n: usize },
    #[error("expected {expected} samples (N^d), got {got}")]
    SampleCount { expected: usize, got: usize },
    #[error("coefficient of {f:?} is not finite")]
    NonFiniteCoefficient { f: [i32; 3] },
    #[error(
        "the face-normal constraint needs a reference element; the group {group} has none (only D3, D4, Td and Oh)"
    )]
    NoReferenceElement { group: String },
    #[error(
        "the face-normal constraint did not converge ({rows}×{cols} block, relative violation {relative:.1e})"
    )]
    ConstraintNotConverged {
        rows: usize,
        cols: usize,
        relative: f64,
    },
    #[error(
        "automatic N: the tolerance must be finite and positive, and max_n a power of two from 64 to {limit} (two sizes to compare); got tolerance {tolerance}, max_n {max_n}"
    )]
    AutoOptions {
        tolerance: f64,
        max_n: usize,
        limit: usize,
    },
}

/// Options of [`fit`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FitOptions {
    /// Extension and symmetrization of the samples.
    pub sample: SampleOptions,
    /// Fail with [`FitError::EmptyInput`] / [`FitError::Vanishes`] when the input or the fit
    /// has no surface (costs one inverse FFT).
    pub check_vanishing: bool,
}

impl Default for FitOptions {
    fn default() -> FitOptions {
        FitOptions {
            sample: SampleOptions::default(),
            check_vanishing: true,
        }
    }
}

/// A symmetric cell `Φ(x) = Re Σ_f c_f φ_f(x)` fitted on an `N^d` grid.
///
/// Invariants: coefficients are sorted by `f`, unique, representatives of their orbits, inside
/// the band of `n`, finite, and carry `k_f = K_f`. The expansion used for direct evaluation is
/// built lazily from them, so the fields are private.
#[derive(Debug)]
pub struct FittedCell {
    pub(crate) group: Group,
    pub(crate) n: usize,
    pub(crate) coefficients: Vec<Coefficient>,
    pub(crate) terms: OnceLock<Terms>,
}

impl Clone for FittedCell {
    fn clone(&self) -> FittedCell {
        FittedCell::new_unchecked(self.group.clone(), self.n, self.coefficients.clone())
    }
}

impl PartialEq for FittedCell {
    fn eq(&self, other: &FittedCell) -> bool {
        self.group == other.group && self.n == other.n && self.coefficients == other.coefficients
    }
}

impl FittedCell {
    pub(crate) fn new_unchecked(group: Group, n: usize, coefficients: Vec<Coefficient>) -> Self {
        FittedCell {
            group,
            n,
            coefficients,
            terms: OnceLock::new(),
        }
    }

    /// A cell from explicit coefficients `(f, c_f)`. Each `f` must be the representative of
    /// its orbit (see [`Group::representative`]) inside the band of `n`; `K_f` is computed.
    pub fn from_coefficients(
        group: Group,
        n: usize,
        coefficients: impl IntoIterator<Item = ([i32; 3], Complex64)>,
    ) -> Result<FittedCell, FitError> {
        check_n(n, group.dimension())?;
        let mut cs: Vec<Coefficient> = Vec::new();
        for (f, c) in coefficients {
            // Rules out overflow in the orbit arithmetic below as well as the band.
            if f.iter().any(|&v| v.unsigned_abs() as usize >= n) {
                return Err(FitError::OutOfBand { f, n });
            }
            if group.dimension() == 2 && f[2] != 0 || !group.is_representative(f) {
                return Err(FitError::NotRepresentative { f });
            }
            if !group.in_band(f, n) {
                return Err(FitError::OutOfBand { f, n });
            }
            if !(c.re.is_finite() && c.im.is_finite()) {
                return Err(FitError::NonFiniteCoefficient { f });
            }
            cs.push(Coefficient {
                f,
                c,
                k_f: group.normalization(f),
            });
        }
        cs.sort_by_key(|c| c.f);
        if let Some(w) = cs.windows(2).find(|w| w[0].f == w[1].f) {
            return Err(FitError::Duplicate { f: w[0].f });
        }
        Ok(FittedCell::new_unchecked(group, n, cs))
    }

    /// The symmetry group.
    pub fn group(&self) -> &Group {
        &self.group
    }

    /// The grid size the cell was fitted on; every coefficient lies inside its band.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The coefficients, sorted by `f`.
    pub fn coefficients(&self) -> &[Coefficient] {
        &self.coefficients
    }

    /// `c_f` for a representative `f`, zero if absent.
    pub fn coefficient(&self, f: [i32; 3]) -> Complex64 {
        self.coefficients
            .binary_search_by_key(&f, |c| c.f)
            .map(|i| self.coefficients[i].c)
            .unwrap_or_default()
    }

    /// The cell with every coefficient replaced by `map(f, c_f)`.
    pub fn map_coefficients(&self, map: impl Fn([i32; 3], Complex64) -> Complex64) -> FittedCell {
        let cs = self
            .coefficients
            .iter()
            .map(|c| Coefficient {
                c: map(c.f, c.c),
                ..*c
            })
            .collect();
        FittedCell::new_unchecked(self.group.clone(), self.n, cs)
    }

    /// `Φ + t` (`φ_0 ≡ 1`, so only `c_0` changes). Dilation by `t` is `offset(−t)`.
    pub fn offset(&self, t: f64) -> FittedCell {
        let mut cs = self.coefficients.clone();
        match cs.binary_search_by_key(&[0, 0, 0], |c| c.f) {
            Ok(i) => cs[i].c += t,
            Err(i) => cs.insert(
                i,
                Coefficient {
                    f: [0; 3],
                    c: Complex64::new(t, 0.0),
                    k_f: self.group.normalization([0; 3]),
                },
            ),
        }
        FittedCell::new_unchecked(self.group.clone(), self.n, cs)
    }

    /// `−Φ`: solid and void swapped.
    pub fn negated(&self) -> FittedCell {
        self.map_coefficients(|_, c| -c)
    }
}

/// `c_f = K_f Σ_Q ĝ(Qᵀ f) = K_f |Stab f| Σ_{k ∈ orbit(f)} ĝ(k)` for every `f` in the band
/// of the spectrum's grid.
///
/// One streaming pass over the spectrum instead of |S| random reads per coefficient: every
/// stored bin `k` adds `ĝ(k)` to the accumulator of its representative, and, when the
/// half-spectrum stores `k` for both signs (`0 < kx < N/2`), `ĝ(−k) = conj ĝ(k)` to that of
/// `−k`. Bins whose orbit leaves the band have no accumulator and are skipped.
pub(crate) fn project(group: &Group, spectrum: &Spectrum) -> Vec<Coefficient> {
    let n = spectrum.n;
    let d = group.dimension();
    let phase = OriginPhase::new(group.domain());
    let scale = 1.0 / (n as f64).powi(d as i32);
    let reps = group.frequency_set(n);
    let index = FrequencyIndex::complete(group, &reps, n);
    let half = (n / 2) as i32;
    let in_box = |k: [i32; 3]| (0..d).all(|a| k[a].abs() < half);
    let zero = Complex64::new(0.0, 0.0);
    // The representative of −k is the partner of k's: one index look-up per bin.
    let partner: Vec<usize> = reps
        .par_iter()
        .map(|&f| index.find(group.partner(f)).unwrap_or(usize::MAX))
        .collect();
    let accs = spectrum.par_fold_entries(
        || vec![zero; reps.len()],
        |acc, k, v| {
            if !in_box(k) {
                return;
            }
            let Some(i) = index.find(group.representative_fast(k)) else {
                return;
            };
            let g = v * phase.at(k);
            acc[i] += g;
            if k[0] > 0 {
                // ĝ(−k) = conj ĝ(k) for real samples (the phase conjugates too).
                if let Some(a) = acc.get_mut(partner[i]) {
                    *a += g.conj();
                }
            }
        },
    );
    let mut total = vec![zero; reps.len()];
    for acc in accs {
        for (t, a) in total.iter_mut().zip(acc) {
            *t += a;
        }
    }
    reps.into_par_iter()
        .zip(total)
        .map(|(f, sum)| {
            let k_f = group.normalization(f);
            let stab = group.stabilizer_order(f) as f64;
            Coefficient {
                f,
                c: sum * (k_f * stab * scale),
                k_f,
            }
        })
        .collect()
}

/// Which side a set of values lies on, if it is one-signed (≤ 0 counts as inside).
pub(crate) fn one_side(min: f64, max: f64) -> Option<Side> {
    if max <= 0.0 {
        Some(Side::Inside)
    } else if min > 0.0 {
        Some(Side::Outside)
    } else {
        None
    }
}

/// Fits `source` with the symmetric basis of `group` on an `N^d` grid.
///
/// Errors: `N` odd, below 4 or too large; a non-finite sample; with
/// `options.check_vanishing`, an input or a fit without a surface.
pub fn fit(
    group: &Group,
    n: usize,
    source: &dyn Source,
    options: &FitOptions,
) -> Result<FittedCell, FitError> {
    check_n(n, group.dimension())?;
    let ps = PlaneSource::new(group, n, source, options.sample);
    let (spectrum, range) = Spectrum::forward(n, &ps)?;
    if options.check_vanishing
        && let Some(side) = one_side(range.min, range.max)
    {
        return Err(FitError::EmptyInput { side });
    }
    let cell = FittedCell::new_unchecked(group.clone(), n, project(group, &spectrum));
    drop(spectrum);
    if options.check_vanishing {
        check_surface(&cell, range.min.abs().max(range.max.abs()))?;
    }
    Ok(cell)
}

/// Fails with [`FitError::Vanishes`] if the cell's values on its own grid are one-signed or
/// zero relative to `scale` (the input's magnitude).
pub fn check_surface(cell: &FittedCell, scale: f64) -> Result<(), FitError> {
    let g = cell.grid(cell.n)?;
    let (min, max) = g
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if min.abs().max(max.abs()) <= 1e-12 * scale {
        return Err(FitError::Vanishes { side: Side::Zero });
    }
    match one_side(min, max) {
        Some(side) => Err(FitError::Vanishes { side }),
        None => Ok(()),
    }
}

/// Fits an already sampled grid (`N^d` values on the group's domain grid, x fastest, as
/// produced by [`sample`](super::domain::sample)). No vanishing check.
pub fn fit_samples(group: &Group, n: usize, samples: &[f64]) -> Result<FittedCell, FitError> {
    check_n(n, group.dimension())?;
    let d = group.dimension();
    let expected = n.pow(d as u32);
    if samples.len() != expected {
        return Err(FitError::SampleCount {
            expected,
            got: samples.len(),
        });
    }
    if let Some(p) = samples.iter().position(|v| !v.is_finite()) {
        let origin = group.domain().origin();
        let idx = [p % n, (p / n) % n, p / (n * n)];
        let s: [f64; 3] = std::array::from_fn(|a| {
            if a < d {
                origin[a] + idx[a] as f64 / n as f64
            } else {
                0.0
            }
        });
        return Err(FitError::NonFinite {
            point: group.domain().frame().to_cartesian(s),
            value: samples[p],
        });
    }
    let spectrum = Spectrum::forward_grid(n, d, samples);
    Ok(FittedCell::new_unchecked(
        group.clone(),
        n,
        project(group, &spectrum),
    ))
}
