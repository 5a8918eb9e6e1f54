//! Coefficient optimisation (docs/method.md §Coefficient optimisation, §Surface area): the
//! cell closest to a fitted one, in the basis's L² norm, whose solid `{Φ ≤ 0}` fills a target
//! volume fraction of its reference element and/or whose surface has a target area density.
//!
//! Surface area (the volume-only path below is unchanged, to the bit): the constraint value
//! is the sharp marching area on the optimisation grid ([`super::measure`]), its gradient the
//! curvature form `−w δ_ε(d) κ/|∇Φ|` fitted like the volume's (`objective.rs`); with both
//! targets the steps solve the 2×2 system `J Jᵀ λ = r` (restoration) and go to `c₀ + Jᵀμ`
//! (least change); residuals are scaled (`|V − V*|`, `|A − A*|/A*`).
//!
//! Method and why:
//! - Problem: `min ‖c − c₀‖` subject to `V(c) = V*` (and, when asked, the face-normal rows
//!   `C c = 0`), with `c − c₀` in the span of the frequencies `|f_a| ≤` [`CHANGE_BAND`]. The
//!   `φ_f` are orthonormal on the domain, so `‖c − c₀‖` is the L² change of the field.
//!   Staying in the symmetric basis keeps the group symmetry for free. The band matters: over
//!   all frequencies the least L² change is a thin, rippled bump at the surface (flat field,
//!   loose specks of solid); over a low band it is a smooth field, and the level shift (`f =
//!   0`) is still among the changes allowed. With the face-normal projection the change may
//!   leave the band along the rows' lines of frequencies.
//! - Objective: `V(c) = Σ w H_ε(−Φ/|∇Φ|) / Σ w` on the domain grid (`w` the reference
//!   element's indicator; the whole domain for groups without one), with the smoothed
//!   Heaviside `H_ε(t) = ½(1 + t/ε + sin(πt/ε)/π)` on `|t| < ε`, applied to the first-order
//!   distance (gradient by central differences) so that the band is `ε` cell units wide
//!   however flat the field is. Its derivative in `c`, with `|∇Φ|` held fixed (Gauss–Newton),
//!   is the band-limited surface integral `∂V/∂c_f = −⟨w δ_ε(Φ/|∇Φ|)/|∇Φ|, φ_f⟩ / mean(w)`:
//!   those samples fitted in the same basis (one forward FFT), no per-coefficient loop.
//! - `P` removes from every direction its component in the face-normal rows' row space (the
//!   least-change projection of `constrain`), so steps keep the condition.
//! - Restoration: Newton steps along `g = P∇V`, `c + t g` with `t = (V* − V)/‖g‖²`, halved
//!   until `|V − V*|` shrinks. A step adds a bump at the current surface, so it moves the
//!   surface by about `ε` at most: the solve is continued from `ε = 0.1` cell units, halving
//!   to the final [`BAND_CELLS`] grid spacings.
//! - Least change: from a point meeting the target, a step towards `c₀ + μ g`, the point of
//!   the linearised constraint nearest `c₀` (sequential quadratic programming for one
//!   constraint), then restoration; kept only if `‖c − c₀‖` shrank (halving up to four
//!   times). At a solution `c − c₀ ∥ g`, the Lagrange condition.
//! - The smoothed `V` is biased by about `ε²` times the mean curvature of the surface; the
//!   sharp share of samples with `Φ ≤ 0` on a grid twice as fine is measured, and the
//!   smoothed target moved by the difference and restored (up to [`CORRECTIONS`] times).
//! - Stop: converged when the least-change steps stall (less than 10⁻³ of `‖c − c₀‖`) and the
//!   sharp fraction is within 10 × `tolerance`; otherwise, after `max_iterations` accepted
//!   steps or when no step helps, `converged` is false and the report holds what was reached.
//! - Grid: `N` clamped to [32, 64] in 3D and [64, 256] in 2D; a cell fitted on a finer grid
//!   keeps its higher frequencies unchanged (the change lies in the grid's band).
//!
//! Invariants: the result is in the symmetric basis (so exactly symmetric); each step is
//! projected, so a cell that met the face-normal condition still does; the same bits for any
//! thread count (grids and fits are).

