//! The shape-function numerators against independent values (the floating-point shape
//! functions of `scaffold::element`, analytic quadratic fields, the old corner weights), in
//! exact integers where the claim is exact; and on real scaffolds: bitwise equal graded and
//! transition values from both sides of every shared face or edge, watertight tilings with
//! quadratic grading, the clamp of overshooting weights and the error on a thickness that
//! dips to ≤ 0.

use super::super::cube::CubeLattice;
use super::super::lattice::Lattice;
use super::super::simplex::TetLattice;
use super::super::square::SquareLattice;
use super::super::triangle::TriangleLattice;
use super::super::{
    ElementSamples, TileError, TiledSolid, Transition, extrude, symmetric_samples, tile_scaffold,
    tile_surface_scaffold,
};
use super::*;
use crate::field::{ScalarField, Solid};
use crate::scaffold::{Scaffold, grid, read_scaffold};
use crate::validate::check;
use std::collections::HashMap;

fn lattice(kind: ElementKind, n: usize) -> Box<dyn Lattice> {
    match (kind.dimension(), kind.is_simplex()) {
        (3, false) => Box::new(CubeLattice::new(n)),
        (3, true) => Box::new(TetLattice::new(n)),
        (_, false) => Box::new(SquareLattice::new(n)),
        _ => Box::new(TriangleLattice::new(n)),
    }
}

fn points(lattice: &dyn Lattice) -> impl Iterator<Item = u32> + '_ {
    (0..lattice.index_len() as u32).filter(|&p| lattice.is_point(p))
}

/// The corners a node is the midpoint of (itself for a corner; its edge's, face's or all the
/// element's corners for a mid-edge, mid-face or centre node).
fn support(kind: ElementKind, i: usize) -> Vec<usize> {
    let corners = kind.corner_count();
    if i < corners {
        return vec![i];
    }
    if kind.is_simplex() {
        return kind.edges()[i - corners].to_vec();
    }
    let s = |j: usize| kind.reference_node(j).map(|x| (2.0 * x).round() as i8);
    let node = s(i);
    (0..corners)
        .filter(|&c| (0..kind.dimension()).all(|a| node[a] == 0 || s(c)[a] == node[a]))
        .collect()
}

#[test]
fn numerators_are_a_partition_of_unity_in_integers() {
    for kind in ElementKind::ALL {
        for n in [2, 3, 4, 5, 8, 13] {
            let lattice = lattice(kind, n);
            let shape = Shape::new(kind, n as u32 - 1);
            let mut out = [0; MAX_NODES];
            for p in points(lattice.as_ref()) {
                shape.numerators(&shape.point(&lattice.weights(p)), &mut out);
                let sum: i64 = out[..kind.node_count()].iter().sum();
                assert_eq!(sum, shape.denominator(), "{kind} n = {n} point {p}");
            }
        }
    }
}

#[test]
fn numerators_at_the_largest_resolution_stay_exact_in_f64() {
    // m = 255: D = m⁶ for hex27 and the largest |n| (5m⁴ for hex20 corners, m⁶ for hex27)
    // are below 2⁵³; the partition of unity still holds exactly.
    let m = 255i64;
    let axis = [0, 1, 64, 127, 128, 200, 254, 255];
    for kind in [ElementKind::Hex27, ElementKind::Hex20, ElementKind::Tet10] {
        let shape = Shape::new(kind, m as u32);
        assert!(shape.denominator() < 1 << 53, "{kind}");
        let mut out = [0; MAX_NODES];
        for &x in &axis {
            for &y in &axis {
                for &z in &axis {
                    let point = if kind.is_simplex() {
                        if x + y + z > m {
                            continue;
                        }
                        Point([m - x - y - z, x, y, z])
                    } else {
                        Point([x, y, z, 0])
                    };
                    shape.numerators(&point, &mut out);
                    let numerators = &out[..kind.node_count()];
                    assert!(numerators.iter().all(|n| n.abs() < 1 << 53), "{kind}");
                    assert_eq!(numerators.iter().sum::<i64>(), shape.denominator());
                }
            }
        }
    }
}

