//! The optimisation of a reconstructed surface (Wang §5.3, eq. 12): maximise the porosity
//! `φ` subject to `max_n |ψ(r_n)| / ψ_M ≤ ε`, over the moments of the basis vectors.
//!
//! Why a greedy term drop alone cannot help: at the scale where the search converges the
//! exact fits usually form a one-dimensional space (Faujasite's Si at scale 1: five terms,
//! every other moment zero), so no term can go without the error leaving the tolerance.
//! What eq. 12 can move is the choice among exact fits, and there are more of them one scale
//! further (Faujasite at scales 1, 2: a six-dimensional space). So the candidates are
//! - the terms dropped greedily, each time the one whose removal raises the porosity most;
//! - on the converged basis and on the basis one scale further, the combination of the exact
//!   fits (the repeated smallest singular value's subspace) with the highest porosity,
//!   searched by Nelder–Mead from each canonical basis vector of the subspace.
//!
//! and the result is the candidate with the highest porosity whose error is below the
//! tolerance, or the surface unchanged when none beats it. The phase shift of eq. 12 and the
//! domain are [`super::phase`]'s, which runs this at the phase it chooses.
//!
//! Invariants:
//! - Deterministic and independent of the atom order: the search runs in the subspace's
//!   canonical basis ([`super::nullspace`]), from fixed starts, for a fixed number of steps.
//! - Every figure reported is measured like the unoptimised one (same porosity grid rule,
//!   same normalisation); the search itself only ranks on a coarser grid.

use nalgebra::DVector;

use super::model::{PsModel, PsTerm};
use super::nullspace::smallest_subspace;
use super::phase::PhaseChoice;
use super::reconstruct::{Metrics, ReconstructError, design_matrix, fit, normalised};

/// Before and after eq. 12.
#[derive(Clone, Debug, PartialEq)]
pub struct Optimization {
    pub before: Metrics,
    pub after: Metrics,
    /// The scales of the basis the result lives on.
    pub scales: Vec<u32>,
    /// How the result was found.
    pub method: Method,
    /// The dimension of the space of exact fits searched (1 when there was no choice).
    pub freedom: usize,
    /// The phase shift chosen ([`super::phase`]); `None` only inside that search.
    pub phase: Option<PhaseChoice>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Nothing found raised the porosity.
    Unchanged,
    /// Terms dropped greedily.
    DroppedTerms,
    /// The best combination of the exact fits.
    Subspace,
}

impl Method {
    pub fn describe(self) -> &'static str {
        match self {
            Method::Unchanged => "unchanged (no exact fit has a higher porosity)",
            Method::DroppedTerms => "terms dropped",
            Method::Subspace => "best combination of the exact fits",
        }
    }
}

/// Eq. 12 from the converged surface `current` on `at = (scales, basis)`, also trying the
/// basis one scale further when there is one.
pub(super) fn optimize(
    points: &[[f64; 3]],
    current: (&PsModel, &Metrics),
    at: (&[u32], &[PsTerm]),
    next: Option<(&[u32], &[PsTerm])>,
    tolerance: f64,
) -> Result<(PsModel, Optimization), ReconstructError> {
    let before = current.1.clone();
    let mut best = (
        current.0.clone(),
        Optimization {
            before: before.clone(),
            after: before.clone(),
            scales: at.0.to_vec(),
            method: Method::Unchanged,
            freedom: before.multiplicity,
            phase: None,
        },
    );
    let better = |m: &Metrics, than: &Metrics| {
        m.max_error < tolerance
            && (m.porosity > than.porosity + 1e-9
                || (m.porosity > than.porosity - 1e-9 && m.dimension < than.dimension))
    };
    let (dropped, dropped_metrics) = drop_terms(points, at.1.to_vec(), tolerance)?;
    if better(&dropped_metrics, &best.1.after) {
        best.0 = dropped;
        best.1.after = dropped_metrics;
        best.1.method = Method::DroppedTerms;
    }
    for (scales, basis) in [Some(at), next].into_iter().flatten() {
        if let Some((model, metrics, freedom)) = best_exact_fit(points, basis)?
            && better(&metrics, &best.1.after)
        {
            best.0 = model;
            best.1.after = metrics;
            best.1.scales = scales.to_vec();
            best.1.method = Method::Subspace;
            best.1.freedom = freedom;
        }
    }
    Ok(best)
}

