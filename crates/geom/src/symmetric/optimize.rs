//! Coefficient optimisation (docs/method.md §Coefficient optimisation, §Surface area): the
//! cell closest to a fitted one, in the basis's L² norm, whose solid `{Φ ≤ 0}` fills a target
//! volume fraction of its reference element and/or whose surface has a target area density.
//!
//! Surface area (the volume-only path below is unchanged, to the bit): the constraint value
//! is the sharp marching area on the optimisation grid ([`super::measure`]), its gradient the
//! curvature form `−w δ_ε(d) κ/|∇Φ|` fitted like the volume's (`objective.rs`); with both
//! targets restoration takes trust-region steps in the plane of two smoothed gradient
//! directions with a measured 2×2 Jacobian ([`Walk::plane_step`]: the gradients are nearly
//! parallel and the area strongly convex across them), and least change goes to `c₀ + Jᵀμ`;
//! residuals are scaled (`|V − V*|`, `|A − A*|/A*`).
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
//! - Stop: the least-change walk ends when its steps gain less than 10⁻³ of `‖c − c₀‖`.
//!   `converged` means the targets are met as measured independently: the sharp measures on
//!   the grid twice as fine within 10 × `tolerance` (not how the coarse-grid restorations
//!   ended). A restoration that stalls (no step helps, or two steps take less than
//!   [`STALL_PROGRESS`] off the residual) ends the run at once, `stalled` in the report: an
//!   unreachable target stops in a few steps instead of spending `max_iterations`.
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

/// Restoration stalls when two accepted steps together take less than this share off the
/// scaled residual (an unreachable target: the run stops instead of spending its budget).
const STALL_PROGRESS: f64 = 0.1;

/// Two constraints: the trust radius (and so the forward-difference probes of the Jacobian
/// in the gradients' plane) stays at least [`PROBE`] in `‖c‖` (fields of order one; below it
/// the sharp area's kinks would show), and gradients whose difference is less than
/// [`PARALLEL`] of their length count as parallel.
const PROBE: f64 = 1e-3;
const PARALLEL: f64 = 1e-3;

/// The trust radius of two-constraint steps in `‖c‖`: where it starts and its largest.
const START_RADIUS: f64 = 0.05;

/// The squared frequency at which [`Problem::smoothed`] halves a coefficient.
const SMOOTHING: f64 = 4.0;
const MAX_RADIUS: f64 = 0.2;

