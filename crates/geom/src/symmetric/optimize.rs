//! Coefficient optimisation (docs/method.md §Coefficient optimisation): the cell closest to a
//! fitted one, in the basis's L² norm, whose solid `{Φ ≤ 0}` fills a target volume fraction
//! of its reference element.
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

use rustfft::num_complex::Complex64;

use super::fit::{Coefficient, FitError, FittedCell, fit_samples};
use super::group::ReferenceElement;
use crate::contour2d::Element2;
use crate::element::Element3;

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

/// What to optimise for.
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

/// One iterate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Iterate {
    /// `V(c_k)` (smoothed, on the optimisation grid).
    pub volume_fraction: f64,
    /// `‖c_k − c₀‖`.
    pub change: f64,
    /// The smoothing half-width `ε` of `V` (cell units) at this iterate.
    pub smoothing: f64,
}

/// What [`FittedCell::optimize`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct OptimizationReport {
    pub converged: bool,
    pub target: f64,
    /// The volume fraction reached: the share of samples with `Φ ≤ 0` on a grid twice as
    /// fine as the optimisation's (not smoothed).
    pub reached: f64,
    /// `‖c − c₀‖` of the result.
    pub change: f64,
    /// Iterate 0 is the starting cell.
    pub iterates: Vec<Iterate>,
}

/// Coefficients by frequency, sorted; the vector space the optimisation walks in.
#[derive(Clone, Debug, Default)]
struct Vector(Vec<([i32; 3], Complex64)>);

impl Vector {
    fn of(cell: &FittedCell) -> Vector {
        Vector(cell.coefficients.iter().map(|c| (c.f, c.c)).collect())
    }

    /// `a·self + b·other`, over the union of frequencies.
    fn combine(&self, a: f64, other: &Vector, b: f64) -> Vector {
        let (x, y) = (&self.0, &other.0);
        let (mut i, mut j) = (0, 0);
        let mut out = Vec::with_capacity(x.len().max(y.len()));
        while i < x.len() || j < y.len() {
            let take_x = j == y.len() || (i < x.len() && x[i].0 <= y[j].0);
            let take_y = i == x.len() || (j < y.len() && y[j].0 <= x[i].0);
            let f = if take_x { x[i].0 } else { y[j].0 };
            let mut v = Complex64::new(0.0, 0.0);
            if take_x {
                v += x[i].1 * a;
                i += 1;
            }
            if take_y {
                v += y[j].1 * b;
                j += 1;
            }
            out.push((f, v));
        }
        Vector(out)
    }

    /// The real inner product `Re Σ conj(a_f) b_f`.
    fn dot(&self, other: &Vector) -> f64 {
        let (x, y) = (&self.0, &other.0);
        let (mut i, mut j, mut sum) = (0, 0, 0.0);
        while i < x.len() && j < y.len() {
            match x[i].0.cmp(&y[j].0) {
                std::cmp::Ordering::Less => i += 1,
                std::cmp::Ordering::Greater => j += 1,
                std::cmp::Ordering::Equal => {
                    sum += (x[i].1.conj() * y[j].1).re;
                    i += 1;
                    j += 1;
                }
            }
        }
        sum
    }

    fn norm(&self) -> f64 {
        self.0.iter().map(|e| e.1.norm_sqr()).sum::<f64>().sqrt()
    }

    fn cell(&self, like: &FittedCell, n: usize) -> FittedCell {
        let group = &like.group;
        let cs = self
            .0
            .iter()
            .map(|&(f, c)| Coefficient {
                f,
                c,
                k_f: group.normalization(f),
            })
            .collect();
        FittedCell::new_unchecked(group.clone(), n, cs)
    }
}

