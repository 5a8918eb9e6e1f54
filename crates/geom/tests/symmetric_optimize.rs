//! Tests of coefficient optimisation (docs/method.md §Coefficient optimisation), each against a
//! value the test computes its own way: volume fractions by counting midpoint samples of the
//! separable sampler (not the optimiser's smoothed FFT-grid sum), symmetry at group images
//! written out by hand, face-normal residuals by direct summation, and the level shift found
//! by bisection on the counted fraction.
//!
//! `cargo test -p latticebuild-geom --test integration symmetric_optimize`

use latticebuild_geom::density::{self, Region};
use latticebuild_geom::symmetric::{
    Extend, FitOptions, FittedCell, Group, Matrix, Optimization, ReferenceElement, SampleOptions,
    fit, from_fn,
};
use std::f64::consts::TAU;

/// Oh and Td elements written out: signed permutations (Td keeps those with product +1).
pub(crate) fn signed_perms(positive_only: bool) -> Vec<Matrix> {
    let perms = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut out = Vec::new();
    for p in perms {
        for signs in 0..8 {
            let s = |r: usize| if signs >> r & 1 == 1 { -1 } else { 1 };
            if positive_only && (0..3).map(s).product::<i32>() != 1 {
                continue;
            }
            let mut m = [[0; 3]; 3];
            for r in 0..3 {
                m[r][p[r]] = s(r);
            }
            out.push(m);
        }
    }
    out
}

pub(crate) fn random_points(count: usize) -> Vec<[f64; 3]> {
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    (0..count).map(|_| [rnd(), rnd(), rnd()]).collect()
}

/// Fraction of midpoint samples with `Φ ≤ 0` over the reference element.
pub(crate) fn counted_fraction(cell: &FittedCell, element: ReferenceElement, n: usize) -> f64 {
    let values = density::sample(cell, Region::Element(element), n);
    let kept: Vec<f64> = values.into_iter().filter(|v| !v.is_nan()).collect();
    kept.iter().filter(|&&v| v <= 0.0).count() as f64 / kept.len() as f64
}

/// `‖a − b‖` over the union of the coefficients.
pub(crate) fn distance(a: &FittedCell, b: &FittedCell) -> f64 {
    let mut fs: Vec<[i32; 3]> = a.coefficients().iter().map(|c| c.f).collect();
    fs.extend(b.coefficients().iter().map(|c| c.f));
    fs.sort_unstable();
    fs.dedup();
    fs.iter()
        .map(|&f| (a.coefficient(f) - b.coefficient(f)).norm_sqr())
        .sum::<f64>()
        .sqrt()
}

pub(crate) fn wavy(x: [f64; 3]) -> f64 {
    let [c0, c1, c2] = x.map(|v| (TAU * v).cos());
    c0 + c1 + c2 - 0.4 * c0 * c1 * c2
}

fn options(target: f64, keep_face_normal: bool) -> Optimization {
    Optimization {
        volume_fraction: target,
        keep_face_normal,
        max_iterations: 30,
        tolerance: 1e-4,
    }
}

#[test]
fn oh_cell_reaches_the_target_with_less_change_than_a_level_shift() {
    let cell = fit(&Group::oh(), 32, &from_fn(wavy), &FitOptions::default()).unwrap();
    let start = counted_fraction(&cell, ReferenceElement::Cube, 96);
    let target = 0.3;
    assert!((start - target).abs() > 0.1, "the start is far: {start}");
    let (opt, report) = cell.optimize(&options(target, false)).unwrap();
    assert!(report.converged, "{report:?}");
    assert!(report.iterates.len() <= 31, "{report:?}");

    // The counted fraction (96³ midpoints) is the target.
    let reached = counted_fraction(&opt, ReferenceElement::Cube, 96);
    assert!((reached - target).abs() <= 2e-3, "{reached}");

    // The change reported is the coefficient distance.
    let change = distance(&opt, &cell);
    assert!(
        (change - report.change).abs() <= 1e-12 * change,
        "{change} {report:?}"
    );

    // The level shift Φ + t reaching the same counted fraction changes c₀ by |t| (φ₀ ≡ 1).
    let (mut lo, mut hi) = (0.0, 3.0);
    for _ in 0..40 {
        let t = 0.5 * (lo + hi);
        if counted_fraction(&cell.offset(t), ReferenceElement::Cube, 48) > target {
            lo = t;
        } else {
            hi = t;
        }
    }
    let shift = 0.5 * (lo + hi);
    assert!(
        change < 0.8 * shift,
        "optimised change {change}, level shift {shift}"
    );

    // Exactly Oh-symmetric: equal at all 48 images of random points.
    for x in random_points(20) {
        let v = opt.value(x);
        for q in signed_perms(false) {
            let qx: [f64; 3] = std::array::from_fn(|i| (0..3).map(|j| q[i][j] as f64 * x[j]).sum());
            assert!((opt.value(qx) - v).abs() <= 1e-12, "Q = {q:?}");
        }
    }
}