use super::coefficient_space::Vector;
use super::fit::{FitError, FittedCell, fit_samples};
use super::measure::{CellMeasures, sharp_area, sharp_fraction};
use super::objective::{
    GridSamples, area_gradient_samples, element_weights, grid_samples, smoothed_area,
    smoothed_volume, volume_gradient_samples,
};

/// Samples per axis of the optimisation grid for 3D and 2D groups.
pub const OPTIMIZE_GRID_3D: usize = 64;
pub const OPTIMIZE_GRID_2D: usize = 256;

/// The change is made of the frequencies with every `|f_a|` at most this: a smooth field, so
/// the surface stays as smooth as the fitted one (module docs).
pub const CHANGE_BAND: u32 = 6;

/// The final smoothing half-width in grid spacings.
pub const BAND_CELLS: f64 = 1.5;

/// Default largest number of iterations and tolerance on the volume fraction.
pub const DEFAULT_MAX_ITERATIONS: usize = 30;
pub const DEFAULT_TOLERANCE: f64 = 1e-4;

/// The widest smoothing half-width of the continuation (cell units), and the tolerance of
/// the stages before the last.
const MAX_BAND: f64 = 0.1;
const STAGE_TOLERANCE: f64 = 1e-3;

/// Halvings of the line search before giving up.
const LINE_SEARCH_HALVINGS: usize = 12;

/// Sharp-count corrections, and how much looser than the smoothed tolerance the sharp count
/// may be (a count moves in steps of one sample).
pub const CORRECTIONS: usize = 3;
const SHARP_TOLERANCE_FACTOR: f64 = 10.0;

/// Least-change steps: halvings tried, restoration steps allowed after each, and the relative
/// decrease of `‖c − c₀‖` below which the walk stops.
const LEAST_CHANGE_HALVINGS: usize = 4;
const RESTORE_STEPS: usize = 4;
const LEAST_CHANGE_STALL: f64 = 1e-3;

/// What to optimise for: a volume fraction (the original interface; see
/// [`OptimizationTargets`] for the surface area).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Optimization {
    /// Target volume fraction of the solid `{Φ ≤ 0}` in the reference element, in (0, 1).
    pub volume_fraction: f64,
    /// Keep `∇Φ·n = 0` on the element's faces: every step is projected onto the rows'
    /// null space.
    pub keep_face_normal: bool,
    pub max_iterations: usize,
    /// Tolerance on `|V − V*|`.
    pub tolerance: f64,
}

/// What to optimise for: a volume fraction, a surface-area density, or both.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OptimizationTargets {
    /// Target volume fraction of the solid `{Φ ≤ 0}` in the reference element, in (0, 1).
    pub volume_fraction: Option<f64>,
    /// Target surface-area density (area of `{Φ = 0}` in the element per element volume,
    /// perimeter per area in 2D; [`super::measure`]), positive.
    pub surface_area: Option<f64>,
    pub keep_face_normal: bool,
    pub max_iterations: usize,
    /// Tolerance on `|V − V*|`, and on `|A − A*| / A*`.
    pub tolerance: f64,
}

impl From<&Optimization> for OptimizationTargets {
    fn from(o: &Optimization) -> OptimizationTargets {
        OptimizationTargets {
            volume_fraction: Some(o.volume_fraction),
            surface_area: None,
            keep_face_normal: o.keep_face_normal,
            max_iterations: o.max_iterations,
            tolerance: o.tolerance,
        }
    }
}

/// One iterate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Iterate {
    /// `V(c_k)` (smoothed, on the optimisation grid).
    pub volume_fraction: f64,
    /// `A(c_k)` (smoothed, on the optimisation grid).
    pub surface_area: f64,
    /// `‖c_k − c₀‖`.
    pub change: f64,
    /// The smoothing half-width `ε` of `V` (cell units) at this iterate.
    pub smoothing: f64,
}