#[test]
fn numerators_over_the_denominator_are_the_elements_shape_functions() {
    // Independent values: `ElementKind::shape` in floating point at the lattice's ξ.
    for kind in ElementKind::ALL {
        for n in [2, 3, 6, 9] {
            let lattice = lattice(kind, n);
            let shape = Shape::from_weights(kind, &lattice.weights(0));
            assert_eq!(shape, Shape::new(kind, n as u32 - 1));
            let (mut out, mut float) = ([0; MAX_NODES], [0.0; MAX_NODES]);
            for p in points(lattice.as_ref()) {
                shape.numerators(&shape.point(&lattice.weights(p)), &mut out);
                kind.shape(lattice.xi(p), &mut float);
                for i in 0..kind.node_count() {
                    let exact = out[i] as f64 / shape.denominator() as f64;
                    assert!(
                        (exact - float[i]).abs() < 1e-13,
                        "{kind} n = {n} point {p} node {i}: {exact} vs {}",
                        float[i]
                    );
                }
            }
        }
    }
}

#[test]
fn linear_numerators_are_the_corner_weights() {
    for kind in [
        ElementKind::Tri3,
        ElementKind::Quad4,
        ElementKind::Tet4,
        ElementKind::Hex8,
    ] {
        for n in [2, 5, 11] {
            let lattice = lattice(kind, n);
            let shape = Shape::new(kind, n as u32 - 1);
            let mut out = [0; MAX_NODES];
            for p in points(lattice.as_ref()) {
                let weights = lattice.weights(p);
                shape.numerators(&shape.point(&weights), &mut out);
                let mut expected = [0; MAX_NODES];
                for &(c, w) in weights.as_slice() {
                    expected[c as usize] = i64::from(w);
                }
                assert_eq!(out, expected, "{kind} n = {n} point {p}");
            }
        }
    }
}

#[test]
fn nodes_off_a_face_have_zero_numerators_on_it() {
    for kind in ElementKind::ALL {
        for n in [2, 3, 4, 7] {
            let lattice = lattice(kind, n);
            let shape = Shape::new(kind, n as u32 - 1);
            let mut out = [0; MAX_NODES];
            let (mut checked, mut on_face_nonzero) = (0usize, 0usize);
            for &face in lattice.face_masks() {
                let off: Vec<usize> = (0..kind.node_count())
                    .filter(|&i| support(kind, i).iter().any(|&c| face & 1 << c == 0))
                    .collect();
                for p in points(lattice.as_ref()) {
                    let weights = lattice.weights(p);
                    if weights.mask() & !face != 0 {
                        continue;
                    }
                    shape.numerators(&shape.point(&weights), &mut out);
                    for (i, &numerator) in out.iter().enumerate().take(kind.node_count()) {
                        if off.contains(&i) {
                            checked += 1;
                            assert_eq!(numerator, 0, "{kind} n = {n} face {face:b} node {i}");
                        } else if numerator != 0 && i >= kind.corner_count() {
                            on_face_nonzero += 1;
                        }
                    }
                }
            }
            assert!(checked > 0, "{kind}");
            // The face's own mid-edge/face nodes do take part once there are interior face points.
            if kind.order() == 2 && n > 2 {
                assert!(on_face_nonzero > 0, "{kind} n = {n}");
            }
        }
    }
}