/// Max |∇Φ·n| over a barycentric grid on the tetrahedron's faces, gradients by direct
/// summation (the cell's own `value_gradient`, not the constraint's line sums).
pub(crate) fn tet_face_residual(cell: &FittedCell, m: usize) -> f64 {
    let p = [
        [-0.5, -0.5, -0.5],
        [0.5, 0.5, -0.5],
        [-0.5, 0.5, 0.5],
        [0.5, -0.5, 0.5],
    ];
    let normals = [
        [1.0, 1.0, 1.0],
        [-1.0, -1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
    ];
    let mut worst: f64 = 0.0;
    for (face, normal) in normals.iter().enumerate() {
        let v: Vec<[f64; 3]> = (0..4).filter(|&j| j != face).map(|j| p[j]).collect();
        let n = normal.map(|x: f64| x / 3f64.sqrt());
        for i in 0..m {
            for j in 0..m - i {
                let (u, w) = (i as f64 / (m - 1) as f64, j as f64 / (m - 1) as f64);
                let x: [f64; 3] = std::array::from_fn(|a| {
                    v[0][a] + u * (v[1][a] - v[0][a]) + w * (v[2][a] - v[0][a])
                });
                let (_, g) = cell.value_gradient(x);
                worst = worst.max((g[0] * n[0] + g[1] * n[1] + g[2] * n[2]).abs());
            }
        }
    }
    worst
}

pub(crate) fn td_source(x: [f64; 3]) -> f64 {
    0.6 * (TAU * x[0]).sin() * (TAU * x[1]).sin() * (TAU * x[2]).sin()
        + (x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
        - 0.15
}

#[test]
fn td_cell_keeps_the_face_normal_condition_and_its_symmetry() {
    let options_fit = FitOptions {
        sample: SampleOptions {
            extend: Extend::None,
            symmetrize: false,
        },
        check_vanishing: true,
    };
    let fitted = fit(&Group::td(), 16, &from_fn(td_source), &options_fit).unwrap();
    let (cell, _) = fitted.constrain_normal_to_faces().unwrap();
    let scale = cell
        .coefficients()
        .iter()
        .map(|c| c.c.norm())
        .fold(0.0, f64::max);
    assert!(tet_face_residual(&cell, 12) <= 1e-9 * scale);
    let start = counted_fraction(&cell, ReferenceElement::Tetrahedron, 64);
    let target = if start > 0.45 {
        start - 0.15
    } else {
        start + 0.15
    };
    let (opt, report) = cell.optimize(&options(target, true)).unwrap();
    assert!(report.converged, "{report:?}");
    let reached = counted_fraction(&opt, ReferenceElement::Tetrahedron, 96);
    assert!(
        (reached - target).abs() <= 3e-3,
        "{start} → {reached}, {target}"
    );

    // The optimiser changed frequencies the constraint couples, and the condition held.
    let gradient_scale = (0..50)
        .map(|i| opt.value_gradient([0.01 * i as f64 - 0.25, 0.1, -0.05]).1)
        .map(|g| (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt())
        .fold(0.0, f64::max);
    let residual = tet_face_residual(&opt, 12);
    assert!(
        residual <= 1e-8 * gradient_scale,
        "{residual} vs |∇Φ| up to {gradient_scale}"
    );
    // Without the projection the same run breaks it: the check above is not vacuous.
    let (free, _) = cell.optimize(&options(target, false)).unwrap();
    assert!(tet_face_residual(&free, 12) > 1e-4 * gradient_scale);

    for x in random_points(10) {
        let v = opt.value(x);
        for q in signed_perms(true) {
            let qx: [f64; 3] = std::array::from_fn(|i| (0..3).map(|j| q[i][j] as f64 * x[j]).sum());
            assert!((opt.value(qx) - v).abs() <= 1e-12, "Q = {q:?}");
        }
    }
}

#[test]
fn a_cell_already_at_the_target_is_left_alone() {
    let cell = fit(&Group::oh(), 16, &from_fn(wavy), &FitOptions::default()).unwrap();
    let (_, first) = cell.optimize(&options(0.4, false)).unwrap();
    let (again, second) = cell
        .optimize(&options(first.iterates[0].volume_fraction, false))
        .unwrap();
    assert!(second.converged && second.change == 0.0, "{second:?}");
    assert_eq!(distance(&again, &cell), 0.0);
}

#[test]
fn an_unreachable_run_reports_what_it_reached() {
    let cell = fit(&Group::oh(), 16, &from_fn(wavy), &FitOptions::default()).unwrap();
    let mut o = options(0.3, false);
    o.max_iterations = 1;
    let (_, report) = cell.optimize(&o).unwrap();
    assert!(!report.converged);
    assert_eq!(report.iterates.len(), 2);
    assert!((report.reached - 0.3).abs() > 1e-4, "{report:?}");
}
