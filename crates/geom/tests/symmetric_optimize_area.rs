//! Tests of the surface-area target of coefficient optimisation (docs/method.md §Surface
//! area), each against a value computed its own way: areas of the contoured meshes (marching
//! cubes of the element, its cap faces left out) and perimeters of marching-squares regions
//! (the square's sides left out), not the optimiser's marching tetrahedra; volume fractions by
//! counting midpoint samples; symmetry at group images written out by hand; face-normal
//! residuals by direct summation; the level shift by bisection on the measured area.
//!
//! `cargo test -p latticebuild-geom --test integration symmetric_optimize_area`

use latticebuild_geom::contour2d::{Element2, contour_planar};
use latticebuild_geom::element::{Element3, contour_clipped};
use latticebuild_geom::symmetric::{
    Extend, FitOptions, FittedCell, Group, OptimizationTargets, ReferenceElement, SampleOptions,
    fit, from_fn, measure,
};
use std::f64::consts::TAU;

use crate::symmetric_optimize::{
    counted_fraction, distance, random_points, signed_perms, td_source, tet_face_residual, wavy,
};

fn targets(volume: Option<f64>, area: Option<f64>, keep: bool) -> OptimizationTargets {
    OptimizationTargets {
        volume_fraction: volume,
        surface_area: area,
        keep_face_normal: keep,
        max_iterations: 30,
        tolerance: 1e-4,
    }
}

/// Area of `{Φ = 0}` in the cube: the clipped mesh's triangles, less those on a cube face.
fn mesh_area(cell: &FittedCell, samples: usize) -> f64 {
    let mesh = contour_clipped(cell, Element3::Cube, samples, &|_| {}).expect("contoured");
    let v = |i: u32| mesh.vertices[i as usize].map(f64::from);
    mesh.triangles
        .iter()
        .filter(|t| {
            !(0..3).any(|a| {
                let on = |i: u32| (v(i)[a].abs() - 0.5).abs() < 1e-6;
                on(t[0]) && on(t[1]) && on(t[2]) && (v(t[0])[a] > 0.0) == (v(t[1])[a] > 0.0)
            })
        })
        .map(|t| triangle_area(v(t[0]), v(t[1]), v(t[2])))
        .sum()
}

