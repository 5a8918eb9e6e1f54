//! The phase shift and the domain of Wang's eq. 12 (issue 26 item 2).
//!
//! - A term shifted by `θ` is the unshifted term at the point moved by `θ h / |h|²` along its
//!   own direction, and the shifted model is the sum of those (direct evaluation, not the
//!   model's code).
//! - The phase search finds an off-grid phase where it is the only one through the atoms,
//!   keeps every atom on the surface, never lowers the porosity, and on Faujasite keeps
//!   `θ = 0`, as the paper found.
//! - Moving the unit cell (origin shifts, images) changes neither the surface nor the porosity:
//!   the domain is nothing to search.
//! - Re-ordering the atoms changes nothing.

use std::f64::consts::TAU;

use latticebuild_geom::periodic::phase::{GRID, PERIOD, shift_terms, shifted};
use latticebuild_geom::periodic::reconstruct::{ReconstructOptions, reconstruct};
use latticebuild_geom::periodic::{
    Crystal, ExpandOptions, PsModel, PsTerm, positions_of, read_crystal,
};

fn crystal(name: &str) -> Crystal {
    let path = format!("{}/tests/data/crystals/{name}", env!("CARGO_MANIFEST_DIR"));
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    read_crystal(name, &bytes).unwrap_or_else(|e| panic!("{e}"))
}

fn faujasite_si() -> Vec<[f64; 3]> {
    positions_of(
        &crystal("FAU.cif").atoms(&ExpandOptions::default()),
        Some("Si"),
    )
}

/// `max |ψ|` on a 72³ grid (a lower bound of the true maximum, close to it).
fn direct_max(model: &PsModel) -> f64 {
    let n = 72;
    let mut max: f64 = 0.0;
    for i in 0..n * n * n {
        let p = [i % n, (i / n) % n, i / (n * n)].map(|c| c as f64 / n as f64);
        max = max.max(model.value(p).abs());
    }
    max
}

/// The mean of ψ² over the `n³` grid of the unit box with origin `origin`.
fn mean_square(model: &PsModel, origin: [f64; 3], n: usize) -> f64 {
    let mut sum = 0.0;
    for i in 0..n * n * n {
        let c = [i % n, (i / n) % n, i / (n * n)];
        let p: [f64; 3] = std::array::from_fn(|a| origin[a] + c[a] as f64 / n as f64);
        sum += model.value(p).powi(2);
    }
    sum / (n * n * n) as f64
}

#[test]
fn a_shifted_term_is_the_term_at_a_point_moved_along_its_direction() {
    let terms: Vec<PsTerm> = [
        (0.7, 1.0, [1.0, 0.0, 0.0, 0.0]),
        (-0.3, 2.0, [1.0, 1.0, 0.0, 0.0]),
        (0.2, 4.0, [1.0, -1.0, 1.0, 0.0]),
        (0.4, 1.0, [0.0, 0.0, 0.0, 0.0]),
    ]
    .iter()
    .map(|&(moment, scale, vector)| PsTerm {
        moment,
        scale,
        vector,
    })
    .collect();
    for theta in [0.0, 0.1, 0.25, 0.61] {
        let shifted = PsModel::new(shift_terms(&terms, theta));
        for i in 0..50 {
            let r = [
                0.031 * i as f64,
                0.017 * (i * i % 13) as f64,
                1.0 - 0.029 * i as f64,
            ];
            let mut moved = 0.0;
            let mut formula = 0.0;
            for t in &terms {
                let h = [t.vector[0], t.vector[1], t.vector[2]];
                let h2: f64 = h.iter().map(|v| v * v).sum();
                // The point moved by θ h / |h|² (the constant does not move).
                let s: [f64; 3] = std::array::from_fn(|a| {
                    if h2 > 0.0 {
                        r[a] + theta * h[a] / h2
                    } else {
                        r[a]
                    }
                });
                moved += PsModel::new(vec![*t]).value(s);
                let dot: f64 = (0..3).map(|a| h[a] * r[a]).sum();
                let phase = if h2 > 0.0 { theta } else { 0.0 };
                formula += t.moment * (TAU * t.scale * (dot + phase)).cos();
            }
            let v = shifted.value(r);
            assert!(
                (v - moved).abs() < 1e-12,
                "θ {theta} at {r:?}: {v} vs {moved}"
            );
            assert!(
                (v - formula).abs() < 1e-12,
                "θ {theta} at {r:?}: {v} vs {formula}"
            );
        }
    }
}

