//! Automatic choice of the FFT size `N` (docs/method.md §Choosing N, `n = "auto"`).
//!
//! [`fit_auto`] fits at `N = 32, 64, 128, …` (at most `max_n`, a power of two) and stops at
//! the first `N` whose next doubling moves the fitted zero set less than `tolerance`; it
//! returns that (coarser) fit. When even `max_n` does not get there it returns the fit at
//! `max_n`, marked not converged, with the last movement: the caller says so to the user.
//!
//! Sampling is nested: the grid `s_i = x_0 + i/N` of one size holds every point of the size
//! before it (`x_0 + 2i/2N` is the same number), so each doubling evaluates the source only
//! at the new points, those with an odd index (7/8 of them in 3D, 3/4 in 2D), and copies
//! the rest. The source is evaluated once per point of the finest grid in all, and the
//! samples (hence the fits) are those of sampling each size from scratch.
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
//! Values and gradients on the probe grid come from inverse FFTs ([`FittedCell::grid`],
//! [`FittedCell::derivative_grid`]), exact at grid points; a rich fit's gradient by direct
//! summation at every near point cost minutes at `N = 256`.

use rayon::prelude::*;

use super::domain::{PlaneSource, Source, check_n, max_grid_n};
use super::fit::{FitError, FitOptions, FittedCell, check_surface, fit_samples, one_side};
use super::group::Group;

/// The first `N` tried.
pub const AUTO_START_N: usize = 32;

/// Probe grid points per axis for [`surface_movement`].
pub const PROBE_N: usize = 48;

/// What [`fit_auto`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct AutoFit {
    /// The fit at [`n`](Self::n).
    pub cell: FittedCell,
    /// The first `N` whose doubling moved the surface less than the tolerance, or `max_n`
    /// when none did.
    pub n: usize,
    /// The movement from `n` to `2n` when converged, else from `max_n/2` to `max_n`.
    pub movement: f64,
    /// Whether the tolerance was met.
    pub converged: bool,
    /// The `N` of the finest grid sampled (`2n` when converged, else `max_n`): the source
    /// was evaluated at its `N^d` points, once each.
    pub sampled_n: usize,
}

/// Fits `source` at `N = 32, 64, …` up to `max_n` (module docs).
///
/// Errors: `tolerance` not finite and positive, or `max_n` not a power of two from 64 to the
/// dimension's largest grid ([`FitError::AutoOptions`]); a non-finite sample; an input
/// without a surface; with `options.check_vanishing`, a returned fit without one.
pub fn fit_auto(
    group: &Group,
    source: &dyn Source,
    options: &FitOptions,
    tolerance: f64,
    max_n: usize,
) -> Result<AutoFit, FitError> {
    let d = group.dimension();
    let options_ok = tolerance.is_finite()
        && tolerance > 0.0
        && max_n.is_power_of_two()
        && max_n >= 2 * AUTO_START_N
        && check_n(max_n, d).is_ok();
    if !options_ok {
        return Err(FitError::AutoOptions {
            tolerance,
            max_n,
            limit: max_grid_n(d),
        });
    }
    let mut n = AUTO_START_N;
    let mut samples = sample_level(group, n, source, options, None)?;
    let mut coarse = fit_samples(group, n, &samples)?;
    let mut movement = f64::INFINITY;
    let converged = loop {
        if 2 * n > max_n {
            break false;
        }
        samples = sample_level(group, 2 * n, source, options, Some(&samples))?;
        let fine = fit_samples(group, 2 * n, &samples)?;
        movement = surface_movement(&coarse, &fine)?;
        if movement < tolerance {
            break true;
        }
        coarse = fine;
        n *= 2;
    };
    if options.check_vanishing {
        let scale = samples.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        check_surface(&coarse, scale)?;
    }
    Ok(AutoFit {
        cell: coarse,
        n,
        movement,
        converged,
        sampled_n: if converged { 2 * n } else { n },
    })
}