/// What [`FittedCell::optimize`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct OptimizationReport {
    pub converged: bool,
    /// The volume-fraction target, if any.
    pub target: Option<f64>,
    /// The volume fraction reached: the share of samples with `Φ ≤ 0` on a grid twice as
    /// fine as the optimisation's (not smoothed).
    pub reached: f64,
    /// The surface-area target, if any.
    pub area_target: Option<f64>,
    /// The surface-area density reached, measured sharply on the same grid
    /// ([`super::measure`]).
    pub area_reached: f64,
    /// The starting cell's sharp measures on that grid.
    pub before: CellMeasures,
    /// `‖c − c₀‖` of the result.
    pub change: f64,
    /// Iterate 0 is the starting cell.
    pub iterates: Vec<Iterate>,
}

/// A constrained quantity.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Volume,
    Area,
}

/// The grid of the optimisation for this cell (module docs).
pub(super) fn optimization_grid(cell: &FittedCell) -> usize {
    if cell.group.dimension() == 3 {
        cell.n.clamp(32, OPTIMIZE_GRID_3D)
    } else {
        cell.n.clamp(64, OPTIMIZE_GRID_2D)
    }
}

/// The fixed pieces of one optimisation: grid, element weights, smoothing width.
struct Problem<'a> {
    start: &'a FittedCell,
    /// Grid samples per axis and the result's `n` (holding both bands).
    grid: usize,
    n: usize,
    weights: Vec<f64>,
    weight_sum: f64,
    eps: f64,
    keep_face_normal: bool,
    kinds: Vec<Kind>,
}

impl Problem<'_> {
    /// The constrained values (in the order of `kinds`), `(V, A)` and the grid samples at
    /// `cell`. `V` is smoothed; `A` is the sharp marching area on the optimisation grid when
    /// it is a target (its first variation is the curvature form of the gradient, and it
    /// has neither the smoothed sum's bias nor its grid noise: module docs), the smoothed
    /// `A_ε` otherwise (only reported).
    fn evaluate(&self, cell: &FittedCell) -> Result<Evaluation, FitError> {
        let curvature = self.kinds.contains(&Kind::Area);
        let samples = grid_samples(cell, self.grid, curvature)?;
        let volume = smoothed_volume(&samples, &self.weights, self.eps);
        let area = if curvature {
            sharp_area(cell, self.grid)?
        } else {
            smoothed_area(&samples, &self.weights, self.eps)
        };
        let values = self
            .kinds
            .iter()
            .map(|k| match k {
                Kind::Volume => volume,
                Kind::Area => area,
            })
            .collect();
        Ok(Evaluation {
            values,
            volume,
            area,
            samples,
        })
    }

    /// `P∇F_i` per constraint at the cell whose grid samples are `samples`.
    fn gradients(&self, samples: &GridSamples) -> Result<Vec<Vector>, FitError> {
        self.kinds
            .iter()
            .map(|k| {
                let s = match k {
                    Kind::Volume => {
                        volume_gradient_samples(samples, &self.weights, self.weight_sum, self.eps)
                    }
                    Kind::Area => {
                        area_gradient_samples(samples, &self.weights, self.weight_sum, self.eps)
                    }
                };
                self.band_projection(&s)
            })
            .collect()
    }

    /// The fit of gradient samples, kept to the change band and projected (module docs).
    fn band_projection(&self, samples: &[f64]) -> Result<Vector, FitError> {
        let g = fit_samples(&self.start.group, self.grid, samples)?;
        let smooth = g
            .coefficients
            .into_iter()
            .filter(|c| c.f.iter().all(|v| v.unsigned_abs() <= CHANGE_BAND))
            .collect();
        let g = FittedCell::new_unchecked(g.group, self.n, smooth);
        if !self.keep_face_normal {
            return Ok(Vector::of(&g));
        }
        let (projected, _) = g.constrain_normal_to_faces()?;
        Ok(Vector::of(&projected))
    }
}

/// The Gauss–Newton system `J Jᵀ λ = r` for one or two constraints; `None` when `J Jᵀ` is
/// singular (a zero gradient, or two parallel ones: the targets cannot move independently).
fn solve_gram(g: &[Vector], r: &[f64]) -> Option<Vec<f64>> {
    match g.len() {
        1 => {
            let gg = g[0].dot(&g[0]);
            (gg > 0.0).then(|| vec![r[0] / gg])
        }
        2 => {
            let (a, b, c) = (g[0].dot(&g[0]), g[0].dot(&g[1]), g[1].dot(&g[1]));
            let det = a * c - b * b;
            if det.is_nan() || det <= 1e-10 * a * c {
                return None;
            }
            Some(vec![
                (c * r[0] - b * r[1]) / det,
                (a * r[1] - b * r[0]) / det,
            ])
        }
        _ => None,
    }
}

