//! Marching tetrahedra against independent checks: closedness (the edge and vertex-link check
//! of the marching cubes tests) on random fields, volumes against analytic values and against
//! marching cubes on the same samples.

use std::f64::consts::PI;

use super::tests::{FnSampler, assert_closed_manifold, noise, run, tpms, volume};
use super::*;
use crate::field::{Grid, ScalarField};

fn tetra(grid: Grid, f: impl Fn([f64; 3]) -> f64 + Sync) -> Mesh {
    contour_tetrahedra(&FnSampler { grid, f }, &grid, &|_| {}).expect("contour")
}

fn ball(r: f64) -> impl Fn([f64; 3]) -> f64 + Sync {
    move |p: [f64; 3]| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() - r
}

#[test]
fn random_fields_give_closed_manifold_surfaces() {
    for (seed, counts) in [
        (1, [5, 4, 3]),
        (2, [9, 7, 20]),
        (3, [2, 2, 2]),
        (4, [17, 3, 11]),
    ] {
        let grid = Grid::spanning([0.0; 3], [1.0, 2.0, 3.0], counts);
        let h = grid.spacing;
        let mesh = tetra(grid, |p| {
            let idx = |a: usize| (p[a] / h[a]).round() as i64;
            noise(idx(0), idx(1), idx(2), seed)
        });
        assert!(!mesh.is_empty());
        assert_closed_manifold(&mesh);
        assert!(volume(&mesh) > 0.0, "seed {seed}: outward orientation");
    }
}

#[test]
fn linear_fields_and_full_boxes_are_exact() {
    // Linear interpolation reproduces a plane exactly: z < 0.312 − 0.01 x.
    let grid = Grid::spanning([0.0; 3], [1.0; 3], [11, 12, 41]);
    let mesh = tetra(grid, |p| p[2] - 0.312 + 0.01 * p[0]);
    assert_eq!(assert_closed_manifold(&mesh), 2);
    assert!((volume(&mesh) - 0.307).abs() < 1e-6, "{}", volume(&mesh));
    let grid = Grid::spanning([0.0; 3], [2.0, 3.0, 4.0], [5, 6, 7]);
    let full = tetra(grid, |_| -1.0);
    assert_eq!(assert_closed_manifold(&full), 2);
    assert!((volume(&full) - 24.0).abs() < 1e-5);
    // Exact zeros on whole planes still give distinct vertices.
    let grid = Grid::spanning([-1.0; 3], [1.0; 3], [9, 9, 9]);
    assert_closed_manifold(&tetra(grid, |p| {
        (p[0] * 4.0).round() * (p[1] * 4.0).round()
    }));
}

#[test]
fn sphere_volume_matches_the_analytic_one_and_marching_cubes() {
    let r = 0.7;
    let exact = 4.0 / 3.0 * PI * r * r * r;
    let mut errors = Vec::new();
    for n in [21, 41, 81] {
        let grid = Grid::spanning([-1.0; 3], [1.0; 3], [n; 3]);
        let mesh = tetra(grid, ball(r));
        assert_eq!(assert_closed_manifold(&mesh), 2, "one sphere: genus 0");
        let cubes = volume(&run(grid, ball(r)));
        let v = volume(&mesh);
        let h = 2.0 / (n - 1) as f64;
        // Chords cut inside a convex surface: below the sphere, by O(h²) of its area.
        assert!(
            v < exact && exact - v < 0.5 * h * h * 4.0 * PI * r * r,
            "{n}: {v}"
        );
        assert!(
            (v - cubes).abs() < 0.5 * h * h * 4.0 * PI * r * r,
            "{n}: {v} vs {cubes}"
        );
        errors.push(exact - v);
    }
    // Second order: halving the spacing quarters the error (within a margin).
    assert!(
        errors[1] < errors[0] / 3.0 && errors[2] < errors[1] / 3.0,
        "{errors:?}"
    );
}

#[test]
fn a_ball_cut_by_the_box_is_capped() {
    let r = 0.8;
    let grid = Grid::spanning([0.0; 3], [1.0; 3], [61, 61, 61]);
    let mesh = tetra(grid, ball(r));
    assert_eq!(assert_closed_manifold(&mesh), 2);
    let exact = 4.0 / 3.0 * PI * r * r * r / 8.0;
    assert!((volume(&mesh) - exact).abs() < 2e-3, "{}", volume(&mesh));
}

#[test]
fn gyroid_is_closed_and_half_the_box() {
    // The gyroid at level 0 splits its cell into two congruent halves; capped on a period
    // moved off the symmetry planes, the solid is half the box.
    let g = tpms("gyroid");
    let f = |p: [f64; 3]| {
        let mut v = [0.0];
        g.eval_points(&[p[0]], &[p[1]], &[p[2]], &mut v);
        v[0]
    };
    let grid = Grid::spanning([0.1, 0.2, 0.3], [1.1, 1.2, 1.3], [41; 3]);
    let mesh = tetra(grid, f);
    let cubes_mesh = run(grid, f);
    // The same topology as marching cubes finds on these samples.
    assert_eq!(
        assert_closed_manifold(&mesh),
        assert_closed_manifold(&cubes_mesh)
    );
    let v = volume(&mesh);
    let cubes = volume(&cubes_mesh);
    assert!((v - 0.5).abs() < 2e-3, "{v}");
    assert!((v - cubes).abs() < 2e-3, "{v} vs {cubes}");
    // The diagonals cut the surface too: more triangles than marching cubes.
    assert!(mesh.triangles.len() > cubes_mesh.triangles.len());
}
