//! Combining cells of one group: weighted averages and Minkowski sum/difference (docs/method.md
//! §Blends and Minkowski combinations).
//!
//! - Weighted average: cells share a basis, so the blend is the weighted average of their
//!   coefficient vectors (weights normalised by their sum). Linear in the inputs: the average
//!   of fits equals the fit of the average of the inputs.
//! - Minkowski sum on the periodic domain: `A ⊕ B = {h > 0}` with `h = χ_A ∗ χ_B` the
//!   periodic convolution of the indicators, computed by FFT on the cells' `N^d` grid. On the
//!   grid `h` is `1/N^d` times a count of point pairs, so "positive" is tested against half a
//!   grid cell, `h > ½ N^{−d}`. The result (−1 inside, +1 outside) is fitted back onto the
//!   basis; a Minkowski sum of `S`-symmetric sets is `S`-symmetric.
//! - Minkowski difference: `A ⊖ B = (Aᶜ ⊕ (−B))ᶜ`. `−B` is the point reflection of `B`; its
//!   Fourier coefficients are `conj(b̂(k))`, so the convolution becomes a correlation and no
//!   grid is flipped (D3 and Td do not contain −I, so `−B ≠ B` there).
//! - Periodic: sums wrap around the domain; cells meant to stay inside one period must be
//!   small enough.

use std::collections::BTreeMap;

use rustfft::num_complex::Complex64;

use super::domain::{check_n, origin_phase};
use super::fft::Spectrum;
use super::fit::{Coefficient, FitError, FittedCell, fit_samples};

fn same_group(a: &FittedCell, b: &FittedCell) -> Result<(), FitError> {
    if a.group() == b.group() {
        Ok(())
    } else {
        Err(FitError::GroupMismatch(
            a.group().name().to_string(),
            b.group().name().to_string(),
        ))
    }
}

/// `Σ w_i Φ_i / Σ w_i` for cells of one group. The result's `N` is the largest input `N`
/// (a coefficient missing from a smaller fit counts as zero).
pub fn weighted_average(cells: &[(&FittedCell, f64)]) -> Result<FittedCell, FitError> {
    let (first, _) = cells.first().ok_or(FitError::NoCells)?;
    for (c, _) in cells {
        same_group(first, c)?;
    }
    let total: f64 = cells.iter().map(|(_, w)| w).sum();
    if cells.iter().any(|(_, w)| !w.is_finite()) || !total.is_finite() || total == 0.0 {
        return Err(FitError::BadWeights);
    }
    let mut sum: BTreeMap<[i32; 3], (Complex64, f64)> = BTreeMap::new();
    for (cell, w) in cells {
        for c in cell.coefficients() {
            let e = sum.entry(c.f).or_insert((Complex64::new(0.0, 0.0), c.k_f));
            e.0 += c.c * (*w / total);
        }
    }
    let n = cells.iter().map(|(c, _)| c.n()).max().unwrap_or(first.n());
    let coefficients = sum
        .into_iter()
        .map(|(f, (c, k_f))| Coefficient { f, c, k_f })
        .collect();
    Ok(FittedCell::new_unchecked(
        first.group().clone(),
        n,
        coefficients,
    ))
}

/// Indicator (1 inside, `Φ ≤ 0`; 0 outside) of a cell on the `n`-grid, optionally complemented.
fn indicator(cell: &FittedCell, n: usize, complement: bool) -> Result<Vec<f64>, FitError> {
    Ok(cell
        .grid(n)?
        .into_iter()
        .map(|v| if (v <= 0.0) != complement { 1.0 } else { 0.0 })
        .collect())
}

/// Shared part: `h = χ_P ∗ χ_Q` (or `χ_P ∗ χ_{−Q}` when `reflect`), thresholded and refitted.
fn convolve(
    p: &[f64],
    q: &[f64],
    reflect: bool,
    complement: bool,
    like: &FittedCell,
    n: usize,
) -> Result<FittedCell, FitError> {
    let group = like.group();
    let d = group.dimension();
    let domain = group.domain();
    let sp = Spectrum::forward_grid(n, d, p);
    let sq = Spectrum::forward_grid(n, d, q);
    let mut prod = sp;
    for (a, b) in prod.data.iter_mut().zip(&sq.data) {
        *a *= if reflect { b.conj() } else { *b };
    }
    // Continuous coefficients are â(k) = A[k]·exp(−2πi k·x_0)/N^d, and the inverse on the
    // grid x_0 + j/N supplies exp(+2πi k·x_0). A product â·b̂ thus keeps one
    // exp(−2πi k·x_0); a correlation â·conj(b̂) cancels the corner phases of the factors and
    // keeps the inverse's exp(+2πi k·x_0).
    let scale = 1.0 / (n as f64).powi(2 * d as i32);
    prod.map_with_frequency(|k| {
        let ph = origin_phase(domain, k);
        (if reflect { ph.conj() } else { ph }) * scale
    });
    let h = prod.inverse();
    let threshold = 0.5 / (n as f64).powi(d as i32);
    let samples: Vec<f64> = h
        .into_iter()
        .map(|v| {
            if (v > threshold) != complement {
                -1.0
            } else {
                1.0
            }
        })
        .collect();
    fit_samples(group, n, &samples)
}

/// The Minkowski sum `A ⊕ B` on the periodic domain, computed on an `n`-grid and refitted
/// there (`n` even, ≥ 4; typically the larger of the two cells' `N`).
pub fn minkowski_sum(a: &FittedCell, b: &FittedCell, n: usize) -> Result<FittedCell, FitError> {
    same_group(a, b)?;
    check_n(n, a.group().dimension())?;
    let ia = indicator(a, n, false)?;
    let ib = indicator(b, n, false)?;
    convolve(&ia, &ib, false, false, a, n)
}

/// The Minkowski difference `A ⊖ B = (Aᶜ ⊕ (−B))ᶜ` on the periodic domain, on an `n`-grid.
pub fn minkowski_difference(
    a: &FittedCell,
    b: &FittedCell,
    n: usize,
) -> Result<FittedCell, FitError> {
    same_group(a, b)?;
    check_n(n, a.group().dimension())?;
    let iac = indicator(a, n, true)?;
    let ib = indicator(b, n, false)?;
    convolve(&iac, &ib, true, true, a, n)
}