/// `c + Σ α λ_i g_i`, added one gradient at a time (for one constraint, exactly `c + αλg`).
fn step(c: &Vector, g: &[Vector], lambda: &[f64], alpha: f64) -> Vector {
    g.iter()
        .zip(lambda)
        .fold(c.clone(), |acc, (gi, &l)| acc.combine(1.0, gi, alpha * l))
}

impl FittedCell {
    /// The cell nearest this one (least `‖c − c₀‖`) whose solid fills `options.volume_fraction`
    /// of the reference element (module docs), and the iterations. A run that does not reach
    /// the tolerance is not an error: the report says `converged == false` and what it reached.
    ///
    /// Errors: the constraint projection failed, or the field has no surface in the element.
    pub fn optimize(
        &self,
        options: &Optimization,
    ) -> Result<(FittedCell, OptimizationReport), FitError> {
        self.optimize_for(&OptimizationTargets::from(options))
    }

    /// As [`optimize`](Self::optimize), for a volume fraction, a surface-area density or both
    /// (module docs). With neither, the cell is returned unchanged, converged.
    pub fn optimize_for(
        &self,
        options: &OptimizationTargets,
    ) -> Result<(FittedCell, OptimizationReport), FitError> {
        let grid = optimization_grid(self);
        let weights = element_weights(self, grid);
        let weight_sum: f64 = weights.iter().sum();
        let phi0 = self.grid(grid)?;
        let signs = phi0
            .iter()
            .zip(&weights)
            .filter(|(_, w)| **w > 0.0)
            .fold((false, false), |(neg, pos), (&v, _)| {
                (neg || v <= 0.0, pos || v > 0.0)
            });
        if signs != (true, true) {
            return Err(FitError::Vanishes {
                side: super::fit::Side::Zero,
            });
        }
        let mut kinds = Vec::new();
        let mut targets = Vec::new();
        let mut scales = Vec::new();
        if let Some(v) = options.volume_fraction {
            kinds.push(Kind::Volume);
            targets.push(v);
            scales.push(1.0);
        }
        if let Some(a) = options.surface_area {
            kinds.push(Kind::Area);
            targets.push(a);
            scales.push(a);
        }
        let sharp_grid = 2 * grid;
        let before = CellMeasures {
            volume_fraction: sharp_fraction(self, sharp_grid)?,
            surface_area: sharp_area(self, sharp_grid)?,
        };
        let mut problem = Problem {
            start: self,
            grid,
            n: self.n.max(grid),
            weights,
            weight_sum,
            eps: 0.0,
            keep_face_normal: options.keep_face_normal,
            kinds: kinds.clone(),
        };
        let c0 = Vector::of(self);
        let mut state = State {
            cell: self.clone(),
            c: c0.clone(),
            at: None,
        };
        let mut iterates = Vec::new();
        let mut met = true;
        // Continuation in ε: each band twice the next, the last the final one (module docs).
        let final_band = BAND_CELLS / grid as f64;
        let stages = (0..)
            .take_while(|&k| final_band * f64::from(1u32 << k) <= MAX_BAND)
            .count()
            .max(1);
        let mut walk = Walk {
            problem: &mut problem,
            c0: &c0,
            targets: targets.clone(),
            scales: &scales,
            budget: options.max_iterations,
            iterates: &mut iterates,
        };
        for stage in (0..stages).rev() {
            let band = final_band * f64::from(1u32 << stage);
            walk.problem.eps = band;
            state.at = Some(walk.problem.evaluate(&state.cell)?);
            if walk.iterates.is_empty() {
                walk.record(&state);
            }
            // Earlier stages only bring the cell near: their ε biases V anyway.
            let tolerance = if stage == 0 {
                options.tolerance
            } else {
                options.tolerance.max(STAGE_TOLERANCE)
            };
            met = walk.restore(&mut state, tolerance)?;
        }
        let mut converged = met && walk.least_change(&mut state, options.tolerance)?;
        // Defect correction: the smoothed values are biased by about ε² times curvatures;
        // aim the smoothed targets off by the sharp measures' differences (module docs).
        let sharp = |cell: &FittedCell, kind: Kind| match kind {
            Kind::Volume => sharp_fraction(cell, sharp_grid),
            Kind::Area => sharp_area(cell, sharp_grid),
        };
        let close = |reached: &[f64]| {
            reached
                .iter()
                .zip(&targets)
                .zip(&scales)
                .all(|((r, t), s)| (r - t).abs() / s <= SHARP_TOLERANCE_FACTOR * options.tolerance)
        };
        let mut reached = kinds
            .iter()
            .map(|&k| sharp(&state.cell, k))
            .collect::<Result<Vec<_>, _>>()?;
        for _ in 0..CORRECTIONS {
            if close(&reached) {
                break;
            }
            for (i, r) in reached.iter().enumerate() {
                walk.targets[i] += targets[i] - r;
            }
            converged = walk.restore(&mut state, options.tolerance)?;
            reached = kinds
                .iter()
                .map(|&k| sharp(&state.cell, k))
                .collect::<Result<Vec<_>, _>>()?;
        }
        converged &= close(&reached);
        let change = state.c.combine(1.0, &c0, -1.0).norm();
        let of = |kind: Kind| kinds.iter().position(|&k| k == kind).map(|i| reached[i]);
        let volume_reached = match of(Kind::Volume) {
            Some(v) => v,
            None => sharp_fraction(&state.cell, sharp_grid)?,
        };
        let area_reached = match of(Kind::Area) {
            Some(a) => a,
            None => sharp_area(&state.cell, sharp_grid)?,
        };
        Ok((
            state.cell,
            OptimizationReport {
                converged,
                target: options.volume_fraction,
                reached: volume_reached,
                area_target: options.surface_area,
                area_reached,
                before,
                change,
                iterates,
            },
        ))
    }
}

