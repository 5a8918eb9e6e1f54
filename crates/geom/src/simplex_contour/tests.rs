//! The symmetric subdivision's output: symmetric under the element's group, faces exactly on
//! the element's planes, closed, and with the volume and pieces of the true solid.

use super::*;
use crate::validate::{check, components};
use std::f64::consts::TAU;

/// A field of the position, as the tests pass it around.
type Field3 = dyn Fn([f64; 3]) -> f64 + Sync;

/// A field given by a closure of the position.
struct FnField<F>(F);

impl<F: Fn([f64; 3]) -> f64 + Sync + Send> ScalarField for FnField<F> {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for (n, v) in out.iter_mut().enumerate() {
            *v = (self.0)([xs[n], ys[n], zs[n]]);
        }
    }
}

const TET: [[f64; 3]; 4] = [
    [-0.5, -0.5, -0.5],
    [0.5, 0.5, -0.5],
    [-0.5, 0.5, 0.5],
    [0.5, -0.5, 0.5],
];

/// Outward unit normals of the tetrahedron's faces; face `i` is `n·x = 1/(2√3)`.
fn tet_planes() -> [[f64; 3]; 4] {
    let s = 1.0 / 3f64.sqrt();
    [[s, s, s], [-s, -s, s], [s, -s, -s], [-s, s, -s]]
}

/// The 24 signed permutation matrices that map the tetrahedron's vertices onto themselves.
fn td_operators() -> Vec<[[f64; 3]; 3]> {
    let perms = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut ops = Vec::new();
    for p in perms {
        for signs in 0..8 {
            let s = |a: usize| if (signs >> a) & 1 == 1 { -1.0 } else { 1.0 };
            let m: [[f64; 3]; 3] = std::array::from_fn(|r| {
                std::array::from_fn(|c| if p[r] == c { s(r) } else { 0.0 })
            });
            let keeps = TET.iter().all(|v| {
                let w = apply3(&m, *v);
                TET.iter().any(|t| t == &w)
            });
            if keeps {
                ops.push(m);
            }
        }
    }
    ops
}