/// The smoothed Heaviside and its derivative (module docs).
fn heaviside(t: f64, eps: f64) -> (f64, f64) {
    use std::f64::consts::PI;
    if t <= -eps {
        (0.0, 0.0)
    } else if t >= eps {
        (1.0, 0.0)
    } else {
        let a = PI * t / eps;
        (
            0.5 * (1.0 + t / eps + a.sin() / PI),
            (1.0 + a.cos()) / (2.0 * eps),
        )
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
}

impl Problem<'_> {
    /// `V(c)` and `(Φ/|∇Φ|, |∇Φ|)` at the grid points.
    fn volume(&self, cell: &FittedCell) -> Result<(f64, Vec<(f64, f64)>), FitError> {
        let phi = distances(cell, self.grid)?;
        let v: f64 = phi
            .iter()
            .zip(&self.weights)
            .map(|(&(h, _), &w)| w * heaviside(-h, self.eps).0)
            .sum();
        Ok((v / self.weight_sum, phi))
    }

    /// `P∇V` at the cell whose distances are `phi` (`|∇Φ|` held fixed: Gauss–Newton).
    fn gradient(&self, phi: &[(f64, f64)]) -> Result<Vector, FitError> {
        let m = phi.len() as f64;
        let samples: Vec<f64> = phi
            .iter()
            .zip(&self.weights)
            .map(|(&(h, g), &w)| -w * heaviside(-h, self.eps).1 / g * m / self.weight_sum)
            .collect();
        let g = fit_samples(&self.start.group, self.grid, &samples)?;
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

/// Indicator of the group's reference element at the domain grid's points (½ on its
/// boundary); all ones where the element is the domain or there is none.
fn element_weights(cell: &FittedCell, grid: usize) -> Vec<f64> {
    let group = &cell.group;
    let d = group.dimension();
    let m = grid.pow(d as u32);
    let inside: Option<Box<dyn Fn([f64; 3]) -> f64>> = match group.reference_element() {
        Some(ReferenceElement::Tetrahedron) => {
            Some(Box::new(|x| Element3::Tetrahedron.signed_distance(x)))
        }
        Some(ReferenceElement::Triangle) => Some(Box::new(|x| {
            Element2::Triangle.signed_distance([x[0], x[1]])
        })),
        _ => None,
    };
    let Some(inside) = inside else {
        return vec![1.0; m];
    };
    let domain = group.domain();
    let (origin, frame) = (domain.origin(), domain.frame());
    let tiny = 1e-9;
    (0..m)
        .map(|p| {
            let idx = [p % grid, (p / grid) % grid, p / (grid * grid)];
            let s: [f64; 3] = std::array::from_fn(|a| {
                if a < d {
                    origin[a] + idx[a] as f64 / grid as f64
                } else {
                    0.0
                }
            });
            let sd = inside(frame.to_cartesian(s));
            if sd < -tiny {
                1.0
            } else if sd <= tiny {
                0.5
            } else {
                0.0
            }
        })
        .collect()
}

/// `(Φ/|∇Φ|, |∇Φ|)` on the domain grid: the first-order distance to the surface (cell units)
/// with the gradient by central differences (Cartesian, through the frame).
fn distances(cell: &FittedCell, grid: usize) -> Result<Vec<(f64, f64)>, FitError> {
    let phi = cell.grid(grid)?;
    let d = cell.group.dimension();
    let frame = cell.group.domain().frame();
    let strides = [1, grid, grid * grid];
    let half_step = 0.5 * grid as f64;
    let scale = phi.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    Ok((0..phi.len())
        .map(|p| {
            let idx = [p % grid, (p / grid) % grid, p / (grid * grid)];
            let gs: [f64; 3] = std::array::from_fn(|a| {
                if a >= d {
                    return 0.0;
                }
                let up = p - idx[a] * strides[a] + (idx[a] + 1) % grid * strides[a];
                let down = p - idx[a] * strides[a] + (idx[a] + grid - 1) % grid * strides[a];
                (phi[up] - phi[down]) * half_step
            });
            let g = frame.gradient_to_cartesian(gs);
            let norm = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
                .sqrt()
                .max(1e-12 * scale);
            (phi[p] / norm, norm)
        })
        .collect())
}

/// The weighted share of the domain grid's samples with `Φ ≤ 0`.
fn sharp_fraction(cell: &FittedCell, grid: usize) -> Result<f64, FitError> {
    let weights = element_weights(cell, grid);
    let phi = cell.grid(grid)?;
    let inside: f64 = phi
        .iter()
        .zip(&weights)
        .filter(|(v, _)| **v <= 0.0)
        .map(|(_, w)| w)
        .sum();
    Ok(inside / weights.iter().sum::<f64>())
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
        let d = self.group.dimension();
        let grid = if d == 3 {
            self.n.clamp(32, OPTIMIZE_GRID_3D)
        } else {
            self.n.clamp(64, OPTIMIZE_GRID_2D)
        };
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
        let mut problem = Problem {
            start: self,
            grid,
            n: self.n.max(grid),
            weights,
            weight_sum,
            eps: 0.0,
            keep_face_normal: options.keep_face_normal,
        };
        let target = options.volume_fraction;
        let c0 = Vector::of(self);
        let mut state = State {
            cell: self.clone(),
            c: c0.clone(),
            v: 0.0,
            phi: Vec::new(),
        };
        let mut iterates = Vec::new();
        let mut met = false;
        // Continuation in ε: each band twice the next, the last the final one (module docs).
        let final_band = BAND_CELLS / grid as f64;
        let stages = (0..)
            .take_while(|&k| final_band * f64::from(1u32 << k) <= MAX_BAND)
            .count()
            .max(1);
        let mut walk = Walk {
            problem: &mut problem,
            c0: &c0,
            target,
            budget: options.max_iterations,
            iterates: &mut iterates,
        };
        for stage in (0..stages).rev() {
            let band = final_band * f64::from(1u32 << stage);
            walk.problem.eps = band;
            (state.v, state.phi) = walk.problem.volume(&state.cell)?;
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
        // Defect correction: the smoothed V is biased by about ε² times the mean curvature;
        // aim the smoothed target off by the sharp count's difference (module docs).
        let sharp_grid = 2 * grid;
        let mut reached = sharp_fraction(&state.cell, sharp_grid)?;
        for _ in 0..CORRECTIONS {
            if (reached - target).abs() <= SHARP_TOLERANCE_FACTOR * options.tolerance {
                break;
            }
            walk.target += target - reached;
            converged = walk.restore(&mut state, options.tolerance)?;
            reached = sharp_fraction(&state.cell, sharp_grid)?;
        }
        converged &= (reached - target).abs() <= SHARP_TOLERANCE_FACTOR * options.tolerance;
        let change = state.c.combine(1.0, &c0, -1.0).norm();
        Ok((
            state.cell,
            OptimizationReport {
                converged,
                target,
                reached,
                change,
                iterates,
            },
        ))
    }
}

/// The current iterate: coefficients, cell, `V` and grid values.
struct State {
    cell: FittedCell,
    c: Vector,
    v: f64,
    phi: Vec<(f64, f64)>,
}

/// The two kinds of steps and what they share.
struct Walk<'p, 'a> {
    problem: &'p mut Problem<'a>,
    c0: &'p Vector,
    target: f64,
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
        self.iterates.push(Iterate {
            volume_fraction: state.v,
            change,
            smoothing: self.problem.eps,
        });
    }

    fn evaluate(&self, c: Vector) -> Result<State, FitError> {
        let cell = c.cell(self.problem.start, self.problem.n);
        let (v, phi) = self.problem.volume(&cell)?;
        Ok(State { cell, c, v, phi })
    }

    /// Newton steps on `V` along the projected gradient, `c + t g` with
    /// `t = (V* − V)/‖g‖²`, halved until `|V − V*|` shrinks, until within `tolerance`.
    /// Each step adds a band-limited bump at the current surface, so the surface moves
    /// along its normal. False when the budget ran out or no step helped.
    fn restore(&mut self, state: &mut State, tolerance: f64) -> Result<bool, FitError> {
        while (state.v - self.target).abs() > tolerance {
            if self.budget == 0 {
                return Ok(false);
            }
            let g = self.problem.gradient(&state.phi)?;
            let gg = g.dot(&g);
            if gg <= 0.0 {
                return Ok(false);
            }
            let t = (self.target - state.v) / gg;
            let before = (state.v - self.target).abs();
            let mut accepted = None;
            let mut alpha = 1.0;
            for _ in 0..=LINE_SEARCH_HALVINGS {
                let trial = self.evaluate(state.c.combine(1.0, &g, alpha * t))?;
                if (trial.v - self.target).abs() < (1.0 - 0.25 * alpha) * before {
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

    /// From a point meeting the target, steps towards the point of the linearised constraint
    /// nearest `c₀` (`c₀ + μ g`), each followed by restoration, kept only when `‖c − c₀‖`
    /// shrinks and the target still holds; stops when it shrinks by less than
    /// [`LEAST_CHANGE_STALL`] of itself or no step shrinks it (true), or the budget runs out
    /// (false).
    fn least_change(&mut self, state: &mut State, tolerance: f64) -> Result<bool, FitError> {
        loop {
            if self.budget == 0 {
                return Ok(false);
            }
            let g = self.problem.gradient(&state.phi)?;
            let gg = g.dot(&g);
            if gg <= 0.0 {
                return Ok(true);
            }
            let to_start = self.c0.combine(1.0, &state.c, -1.0);
            let mu = (self.target - state.v - g.dot(&to_start)) / gg;
            let step = self.c0.combine(1.0, &g, mu).combine(1.0, &state.c, -1.0);
            let now = self.change(&state.c);
            let mut alpha = 1.0;
            let mut improved = None;
            for _ in 0..LEAST_CHANGE_HALVINGS {
                let mut trial = self.evaluate(state.c.combine(1.0, &step, alpha))?;
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
