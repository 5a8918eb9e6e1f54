//! The phase shift of eq. 12 (Wang §5.3, Tab. 5): one `θ` added to every periodic vector,
//! chosen to maximise the porosity while every atom stays on the surface.
//!
//! What the shift means: the paper's optimised Faujasite model writes every non-constant term
//! as `cos(2π κ (h · r + θ*))`, the same `θ*` in every basis vector `p = [h, θ]`. So the
//! basis of the search becomes `cos(2π κ_t (h_t · r + θ))` for the 13 directions `h_t`; the
//! constant stays the constant. This is *not* a translation of the surface: a translation by
//! `t` shifts each vector by its own `h_t · t` (Lemma 3), while a common `θ` mixes sines into
//! the basis (`cos(φ + 2πκθ) = cos φ cos 2πκθ − sin φ sin 2πκθ`), so the surfaces through the
//! atoms differ. With natural scales, `θ + ½` turns every term into itself (`κ` even) or its
//! negative (`κ` odd): the same basis up to signs, so the same surface. The search therefore
//! covers `θ ∈ [0, ½)`.
//!
//! The search is deterministic: the plain incremental search ([`super::reconstruct`]) at
//! `θ = j / (2 GRID)` for `j = 0 … GRID−1`, ranked first by convergence (error below the
//! tolerance), then by porosity (converged) or by the smallest error of any step (not). Then
//! golden-section steps on the same ranking over the two grid intervals around (a) the best
//! grid point when its neighbours converge too, so the porosity varies smoothly there, and
//! (b) the three lowest unconverged local minima of the error, where an isolated exact fit may
//! sit between grid points. The best `θ` seen wins, ties to the one found first (so `θ = 0`).
//! The eq. 12 optimisation over the moments ([`super::optimize`]) then runs at `θ = 0` and at
//! the winner, and the higher porosity wins.
//!
//! The domain of eq. 11–12: the code's domain is the unit cell, one full period of the
//! lattice. Moving it (any origin shift, any choice of images) changes neither the porosity —
//! the mean and maximum of a period-1 function over any unit box are the same — nor the
//! constraints, since an atom and its image give the same row of the design matrix. So there
//! is nothing to search there: the tests show it, and the command reports the domain used.
//!
//! Invariants:
//! - `θ ∈ [0, 1)`, and the result's metrics are measured like every other surface's.
//! - The result's porosity is never below the `θ = 0` optimisation's.

use super::model::PsTerm;
use super::reconstruct::{ReconstructError, ReconstructOptions, Reconstruction, search};

/// The search's period in `θ`: `θ + ½` gives the same basis up to signs (natural scales).
pub const PERIOD: f64 = 0.5;

/// Grid points of the first pass over `[0, ½)`.
pub const GRID: usize = 24;

/// Unconverged local minima of the error refined, at most.
const MINIMA: usize = 3;

/// When a golden-section refinement stops.
#[derive(Clone, Copy)]
enum Stop {
    /// Among converged phases: once the interval is below 10⁻⁶ (porosity is flat there).
    Porosity,
    /// Seeking an isolated exact fit: once one is found (interval below 10⁻⁶) or the interval is
    /// below 10⁻¹².
    ExactFit,
}

/// How the phase was chosen.
#[derive(Clone, Debug, PartialEq)]
pub struct PhaseChoice {
    /// The shift added to every non-constant basis vector, in `[0, 1)`.
    pub theta: f64,
    /// Plain (unoptimised) searches run to choose it.
    pub evaluations: usize,
    /// The plain search's porosity at `θ = 0` and at `theta` (`None`: not converged there).
    pub porosity_at_zero: Option<f64>,
    pub porosity_at_theta: Option<f64>,
}

/// The directions with `theta` added to every non-constant vector's phase.
pub fn shifted(directions: &[[f64; 4]], theta: f64) -> Vec<[f64; 4]> {
    directions
        .iter()
        .map(|d| {
            if d[..3].iter().all(|&v| v == 0.0) {
                *d
            } else {
                [d[0], d[1], d[2], d[3] + theta]
            }
        })
        .collect()
}

/// A model's terms with `theta` added to every non-constant vector's phase (the shifted basis
/// carries its moments over unchanged).
pub fn shift_terms(terms: &[PsTerm], theta: f64) -> Vec<PsTerm> {
    terms
        .iter()
        .map(|t| {
            if t.is_constant() {
                *t
            } else {
                let [a, b, c, p] = t.vector;
                PsTerm {
                    vector: [a, b, c, p + theta],
                    ..*t
                }
            }
        })
        .collect()
}

/// The ranking of one plain search: converged beats not; then porosity, or a lower error.
#[derive(Clone, Copy, Debug)]
struct Score {
    converged: bool,
    porosity: f64,
    max_error: f64,
}

impl Score {
    fn of(r: &Reconstruction) -> Score {
        Score {
            converged: r.converged,
            porosity: r.metrics.porosity,
            // Unconverged, the closest any step came (the last step need not be closest).
            max_error: r
                .steps
                .iter()
                .map(|s| s.metrics.max_error)
                .fold(r.metrics.max_error, f64::min),
        }
    }