fn apply3(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

/// The largest distance from an image of a point to the nearest point of the set.
fn worst_image_gap<const D: usize>(points: &[[f64; D]], op: impl Fn([f64; D]) -> [f64; D]) -> f64 {
    let mut sorted: Vec<[f64; D]> = points.to_vec();
    sorted.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let mut worst: f64 = 0.0;
    for &p in points {
        let q = op(p);
        // Candidates within 1e-6 in x, then the nearest among them.
        let from = sorted.partition_point(|s| s[0] < q[0] - 1e-6);
        let best = sorted[from..]
            .iter()
            .take_while(|s| s[0] <= q[0] + 1e-6)
            .map(|s| (0..D).map(|d| (s[d] - q[d]).powi(2)).sum::<f64>().sqrt())
            .fold(f64::INFINITY, f64::min);
        worst = worst.max(best);
    }
    worst
}

/// The example's Td cell: `f = sin τx sin τy sin τz + 0.3 (cos τx + cos τy + cos τz)`.
fn td_cell(p: [f64; 3]) -> f64 {
    let t = p.map(|c| TAU * c);
    t[0].sin() * t[1].sin() * t[2].sin() + 0.3 * (t[0].cos() + t[1].cos() + t[2].cos())
}

/// A deterministic stream of numbers in [0, 1).
fn uniform(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    (*seed >> 11) as f64 / (1u64 << 53) as f64
}

/// Monte Carlo volume of `{f < 0}` in the tetrahedron (uniform barycentric points).
fn monte_carlo_volume(f: impl Fn([f64; 3]) -> f64, n: usize) -> f64 {
    let mut seed = 7;
    let mut hits = 0;
    for _ in 0..n {
        // Sorted uniforms give a uniform point of the simplex.
        let mut u = [uniform(&mut seed), uniform(&mut seed), uniform(&mut seed)];
        u.sort_by(f64::total_cmp);
        let w = [u[0], u[1] - u[0], u[2] - u[1], 1.0 - u[2]];
        let p: [f64; 3] = std::array::from_fn(|d| (0..4).map(|v| w[v] * TET[v][d]).sum());
        if f(p) < 0.0 {
            hits += 1;
        }
    }
    hits as f64 / n as f64 / 3.0
}

#[test]
fn tetrahedron_output_is_symmetric_under_td_closed_and_on_the_face_planes() {
    // The high side of the Td cell (one body reaching every face) and its low side (a piece
    // at each vertex) at two resolutions.
    let fields: [(&str, &Field3); 2] = [
        ("high", &|p| 0.4 - td_cell(p)),
        ("low", &|p| td_cell(p) - 0.1),
    ];
    let ops = td_operators();
    assert_eq!(ops.len(), 24);
    for (name, f) in fields {
        for cells in [16, 27] {
            let what = format!("{name} at {cells}");
            let out = contour_tetrahedron(&FnField(f), cells, &|_| {});
            let c = check(&out.mesh);
            assert!(
                c.watertight && c.manifold && c.volume > 0.0,
                "{what}: {c:?}"
            );
            for op in &ops {
                let gap = worst_image_gap(&out.positions, |p| apply3(op, p));
                assert!(gap < 1e-9, "{what}: image under {op:?} is {gap} off");
            }
            // Every vertex is inside the element; one near a face plane is on it (no
            // sawtooth): off a plane a crossing is at least 1/256 of an edge away.
            let h = 1.0 / cells as f64;
            for p in &out.positions {
                for n in tet_planes() {
                    let d = n[0] * p[0] + n[1] * p[1] + n[2] * p[2] - 0.5 / 3f64.sqrt();
                    assert!(d < 1e-12, "{what}: vertex {p:?} outside by {d}");
                    assert!(
                        d > -1e-12 || d < -h / 1000.0,
                        "{what}: {p:?} {d} off a face"
                    );
                }
            }
            let exact = monte_carlo_volume(f, 400_000);
            let error = (c.volume - exact).abs() / exact;
            assert!(
                error < 0.02,
                "{what}: volume {} vs Monte Carlo {exact}",
                c.volume
            );
        }
    }
}

#[test]
fn tetrahedron_pieces_match_the_true_solid() {
    // The high side is one body; the low side is one piece per vertex; balls at the vertices
    // smaller than a cell are each found, as the vertices are nodes.
    let high = contour_tetrahedron(&FnField(|p| 0.4 - td_cell(p)), 20, &|_| {});
    assert_eq!(components(&high.mesh), 1);
    let low = contour_tetrahedron(&FnField(|p| td_cell(p) - 0.1), 20, &|_| {});
    assert_eq!(components(&low.mesh), 4);
    let corners = |p: [f64; 3]| {
        let d = TET
            .iter()
            .map(|v| (0..3).map(|a| (p[a] - v[a]).powi(2)).sum::<f64>().sqrt())
            .fold(f64::INFINITY, f64::min);
        d - 0.02
    };
    let tiny = contour_tetrahedron(&FnField(corners), 20, &|_| {});
    assert_eq!(components(&tiny.mesh), 4);
    assert!(check(&tiny.mesh).watertight);
}

#[test]
fn constant_inside_gives_the_tetrahedron() {
    for cells in [1, 2, 3, 9] {
        let out = contour_tetrahedron(&FnField(|_| -1.0), cells, &|_| {});
        let c = check(&out.mesh);
        assert!(c.watertight && c.manifold, "{cells}: {c:?}");
        assert!((c.volume * 3.0 - 1.0).abs() < 1e-6, "{cells}: {}", c.volume);
    }
}

/// The six operators of D3 on the plane: rotations by a third of a turn and mirrors.
fn d3_operators() -> Vec<[[f64; 2]; 2]> {
    (0..3)
        .flat_map(|k| {
            let (s, c) = (TAU * k as f64 / 3.0).sin_cos();
            [[[c, -s], [s, c]], [[-c, -s], [-s, c]]]
        })
        .collect()
}

fn apply2(m: &[[f64; 2]; 2], v: [f64; 2]) -> [f64; 2] {
    [
        m[0][0] * v[0] + m[0][1] * v[1],
        m[1][0] * v[0] + m[1][1] * v[1],
    ]
}

/// The triangle's vertices.
const TRI: [[f64; 2]; 3] = [
    [-0.5, -SQRT3 / 6.0],
    [0.5, -SQRT3 / 6.0],
    [0.0, SQRT3 / 3.0],
];

/// A D3-symmetric planar field: the example's `cos 2τx + cos 2τy − 0.3` averaged over D3.
fn d3_cell(p: [f64; 2]) -> f64 {
    d3_operators()
        .iter()
        .map(|m| {
            let q = apply2(m, p);
            (2.0 * TAU * q[0]).cos() + (2.0 * TAU * q[1]).cos()
        })
        .sum::<f64>()
        / 6.0
        - 0.3
}

#[test]
fn triangle_output_is_symmetric_under_d3_and_exact_on_its_sides() {
    for cells in [16, 33, 64] {
        let out = contour_triangle(&d3_cell, cells);
        for op in d3_operators() {
            let gap = worst_image_gap(&out.positions, |p| apply2(&op, p));
            assert!(gap < 1e-9, "{cells}: image under {op:?} is {gap} off");
        }
        // Every vertex is inside; near a side means on it.
        let h = 1.0 / cells as f64;
        let normals = [[0.0, -1.0], [SQRT3 / 2.0, 0.5], [-SQRT3 / 2.0, 0.5]];
        for p in &out.positions {
            for n in normals {
                let d = n[0] * p[0] + n[1] * p[1] - SQRT3 / 6.0;
                assert!(d < 1e-12, "{cells}: {p:?} outside by {d}");
                assert!(
                    d > -1e-12 || d < -h / 1000.0,
                    "{cells}: {p:?} {d} off a side"
                );
            }
        }
        // The bounding box is symmetric about x = 0.
        let (lo, hi) = out
            .positions
            .iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), p| {
                (lo.min(p[0]), hi.max(p[0]))
            });
        assert!((lo + hi).abs() < 1e-12, "{cells}: x from {lo} to {hi}");
    }
}

#[test]
fn triangle_corner_pieces_come_in_threes() {
    // Discs at the vertices smaller than a cell: three pieces, where a lattice from one
    // vertex saw only the piece at its own node.
    let corners = |p: [f64; 2]| {
        TRI.iter()
            .map(|v| (p[0] - v[0]).hypot(p[1] - v[1]))
            .fold(f64::INFINITY, f64::min)
            - 0.01
    };
    let out = contour_triangle(&corners, 40);
    assert_eq!(components(&out.mesh), 3);
    let area: f64 = out
        .mesh
        .triangles
        .iter()
        .map(|t| {
            let p = |v: u32| out.positions[v as usize];
            let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
            0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
        })
        .sum();
    // Three sixths of a disc of radius 0.01; the crossings are linear along rays, so the arcs
    // are chords of the circle (a few per cent short at this resolution).
    let exact = 0.5 * std::f64::consts::PI * 1e-4;
    assert!(
        area > 0.0 && (area - exact).abs() / exact < 0.2,
        "area {area} vs {exact}"
    );
}