/// Points on `cos 2π(x+θ₀) + cos 2π(y+θ₀) + cos 2π(z+θ₀) + ½ cos 2π(x+y+θ₀) = 0`: a surface of
/// the scale-1 basis shifted by `θ₀ = 0.1`, which is not on the search's grid. Unshifted, no
/// surface of scales up to 8 passes through all 150 points; the search finds `θ₀` and the
/// exact fit there.
#[test]
fn the_phase_search_finds_an_off_grid_phase_that_alone_fits_the_atoms() {
    let theta0 = 0.1;
    assert!((theta0 / PERIOD * GRID as f64).fract() > 0.1);
    let f = |p: [f64; 3]| {
        let c = |v: f64| (TAU * (v + theta0)).cos();
        c(p[0]) + c(p[1]) + c(p[2]) + 0.5 * c(p[0] + p[1])
    };
    // Points on the surface: bisection along z from deterministic (x, y).
    let mut points = Vec::new();
    let mut i = 0u32;
    while points.len() < 150 {
        i += 1;
        let (x, y) = (
            (f64::from(i) * 0.618_033_988_7).fract(),
            (f64::from(i) * 0.414_213_562_3).fract(),
        );
        let (mut lo, mut hi) = (0.0, 0.5);
        if f([x, y, lo]).signum() == f([x, y, hi]).signum() {
            (lo, hi) = (0.5, 1.0);
            if f([x, y, lo]).signum() == f([x, y, hi]).signum() {
                continue;
            }
        }
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if f([x, y, mid]).signum() == f([x, y, lo]).signum() {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        points.push([x, y, 0.5 * (lo + hi)]);
    }
    let plain = reconstruct(&points, &ReconstructOptions::default()).expect("plain");
    assert!(!plain.converged, "{:?}", plain.steps);
    let options = ReconstructOptions {
        optimize: true,
        ..ReconstructOptions::default()
    };
    let r = reconstruct(&points, &options).expect("optimised");
    let o = r.optimization.clone().expect("optimisation");
    let phase = o.phase.clone().expect("phase");
    println!("off-grid phase: {phase:?}, {:?}", r.metrics);
    assert!(r.converged);
    assert!((phase.theta - theta0).abs() < 1e-6, "{phase:?}");
    let max = direct_max(&r.model);
    let worst = points
        .iter()
        .map(|&p| r.model.value(p).abs())
        .fold(0.0, f64::max);
    assert!(worst / max < 1e-9, "{worst} / {max}");
    // Every non-constant term carries the phase.
    assert!(
        r.model
            .terms
            .iter()
            .all(|t| t.is_constant() || t.vector[3] == phase.theta)
    );
}

/// Faujasite's Si: `θ = 0` is kept (the paper's Tab. 5 finds θ* = 0.00011, "the phase shift of
/// zeros ... is optimal"), every atom stays on the surface, and the porosity is the θ = 0
/// optimisation's, above the plain search's.
#[test]
fn faujasite_keeps_a_zero_phase_and_every_atom_on_the_surface() {
    let points = faujasite_si();
    let options = ReconstructOptions {
        optimize: true,
        ..ReconstructOptions::default()
    };
    let r = reconstruct(&points, &options).expect("optimised");
    let o = r.optimization.clone().expect("optimisation");
    let phase = o.phase.clone().expect("phase");
    println!("FAU phase: {phase:?}; {:?} → {:?}", o.before, o.after);
    assert_eq!(phase.theta, 0.0);
    assert!(phase.evaluations >= GRID);
    let plain = reconstruct(&points, &ReconstructOptions::default()).expect("plain");
    assert_eq!(plain.metrics, o.before);
    assert_eq!(phase.porosity_at_zero, Some(plain.metrics.porosity));
    assert!(o.after.porosity >= o.before.porosity);
    assert!(o.after.porosity > 0.37, "{o:?}");
    // Why θ = 0: no other grid phase's plain search has a higher porosity.
    for j in 1..GRID {
        let theta = PERIOD * j as f64 / GRID as f64;
        let at = ReconstructOptions {
            directions: shifted(&ReconstructOptions::default().directions, theta),
            ..ReconstructOptions::default()
        };
        let s = reconstruct(&points, &at).expect("shifted");
        let last = s.steps.last().map(|s| s.scales.clone());
        println!(
            "FAU θ = {theta:.4}: converged {} {last:?} {:?}",
            s.converged, s.metrics
        );
        assert!(
            !s.converged || s.metrics.porosity < plain.metrics.porosity,
            "θ {theta}"
        );
    }
    let max = direct_max(&r.model);
    let worst = points
        .iter()
        .map(|&p| r.model.value(p).abs())
        .fold(0.0, f64::max);
    assert!(worst / max <= 1e-9, "{worst} / {max}");
    let direct = mean_square(&r.model, [0.0; 3], 40) / (max * max);
    assert!(
        (direct - r.metrics.porosity).abs() < 0.01,
        "{direct} vs {:?}",
        r.metrics
    );
    // The same surface for the atoms listed backwards and interleaved.
    let mut reordered: Vec<[f64; 3]> = points.iter().rev().copied().collect();
    let half = reordered.split_off(reordered.len() / 2);
    let reordered: Vec<[f64; 3]> = half
        .iter()
        .zip(&reordered)
        .flat_map(|(a, b)| [*a, *b])
        .chain(half.iter().skip(reordered.len()).copied())
        .collect();
    assert_eq!(reordered.len(), points.len());
    let again = reconstruct(&reordered, &options).expect("reordered");
    let o2 = again.optimization.clone().expect("optimisation");
    assert_eq!(o2.phase.as_ref().map(|p| p.theta), Some(0.0));
    // The moments' Nelder–Mead ends on a flat optimum, so rounding moves it a little.
    assert!(
        (again.metrics.porosity - r.metrics.porosity).abs() < 1e-6,
        "{:?} vs {:?}",
        again.metrics,
        r.metrics
    );
    assert_eq!(again.model.terms.len(), r.model.terms.len());
    for (a, b) in again.model.terms.iter().zip(&r.model.terms) {
        assert_eq!((a.scale, a.vector), (b.scale, b.vector));
        assert!((a.moment - b.moment).abs() < 1e-4, "{a:?} vs {b:?}");
    }
}

/// The domain: the atoms wrapped into the unit box at any origin, with or without their images
/// on the faces, give the same surface and porosity; and a period-1 model's mean ψ² over a
/// shifted box is its mean over [0, 1)³.
#[test]
fn moving_the_cell_changes_neither_the_surface_nor_the_porosity() {
    let points = faujasite_si();
    let base = reconstruct(&points, &ReconstructOptions::default()).expect("base");
    let at_origin = mean_square(&base.model, [0.0; 3], 24);
    for origin in [[0.5, 0.5, 0.5], [0.13, 0.37, 0.71], [0.9, 0.05, 0.45]] {
        let wrapped: Vec<[f64; 3]> = points
            .iter()
            .map(|p| std::array::from_fn(|a| origin[a] + (p[a] - origin[a]).rem_euclid(1.0)))
            .collect();
        let r = reconstruct(&wrapped, &ReconstructOptions::default()).expect("wrapped");
        assert_eq!(r.model.terms.len(), base.model.terms.len());
        for (a, b) in r.model.terms.iter().zip(&base.model.terms) {
            assert_eq!(a.vector, b.vector);
            assert!(
                (a.moment - b.moment).abs() < 1e-9,
                "{origin:?}: {a:?} vs {b:?}"
            );
        }
        assert!((r.metrics.porosity - base.metrics.porosity).abs() < 1e-9);
        let shifted = mean_square(&base.model, origin, 24);
        assert!(
            (shifted - at_origin).abs() < 1e-12,
            "{shifted} vs {at_origin}"
        );
    }
    let images = positions_of(
        &crystal("FAU.cif").atoms(&ExpandOptions {
            include_images: true,
            ..ExpandOptions::default()
        }),
        Some("Si"),
    );
    let r = reconstruct(&images, &ReconstructOptions::default()).expect("images");
    assert!((r.metrics.porosity - base.metrics.porosity).abs() < 1e-9);
}
