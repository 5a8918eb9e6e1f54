//! The reference elements and shape functions of every scaffold kind: partition of unity,
//! N_i(node_j) = δ_ij, gradients against finite differences, docs/method.md's reference domains,
//! outward faces, and exact quadrature.

#![allow(clippy::needless_range_loop)] // index loops mirror the formulas (ξ_a, node i)

use latticebuild_geom::scaffold::{ElementKind, Quadrature};

/// Deterministic points inside each reference element.
fn sample_points(kind: ElementKind) -> Vec<[f64; 3]> {
    let mut points = Vec::new();
    let mut state = 0x1234_5678_9abc_def0u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let corners: Vec<[f64; 3]> = (0..kind.corner_count())
        .map(|i| kind.reference_node(i))
        .collect();
    for _ in 0..20 {
        let p = if kind.is_simplex() {
            // A random convex combination of the corners.
            let mut w: Vec<f64> = corners.iter().map(|_| next() + 0.01).collect();
            let s: f64 = w.iter().sum();
            w.iter_mut().for_each(|v| *v /= s);
            let mut p = [0.0; 3];
            for (c, wi) in corners.iter().zip(&w) {
                for a in 0..3 {
                    p[a] += wi * c[a];
                }
            }
            p
        } else {
            let z = if kind.dimension() == 3 {
                next() - 0.5
            } else {
                0.0
            };
            [next() - 0.5, next() - 0.5, z]
        };
        points.push(p);
    }
    points
}

#[test]
fn node_counts_names_and_gmsh_types_are_gmsh_s() {
    let table = [
        (ElementKind::Tri3, "tri3", 3, 3, 2, 2),
        (ElementKind::Tri6, "tri6", 6, 3, 2, 9),
        (ElementKind::Quad4, "quad4", 4, 4, 2, 3),
        (ElementKind::Quad8, "quad8", 8, 4, 2, 16),
        (ElementKind::Quad9, "quad9", 9, 4, 2, 10),
        (ElementKind::Tet4, "tet4", 4, 4, 3, 4),
        (ElementKind::Tet10, "tet10", 10, 4, 3, 11),
        (ElementKind::Hex8, "hex8", 8, 8, 3, 5),
        (ElementKind::Hex20, "hex20", 20, 8, 3, 17),
        (ElementKind::Hex27, "hex27", 27, 8, 3, 12),
    ];
    for (kind, name, nodes, corners, dim, gmsh) in table {
        assert_eq!(kind.name(), name);
        assert_eq!(kind.node_count(), nodes);
        assert_eq!(kind.corner_count(), corners);
        assert_eq!(kind.dimension(), dim);
        assert_eq!(kind.gmsh_type(), gmsh);
        assert_eq!(ElementKind::from_gmsh_type(gmsh), Some(kind));
        assert_eq!(
            kind.is_simplex(),
            name.starts_with("tri") || name.starts_with("tet")
        );
    }
}

