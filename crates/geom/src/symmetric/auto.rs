//! Automatic choice of the FFT size `N` (docs/method.md §Choosing N, `n = "auto"`).
//!
//! [`fit_auto`] fits at `N = 32, 64, 128, …` (at most `max_n`) and stops at the first `N`
//! whose next doubling moves the fitted zero set less than `tolerance`; it returns that
//! (coarser) fit and `N`.
//!
//! The movement ([`surface_movement`]) is measured on a fixed probe grid of [`PROBE_N`]
//! points per axis on the group's sampling domain (the same grid for every `N`, so successive
//! measures are comparable), in reference-cell units (cell size 1, Cartesian):
//! - A probe point is near the zero set of a fit if that fit changes sign between the point
//!   and one of its grid neighbours (periodically); points near the zero set of EITHER fit
//!   count, so a surface that appears or disappears is seen.
//! - At such a point the zero set of the finer fit `Φ₂` lies about `Φ₂(x)/|∇Φ₂(x)|` away, and
//!   that of `Φ₁` about `Φ₁(x)/|∇Φ₂(x)|` to first order, so the local normal displacement is
//!   `|Φ₂(x) − Φ₁(x)| / |∇Φ₂(x)|`. The movement is the maximum over those points.
//! - It is a first-order estimate of the one-sided Hausdorff distance near the surface; it
//!   over-estimates where `∇Φ₂` nearly vanishes on the surface (which then never converges —
//!   honest for a degenerate surface). Features thinner than the probe spacing `1/PROBE_N`
//!   can be missed.
//!
//! Values on the probe grid come from inverse FFTs ([`FittedCell::grid`], exact at grid
//! points); gradients from direct summation ([`FittedCell::value_gradient`]) at the near
//! points only.

use rayon::prelude::*;

use super::domain::Source;
use super::fit::{FitError, FitOptions, FittedCell, fit};

/// The first `N` tried.
pub const AUTO_START_N: usize = 32;

/// Probe grid points per axis for [`surface_movement`].
pub const PROBE_N: usize = 48;

/// Fits `source` at `N = 32, 64, …` up to `max_n` and returns the first fit (and its `N`)
/// whose next doubling moves the zero set less than `tolerance` (cell units, measured by
/// [`surface_movement`]).
///
/// Errors: `tolerance` not finite and positive or `max_n < 64` ([`FitError::AutoOptions`]);
/// the tolerance not met by `max_n` ([`FitError::AutoNotConverged`], with the last
/// movement); any error of [`fit()`] at some `N`.
pub fn fit_auto(
    group: &super::group::Group,
    source: &dyn Source,
    options: &FitOptions,
    tolerance: f64,
    max_n: usize,
) -> Result<(FittedCell, usize), FitError> {
    if !(tolerance.is_finite() && tolerance > 0.0) || max_n < 2 * AUTO_START_N {
        return Err(FitError::AutoOptions { tolerance, max_n });
    }
    let mut n = AUTO_START_N;
    let mut coarse = fit(group, n, source, options)?;
    let mut last = f64::INFINITY;
    while 2 * n <= max_n {
        let fine = fit(group, 2 * n, source, options)?;
        let movement = surface_movement(&coarse, &fine)?;
        if movement < tolerance {
            return Ok((coarse, n));
        }
        last = movement;
        coarse = fine;
        n *= 2;
    }
    Err(FitError::AutoNotConverged {
        tolerance,
        max_n,
        n: n / 2,
        movement: last,
    })
}

/// How far the zero set moves from `coarse` to `fine` (cell units): the maximum of
/// `|Φ_fine − Φ_coarse| / |∇Φ_fine|` over probe points near either zero set (module docs).
/// Zero when neither field changes sign on the probe grid.
pub fn surface_movement(coarse: &FittedCell, fine: &FittedCell) -> Result<f64, FitError> {
    if coarse.group() != fine.group() {
        return Err(FitError::GroupMismatch(
            coarse.group().to_string(),
            fine.group().to_string(),
        ));
    }
    let group = fine.group();
    let d = group.dimension();
    let m = PROBE_N;
    let a = coarse.grid(m)?;
    let b = fine.grid(m)?;
    let strides: Vec<usize> = (0..d).map(|axis| m.pow(axis as u32)).collect();
    let near = |v: &[f64], i: usize| {
        let s = v[i] > 0.0;
        strides.iter().any(|&st| {
            let coord = (i / st) % m;
            let j = if coord + 1 == m {
                i + st - m * st
            } else {
                i + st
            };
            (v[j] > 0.0) != s
        })
    };
    let origin = group.domain().origin();
    let frame = group.domain().frame();
    let movement = (0..a.len())
        .into_par_iter()
        .filter(|&i| near(&a, i) || near(&b, i))
        .map(|i| {
            let s: [f64; 3] = std::array::from_fn(|axis| {
                if axis < d {
                    origin[axis] + ((i / strides[axis]) % m) as f64 / m as f64
                } else {
                    0.0
                }
            });
            let (_, g) = fine.value_gradient(frame.to_cartesian(s));
            let gn = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
            let diff = (b[i] - a[i]).abs();
            if diff == 0.0 {
                0.0
            } else if gn > 0.0 {
                diff / gn
            } else {
                f64::INFINITY
            }
        })
        .reduce(|| 0.0, f64::max);
    Ok(movement)
}
