//! Loci-surface reconstruction (Wang §5): a PS model whose zero set passes through given
//! points.
//!
//! The incremental search (Fig. 2): the basis is the constant plus every direction at scale
//! 1, then at 2, 4, … (`κ ∈ {1, 2, 4, …}` up to `max_scale`); at each step the moments are
//! the right singular vector of the smallest singular value of
//! `A[n, t] = cos(2π κ_t p_t · r_n)` ([`nullspace`](super::nullspace): the canonical one when
//! that value is repeated, and the repetition is reported), and the search stops once the
//! largest `|ψ(r_n)|` is below `tolerance`. Optionally the porosity is then raised
//! ([`optimize`](super::optimize), §5.3 eq. 12) while the error stays below `tolerance`.
//!
//! Invariants:
//! - The returned model is normalised so that `max |ψ|` over the unit cell is 1 (found on a
//!   grid and refined by Newton steps): errors are relative to it (the paper's `ψ_M`), and a
//!   shell thickness is a fraction of it. Its first significant moment is positive.
//! - Porosity (eq. 11) is the mean of `(ψ/ψ_M)²` over a periodic grid of `grid³` points on the
//!   unit cell; for integer basis vectors the mean is exact once the grid exceeds twice the
//!   largest frequency, which the grid size chosen here always does.
//! - Terms whose normalised moment is below 1e-13 (the null vector's rounding noise) are
//!   dropped from the model; the reported error is measured after dropping them.
//! - Basis terms that are the same function (`κ p` equal up to sign) are used once, so the
//!   null vector never cancels a term against its copy.

use nalgebra::DMatrix;

use super::model::{DIRECTIONS_13, PsModel, PsSampler, PsTerm};
use super::nullspace::smallest_subspace;
use super::optimize::{Optimization, optimize};
use crate::field::{Grid, PlaneSampler};

#[derive(Clone, Debug, PartialEq)]
pub struct ReconstructOptions {
    /// Stop when `max_n |ψ(r_n)| / ψ_M` is below this.
    pub tolerance: f64,
    /// The largest scale κ tried (1, 2, 4, … up to it).
    pub max_scale: u32,
    /// Basis vectors `[a, b, c, θ]` (default: the 13 directions with θ = 0).
    pub directions: Vec<[f64; 4]>,
    /// Raise the porosity (eq. 12) while keeping the error below `tolerance`.
    pub optimize: bool,
}

impl Default for ReconstructOptions {
    fn default() -> ReconstructOptions {
        ReconstructOptions {
            tolerance: 1e-9,
            max_scale: 8,
            directions: DIRECTIONS_13
                .iter()
                .map(|d| [d[0], d[1], d[2], 0.0])
                .collect(),
            optimize: false,
        }
    }
}

/// The quality of one model (the paper's Table 3 columns).
#[derive(Clone, Debug, PartialEq)]
pub struct Metrics {
    pub dimension: usize,
    /// `max_n |ψ(r_n)| / ψ_M`.
    pub max_error: f64,
    pub porosity: f64,
    /// How many singular values are the smallest: above 1, the surface through the points is
    /// not unique and the model is the canonical choice among them.
    pub multiplicity: usize,
}

/// One step of the incremental search.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    pub scales: Vec<u32>,
    pub metrics: Metrics,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Reconstruction {
    /// Normalised: `max |ψ|` over the cell is 1.
    pub model: PsModel,
    pub atoms: usize,
    pub metrics: Metrics,
    /// Grid points per axis of the porosity grid.
    pub grid: usize,
    /// Whether the error fell below the tolerance.
    pub converged: bool,
    pub steps: Vec<Step>,
    /// Before and after the §5.3 optimisation, when asked for.
    pub optimization: Option<Optimization>,
}

#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ReconstructError {
    #[error("no atoms to pass through")]
    NoAtoms,
    #[error("the basis is empty: give at least one direction")]
    NoBasis,
    #[error("the singular value decomposition did not converge")]
    Svd,
    #[error("the reconstructed surface vanishes on the whole cell (the basis is degenerate)")]
    Vanishes,
}

/// Reconstructs a loci surface through `points` (cell coordinates); with `optimize`, eq. 12
/// over the moments and the phase shift ([`phase`](super::phase)).
pub fn reconstruct(
    points: &[[f64; 3]],
    options: &ReconstructOptions,
) -> Result<Reconstruction, ReconstructError> {
    if options.optimize {
        super::phase::optimize_with_phase(points, options)
    } else {
        search(points, options)
    }
}