#[test]
fn reference_elements_are_method_s_cell_domains() {
    let s3 = 3f64.sqrt();
    let tri = [
        [-0.5, -s3 / 6.0, 0.0],
        [0.5, -s3 / 6.0, 0.0],
        [0.0, s3 / 3.0, 0.0],
    ];
    let tet = [
        [-0.5, -0.5, -0.5],
        [0.5, 0.5, -0.5],
        [-0.5, 0.5, 0.5],
        [0.5, -0.5, 0.5],
    ];
    for i in 0..3 {
        for a in 0..3 {
            assert!((ElementKind::Tri6.reference_node(i)[a] - tri[i][a]).abs() < 1e-15);
        }
    }
    for i in 0..4 {
        assert_eq!(ElementKind::Tet10.reference_node(i), tet[i]);
    }
    // Gmsh hex corner order at ±½.
    let hex = [
        [-1., -1., -1.],
        [1., -1., -1.],
        [1., 1., -1.],
        [-1., 1., -1.],
        [-1., -1., 1.],
        [1., -1., 1.],
        [1., 1., 1.],
        [-1., 1., 1.],
    ];
    for i in 0..8 {
        assert_eq!(
            ElementKind::Hex27.reference_node(i),
            hex[i].map(|c| c * 0.5)
        );
    }
    for i in 0..4 {
        let q = ElementKind::Quad9.reference_node(i);
        assert_eq!(q, [hex[i][0] * 0.5, hex[i][1] * 0.5, 0.0]);
    }
    // Tet orientation: det[p1-p0, p2-p0, p3-p0] = 2.
    let d = |i: usize, a: usize| tet[i][a] - tet[0][a];
    let det = d(1, 0) * (d(2, 1) * d(3, 2) - d(2, 2) * d(3, 1))
        - d(1, 1) * (d(2, 0) * d(3, 2) - d(2, 2) * d(3, 0))
        + d(1, 2) * (d(2, 0) * d(3, 1) - d(2, 1) * d(3, 0));
    assert_eq!(det, 2.0);
    // Mid-edge nodes: tet10 edges 01,12,20,30,23,31; hex20 edge 4 is 1-5, hex27 node 20 is the
    // centre of face 0123, node 26 the centre.
    assert_eq!(ElementKind::Tet10.reference_node(8), [0.0, 0.0, 0.5]);
    assert_eq!(ElementKind::Tet10.reference_node(9), [0.5, 0.0, 0.0]);
    assert_eq!(ElementKind::Hex20.reference_node(12), [0.5, -0.5, 0.0]);
    assert_eq!(ElementKind::Hex27.reference_node(20), [0.0, 0.0, -0.5]);
    assert_eq!(ElementKind::Hex27.reference_node(26), [0.0, 0.0, 0.0]);
    assert_eq!(ElementKind::Quad8.reference_node(7), [-0.5, 0.0, 0.0]);
    // Reference centres are 0.
    for kind in ElementKind::ALL {
        let c = kind.corner_count() as f64;
        for a in 0..3 {
            let mean: f64 = (0..kind.corner_count())
                .map(|i| kind.reference_node(i)[a])
                .sum::<f64>()
                / c;
            assert!(mean.abs() < 1e-15, "{kind}");
        }
    }
}

#[test]
fn shape_functions_interpolate_the_nodes_and_sum_to_one() {
    for kind in ElementKind::ALL {
        let n = kind.node_count();
        let mut values = vec![0.0; n];
        for j in 0..n {
            kind.shape(kind.reference_node(j), &mut values);
            for (i, &v) in values.iter().enumerate() {
                let expected = if i == j { 1.0 } else { 0.0 };
                assert!(
                    (v - expected).abs() < 1e-14,
                    "{kind}: N_{i}(node {j}) = {v}"
                );
            }
        }
        for p in sample_points(kind) {
            kind.shape(p, &mut values);
            let sum: f64 = values.iter().sum();
            assert!((sum - 1.0).abs() < 1e-14, "{kind}: sum {sum}");
            // They also reproduce linear functions: Σ N_i x_i = x.
            for a in 0..kind.dimension() {
                let x: f64 = (0..n).map(|i| values[i] * kind.reference_node(i)[a]).sum();
                assert!((x - p[a]).abs() < 1e-14, "{kind}: reproduces ξ_{a}");
            }
        }
    }
}

#[test]
fn shape_values_alone_are_bitwise_those_evaluated_with_gradients() {
    for kind in ElementKind::ALL {
        let n = kind.node_count();
        for p in sample_points(kind) {
            let (mut alone, mut with, mut grad) = (vec![0.0; n], vec![0.0; n], vec![[0.0; 3]; n]);
            kind.shape(p, &mut alone);
            kind.evaluate(p, &mut with, &mut grad);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&alone), bits(&with), "{kind} at {p:?}");
        }
    }
}