#[test]
fn interpolants_stay_above_the_undershoot_bound() {
    // Pseudo-random nodal values in [0.1, 1.1]: every interpolant is at least
    // lo − (hi − lo)·undershoot, and the bound is attained closely for the quadratic kinds.
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        0.1 + (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    for kind in ElementKind::ALL {
        let n = 7;
        let lattice = lattice(kind, n);
        let shape = Shape::new(kind, n as u32 - 1);
        let all: Vec<Point> = points(lattice.as_ref())
            .map(|p| shape.point(&lattice.weights(p)))
            .collect();
        let undershoot = shape.undershoot(all.iter().copied());
        if kind.order() == 1 {
            assert_eq!(undershoot, 0.0, "{kind}");
        } else {
            assert!(undershoot > 0.05, "{kind}: {undershoot}");
        }
        let mut out = [0; MAX_NODES];
        for _ in 0..50 {
            let values: Vec<f64> = (0..kind.node_count()).map(|_| next()).collect();
            let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = values.iter().copied().fold(0.0, f64::max);
            for point in &all {
                shape.numerators(point, &mut out);
                let v = interpolate(&out[..kind.node_count()], &values, shape.denominator());
                assert!(v >= lo - (hi - lo) * undershoot - 1e-14, "{kind}: {v}");
            }
        }
    }
}

/// `x² + yz + xy − 0.3x + 0.1`: quadratic, so reproduced exactly by every quadratic kind on
/// affine elements.
fn quadratic(p: [f64; 3]) -> f64 {
    let [x, y, z] = p;
    x * x + y * z + x * y - 0.3 * x + 0.1
}

/// A shear with determinant 1: elements of a box grid become affine, not boxes.
fn shear([x, y, z]: [f64; 3]) -> [f64; 3] {
    [x + 0.3 * y + 0.1 * z, y + 0.2 * z, z]
}

/// A linear grid scaffold of the unit box made quadratic (`kind`), with straight sides: each
/// extra node is the midpoint of its support corners, shared by every element with the same
/// support. The grid's nodes are first moved by the affine `map`.
fn straight_quadratic(
    kind: ElementKind,
    divisions: [usize; 3],
    map: fn([f64; 3]) -> [f64; 3],
) -> Scaffold {
    let linear =
        grid([0.0; 3], [1.0, 1.0, 1.0], divisions, kind.linear()).unwrap_or_else(|e| panic!("{e}"));
    let mut nodes: Vec<[f64; 3]> = linear.nodes.iter().map(|&p| map(p)).collect();
    let mut ids: HashMap<Vec<u32>, u32> = HashMap::new();
    let mut connectivity = Vec::new();
    for e in 0..linear.element_count() {
        let corners = linear.element(e);
        for i in 0..kind.node_count() {
            let mut key: Vec<u32> = support(kind, i).iter().map(|&c| corners[c]).collect();
            if key.len() == 1 {
                connectivity.push(key[0]);
                continue;
            }
            key.sort_unstable();
            let id = *ids.entry(key.clone()).or_insert_with(|| {
                let mut p = [0.0; 3];
                for &c in &key {
                    for a in 0..3 {
                        p[a] += nodes[c as usize][a] / key.len() as f64;
                    }
                }
                nodes.push(p);
                nodes.len() as u32 - 1
            });
            connectivity.push(id);
        }
    }
    Scaffold {
        kind,
        node_tags: (1..=nodes.len() as u64).collect(),
        nodes,
        connectivity,
        ..linear
    }
}

fn nodal(scaffold: &Scaffold, f: impl Fn([f64; 3]) -> f64) -> Vec<f64> {
    scaffold.nodes.iter().map(|&p| f(p)).collect()
}

/// `values` interpolated at lattice point `p` of element `e` (the tiler's own arithmetic).
fn interpolated(
    scaffold: &Scaffold,
    shape: &Shape,
    lattice: &dyn Lattice,
    e: usize,
    p: u32,
    values: &[f64],
) -> f64 {
    let nodes = scaffold.element(e);
    let order = Order::of(nodes);
    let mut out = [0; MAX_NODES];
    shape.numerators(&shape.point(&lattice.weights(p)), &mut out);
    let n = order.arrange(&out);
    interpolate(
        &n[..order.len()],
        &order.gather(nodes, values),
        shape.denominator(),
    )
}

#[test]
fn quadratic_fields_are_reproduced_on_straight_quadratic_elements() {
    for kind in [
        ElementKind::Tet10,
        ElementKind::Hex20,
        ElementKind::Hex27,
        ElementKind::Tri6,
        ElementKind::Quad8,
        ElementKind::Quad9,
    ] {
        let scaffold = straight_quadratic(kind, [2, 2, 2], shear);
        let values = nodal(&scaffold, quadratic);
        let scale = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let n = 7;
        let lattice = lattice(kind, n);
        let shape = Shape::new(kind, n as u32 - 1);
        let (mut worst, mut worst_linear) = (0.0f64, 0.0f64);
        for e in 0..scaffold.element_count() {
            for p in points(lattice.as_ref()) {
                let xi = lattice.xi(p);
                let exact = quadratic(scaffold.map(e, xi));
                let got = interpolated(&scaffold, &shape, lattice.as_ref(), e, p, &values);
                worst = worst.max((got - exact).abs() / scale);
                // What the corner weights alone gave: visibly not the field.
                let w = lattice.weights(p);
                let total: u32 = w.as_slice().iter().map(|&(_, k)| k).sum();
                let corners = scaffold.element(e);
                let linear: f64 = w
                    .as_slice()
                    .iter()
                    .map(|&(c, k)| f64::from(k) * values[corners[c as usize] as usize])
                    .sum::<f64>()
                    / f64::from(total);
                worst_linear = worst_linear.max((linear - exact).abs() / scale);
            }
        }
        assert!(worst < 1e-12, "{kind}: relative error {worst:e}");
        assert!(
            worst_linear > 1e-3,
            "{kind}: corners alone {worst_linear:e}"
        );
    }
}

#[test]
fn linear_elements_interpolate_bitwise_as_by_their_corner_weights() {
    // The corner-weight formula the tiler used before quadratic interpolation: sorted
    // `(global node, weight)` pairs, Σ w v / Σ w.
    for (file, n) in [
        ("bracket_tet4_weight.msh", 6),
        ("cylinder_r5h20_hex8.msh", 5),
        ("plate_hole_tri3.msh", 7),
        ("plate_hole_quad4.msh", 6),
    ] {
        let scaffold = read(file);
        let values = nodal(&scaffold, |p| (0.37 * p[0]).sin() + 0.1 * p[1] * p[2]);
        let lattice = lattice(scaffold.kind, n);
        let shape = Shape::new(scaffold.kind, n as u32 - 1);
        for e in 0..scaffold.element_count().min(300) {
            let corners = scaffold.element(e);
            for p in points(lattice.as_ref()) {
                let mut terms: Vec<(u32, u32)> = lattice
                    .weights(p)
                    .as_slice()
                    .iter()
                    .map(|&(c, w)| (corners[c as usize], w))
                    .collect();
                terms.sort_unstable();
                let (sum, total) = terms.iter().fold((0.0, 0u32), |(s, t), &(node, w)| {
                    (s + f64::from(w) * values[node as usize], t + w)
                });
                let old = sum / f64::from(total);
                let new = interpolated(&scaffold, &shape, lattice.as_ref(), e, p, &values);
                assert_eq!(old.to_bits(), new.to_bits(), "{file} element {e} point {p}");
            }
        }
    }
}

fn read(name: &str) -> Scaffold {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/scaffolds");
    let bytes = std::fs::read(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    read_scaffold(&bytes, name, None).unwrap_or_else(|e| panic!("{e}"))
}

/// `cos 2πx + cos 2πy + cos 2πz − offset` (every symmetry of every reference element).
struct Waves(f64);

impl ScalarField for Waves {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        let tau = std::f64::consts::TAU;
        for i in 0..out.len() {
            out[i] = (tau * xs[i]).cos() + (tau * ys[i]).cos() + (tau * zs[i]).cos() - self.0;
        }
    }
}

/// `|ξ|² − r²`.
struct Ball(f64);

impl ScalarField for Ball {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for i in 0..out.len() {
            out[i] = xs[i] * xs[i] + ys[i] * ys[i] + zs[i] * zs[i] - self.0 * self.0;
        }
    }
}

