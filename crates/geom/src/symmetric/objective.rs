//! The smoothed functionals of coefficient optimisation on the domain grid (docs/method.md
//! §Coefficient optimisation, §Surface area), and the samples whose fit is their gradient.
//!
//! - `d = Φ/|∇Φ|` is the first-order distance to the surface in Cartesian cell units
//!   (gradient by central differences through the frame), so a band `|d| < ε` is `ε` wide
//!   however flat the field is.
//! - Volume fraction `V_ε = Σ w H_ε(−d) / Σ w`; surface-area density
//!   `A_ε = Σ w δ_ε(d) / Σ w` (`δ_ε = H_ε'`; since `δ(Φ)|∇Φ| = δ(Φ/|∇Φ|)` this is the
//!   smoothed `∫ w δ(Φ)|∇Φ| / ∫ w`: area per element volume, perimeter per area in 2D).
//! - Gradients as samples, to be fitted in the basis: `−w δ_ε(d)/|∇Φ|` for `V` (the surface
//!   moves by `−δΦ/|∇Φ|`) and `−w δ_ε(d) κ/|∇Φ|` for `A`, `κ = ∇·(∇Φ/|∇Φ|)` the mean
//!   curvature (sum of the principal ones, positive on a ball of solid): the first variation
//!   `dA = −∫_S κ δΦ/|∇Φ| dS`. Holding `|∇Φ|` fixed would give `∫ δ_ε'(d) δΦ/|∇Φ|`, whose
//!   band integral is not the area's variation; the curvature form is, up to `O(ε²)`.
//! - `κ` by central differences of the unit normal (two stencils of the grid's spacing):
//!   consistent with `d`, no extra transform, and the samples matter only in the band and
//!   only through their fit's low frequencies, where second-order differences are accurate.
//!   It is clamped to `±1/ε`: a surface bent tighter than the band cannot be resolved by it.
//! - `w` is the reference element's indicator (½ on its boundary), all ones where the element
//!   is the domain. The line where the surface meets an element face also moves when the
//!   field changes; that part of the variation is left out, consistently with `A` counting
//!   only the level set's own surface. It vanishes where the surface meets the faces at right
//!   angles (the face-normal condition; the faces of Oh and D4 cells are mirror planes).
//!
//! Invariant: every value is a pure function of the grid samples, summed in index order.

use super::fit::{FitError, FittedCell};
use super::group::ReferenceElement;
use crate::contour2d::Element2;
use crate::element::Element3;