/// The combination of the smallest singular value's subspace of `basis` with the highest
/// porosity, normalised and measured; `None` when that value is not repeated.
fn best_exact_fit(
    points: &[[f64; 3]],
    basis: &[PsTerm],
) -> Result<Option<(PsModel, Metrics, usize)>, ReconstructError> {
    let subspace = smallest_subspace(&design_matrix(points, basis)).ok_or(ReconstructError::Svd)?;
    let k = subspace.canonical_basis.ncols();
    if subspace.multiplicity < 2 || k < 2 {
        return Ok(None);
    }
    let n = search_grid(basis);
    let samples = grid_points(n);
    let values = design_matrix(&samples, basis) * &subspace.canonical_basis;
    let gram = values.transpose() * &values / samples.len() as f64;
    let porosity = |c: &DVector<f64>| {
        let v = &values * c;
        let max = v.amax();
        if max > 0.0 {
            c.dot(&(&gram * c)) / (max * max)
        } else {
            0.0
        }
    };
    let mut best: Option<(f64, DVector<f64>)> = None;
    // Fixed starts, at most eight, and a budget that shrinks with the dimension.
    let iterations = (4000 / k).clamp(100, 600);
    for start in 0..k.min(8) {
        let mut c = DVector::from_fn(k, |i, _| f64::from(u8::from(i == start)));
        // Restarts from the best vertex (rescaled: φ does not depend on the length) undo a
        // simplex that collapsed early.
        for _ in 0..3 {
            c = nelder_mead(&|c| -porosity(c), c.normalize(), iterations);
        }
        let p = porosity(&c);
        if best.as_ref().is_none_or(|(b, _)| p > *b) {
            best = Some((p, c));
        }
    }
    let Some((_, c)) = best else {
        return Ok(None);
    };
    let moments = &subspace.canonical_basis * c;
    let (model, metrics, _) = normalised(
        points,
        basis,
        moments.as_slice(),
        None,
        subspace.multiplicity,
    )?;
    Ok(Some((model, metrics, k)))
}

/// Grid points per axis for ranking: eight per period of the fastest term, 16 to 32.
fn search_grid(basis: &[PsTerm]) -> usize {
    let fastest = basis
        .iter()
        .flat_map(|t| t.vector[..3].iter().map(move |v| (v * t.scale).abs()))
        .fold(0.0, f64::max);
    ((8.0 * fastest).ceil() as usize).clamp(16, 32)
}

fn grid_points(n: usize) -> Vec<[f64; 3]> {
    let h = 1.0 / n as f64;
    (0..n * n * n)
        .map(|i| [i % n, (i / n) % n, i / (n * n)].map(|c| c as f64 * h))
        .collect()
}

/// Minimises `f` by Nelder–Mead from `start` (simplex edges 0.5 along each axis), with a
/// fixed number of iterations; the best vertex.
fn nelder_mead(
    f: &dyn Fn(&DVector<f64>) -> f64,
    start: DVector<f64>,
    iterations: usize,
) -> DVector<f64> {
    let k = start.len();
    let mut simplex: Vec<(f64, DVector<f64>)> = (0..=k)
        .map(|i| {
            let mut v = start.clone();
            if i > 0 {
                v[i - 1] += 0.5;
            }
            (f(&v), v)
        })
        .collect();
    for _ in 0..iterations {
        simplex.sort_by(|a, b| a.0.total_cmp(&b.0));
        let centroid = simplex[..k]
            .iter()
            .fold(DVector::zeros(k), |acc, (_, v)| acc + v)
            / k as f64;
        let worst = simplex[k].clone();
        let toward = |t: f64| &centroid + (&worst.1 - &centroid) * t;
        let reflected = toward(-1.0);
        let fr = f(&reflected);
        if fr < simplex[0].0 {
            let expanded = toward(-2.0);
            let fe = f(&expanded);
            simplex[k] = if fe < fr {
                (fe, expanded)
            } else {
                (fr, reflected)
            };
        } else if fr < simplex[k - 1].0 {
            simplex[k] = (fr, reflected);
        } else {
            let contracted = toward(if fr < worst.0 { -0.5 } else { 0.5 });
            let fc = f(&contracted);
            if fc < worst.0.min(fr) {
                simplex[k] = (fc, contracted);
            } else {
                let best = simplex[0].1.clone();
                for (fv, v) in simplex.iter_mut().skip(1) {
                    *v = &best + (&*v - &best) * 0.5;
                    *fv = f(v);
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.0.total_cmp(&b.0));
    simplex.swap_remove(0).1
}

/// §5.3: repeatedly drop the term whose removal gives the highest porosity while the error
/// stays below `tolerance`; stop when no removal raises the porosity. Candidates are ranked
/// on a coarser grid; the result is measured on the full one.
fn drop_terms(
    points: &[[f64; 3]],
    mut basis: Vec<PsTerm>,
    tolerance: f64,
) -> Result<(PsModel, Metrics), ReconstructError> {
    let (mut model, mut metrics, n) = fit(points, &basis, None)?;
    let coarse = (n / 2).max(16);
    let mut porosity = fit(points, &basis, Some(coarse))?.1.porosity;
    while basis.len() > 2 {
        let mut choice: Option<(usize, f64)> = None;
        for drop in 0..basis.len() {
            let mut trial = basis.clone();
            trial.remove(drop);
            let Ok((_, m, _)) = fit(points, &trial, Some(coarse)) else {
                continue;
            };
            if m.max_error < tolerance && choice.is_none_or(|(_, best)| m.porosity > best) {
                choice = Some((drop, m.porosity));
            }
        }
        match choice {
            Some((drop, p)) if p > porosity => {
                basis.remove(drop);
                porosity = p;
            }
            _ => break,
        }
    }
    let (m, full, _) = fit(points, &basis, Some(n))?;
    if full.max_error < tolerance {
        model = m;
        metrics = full;
    }
    Ok((model, metrics))
}