/// The quadratic field on a scaffold of size `size`, in units of it: a weight that leaves
/// [0, 1] (so the clamp matters), a positive thickness and an offset.
fn graded_fields(scaffold: &Scaffold, size: f64) -> [Vec<f64>; 3] {
    let g = |p: [f64; 3]| quadratic(p.map(|c| c / size));
    [
        nodal(scaffold, |p| 1.6 * g(p) - 0.2),
        nodal(scaffold, |p| 0.3 + 0.2 * g(p) * g(p)),
        nodal(scaffold, |p| 0.1 * g(p)),
    ]
}

#[test]
fn graded_values_are_bitwise_equal_from_both_sides_of_every_shared_face() {
    let (waves, ball) = (Waves(0.2), Ball(0.3));
    for (file, size, n) in [
        ("sphere_r10_tet10.msh", 10.0, 6),
        ("cylinder_r5h20_hex20.msh", 10.0, 5),
        ("cylinder_r5h20_hex27.msh", 10.0, 5),
        ("plate_hole_tri6.msh", 50.0, 7),
        ("plate_hole_quad8.msh", 50.0, 6),
        ("plate_hole_quad9.msh", 50.0, 6),
    ] {
        let scaffold = read(file);
        let kind = scaffold.kind;
        let [weight, thickness, _] = graded_fields(&scaffold, size);
        let field = nodal(&scaffold, |p| quadratic(p.map(|c| c / size)));
        let solid = TiledSolid {
            transition: Some(Transition {
                to: &ball,
                weight: &weight,
            }),
            thickness: Some(&thickness),
            ..TiledSolid::of(
                &waves,
                Solid::EccentricShell {
                    offset: 0.1,
                    thickness: 0.0,
                },
            )
        };
        let lattice = lattice(kind, n);
        let lattice = lattice.as_ref();
        let nodes = Nodes {
            kind,
            ids: &scaffold.connectivity,
        };
        let samples =
            ElementSamples::new(lattice, &solid, symmetric_samples(lattice, &waves), nodes)
                .unwrap_or_else(|e| panic!("{file}: {e}"));
        let shape = Shape::new(kind, n as u32 - 1);
        // Per boundary point name: (field bits, sample bits, element).
        let mut seen: HashMap<Vec<(u32, u32)>, (u64, u64, usize)> = HashMap::new();
        let mut values = vec![f64::NAN; lattice.index_len()];
        let (mut compared, mut names, mut quadratic_terms) = (0usize, 0usize, 0usize);
        let mut out = [0; MAX_NODES];
        for e in 0..scaffold.element_count() {
            let element = scaffold.element(e);
            samples.fill(e, &mut values, false);
            for q in points(lattice) {
                let w = lattice.weights(q);
                if !lattice.face_masks().iter().any(|&f| w.mask() & !f == 0) {
                    continue;
                }
                let mut name: Vec<(u32, u32)> = w
                    .as_slice()
                    .iter()
                    .map(|&(c, k)| (element[c as usize], k))
                    .collect();
                name.sort_unstable();
                let bits = (
                    interpolated(&scaffold, &shape, lattice, e, q, &field).to_bits(),
                    values[q as usize].to_bits(),
                );
                shape.numerators(&shape.point(&w), &mut out);
                let uses_quadratic = out[kind.corner_count()..kind.node_count()]
                    .iter()
                    .any(|&n| n != 0);
                match seen.get(&name) {
                    Some(&(field_bits, sample_bits, from)) if from != e => {
                        compared += 1;
                        quadratic_terms += usize::from(uses_quadratic);
                        assert_eq!(
                            (field_bits, sample_bits),
                            bits,
                            "{file}: elements {from} and {e} at {name:?}"
                        );
                    }
                    Some(_) => {}
                    None => {
                        names += 1;
                        seen.insert(name, (bits.0, bits.1, e));
                    }
                }
            }
        }
        assert!(
            compared > names / 2,
            "{file}: {compared} comparisons of {names} names"
        );
        assert!(
            quadratic_terms > compared / 2,
            "{file}: only {quadratic_terms} of {compared} shared points use mid-edge nodes"
        );
    }
}