/// The smoothed values and grid samples of one cell.
struct Evaluation {
    /// Per constraint, in the problem's order.
    values: Vec<f64>,
    volume: f64,
    area: f64,
    samples: GridSamples,
}

/// The current iterate: coefficients, cell and its evaluation (`None` before the first).
struct State {
    cell: FittedCell,
    c: Vector,
    at: Option<Evaluation>,
}

impl State {
    fn values(&self) -> &[f64] {
        self.at.as_ref().map_or(&[], |e| &e.values)
    }
}

/// The two kinds of steps and what they share.
struct Walk<'p, 'a> {
    problem: &'p mut Problem<'a>,
    c0: &'p Vector,
    /// The smoothed targets (moved by the sharp correction).
    targets: Vec<f64>,
    /// What each residual is measured against: 1 for the volume fraction, the target for the
    /// area (a relative tolerance).
    scales: &'p [f64],
    /// Steps left.
    budget: usize,
    iterates: &'p mut Vec<Iterate>,
}

impl Walk<'_, '_> {
    fn change(&self, c: &Vector) -> f64 {
        c.combine(1.0, self.c0, -1.0).norm()
    }

    fn record(&mut self, state: &State) {
        let change = self.change(&state.c);
        let (volume, area) = state.at.as_ref().map_or((0.0, 0.0), |e| (e.volume, e.area));
        self.iterates.push(Iterate {
            volume_fraction: volume,
            surface_area: area,
            change,
            smoothing: self.problem.eps,
        });
    }

    fn evaluate(&self, c: Vector) -> Result<State, FitError> {
        let cell = c.cell(self.problem.start, self.problem.n);
        let at = Some(self.problem.evaluate(&cell)?);
        Ok(State { cell, c, at })
    }

    /// `targets − values`, unscaled.
    fn residuals(&self, values: &[f64]) -> Vec<f64> {
        self.targets
            .iter()
            .zip(values)
            .map(|(t, v)| t - v)
            .collect()
    }