/// The incremental search on `options.directions` as given, then (with `optimize`) eq. 12
/// over the moments.
pub(super) fn search(
    points: &[[f64; 3]],
    options: &ReconstructOptions,
) -> Result<Reconstruction, ReconstructError> {
    if points.is_empty() {
        return Err(ReconstructError::NoAtoms);
    }
    let mut basis = vec![PsTerm {
        moment: 0.0,
        scale: 1.0,
        vector: [0.0; 4],
    }];
    let mut scales = Vec::new();
    let mut steps = Vec::new();
    let mut scale = 1u32;
    let mut best = None;
    while scale <= options.max_scale.max(1) {
        scales.push(scale);
        for d in &options.directions {
            add_unique(
                &mut basis,
                PsTerm {
                    moment: 0.0,
                    scale: f64::from(scale),
                    vector: *d,
                },
            );
        }
        let (model, metrics, grid) = fit(points, &basis, None)?;
        steps.push(Step {
            scales: scales.clone(),
            metrics: metrics.clone(),
        });
        let done = metrics.max_error < options.tolerance;
        best = Some((model, metrics, grid));
        if done {
            break;
        }
        scale = match scale.checked_mul(2) {
            Some(s) => s,
            None => break,
        };
    }
    let (mut model, mut metrics, grid) = best.ok_or(ReconstructError::NoBasis)?;
    let converged = metrics.max_error < options.tolerance;
    let mut optimization = None;
    if options.optimize && converged {
        let next = scale
            .checked_mul(2)
            .filter(|s| *s <= options.max_scale.max(1))
            .map(|s| {
                let mut wider = basis.clone();
                for d in &options.directions {
                    add_unique(
                        &mut wider,
                        PsTerm {
                            moment: 0.0,
                            scale: f64::from(s),
                            vector: *d,
                        },
                    );
                }
                (
                    scales.iter().copied().chain([s]).collect::<Vec<u32>>(),
                    wider,
                )
            });
        let found = optimize(
            points,
            (&model, &metrics),
            (&scales, &basis),
            next.as_ref().map(|(s, b)| (s.as_slice(), b.as_slice())),
            options.tolerance,
        )?;
        model = found.0;
        metrics = found.1.after.clone();
        optimization = Some(found.1);
    }
    Ok(Reconstruction {
        model,
        atoms: points.len(),
        metrics,
        grid,
        converged,
        steps,
        optimization,
    })
}

/// Adds `term` unless the basis already holds the same function (`κ p` equal up to sign).
pub(super) fn add_unique(basis: &mut Vec<PsTerm>, term: PsTerm) {
    let key = |t: &PsTerm| t.vector.map(|v| v * t.scale);
    let k = key(&term);
    let same = |a: [f64; 4], b: [f64; 4]| (0..4).all(|i| (a[i] - b[i]).abs() < 1e-12);
    let negated = k.map(|v| -v);
    if k.iter().all(|v| *v == 0.0) && basis.iter().any(PsTerm::is_constant) {
        return;
    }
    if !basis
        .iter()
        .any(|t| same(key(t), k) || same(key(t), negated))
    {
        basis.push(term);
    }
}

/// Moments below this (with `max |ψ| = 1`) are rounding noise of the decomposition.
const NEGLIGIBLE_MOMENT: f64 = 1e-13;

/// The null-vector model of `basis` through `points`, normalised, with its metrics; `grid`
/// overrides the porosity grid size.
pub(super) fn fit(
    points: &[[f64; 3]],
    basis: &[PsTerm],
    grid: Option<usize>,
) -> Result<(PsModel, Metrics, usize), ReconstructError> {
    if basis.is_empty() {
        return Err(ReconstructError::NoBasis);
    }
    let moments = smallest_subspace(&design_matrix(points, basis)).ok_or(ReconstructError::Svd)?;
    normalised(
        points,
        basis,
        &moments.representative(),
        grid,
        moments.multiplicity,
    )
}

/// `A[n, t] = cos(2π κ_t p_t · r_n)`.
pub(super) fn design_matrix(points: &[[f64; 3]], basis: &[PsTerm]) -> DMatrix<f64> {
    DMatrix::from_fn(points.len(), basis.len(), |n, t| {
        let p = points[n];
        basis[t].phase(p[0], p[1], p[2]).cos()
    })
}