fn assert_closed(mesh: &crate::mesh::Mesh, what: &str) -> f64 {
    let c = check(mesh);
    assert!(c.watertight, "{what}: not watertight: {c:?}");
    assert!(c.manifold, "{what}: not manifold: {c:?}");
    assert!(c.volume > 0.0, "{what}: volume {}", c.volume);
    c.volume
}

#[test]
fn quadratically_graded_tilings_are_watertight() {
    let (waves, ball) = (Waves(0.2), Ball(0.3));
    for (file, size, n) in [
        ("sphere_r10_tet10.msh", 10.0, 6),
        ("cylinder_r5h20_hex20.msh", 10.0, 5),
        ("cylinder_r5h20_hex27.msh", 10.0, 5),
    ] {
        let scaffold = read(file);
        let [weight, thickness, offset] = graded_fields(&scaffold, size);
        let blend = TiledSolid {
            transition: Some(Transition {
                to: &ball,
                weight: &weight,
            }),
            offset: Some(&offset),
            ..TiledSolid::of(&waves, Solid::Inside { offset: 0.0 })
        };
        let shell = TiledSolid {
            transition: Some(Transition {
                to: &ball,
                weight: &weight,
            }),
            thickness: Some(&thickness),
            ..TiledSolid::of(&waves, Solid::Shell { thickness: 0.0 })
        };
        for (what, solid) in [("blend", &blend), ("shell", &shell)] {
            let (mesh, _) =
                tile_scaffold(&scaffold, solid, n).unwrap_or_else(|e| panic!("{file}: {e}"));
            assert_closed(&mesh, &format!("{file} {what}"));
        }
    }
    for (file, n) in [
        ("plate_hole_tri6.msh", 7),
        ("plate_hole_quad8.msh", 6),
        ("plate_hole_quad9.msh", 6),
    ] {
        let scaffold = read(file);
        let [weight, thickness, _] = graded_fields(&scaffold, 50.0);
        let solid = TiledSolid {
            transition: Some(Transition {
                to: &ball,
                weight: &weight,
            }),
            thickness: Some(&thickness),
            ..TiledSolid::of(&waves, Solid::Shell { thickness: 0.0 })
        };
        let region =
            tile_surface_scaffold(&scaffold, &solid, n).unwrap_or_else(|e| panic!("{file}: {e}"));
        let solid = extrude(&region, 1.0).unwrap_or_else(|e| panic!("{file}: {e}"));
        let volume = assert_closed(&solid, file);
        assert!((volume - region.area).abs() < 1e-3 * region.area, "{file}");
    }
}