#[test]
fn gradients_match_finite_differences() {
    let h = 1e-6;
    for kind in ElementKind::ALL {
        let n = kind.node_count();
        let mut grad = vec![[0.0; 3]; n];
        let (mut plus, mut minus) = (vec![0.0; n], vec![0.0; n]);
        for p in sample_points(kind) {
            kind.shape_gradients(p, &mut grad);
            for a in 0..3 {
                let mut pp = p;
                let mut pm = p;
                pp[a] += h;
                pm[a] -= h;
                kind.shape(pp, &mut plus);
                kind.shape(pm, &mut minus);
                for i in 0..n {
                    let fd = if a < kind.dimension() {
                        (plus[i] - minus[i]) / (2.0 * h)
                    } else {
                        0.0
                    };
                    assert!(
                        (grad[i][a] - fd).abs() < 1e-7,
                        "{kind}: dN_{i}/dξ_{a} = {} against {fd}",
                        grad[i][a]
                    );
                }
            }
            // Gradients of a partition of unity sum to zero.
            for a in 0..3 {
                let s: f64 = grad.iter().map(|g| g[a]).sum();
                assert!(s.abs() < 1e-13, "{kind}");
            }
        }
    }
}

#[test]
fn faces_point_out_of_the_element_and_edges_are_corner_pairs() {
    for kind in ElementKind::ALL {
        let corner = |i: usize| kind.reference_node(i);
        for face in kind.faces() {
            let c: Vec<[f64; 3]> = face.iter().map(|&i| corner(i)).collect();
            let centre: [f64; 3] =
                [0, 1, 2].map(|a| c.iter().map(|p| p[a]).sum::<f64>() / c.len() as f64);
            let normal = if kind.dimension() == 3 {
                let u = [0, 1, 2].map(|a| c[1][a] - c[0][a]);
                let v = [0, 1, 2].map(|a| c[2][a] - c[0][a]);
                [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ]
            } else {
                // edge direction × +z
                let d = [0, 1, 2].map(|a| c[1][a] - c[0][a]);
                [d[1], -d[0], 0.0]
            };
            let out: f64 = (0..3).map(|a| normal[a] * centre[a]).sum();
            assert!(out > 0.0, "{kind} face {face:?}");
        }
        assert_eq!(
            kind.faces().len(),
            match kind.corner_count() {
                3 => 3,
                4 if kind.dimension() == 2 => 4,
                4 => 4,
                _ => 6,
            }
        );
        // Each quadratic mid-edge node is the midpoint of its edge.
        let c = kind.corner_count();
        if kind.node_count() > c {
            for (j, &[a, b]) in kind.edges().iter().enumerate() {
                let m = kind.reference_node(c + j);
                for k in 0..3 {
                    assert!((m[k] - (corner(a)[k] + corner(b)[k]) / 2.0).abs() < 1e-15);
                }
            }
        }
    }
}

#[test]
fn quadrature_integrates_polynomials_exactly() {
    // Measures of the reference elements, and ∫ ξ_0² against independent values: cube/square
    // 1/12; the tetrahedron ∫x² = V(Σ x_i² + (Σ x_i)²)/20 over its vertices; the triangle
    // ∫x² = A(Σ x_i² + (Σ x_i)²)/12.
    let s3 = 3f64.sqrt();
    for (kind, measure, second) in [
        (ElementKind::Hex8, 1.0, 1.0 / 12.0),
        (ElementKind::Quad4, 1.0, 1.0 / 12.0),
        (
            ElementKind::Tet4,
            1.0 / 3.0,
            (1.0 / 3.0) * (4.0 * 0.25) / 20.0,
        ),
        (
            ElementKind::Tri3,
            s3 / 4.0,
            (s3 / 4.0) * (0.25 + 0.25) / 12.0,
        ),
    ] {
        // Collapsed rules carry the Duffy factor (1-u)²(1-v): x² needs 3 points per direction.
        for n in [3, 4, 8] {
            let q = Quadrature::new(kind, n);
            let m: f64 = q.weights.iter().sum();
            assert!((m - measure).abs() < 1e-14, "{kind} n={n}: {m}");
            let x2: f64 = q
                .points
                .iter()
                .zip(&q.weights)
                .map(|(p, w)| w * p[0] * p[0])
                .sum();
            assert!(
                (x2 - second).abs() < 1e-14,
                "{kind} n={n}: {x2} against {second}"
            );
        }
    }
}