/// The model `Σ moments[t] basis[t]` scaled to `max |ψ| = 1` with its first significant
/// moment positive, negligible moments dropped, and its metrics.
pub(super) fn normalised(
    points: &[[f64; 3]],
    basis: &[PsTerm],
    moments: &[f64],
    grid: Option<usize>,
    multiplicity: usize,
) -> Result<(PsModel, Metrics, usize), ReconstructError> {
    let model = PsModel::new(
        basis
            .iter()
            .zip(moments)
            .map(|(t, &moment)| PsTerm { moment, ..*t })
            .collect(),
    );
    let n = grid.unwrap_or_else(|| porosity_grid(&model));
    let (psi_max, mean_square) = cell_statistics(&model, n);
    if psi_max <= 1e-300 || !psi_max.is_finite() {
        return Err(ReconstructError::Vanishes);
    }
    let sign = model
        .terms
        .iter()
        .map(|t| t.moment)
        .find(|m| m.abs() > 1e-9 * psi_max)
        .map_or(1.0, f64::signum);
    // Moments at rounding level (the null vector's zero entries) are not terms of the model.
    let mut model = model.times(sign / psi_max);
    model.terms.retain(|t| t.moment.abs() > NEGLIGIBLE_MOMENT);
    let max_error = points
        .iter()
        .map(|&p| model.value(p).abs())
        .fold(0.0, f64::max);
    let metrics = Metrics {
        dimension: model.terms.len(),
        max_error,
        porosity: mean_square / (psi_max * psi_max),
        multiplicity,
    };
    Ok((model, metrics, n))
}

/// Grid points per axis: four per period of the fastest term along an axis, at least 32 and
/// at most 256 (above twice the largest frequency for scales up to 32 on the 13 directions).
pub(super) fn porosity_grid(model: &PsModel) -> usize {
    let fastest = model
        .terms
        .iter()
        .flat_map(|t| t.vector[..3].iter().map(move |v| (v * t.scale).abs()))
        .fold(0.0, f64::max);
    let n = (4.0 * fastest).ceil() as usize;
    n.clamp(32, 256).next_multiple_of(2)
}

/// `(max |ψ|, mean ψ²)` over the periodic grid of `n³` points on the unit cell, the maximum
/// refined by Newton steps from the best grid points.
fn cell_statistics(model: &PsModel, n: usize) -> (f64, f64) {
    let spacing = 1.0 / n as f64;
    let grid = Grid {
        origin: [0.0; 3],
        spacing: [spacing; 3],
        counts: [n; 3],
    };
    let sampler = PsSampler::new(model, &grid);
    let mut plane = vec![0.0; grid.plane_len()];
    let mut sum = 0.0;
    // The few largest |ψ| samples, as (|ψ|, point).
    let mut top: Vec<(f64, [f64; 3])> = Vec::new();
    for k in 0..n {
        sampler.sample_plane(k, &mut plane);
        for (idx, &v) in plane.iter().enumerate() {
            sum += v * v;
            let a = v.abs();
            if top.len() < 4 || a > top[top.len() - 1].0 {
                let p = [
                    (idx % n) as f64 * spacing,
                    (idx / n) as f64 * spacing,
                    k as f64 * spacing,
                ];
                top.push((a, p));
                top.sort_by(|x, y| y.0.total_cmp(&x.0));
                top.truncate(4);
            }
        }
    }
    let mean = sum / (n * n * n) as f64;
    let max = top
        .iter()
        .map(|&(a, p)| refine_maximum(model, p, a, spacing))
        .fold(0.0, f64::max);
    (max, mean)
}

/// Newton steps towards the stationary point of ψ near `start`, kept only while `|ψ|` grows
/// and the point stays within a grid cell or two of where it began.
fn refine_maximum(model: &PsModel, start: [f64; 3], at_start: f64, spacing: f64) -> f64 {
    let mut p = start;
    let mut best = at_start;
    for _ in 0..8 {
        let (_, g, h) = model.value_gradient_hessian(p);
        let Some(step) = solve3(h, g) else {
            break;
        };
        let next: [f64; 3] = std::array::from_fn(|i| p[i] - step[i]);
        if (0..3).any(|i| (next[i] - start[i]).abs() > 2.0 * spacing) {
            break;
        }
        let v = model.value(next).abs();
        if v <= best {
            break;
        }
        best = v;
        p = next;
    }
    best
}

fn solve3(m: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(m);
    if d.abs() < 1e-300 || !d.is_finite() {
        return None;
    }
    // Cramer's rule: three columns replaced by b.
    Some(std::array::from_fn(|c| {
        let mut mc = m;
        for r in 0..3 {
            mc[r][c] = b[r];
        }
        det(mc) / d
    }))
}