/// One straight hex27 (tet10: six of them) on the unit cube with `f(x)` at every node.
fn unit_cube(kind: ElementKind, f: impl Fn(f64) -> f64) -> (Scaffold, Vec<f64>) {
    let scaffold = straight_quadratic(kind, [1, 1, 1], |p| p);
    let values = nodal(&scaffold, |p| f(p[0]));
    (scaffold, values)
}

#[test]
fn overshooting_transition_weights_are_clamped_after_interpolation() {
    // Nodal weights 1, 1, 0 at x = 0, ½, 1, all in [0, 1]: the interpolant 1 + x − 2x² peaks
    // at 9/8 (x = ¼) and is ≥ 1 on [0, ½], where the sample must be the second cell's exactly.
    let (scaffold, weight) = unit_cube(ElementKind::Hex27, |x| if x < 0.75 { 1.0 } else { 0.0 });
    let (waves, ball) = (Waves(0.2), Ball(0.3));
    let solid = TiledSolid {
        transition: Some(Transition {
            to: &ball,
            weight: &weight,
        }),
        ..TiledSolid::of(&waves, Solid::Inside { offset: 0.0 })
    };
    let n = 9;
    let lattice = lattice(scaffold.kind, n);
    let lattice = lattice.as_ref();
    let nodes = Nodes {
        kind: scaffold.kind,
        ids: &scaffold.connectivity,
    };
    let (cell, to) = (
        symmetric_samples(lattice, &waves),
        symmetric_samples(lattice, &ball),
    );
    let samples =
        ElementSamples::new(lattice, &solid, cell.clone(), nodes).unwrap_or_else(|e| panic!("{e}"));
    let mut values = vec![f64::NAN; lattice.index_len()];
    samples.fill(0, &mut values, false);
    let (mut clamped, mut blended) = (0, 0);
    for p in points(lattice) {
        let x = scaffold.map(0, lattice.xi(p))[0];
        let w = 1.0 + x - 2.0 * x * x;
        let p = p as usize;
        if w >= 1.0 {
            clamped += 1;
            assert_eq!(values[p].to_bits(), to[p].to_bits(), "x = {x}");
        } else {
            blended += 1;
            let expected = (1.0 - w) * cell[p] + w * to[p];
            assert!((values[p] - expected).abs() < 1e-12, "x = {x}");
        }
    }
    assert!(clamped > 0 && blended > 0);
}