/// The smoothed Heaviside `H_ε(t) = ½(1 + t/ε + sin(πt/ε)/π)` on `|t| < ε` and its
/// derivative `δ_ε`.
pub(super) fn heaviside(t: f64, eps: f64) -> (f64, f64) {
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

/// Per grid point: `(d, |∇Φ|)` and, when asked, the mean curvature `κ`.
pub(super) struct GridSamples {
    pub distance: Vec<(f64, f64)>,
    pub curvature: Option<Vec<f64>>,
}

/// Indicator of the group's reference element at the domain grid's points (½ on its
/// boundary); all ones where the element is the domain or there is none.
pub(super) fn element_weights(cell: &FittedCell, grid: usize) -> Vec<f64> {
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

/// The central difference along domain axis `a` of `values` at point `p` (periodic), per
/// unit of the domain coordinate.
fn central(values: &[f64], p: usize, a: usize, grid: usize) -> f64 {
    let strides = [1, grid, grid * grid];
    let i = (p / strides[a]) % grid;
    let up = p - i * strides[a] + (i + 1) % grid * strides[a];
    let down = p - i * strides[a] + (i + grid - 1) % grid * strides[a];
    (values[up] - values[down]) * (0.5 * grid as f64)
}

/// `(Φ/|∇Φ|, |∇Φ|)` on the domain grid (module docs) and, with `curvature`, `κ` too.
pub(super) fn grid_samples(
    cell: &FittedCell,
    grid: usize,
    curvature: bool,
) -> Result<GridSamples, FitError> {
    let phi = cell.grid(grid)?;
    let d = cell.group.dimension();
    let frame = cell.group.domain().frame();
    let scale = phi.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let gradients: Vec<[f64; 3]> = (0..phi.len())
        .map(|p| {
            let gs: [f64; 3] = std::array::from_fn(|a| {
                if a < d {
                    central(&phi, p, a, grid)
                } else {
                    0.0
                }
            });
            frame.gradient_to_cartesian(gs)
        })
        .collect();
    let norms: Vec<f64> = gradients
        .iter()
        .map(|g| {
            (g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
                .sqrt()
                .max(1e-12 * scale)
        })
        .collect();
    let distance = phi.iter().zip(&norms).map(|(&v, &n)| (v / n, n)).collect();
    let curvature = curvature.then(|| {
        // κ = Σ_b ∂n_b/∂x_b: each component's Cartesian gradient through the frame.
        let normal: Vec<Vec<f64>> = (0..d)
            .map(|b| {
                gradients
                    .iter()
                    .zip(&norms)
                    .map(|(g, &n)| g[b] / n)
                    .collect()
            })
            .collect();
        (0..phi.len())
            .map(|p| {
                (0..d)
                    .map(|b| {
                        let gs: [f64; 3] = std::array::from_fn(|a| {
                            if a < d {
                                central(&normal[b], p, a, grid)
                            } else {
                                0.0
                            }
                        });
                        frame.gradient_to_cartesian(gs)[b]
                    })
                    .sum()
            })
            .collect()
    });
    Ok(GridSamples {
        distance,
        curvature,
    })
}

/// `V_ε` (module docs).
pub(super) fn smoothed_volume(samples: &GridSamples, weights: &[f64], eps: f64) -> f64 {
    let v: f64 = samples
        .distance
        .iter()
        .zip(weights)
        .map(|(&(h, _), &w)| w * heaviside(-h, eps).0)
        .sum();
    v / weights.iter().sum::<f64>()
}

/// `A_ε` (module docs).
pub(super) fn smoothed_area(samples: &GridSamples, weights: &[f64], eps: f64) -> f64 {
    let a: f64 = samples
        .distance
        .iter()
        .zip(weights)
        .map(|(&(h, _), &w)| w * heaviside(h, eps).1)
        .sum();
    a / weights.iter().sum::<f64>()
}

/// The samples whose fit (`⟨s, φ_f⟩` as [`super::fit::fit_samples`] computes it) is `∂V_ε/∂c`.
pub(super) fn volume_gradient_samples(
    samples: &GridSamples,
    weights: &[f64],
    weight_sum: f64,
    eps: f64,
) -> Vec<f64> {
    let m = samples.distance.len() as f64;
    samples
        .distance
        .iter()
        .zip(weights)
        .map(|(&(h, g), &w)| -w * heaviside(-h, eps).1 / g * m / weight_sum)
        .collect()
}

/// The samples whose fit is `∂A_ε/∂c` by the first variation (module docs). Needs the
/// curvature; without it, zero.
pub(super) fn area_gradient_samples(
    samples: &GridSamples,
    weights: &[f64],
    weight_sum: f64,
    eps: f64,
) -> Vec<f64> {
    let m = samples.distance.len() as f64;
    let Some(kappa) = &samples.curvature else {
        return vec![0.0; samples.distance.len()];
    };
    let bound = 1.0 / eps;
    samples
        .distance
        .iter()
        .zip(weights)
        .zip(kappa)
        .map(|((&(h, g), &w), &k)| {
            -w * heaviside(h, eps).1 * k.clamp(-bound, bound) / g * m / weight_sum
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::symmetric::coefficient_space::Vector;
    use crate::symmetric::fit::fit_samples;
    use crate::symmetric::measure::sharp_area;
    use crate::symmetric::{Complex64, FitOptions, Group, fit, from_fn};
    use std::f64::consts::TAU;

    /// The fitted gradients `⟨fit(samples), ψ⟩` along a band-limited `ψ` (the cell's own low
    /// frequencies with made-up weights, unit norm), and central differences along `ψ` of
    /// `V_ε`, of `A_ε` at the smoothing `band` (grid spacings) and of the sharp area on a grid
    /// twice as fine.
    fn derivatives(
        group: Group,
        n: usize,
        grid: usize,
        band: f64,
        source: fn([f64; 3]) -> f64,
    ) -> [f64; 5] {
        let cell = fit(&group, n, &from_fn(source), &FitOptions::default()).unwrap();
        let weights = element_weights(&cell, grid);
        let sum: f64 = weights.iter().sum();
        let eps = band / grid as f64;
        let psi = Vector(
            cell.coefficients
                .iter()
                .filter(|c| c.f.iter().all(|v| v.abs() <= 3))
                .enumerate()
                .map(|(i, c)| {
                    let w = (-0.7f64).powi(i as i32) / (1.0 + i as f64);
                    (c.f, Complex64::new(w, 0.0))
                })
                .collect(),
        );
        let psi = psi.combine(1.0 / psi.norm(), &Vector::default(), 0.0);
        let c = Vector::of(&cell);
        let moved = |t: f64| c.combine(1.0, &psi, t).cell(&cell, cell.n);
        let smoothed = |t: f64| {
            let s = grid_samples(&moved(t), grid, false).unwrap();
            (
                smoothed_volume(&s, &weights, eps),
                smoothed_area(&s, &weights, eps),
            )
        };
        let sharp = |t: f64| sharp_area(&moved(t), 2 * grid).unwrap();
        let h = 1e-5;
        let ((vp, ap), (vm, am)) = (smoothed(h), smoothed(-h));
        let s = grid_samples(&cell, grid, true).unwrap();
        let fitted = |samples: Vec<f64>| Vector::of(&fit_samples(&group, grid, &samples).unwrap());
        [
            fitted(volume_gradient_samples(&s, &weights, sum, eps)).dot(&psi),
            (vp - vm) / (2.0 * h),
            fitted(area_gradient_samples(&s, &weights, sum, eps)).dot(&psi),
            (ap - am) / (2.0 * h),
            (sharp(h) - sharp(-h)) / (2.0 * h),
        ]
    }

    fn wavy(x: [f64; 3]) -> f64 {
        let [c0, c1, c2] = x.map(|v| (TAU * v).cos());
        c0 + c1 + c2 - 0.4 * c0 * c1 * c2 + 0.5
    }

    fn blob(x: [f64; 3]) -> f64 {
        let [c0, c1, _] = x.map(|v| (TAU * v).cos());
        c0 + c1 + 0.3 * (2.0 * TAU * x[0]).cos() * (TAU * x[1]).cos() + 0.4
    }

    fn close(a: f64, b: f64, relative: f64) -> bool {
        (a - b).abs() <= relative * b.abs()
    }

    /// The curvature form is the area's first variation: it matches the difference of the
    /// sharp (marching) area closely, and that of the smoothed area where the band is wide
    /// enough for the grid sum to be a good quadrature (at 1.5 spacings, as the volume's
    /// final band, the smoothed area's differences are off by tens of per cent; measured).
    #[test]
    fn area_gradient_matches_central_differences() {
        let [dv, fv, da, _, fs] = derivatives(Group::oh(), 16, 64, 1.5, wavy);
        assert!(close(dv, fv, 2e-3), "volume {dv} vs {fv}");
        assert!(close(da, fs, 3e-3), "area {da} vs sharp {fs}");
        let [dv, fv, da, _, fs] = derivatives(Group::d4(), 32, 256, 1.5, blob);
        assert!(close(dv, fv, 2e-3), "volume {dv} vs {fv}");
        assert!(close(da, fs, 1e-3), "area {da} vs sharp {fs}");
        let [_, _, da, fa, _] = derivatives(Group::d4(), 32, 512, 6.0, blob);
        assert!(close(da, fa, 1e-2), "area {da} vs smoothed {fa}");
    }
}