/// How a restoration ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Outcome {
    /// Within the tolerance (or stalled within ten times it).
    Met,
    /// The budget of steps ran out.
    Budget,
    /// No step helps or the residual stopped shrinking: the target is out of reach from here.
    Stalled,
}

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
    /// The targets are met: the sharp measures on the grid twice as fine are within ten
    /// times the tolerance.
    pub converged: bool,
    /// Not converged because the residual stopped shrinking (an unreachable target), rather
    /// than because the budget ran out.
    pub stalled: bool,
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

    /// `v` with each frequency's coefficient scaled by `1/(1 + |f|²/SMOOTHING)`, projected
    /// again when the face-normal condition is kept (the scaling differs along a row's line
    /// of frequencies): a direction that bends the surface less (module docs).
    fn smoothed(&self, v: &Vector) -> Result<Vector, FitError> {
        let scaled = Vector(
            v.0.iter()
                .map(|&(f, c)| {
                    let f2: f64 = f.iter().map(|&a| f64::from(a * a)).sum();
                    (f, c / (1.0 + f2 / SMOOTHING))
                })
                .collect(),
        );
        if !self.keep_face_normal {
            return Ok(scaled);
        }
        let (projected, _) = scaled
            .cell(self.start, self.n)
            .constrain_normal_to_faces()?;
        Ok(Vector::of(&projected))
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

/// The 2×2 system `m x = r`; `None` when `m` is singular relative to its entries.
fn solve2(m: [[f64; 2]; 2], r: &[f64]) -> Option<[f64; 2]> {
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let size = (m[0][0] * m[1][1]).abs().max((m[0][1] * m[1][0]).abs());
    if !det.is_finite() || det.abs() <= 1e-10 * size || size == 0.0 {
        return None;
    }
    Some([
        (m[1][1] * r[0] - m[0][1] * r[1]) / det,
        (m[0][0] * r[1] - m[1][0] * r[0]) / det,
    ])
}

/// The minimiser of `‖r − m a‖` over `‖a‖ ≤ radius`: the Newton step when it fits, else the
/// Levenberg–Marquardt step `(mᵀm + μ) a = mᵀ r` whose length is the radius (μ by bisection
/// on its logarithm; the length falls as μ grows).
fn trust_region_step(m: [[f64; 2]; 2], r: [f64; 2], radius: f64) -> [f64; 2] {
    if let Some(a) = solve2(m, &r)
        && a[0].hypot(a[1]) <= radius
    {
        return a;
    }
    let mtm = [
        [
            m[0][0] * m[0][0] + m[1][0] * m[1][0],
            m[0][0] * m[0][1] + m[1][0] * m[1][1],
        ],
        [
            m[0][1] * m[0][0] + m[1][1] * m[1][0],
            m[0][1] * m[0][1] + m[1][1] * m[1][1],
        ],
    ];
    let mtr = [
        m[0][0] * r[0] + m[1][0] * r[1],
        m[0][1] * r[0] + m[1][1] * r[1],
    ];
    let size = mtm[0][0] + mtm[1][1];
    let at = |mu: f64| {
        let shifted = [[mtm[0][0] + mu, mtm[0][1]], [mtm[1][0], mtm[1][1] + mu]];
        solve2(shifted, &mtr).unwrap_or([0.0, 0.0])
    };
    let (mut lo, mut hi) = ((1e-12 * size).ln(), (1e12 * size).ln());
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        let a = at(mid.exp());
        if a[0].hypot(a[1]) > radius {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    at(hi.exp())
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
        let mut outcome = Outcome::Met;
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
            radius: START_RADIUS,
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
            outcome = walk.restore(&mut state, tolerance)?;
            if outcome == Outcome::Stalled {
                // Out of reach: stop here rather than spend the budget (module docs).
                break;
            }
        }
        if outcome == Outcome::Met {
            walk.least_change(&mut state, options.tolerance)?;
        }
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
        if outcome != Outcome::Stalled {
            // Per constraint, the last smoothed target and the sharp value it gave: after the
            // first correction the next target is a secant step (with two constraints the
            // bias changes as the shape does, and the plain shift oscillates; measured).
            let mut last: Vec<Option<(f64, f64)>> = vec![None; kinds.len()];
            for _ in 0..CORRECTIONS {
                if close(&reached) {
                    break;
                }
                for (i, r) in reached.iter().enumerate() {
                    let slope = match last[i] {
                        Some((t, v)) if (r - v).abs() > 0.0 => {
                            ((walk.targets[i] - t) / (r - v)).clamp(0.5, 2.0)
                        }
                        _ => 1.0,
                    };
                    last[i] = Some((walk.targets[i], *r));
                    walk.targets[i] += slope * (targets[i] - r);
                }
                outcome = walk.restore(&mut state, options.tolerance)?;
                reached = kinds
                    .iter()
                    .map(|&k| sharp(&state.cell, k))
                    .collect::<Result<Vec<_>, _>>()?;
                if outcome != Outcome::Met {
                    break;
                }
            }
        }
        // Converged means what it says: the targets met, measured on the finer grid; how the
        // restorations on the optimisation grid ended does not decide it.
        let converged = close(&reached);
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
                stalled: !converged && outcome == Outcome::Stalled,
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
    /// The trust radius of two-constraint steps ([`Walk::plane_step`]).
    radius: f64,
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

    /// Newton steps on the constraints, halved until the scaled residual shrinks, until within
    /// `tolerance` (module docs: one constraint, Gauss–Newton along its projected gradient;
    /// two, Newton in the plane of the gradients with a measured 2×2 Jacobian). Each step
    /// adds band-limited bumps at the current surface, so the surface moves along its normal.
    /// Stops with [`Outcome::Budget`] when the budget ran out, and [`Outcome::Stalled`] when
    /// no step helps, the Jacobian is singular, or two steps together took less than
    /// [`STALL_PROGRESS`] off the residual; a stall within [`SHARP_TOLERANCE_FACTOR`] times
    /// `tolerance` counts as met (the sharp area's kinks on a coarse grid can hold the last
    /// digits back; the final check is the finer grid's).
    fn restore(&mut self, state: &mut State, tolerance: f64) -> Result<Outcome, FitError> {
        let mut merits = vec![self.merit(state.values())];
        let stalled = |walk: &Self, state: &State| {
            if walk.within(state.values(), SHARP_TOLERANCE_FACTOR * tolerance) {
                Outcome::Met
            } else {
                Outcome::Stalled
            }
        };
        while !self.within(state.values(), tolerance) {
            if self.budget == 0 {
                return Ok(Outcome::Budget);
            }
            let Some(at) = &state.at else {
                return Ok(Outcome::Stalled);
            };
            let g = self.problem.gradients(&at.samples)?;
            let r = self.residuals(&at.values);
            let next = if g.len() == 2 {
                self.plane_step(state, &g, &r)?
            } else {
                self.line_search(state, g, &r)?
            };
            let Some(next) = next else {
                return Ok(stalled(self, state));
            };
            *state = next;
            self.budget -= 1;
            self.record(state);
            merits.push(self.merit(state.values()));
            let k = merits.len();
            if k >= 3
                && merits[k - 1] > (1.0 - STALL_PROGRESS) * merits[k - 3]
                && !self.within(state.values(), tolerance)
            {
                return Ok(stalled(self, state));
            }
        }
        Ok(Outcome::Met)
    }

    /// One constraint (or more than two): the Gauss–Newton step `c + α Σ λ_i g_i` with
    /// `J Jᵀ λ = r`, `α` halved until the scaled residual shrinks; `None` when `J Jᵀ` is
    /// singular or no `α` helps.
    fn line_search(
        &self,
        state: &State,
        g: Vec<Vector>,
        r: &[f64],
    ) -> Result<Option<State>, FitError> {
        let Some(lambda) = solve_gram(&g, r) else {
            return Ok(None);
        };
        let before = self.merit(state.values());
        let mut alpha = 1.0;
        for _ in 0..=LINE_SEARCH_HALVINGS {
            let trial = self.evaluate(step(&state.c, &g, &lambda, alpha))?;
            if self.merit(trial.values()) < (1.0 - 0.25 * alpha) * before {
                return Ok(Some(trial));
            }
            alpha *= 0.5;
        }
        Ok(None)
    }

    /// Two constraints: a trust-region step in the plane of the two projected gradients;
    /// `None` when they are parallel or no radius down to [`PROBE`] helps.
    ///
    /// Why: the gradients are nearly parallel (cosines of 0.9 to 0.98 measured for an Oh
    /// cell), so the step that moves one target and not the other is their small difference,
    /// which the gradients' errors decide (tens of per cent for the volume's, which holds
    /// `|∇Φ|` fixed), and along which the area is strongly convex (measured: its secant slope
    /// changes sign within 0.05 of `‖c‖`). So the plane `u₁ ∥ g_V`, `u₂ ⟂ u₁` is kept, but the
    /// 2×2 Jacobian `∂F_i/∂u_j` is measured by forward differences over the trust radius `Δ`
    /// (secants at the scale of the step), the step minimises the scaled linear model within
    /// `‖a‖ ≤ Δ` (Levenberg–Marquardt), and `Δ` doubles after a good step and halves after a
    /// poor one. Each step re-linearises both constraints.
    fn plane_step(
        &mut self,
        state: &State,
        g: &[Vector],
        r: &[f64],
    ) -> Result<Option<State>, FitError> {
        let unit = |v: &Vector| {
            let n = v.norm();
            (n.is_finite() && n > 0.0).then(|| v.combine(1.0 / n, &Vector::default(), 0.0))
        };
        // Smooth directions: the gradients in a Sobolev-like metric (module docs).
        let smooth = [self.problem.smoothed(&g[0])?, self.problem.smoothed(&g[1])?];
        let (vv, va) = (g[0].dot(&smooth[0]), g[0].dot(&smooth[1]));
        if vv.is_nan() || vv <= 0.0 {
            return Ok(None);
        }
        // The area's descent that keeps the volume to first order: `g_V · across = 0`.
        let across = smooth[1].combine(1.0, &smooth[0], -va / vv);
        if across.norm() <= PARALLEL * smooth[1].norm() {
            return Ok(None);
        }
        let (Some(u1), Some(u2)) = (unit(&smooth[0]), unit(&across)) else {
            return Ok(None);
        };
        let u = [u1, u2];
        let scale = [self.scales[0], self.scales[1]];
        let rs = [r[0] / scale[0], r[1] / scale[1]];
        // The gradients' guess at the direction of each component (the probes' signs).
        let predicted = [
            [g[0].dot(&u[0]) / scale[0], g[0].dot(&u[1]) / scale[0]],
            [g[1].dot(&u[0]) / scale[1], g[1].dot(&u[1]) / scale[1]],
        ];
        let guess = solve2(predicted, &rs).unwrap_or([1.0, 1.0]);
        let base = state.values().to_vec();
        let before = self.merit(&base);
        while self.radius >= PROBE {
            let radius = self.radius;
            let mut m = [[0.0; 2]; 2];
            for j in 0..2 {
                let h = radius.copysign(guess[j]);
                let probe = self.evaluate(state.c.combine(1.0, &u[j], h))?;
                for i in 0..2 {
                    m[i][j] = (probe.values()[i] - base[i]) / h / scale[i];
                }
            }
            let a = trust_region_step(m, rs, radius);
            let model = [
                rs[0] - m[0][0] * a[0] - m[0][1] * a[1],
                rs[1] - m[1][0] * a[0] - m[1][1] * a[1],
            ];
            let predicted_gain = before - model[0].hypot(model[1]);
            let trial = self.evaluate(step(&state.c, &u, &a, 1.0))?;
            let gain = before - self.merit(trial.values());
            if predicted_gain > 0.0 && gain >= 0.1 * predicted_gain {
                if gain >= 0.75 * predicted_gain && a[0].hypot(a[1]) >= 0.99 * radius {
                    self.radius = (2.0 * radius).min(MAX_RADIUS);
                }
                return Ok(Some(trial));
            }
            self.radius = 0.5 * radius;
        }
        // Leave the next restoration a radius to start from.
        self.radius = PROBE;
        Ok(None)
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
        Ok(met? == Outcome::Met)
    }
}