#[test]
fn a_thickness_that_dips_below_zero_inside_an_element_is_an_error_naming_it() {
    // Nodal thickness 1, 0.01, 0.05 at x = 0, ½, 1 (all > 0): along x the interpolant is
    // (2x − 1)(x − 1) + 0.04x(1 − x) + 0.05x(2x − 1), negative around x = ¾.
    let profile =
        |x: f64| (2.0 * x - 1.0) * (x - 1.0) + 0.04 * x * (1.0 - x) + 0.05 * x * (2.0 * x - 1.0);
    let step = |x: f64| {
        if x < 0.25 {
            1.0
        } else if x < 0.75 {
            0.01
        } else {
            0.05
        }
    };
    let waves = Waves(0.2);
    let n = 9;
    for kind in [ElementKind::Hex27, ElementKind::Tet10] {
        let (scaffold, thickness) = unit_cube(kind, step);
        let solid = TiledSolid {
            thickness: Some(&thickness),
            ..TiledSolid::of(&waves, Solid::Shell { thickness: 0.0 })
        };
        let err = tile_scaffold(&scaffold, &solid, n).map(|_| ());
        let Err(TileError::Thickness {
            element,
            value_bits,
        }) = err
        else {
            panic!("{kind}: expected a thickness error, got {err:?}");
        };
        let value = f64::from_bits(value_bits);
        // The lowest element whose samples dip: for the hex its only one (tag 1); for the
        // tets, the first of the six with an edge along x through x = ¾ at the lattice.
        let lowest = (0..n)
            .map(|i| profile(i as f64 / (n - 1) as f64))
            .fold(f64::INFINITY, f64::min);
        assert!(value < 0.0, "{kind}: {value}");
        if kind == ElementKind::Hex27 {
            assert_eq!(element, scaffold.element_tags[0]);
            assert!((value - lowest).abs() < 1e-12, "{value} vs {lowest}");
        } else {
            assert!(scaffold.element_tags.contains(&element));
            assert!(value >= lowest - 1e-12, "{value} vs {lowest}");
        }
        let message = TileError::Thickness {
            element,
            value_bits,
        }
        .to_string();
        assert!(message.contains(&format!("element {element}")), "{message}");
        // The same nodal values on the linear element are a convex combination: no error.
        let hex8 =
            grid([0.0; 3], [1.0; 3], [1, 1, 1], kind.linear()).unwrap_or_else(|e| panic!("{e}"));
        let linear_thickness = nodal(&hex8, |p| step(p[0]));
        let linear = TiledSolid {
            thickness: Some(&linear_thickness),
            ..TiledSolid::of(&waves, Solid::Shell { thickness: 0.0 })
        };
        assert!(tile_scaffold(&hex8, &linear, n).is_ok(), "{kind}");
    }
}