    /// Strictly better (by more than rounding in porosity).
    fn beats(&self, other: &Score) -> bool {
        match (self.converged, other.converged) {
            (true, false) => true,
            (false, true) => false,
            (true, true) => self.porosity > other.porosity + 1e-9,
            (false, false) => self.max_error < other.max_error,
        }
    }
}

/// Eq. 12 over the phase: the plain search scanned over `θ`, then the porosity optimisation at
/// `θ = 0` and at the best `θ`; `options.optimize` is taken as set.
pub(super) fn optimize_with_phase(
    points: &[[f64; 3]],
    options: &ReconstructOptions,
) -> Result<Reconstruction, ReconstructError> {
    let at = |theta: f64, optimize: bool| {
        search(
            points,
            &ReconstructOptions {
                directions: shifted(&options.directions, theta),
                optimize,
                ..options.clone()
            },
        )
    };
    let mut evaluations = 0;
    let mut score = |theta: f64| -> Result<Score, ReconstructError> {
        evaluations += 1;
        Ok(Score::of(&at(theta, false)?))
    };
    let h = PERIOD / GRID as f64;
    let grid: Vec<(f64, Score)> = (0..GRID)
        .map(|j| {
            let theta = j as f64 * h;
            score(theta).map(|s| (theta, s))
        })
        .collect::<Result<_, _>>()?;
    let zero = grid[0].1;
    let mut best = grid[0];
    for &(theta, s) in &grid[1..] {
        if s.beats(&best.1) {
            best = (theta, s);
        }
    }
    let neighbours = |j: usize| (grid[(j + GRID - 1) % GRID].1, grid[(j + 1) % GRID].1);
    // Intervals to refine: around the best grid point when its neighbours converge too (the
    // porosity varies smoothly there; an exact fit between unconverged neighbours is isolated
    // and cannot be bettered nearby), and around the unconverged local minima of the error,
    // lowest first, where an isolated exact fit may sit between grid points.
    let mut centres: Vec<(f64, Stop)> = Vec::new();
    if let Some(j) = grid.iter().position(|g| g.0 == best.0) {
        let (prev, next) = neighbours(j);
        if best.1.converged && prev.converged && next.converged {
            centres.push((best.0, Stop::Porosity));
        }
    }
    let mut minima: Vec<(f64, f64)> = (0..GRID)
        .filter(|&j| {
            let (prev, next) = neighbours(j);
            let e = grid[j].1;
            !e.converged
                && !prev.converged
                && !next.converged
                && e.max_error <= prev.max_error
                && e.max_error <= next.max_error
        })
        .map(|j| (grid[j].0, grid[j].1.max_error))
        .collect();
    minima.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.total_cmp(&b.0)));
    centres.extend(minima.iter().take(MINIMA).map(|m| (m.0, Stop::ExactFit)));
    for (centre, stop) in centres {
        // Golden section for the best score in [centre − h, centre + h].
        let ratio = (5f64.sqrt() - 1.0) / 2.0;
        let (mut lo, mut hi) = (centre - h, centre + h);
        let mut x1 = hi - ratio * (hi - lo);
        let mut x2 = lo + ratio * (hi - lo);
        let (mut s1, mut s2) = (score(wrap(x1))?, score(wrap(x2))?);
        loop {
            for (x, s) in [(x1, s1), (x2, s2)] {
                if s.beats(&best.1) {
                    best = (wrap(x), s);
                }
            }
            let width = hi - lo;
            let done = match stop {
                Stop::Porosity => width < 1e-6,
                Stop::ExactFit => width < 1e-12 || (width < 1e-6 && (s1.converged || s2.converged)),
            };
            if done {
                break;
            }
            if s2.beats(&s1) {
                lo = x1;
                (x1, s1) = (x2, s2);
                x2 = lo + ratio * (hi - lo);
                s2 = score(wrap(x2))?;
            } else {
                hi = x2;
                (x2, s2) = (x1, s1);
                x1 = hi - ratio * (hi - lo);
                s1 = score(wrap(x1))?;
            }
        }
    }
    let theta = best.0;
    let mut result = at(0.0, true)?;
    let mut kept = 0.0;
    if theta != 0.0 {
        let shifted_result = at(theta, true)?;
        let better = shifted_result.converged
            && (!result.converged
                || shifted_result.metrics.porosity > result.metrics.porosity + 1e-9);
        if better {
            let before = result.optimization.as_ref().map(|o| o.before.clone());
            result = shifted_result;
            kept = theta;
            // "Before" stays the unshifted search's surface, the one without `--optimize`.
            if let (Some(o), Some(before)) = (result.optimization.as_mut(), before) {
                o.before = before;
            }
        }
    }
    let choice = PhaseChoice {
        theta: kept,
        evaluations,
        porosity_at_zero: zero.converged.then_some(zero.porosity),
        porosity_at_theta: best.1.converged.then_some(best.1.porosity),
    };
    if let Some(o) = result.optimization.as_mut() {
        o.phase = Some(choice);
    }
    Ok(result)
}

/// `θ` reduced to `[0, ½)`.
fn wrap(theta: f64) -> f64 {
    let w = theta.rem_euclid(PERIOD);
    if w >= PERIOD { 0.0 } else { w }
}