/// The source's samples on the `N^d` domain grid; with `coarse` (the `N/2` grid's samples)
/// only the points not on the coarse grid are evaluated. Fails on an input without a surface
/// when `options.check_vanishing`.
pub(crate) fn sample_level(
    group: &Group,
    n: usize,
    source: &dyn Source,
    options: &FitOptions,
    coarse: Option<&[f64]>,
) -> Result<Vec<f64>, FitError> {
    let ps = PlaneSource::new(group, n, source, options.sample);
    let (plane, coarse_plane) = (n * n, (n / 2) * (n / 2));
    let mut out = vec![0.0; plane * ps.planes()];
    out.par_chunks_mut(plane)
        .enumerate()
        .try_for_each(|(k, out)| match coarse {
            Some(c) if k % 2 == 0 => {
                ps.refine_plane(k, &c[(k / 2) * coarse_plane..][..coarse_plane], out)
            }
            _ => ps.sample_plane(k, out),
        })?;
    if options.check_vanishing {
        let (min, max) = out
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        if let Some(side) = one_side(min, max) {
            return Err(FitError::EmptyInput { side });
        }
    }
    Ok(out)
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
    let derivatives = (0..d)
        .map(|axis| fine.derivative_grid(m, axis))
        .collect::<Result<Vec<_>, _>>()?;
    let frame = group.domain().frame();
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
    let movement = (0..a.len())
        .into_par_iter()
        .filter(|&i| near(&a, i) || near(&b, i))
        .map(|i| {
            let ds: [f64; 3] =
                std::array::from_fn(|axis| derivatives.get(axis).map_or(0.0, |g| g[i]));
            let g = frame.gradient_to_cartesian(ds);
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

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};

    use super::*;
    use crate::field::ScalarField;
    use crate::mesh_read::TriangleSoup;
    use crate::mesh_sdf::{PeriodicMeshSdf, SdfOptions};
    use crate::symmetric::{Extend, SampleOptions, fit, from_fn, sample};

    /// Not separable and not symmetric: every sample is a real evaluation.
    fn blob(p: [f64; 3]) -> f64 {
        let r = (p[0] * p[0] + 1.3 * p[1] * p[1] + 0.8 * p[2] * p[2]).sqrt();
        r - 0.3 + 0.04 * (7.0 * p[0]).sin() * (5.0 * p[1] + 0.3).cos() + 0.02 * p[2]
    }

    /// A field that counts the points it is asked for (its grid sampler is the pointwise one,
    /// so it counts those too).
    struct Counting(AtomicUsize);

    impl ScalarField for Counting {
        fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
            self.0.fetch_add(out.len(), Ordering::Relaxed);
            for (i, o) in out.iter_mut().enumerate() {
                *o = blob([xs[i], ys[i], zs[i]]);
            }
        }
    }

    /// The reference: fit every size from scratch with [`fit`] and stop as [`fit_auto`] is
    /// documented to.
    fn brute_force(
        group: &Group,
        source: &dyn Source,
        options: &FitOptions,
        tolerance: f64,
        max_n: usize,
    ) -> (FittedCell, usize, bool) {
        let mut n = AUTO_START_N;
        let mut coarse = fit(group, n, source, options).unwrap();
        while 2 * n <= max_n {
            let fine = fit(group, 2 * n, source, options).unwrap();
            if surface_movement(&coarse, &fine).unwrap() < tolerance {
                return (coarse, n, true);
            }
            coarse = fine;
            n *= 2;
        }
        (coarse, n, false)
    }

    fn assert_same_fit(a: &FittedCell, b: &FittedCell) {
        assert_eq!(a.n(), b.n());
        assert_eq!(a.coefficients().len(), b.coefficients().len());
        for (x, y) in a.coefficients().iter().zip(b.coefficients()) {
            assert_eq!(x.f, y.f);
            assert!((x.c - y.c).norm() <= 1e-13, "{:?}: {} vs {}", x.f, x.c, y.c);
        }
    }

    /// Nested samples equal the samples of the finer grid taken from scratch, bit for bit:
    /// the plain cube, the mirrored tetrahedron (through a grid sampler), the mirrored and the
    /// symmetrized rhombus.
    #[test]
    fn refined_samples_are_the_samples_of_the_finer_grid() {
        let counting = Counting(AtomicUsize::new(0));
        let pointwise = from_fn(blob);
        let mirror = SampleOptions::default();
        let cases: [(Group, &dyn Source, SampleOptions, usize); 4] = [
            (Group::oh(), &counting, mirror, 16),
            (Group::td(), &counting, mirror, 16),
            (Group::d3(), &pointwise, mirror, 64),
            (
                Group::d3(),
                &pointwise,
                SampleOptions {
                    extend: Extend::None,
                    symmetrize: true,
                },
                64,
            ),
        ];
        for (group, source, sample_options, n) in cases {
            let options = FitOptions {
                sample: sample_options,
                check_vanishing: true,
            };
            let coarse = sample_level(&group, n, source, &options, None).unwrap();
            let refined = sample_level(&group, 2 * n, source, &options, Some(&coarse)).unwrap();
            let scratch = sample(&group, 2 * n, source, sample_options).unwrap();
            assert!(refined == scratch, "{group}: refined samples differ");
        }
    }

    /// Each doubling asks the source only for the points the coarser grid lacks: fitting up
    /// to `max_n` evaluates exactly `max_n^d` points, where sampling every size afresh costs
    /// `Σ N^d` (32³ + 64³ here).
    #[test]
    fn doubling_evaluates_only_the_new_points() {
        let counting = Counting(AtomicUsize::new(0));
        let options = FitOptions::default();
        let found = fit_auto(&Group::oh(), &counting, &options, 1e-12, 64).unwrap();
        assert!(!found.converged);
        assert_eq!(counting.0.load(Ordering::Relaxed), 64 * 64 * 64);
        let counter = AtomicUsize::new(0);
        let d3 = from_fn(|p| {
            counter.fetch_add(1, Ordering::Relaxed);
            blob(p)
        });
        let found = fit_auto(&Group::d3(), &d3, &options, 1e-12, 256).unwrap();
        assert_eq!(found.sampled_n, 256);
        // The mirrored half of the rhombus is copied, never evaluated: i + j ≤ N.
        let evaluated = (0..256usize)
            .map(|j| (0..256usize).filter(|i| i + j <= 256).count())
            .sum::<usize>();
        assert_eq!(counter.load(Ordering::Relaxed), evaluated);
    }

    /// With reused samples, automatic N picks the N that fitting every size from scratch
    /// picks, with the same coefficients (2D and 3D, converged and not).
    #[test]
    fn reuse_chooses_the_n_and_coefficients_of_fitting_from_scratch() {
        let source = from_fn(blob);
        let options = FitOptions::default();
        for (group, tolerance, max_n) in [
            (Group::d4(), 1e-3, 1024),
            (Group::d3(), 1e-2, 1024),
            (Group::oh(), 0.05, 64),
            (Group::td(), 1e-9, 64),
        ] {
            let found = fit_auto(&group, &source, &options, tolerance, max_n).unwrap();
            let (cell, n, converged) = brute_force(&group, &source, &options, tolerance, max_n);
            assert_eq!((found.n, found.converged), (n, converged), "{group}");
            assert_same_fit(&found.cell, &cell);
        }
    }

    /// Spectral derivatives equal the direct-summation gradient at the grid points, on a grid
    /// coarser than the fit (folded) and finer (gathered), Cartesian and hexagonal frames.
    #[test]
    fn derivative_grids_are_the_gradient_of_direct_summation() {
        let source = from_fn(blob);
        for group in [Group::oh(), Group::d3()] {
            let cell = fit(&group, 32, &source, &FitOptions::default()).unwrap();
            let (d, frame, origin) = (
                group.dimension(),
                group.domain().frame(),
                group.domain().origin(),
            );
            for m in [12, 48] {
                let grids: Vec<Vec<f64>> = (0..d)
                    .map(|a| cell.derivative_grid(m, a).unwrap())
                    .collect();
                for i in (0..grids[0].len()).step_by(97) {
                    let s: [f64; 3] = std::array::from_fn(|a| {
                        let idx = [i % m, (i / m) % m, i / (m * m)][a];
                        if a < d {
                            origin[a] + idx as f64 / m as f64
                        } else {
                            0.0
                        }
                    });
                    let ds: [f64; 3] = std::array::from_fn(|a| grids.get(a).map_or(0.0, |g| g[i]));
                    let spectral = frame.gradient_to_cartesian(ds);
                    let (_, direct) = cell.value_gradient(frame.to_cartesian(s));
                    for a in 0..3 {
                        assert!(
                            (spectral[a] - direct[a]).abs() < 1e-9 * (1.0 + direct[a].abs()),
                            "{group} m {m} point {i}: {spectral:?} vs {direct:?}"
                        );
                    }
                }
            }
        }
    }

    /// Three crossing square struts of half-width `h` through the cell, as overlapping boxes
    /// (a self-intersecting soup, like the shipped `cross.obj`).
    fn cross(h: f64) -> TriangleSoup {
        let mut soup = TriangleSoup {
            positions: Vec::new(),
            triangles: Vec::new(),
        };
        for axis in 0..3 {
            let corner = |c: usize| -> [f64; 3] {
                std::array::from_fn(|a| {
                    let bit = (c >> a) & 1 == 1;
                    let r = if a == axis { 0.5 } else { h };
                    if bit { r } else { -r }
                })
            };
            let base = soup.positions.len() as u32;
            soup.positions.extend((0..8).map(corner));
            // Faces of the box with corners by bits (x, y, z), outward.
            for q in [
                [0, 2, 3, 1],
                [4, 5, 7, 6],
                [0, 1, 5, 4],
                [2, 6, 7, 3],
                [0, 4, 6, 2],
                [1, 3, 7, 5],
            ] {
                soup.triangles.push([base + q[0], base + q[1], base + q[2]]);
                soup.triangles.push([base + q[0], base + q[2], base + q[3]]);
            }
        }
        soup
    }

    /// A mesh cell (the periodic signed distance of three struts) fitted with automatic N
    /// gets the N and coefficients of the from-scratch loop.
    #[test]
    fn a_mesh_cell_gets_the_n_of_the_brute_force_loop() {
        let sdf = PeriodicMeshSdf::new(&cross(0.12), SdfOptions::default()).unwrap();
        let options = FitOptions::default();
        let group = Group::oh();
        for tolerance in [0.5, 1e-6] {
            let found = fit_auto(&group, &sdf, &options, tolerance, 64).unwrap();
            let (cell, n, converged) = brute_force(&group, &sdf, &options, tolerance, 64);
            assert_eq!((found.n, found.converged), (n, converged), "{tolerance}");
            assert_same_fit(&found.cell, &cell);
        }
    }
}