/// Area of `{Φ = 0}` in the tetrahedron per its volume (⅓): the clipped mesh's triangles,
/// less those lying in a face plane `±x ± y ± z = ½·…` of the element.
fn tet_area(cell: &FittedCell, samples: usize) -> f64 {
    let mesh = contour_clipped(cell, Element3::Tetrahedron, samples, &|_| {}).expect("contoured");
    let v = |i: u32| mesh.vertices[i as usize].map(f64::from);
    let normals = [
        [1.0, 1.0, 1.0],
        [-1.0, -1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
    ];
    let area: f64 = mesh
        .triangles
        .iter()
        .filter(|t| {
            !normals.iter().any(|n: &[f64; 3]| {
                t.iter().all(|&i| {
                    let p = v(i);
                    (n[0] * p[0] + n[1] * p[1] + n[2] * p[2] - 0.5).abs() < 1e-4
                })
            })
        })
        .map(|t| triangle_area(v(t[0]), v(t[1]), v(t[2])))
        .sum();
    area * 3.0
}

fn triangle_area(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let (u, w) = (
        [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
        [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
    );
    let x = [
        u[1] * w[2] - u[2] * w[1],
        u[2] * w[0] - u[0] * w[2],
        u[0] * w[1] - u[1] * w[0],
    ];
    0.5 * (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt()
}

/// Perimeter of `{Φ = 0}` in the square: the region's boundary, less the square's sides.
fn perimeter(cell: &FittedCell, samples: usize) -> f64 {
    let region = contour_planar(
        &|p| cell.value([p[0], p[1], 0.0]),
        Element2::Square,
        samples,
    )
    .expect("contoured");
    let mut total = 0.0;
    for lp in &region.boundary {
        for i in 0..lp.len() {
            let (a, b) = (lp[i], lp[(i + 1) % lp.len()]);
            let side = (0..2).any(|k| {
                (a[k].abs() - 0.5).abs() < 1e-12 && (b[k].abs() - 0.5).abs() < 1e-12 && a[k] == b[k]
            });
            if !side {
                total += (b[0] - a[0]).hypot(b[1] - a[1]);
            }
        }
    }
    total
}

/// The level shift `t ≥ 0` (either sign of the offset) whose measured area is `target`, by
/// bisection; `None` when no shift up to 1 reaches it.
fn level_shift(
    cell: &FittedCell,
    target: f64,
    measure: &dyn Fn(&FittedCell) -> f64,
) -> Option<f64> {
    let start = measure(cell);
    for sign in [1.0, -1.0] {
        let f = |t: f64| measure(&cell.offset(sign * t)) - target;
        let (mut lo, mut hi) = (0.0, 1.0);
        if (f(hi) > 0.0) == (start - target > 0.0) {
            continue;
        }
        for _ in 0..30 {
            let mid = 0.5 * (lo + hi);
            if (f(mid) > 0.0) == (start - target > 0.0) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        return Some(0.5 * (lo + hi));
    }
    None
}

fn d4_source(x: [f64; 3]) -> f64 {
    let [c0, c1, _] = x.map(|v| (TAU * v).cos());
    c0 + c1 + 0.3 * ((2.0 * TAU * x[0]).cos() + (2.0 * TAU * x[1]).cos()) + 0.6
}

fn d4_images(x: [f64; 3]) -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    for swap in [false, true] {
        for sx in [1.0, -1.0] {
            for sy in [1.0, -1.0] {
                let (a, b) = if swap { (x[1], x[0]) } else { (x[0], x[1]) };
                out.push([sx * a, sy * b, 0.0]);
            }
        }
    }
    out
}

#[test]
fn d4_cell_reaches_a_perimeter_with_less_change_than_a_level_shift() {
    let cell = fit(
        &Group::d4(),
        64,
        &from_fn(d4_source),
        &FitOptions::default(),
    )
    .unwrap();
    let start = perimeter(&cell, 257);
    let target = 1.1 * start;
    let t0 = std::time::Instant::now();
    let (opt, report) = cell
        .optimize_for(&targets(None, Some(target), false))
        .unwrap();
    eprintln!("D4: {:?} {report:?}", t0.elapsed());
    assert!(report.converged, "{report:?}");
    assert!(
        (report.before.surface_area - start).abs() <= 5e-3 * start,
        "{report:?} {start}"
    );
    let reached = perimeter(&opt, 257);
    assert!(
        (reached - target).abs() <= 5e-3 * target,
        "{start} → {reached}, {target}"
    );
    assert!((report.area_reached - reached).abs() <= 5e-3 * target);
    let change = distance(&opt, &cell);
    assert!((change - report.change).abs() <= 1e-12 * change);

    let shift = level_shift(&cell, target, &|c| perimeter(c, 129)).expect("a shift exists");
    assert!(
        change < shift,
        "optimised change {change}, level shift {shift}"
    );

    for x in random_points(20) {
        let x = [x[0], x[1], 0.0];
        let v = opt.value(x);
        for y in d4_images(x) {
            assert!((opt.value(y) - v).abs() <= 1e-12, "{y:?}");
        }
    }
}

#[test]
fn oh_cell_reaches_a_surface_area_with_less_change_than_a_level_shift() {
    let cell = fit(&Group::oh(), 16, &from_fn(wavy), &FitOptions::default())
        .unwrap()
        .offset(0.5);
    let start = mesh_area(&cell, 97);
    let target = 0.9 * start;
    let t0 = std::time::Instant::now();
    let (opt, report) = cell
        .optimize_for(&targets(None, Some(target), false))
        .unwrap();
    eprintln!("Oh: {:?} {report:?}", t0.elapsed());
    assert!(report.converged, "{report:?}");
    let reached = mesh_area(&opt, 97);
    assert!(
        (reached - target).abs() <= 1e-2 * target,
        "{start} → {reached}, {target}"
    );

    let change = distance(&opt, &cell);
    let shift = level_shift(&cell, target, &|c| mesh_area(c, 49)).expect("a shift exists");
    assert!(
        change < shift,
        "optimised change {change}, level shift {shift}"
    );

    for x in random_points(10) {
        let v = opt.value(x);
        for q in signed_perms(false) {
            let qx: [f64; 3] = std::array::from_fn(|i| (0..3).map(|j| q[i][j] as f64 * x[j]).sum());
            assert!((opt.value(qx) - v).abs() <= 1e-12, "Q = {q:?}");
        }
    }
}

/// Both targets: a fuller solid (+0.02) with 1 % more area than the level shift to that
/// fraction gives. (Keeping the start's area, 0.9 % below the shift's, is out of reach near
/// this cell: its level sets are nearly area-minimising for their volume, the area at a fixed
/// volume being convex along every smooth direction tried; runs stop, stalled, near fraction
/// 0.392 and area 2.290.)
#[test]
fn oh_cell_meets_a_volume_fraction_and_a_surface_area_together() {
    let cell = fit(&Group::oh(), 16, &from_fn(wavy), &FitOptions::default())
        .unwrap()
        .offset(0.5);
    let area = mesh_area(&cell, 97);
    let goal = counted_fraction(&cell, ReferenceElement::Cube, 96) + 0.02;
    // The level shift to the same fraction, and its area.
    let fraction_of = |c: &FittedCell| counted_fraction(c, ReferenceElement::Cube, 48);
    let t = level_shift(&cell, goal, &fraction_of).expect("a shift exists");
    let shifted = [cell.offset(t), cell.offset(-t)]
        .into_iter()
        .min_by(|a, b| {
            (fraction_of(a) - goal)
                .abs()
                .total_cmp(&(fraction_of(b) - goal).abs())
        })
        .expect("two candidates");
    let shifted_area = mesh_area(&shifted, 97);
    assert!(
        shifted_area - area > 5e-3 * area,
        "{shifted_area} vs {area}"
    );
    let target = shifted_area + 1e-2 * area;
    let t0 = std::time::Instant::now();
    let (opt, report) = cell
        .optimize_for(&OptimizationTargets {
            max_iterations: 60,
            ..targets(Some(goal), Some(target), false)
        })
        .unwrap();
    eprintln!("Oh both: {:?} {report:?}", t0.elapsed());
    assert!(report.converged && !report.stalled, "{report:?}");
    let fraction = counted_fraction(&opt, ReferenceElement::Cube, 96);
    assert!((fraction - goal).abs() <= 2e-3, "{fraction}");
    let reached = mesh_area(&opt, 97);
    // Both targets acted: the area is nearer the target than the level shift's, by twice.
    assert!(
        (reached - target).abs() <= 0.5 * (target - shifted_area),
        "{reached} vs {target} (shift {shifted_area})"
    );
    assert!((reached - target).abs() <= 1e-2 * target);
}

#[test]
fn td_cell_keeps_the_face_normal_condition_with_an_area_target() {
    let options_fit = FitOptions {
        sample: SampleOptions {
            extend: Extend::None,
            symmetrize: false,
        },
        check_vanishing: true,
    };
    let fitted = fit(&Group::td(), 16, &from_fn(td_source), &options_fit).unwrap();
    let (cell, _) = fitted.constrain_normal_to_faces().unwrap();
    let target = 0.95 * measure(&cell).unwrap().surface_area;
    let (opt, report) = cell
        .optimize_for(&targets(None, Some(target), true))
        .unwrap();
    eprintln!("Td: {report:?}");
    // Converged means the target is met on the finer grid, and the contoured element agrees.
    assert!(report.converged, "{report:?}");
    assert!(
        (report.area_reached - target).abs() <= 1e-3 * target,
        "{report:?}"
    );
    let contoured = tet_area(&opt, 97);
    assert!(
        (contoured - target).abs() <= 1e-2 * target,
        "contoured {contoured} vs {target}"
    );
    let gradient_scale = (0..50)
        .map(|i| opt.value_gradient([0.01 * i as f64 - 0.25, 0.1, -0.05]).1)
        .map(|g| (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt())
        .fold(0.0, f64::max);
    let residual = tet_face_residual(&opt, 12);
    assert!(
        residual <= 1e-8 * gradient_scale,
        "{residual} vs {gradient_scale}"
    );
    for x in random_points(10) {
        let v = opt.value(x);
        for q in signed_perms(true) {
            let qx: [f64; 3] = std::array::from_fn(|i| (0..3).map(|j| q[i][j] as f64 * x[j]).sum());
            assert!((opt.value(qx) - v).abs() <= 1e-12, "Q = {q:?}");
        }
    }
}

/// Targets out of reach stop within a few steps, unconverged and stalled, with what they
/// reached. Why out of reach, independently of the optimiser: along a line parallel to an axis
/// a trigonometric polynomial of degree `K` in that coordinate vanishes at most `2K` times per
/// period, and `area ≤ ∫ (|n_x| + |n_y| + |n_z|) dS` counts those crossings, so the area
/// density is at most `6K` (`K = 8` here: the cell's `n = 16` and the change band 6), far
/// below 100; and in the unit torus a solid of half its volume has area at least 2 (the
/// slab), so area 1 with fraction ½ is impossible.
#[test]
fn an_unreachable_target_stops_early_and_says_so() {
    let cell = fit(&Group::oh(), 16, &from_fn(wavy), &FitOptions::default())
        .unwrap()
        .offset(0.5);
    let max_frequency = cell
        .coefficients()
        .iter()
        .flat_map(|c| c.f)
        .map(i32::unsigned_abs)
        .max()
        .expect("coefficients")
        .max(6);
    assert!(6.0 * f64::from(max_frequency) < 100.0, "{max_frequency}");
    for (volume, area) in [(None, 100.0), (Some(0.5), 1.0)] {
        let t0 = std::time::Instant::now();
        let (opt, report) = cell
            .optimize_for(&targets(volume, Some(area), false))
            .unwrap();
        eprintln!(
            "unreachable {volume:?} {area}: {:?} {report:?}",
            t0.elapsed()
        );
        assert!(!report.converged && report.stalled, "{report:?}");
        // Stopped long before the 30 allowed.
        assert!(report.iterates.len() <= 8, "{report:?}");
        let reached = mesh_area(&opt, 49);
        assert!((reached - area).abs() > 0.5 * area, "{reached} vs {area}");
        assert!(
            (report.area_reached - reached).abs() <= 5e-2 * reached,
            "{report:?} vs {reached}"
        );
    }
}

/// The level-0 nodal surfaces' area densities (marching tetrahedra of [`measure`], 64³)
/// against the minimal surfaces' known values per unit cube (Schwarz P 2.3451, gyroid 3.0919,
/// Schwarz D 3.8377): the nodal approximations differ from them by a few tenths of a per
/// cent, and so do contoured meshes of the fits (a third computation, marching cubes).
#[test]
fn level_zero_surfaces_have_the_known_area_densities() {
    let identity = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
    let whole = Group::from_generators(3, &[identity]).unwrap();
    let p = |x: [f64; 3]| x.map(|v| (TAU * v).cos()).iter().sum::<f64>();
    let gyroid = |x: [f64; 3]| {
        let [s, c] = [x.map(|v| (TAU * v).sin()), x.map(|v| (TAU * v).cos())];
        s[0] * c[1] + s[1] * c[2] + s[2] * c[0]
    };
    let d = |x: [f64; 3]| {
        let [s, c] = [x.map(|v| (TAU * v).sin()), x.map(|v| (TAU * v).cos())];
        s[0] * s[1] * s[2] + s[0] * c[1] * c[2] + c[0] * s[1] * c[2] + c[0] * c[1] * s[2]
    };
    let cells = [
        (
            "P",
            fit(&Group::oh(), 32, &from_fn(p), &FitOptions::default()),
            2.3451,
        ),
        (
            "gyroid",
            fit(&whole, 32, &from_fn(gyroid), &FitOptions::default()),
            3.0919,
        ),
        (
            "D",
            fit(&whole, 32, &from_fn(d), &FitOptions::default()),
            3.8377,
        ),
    ];
    for (name, cell, known) in cells {
        let cell = cell.unwrap();
        let m = measure(&cell).unwrap();
        eprintln!("{name}: {m:?} (known {known})");
        assert!(
            (m.surface_area - known).abs() <= 1e-2 * known,
            "{name}: {m:?} vs {known}"
        );
        assert!((m.volume_fraction - 0.5).abs() <= 5e-3, "{name}: {m:?}");
        let contoured = mesh_area(&cell, 129);
        assert!(
            (contoured - known).abs() <= 1e-2 * known,
            "{name}: contoured {contoured} vs {known}"
        );
    }
}