    /// The size of the scaled residual: `|r|` for one constraint, its Euclidean norm for more.
    fn merit(&self, values: &[f64]) -> f64 {
        let scaled = values
            .iter()
            .zip(&self.targets)
            .zip(self.scales)
            .map(|((v, t), s)| (v - t).abs() / s);
        if values.len() == 1 {
            scaled.sum()
        } else {
            scaled.map(|r| r * r).sum::<f64>().sqrt()
        }
    }

    fn within(&self, values: &[f64], tolerance: f64) -> bool {
        values
            .iter()
            .zip(&self.targets)
            .zip(self.scales)
            .all(|((v, t), s)| (v - t).abs() / s <= tolerance)
    }

    /// Gauss–Newton steps on the constraints along the projected gradients,
    /// `c + Σ λ_i g_i` with `J Jᵀ λ = r`, halved until the residual shrinks, until within
    /// `tolerance`. Each step adds band-limited bumps at the current surface, so the surface
    /// moves along its normal. False when the budget ran out or no step helped.
    fn restore(&mut self, state: &mut State, tolerance: f64) -> Result<bool, FitError> {
        while !self.within(state.values(), tolerance) {
            if self.budget == 0 {
                return Ok(false);
            }
            let Some(at) = &state.at else {
                return Ok(false);
            };
            let g = self.problem.gradients(&at.samples)?;
            let Some(lambda) = solve_gram(&g, &self.residuals(&at.values)) else {
                return Ok(false);
            };
            let before = self.merit(&at.values);
            let mut accepted = None;
            let mut alpha = 1.0;
            for _ in 0..=LINE_SEARCH_HALVINGS {
                let trial = self.evaluate(step(&state.c, &g, &lambda, alpha))?;
                if self.merit(trial.values()) < (1.0 - 0.25 * alpha) * before {
                    accepted = Some(trial);
                    break;
                }
                alpha *= 0.5;
            }
            let Some(next) = accepted else {
                return Ok(false);
            };
            *state = next;
            self.budget -= 1;
            self.record(state);
        }
        Ok(true)
    }

    /// From a point meeting the targets, steps towards the point of the linearised
    /// constraints nearest `c₀` (`c₀ + Jᵀμ`), each followed by restoration, kept only when
    /// `‖c − c₀‖` shrinks and the targets still hold; stops when it shrinks by less than
    /// [`LEAST_CHANGE_STALL`] of itself or no step shrinks it (true), or the budget runs out
    /// (false).
    fn least_change(&mut self, state: &mut State, tolerance: f64) -> Result<bool, FitError> {
        loop {
            if self.budget == 0 {
                return Ok(false);
            }
            let Some(at) = &state.at else {
                return Ok(false);
            };
            let g = self.problem.gradients(&at.samples)?;
            let to_start = self.c0.combine(1.0, &state.c, -1.0);
            let rhs: Vec<f64> = self
                .residuals(&at.values)
                .iter()
                .zip(&g)
                .map(|(r, gi)| r - gi.dot(&to_start))
                .collect();
            let Some(mu) = solve_gram(&g, &rhs) else {
                return Ok(true);
            };
            let toward = step(self.c0, &g, &mu, 1.0).combine(1.0, &state.c, -1.0);
            let now = self.change(&state.c);
            let mut alpha = 1.0;
            let mut improved = None;
            for _ in 0..LEAST_CHANGE_HALVINGS {
                let mut trial = self.evaluate(state.c.combine(1.0, &toward, alpha))?;
                if self.restore_quietly(&mut trial, tolerance)? && self.change(&trial.c) < now {
                    improved = Some(trial);
                    break;
                }
                alpha *= 0.5;
            }
            let Some(next) = improved else {
                return Ok(true);
            };
            let after = self.change(&next.c);
            *state = next;
            self.budget -= 1;
            self.record(state);
            if now - after <= LEAST_CHANGE_STALL * now {
                return Ok(true);
            }
        }
    }

    /// [`Walk::restore`] within [`RESTORE_STEPS`], its steps not recorded (a trial of
    /// `least_change`).
    fn restore_quietly(&mut self, state: &mut State, tolerance: f64) -> Result<bool, FitError> {
        let (len, budget) = (self.iterates.len(), self.budget);
        self.budget = RESTORE_STEPS;
        let met = self.restore(state, tolerance);
        self.iterates.truncate(len);
        self.budget = budget;
        met
    }
}
