//! Fields clipped to the 3D reference elements: closed, manifold, outward meshes with the
//! element's volume reproduced exactly where the field does not cut it.

use latticebuild_geom::contour::ContourError;
use latticebuild_geom::element::{Element3, TETRAHEDRON_VERTICES, contour_clipped};
use latticebuild_geom::field::ScalarField;
use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::validate::check;
use std::f64::consts::PI;

/// A field given by a closure of the position.
struct FnField<F>(F);

impl<F: Fn([f64; 3]) -> f64 + Sync + Send> ScalarField for FnField<F> {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for (n, v) in out.iter_mut().enumerate() {
            *v = (self.0)([xs[n], ys[n], zs[n]]);
        }
    }
}

fn gyroid(p: [f64; 3]) -> f64 {
    let t = p.map(|c| 2.0 * PI * c);
    t[0].sin() * t[1].cos() + t[1].sin() * t[2].cos() + t[2].sin() * t[0].cos()
}

fn clipped(f: impl Fn([f64; 3]) -> f64 + Sync + Send, element: Element3, samples: usize) -> Mesh {
    contour_clipped(&FnField(f), element, samples, &|_| {}).expect("contour")
}

fn assert_closed(mesh: &Mesh, what: &str) -> f64 {
    let c = check(mesh);
    assert!(c.watertight, "{what}: not watertight: {c:?}");
    assert!(c.manifold, "{what}: not manifold: {c:?}");
    assert!(c.volume > 0.0, "{what}: volume {} (inward?)", c.volume);
    c.volume
}

#[test]
fn element_gyroid_clipped_is_closed_manifold_and_inside_the_element() {
    for element in [Element3::Cube, Element3::Tetrahedron] {
        for samples in [5, 12, 17, 33] {
            let what = format!("{element:?} at {samples}");
            let mesh = clipped(gyroid, element, samples);
            let volume = assert_closed(&mesh, &what);
            // The gyroid splits space in halves; clipped, it must not exceed the element.
            assert!(volume < element.volume(), "{what}: volume {volume}");
            for v in &mesh.vertices {
                let d = element.signed_distance(v.map(f64::from));
                assert!(d <= 1e-6, "{what}: vertex {v:?} outside by {d}");
            }
        }
    }
}

#[test]
fn element_gyroid_halves_fill_the_element() {
    // The sheet splits each element into two solids, Φ ≤ 0 and −Φ ≤ 0, whose volumes add up to
    // the element's. In the cube the box caps are exact, so only the face rule's choices differ.
    // In the tetrahedron the halves are the two sides of one linear interpolant in each small
    // tetrahedron: they fill it but where crossings are kept off a node (and it converges).
    let halves = |element: Element3, samples: usize| {
        let a = assert_closed(&clipped(gyroid, element, samples), "inside");
        let b = assert_closed(&clipped(|p| -gyroid(p), element, samples), "outside");
        (a + b - element.volume()) / element.volume()
    };
    let cube = halves(Element3::Cube, 40);
    assert!(cube.abs() < 1e-3, "cube: relative error {cube:e}");
    let coarse = halves(Element3::Tetrahedron, 24);
    let fine = halves(Element3::Tetrahedron, 48);
    assert!(
        fine.abs() < 1e-2,
        "tetrahedron at 48: relative error {fine:e}"
    );
    assert!(
        fine.abs() < 0.4 * coarse.abs(),
        "tetrahedron: error {coarse:e} at 24, {fine:e} at 48 (not second order)"
    );
}

#[test]
fn element_constant_inside_field_gives_the_element_exactly() {
    for samples in [2, 3, 8, 31] {
        for (element, level) in [(Element3::Cube, -1.0), (Element3::Tetrahedron, -1.0)] {
            let mesh = clipped(|_| level, element, samples);
            let volume = assert_closed(&mesh, &format!("{element:?} at {samples}"));
            let exact = element.volume();
            assert!(
                ((volume - exact) / exact).abs() < 1e-6,
                "{element:?} at {samples}: volume {volume}, expected {exact}"
            );
        }
    }
    // A shallow constant still gives the element: its faces are the subdivision's.
    let mesh = clipped(|_| -0.01, Element3::Tetrahedron, 20);
    let volume = assert_closed(&mesh, "shallow");
    assert!((volume * 3.0 - 1.0).abs() < 1e-6, "shallow: {volume}");
}

#[test]
fn element_tetrahedron_mesh_reaches_every_vertex() {
    let mesh = clipped(|_| -1.0, Element3::Tetrahedron, 6);
    for p in TETRAHEDRON_VERTICES {
        let nearest = mesh
            .vertices
            .iter()
            .map(|v| {
                let d: f64 = (0..3).map(|a| (f64::from(v[a]) - p[a]).powi(2)).sum();
                d.sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            nearest < 1e-6,
            "vertex {p:?}: nearest mesh vertex at {nearest}"
        );
    }
}

/// Volume of the ball of radius `r` at the centroid, clipped to the tetrahedron: its inradius
/// is √6/6 · √2/2 = 1/(2√3) ≈ 0.2887, so a ball of radius 0.3 loses four thin caps.
fn ball_in_tetrahedron(r: f64) -> f64 {
    let inradius = 1.0 / (2.0 * 3f64.sqrt());
    let cap_height = (r - inradius).max(0.0);
    let cap = PI * cap_height * cap_height * (3.0 * r - cap_height) / 3.0;
    4.0 / 3.0 * PI * r.powi(3) - 4.0 * cap
}

#[test]
fn element_ball_in_tetrahedron_has_the_ball_volume() {
    for (r, samples, tolerance) in [(0.3, 48, 5e-3), (0.3, 96, 1.5e-3), (0.25, 64, 6e-3)] {
        let mesh = clipped(
            move |p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() - r,
            Element3::Tetrahedron,
            samples,
        );
        let volume = assert_closed(&mesh, &format!("ball {r} at {samples}"));
        let exact = ball_in_tetrahedron(r);
        let error = (volume - exact) / exact;
        assert!(
            error.abs() < tolerance,
            "ball {r} at {samples}: volume {volume}, expected {exact} (relative {error:e})"
        );
    }
    // Radius 0.3 is slightly more than the inradius: the four caps cut off are 0.42 % of the
    // ball, more than the tolerance at 96 samples, so the test does see the clip.
    let ratio = ball_in_tetrahedron(0.3) / (4.0 / 3.0 * PI * 0.027);
    assert!((0.995..0.997).contains(&ratio), "{ratio}");
}

#[test]
fn element_ball_in_cube_has_the_ball_volume() {
    let mesh = clipped(
        |p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() - 0.3,
        Element3::Cube,
        64,
    );
    let volume = assert_closed(&mesh, "ball in cube");
    let exact = 4.0 / 3.0 * PI * 0.027;
    assert!(
        ((volume - exact) / exact).abs() < 3e-3,
        "{volume} vs {exact}"
    );
}

#[test]
fn element_bad_input_is_an_error_not_a_panic() {
    for element in [Element3::Cube, Element3::Tetrahedron] {
        for samples in [0, 1] {
            assert_eq!(
                contour_clipped(&FnField(gyroid), element, samples, &|_| {}),
                Err(ContourError::TooFewSamples([samples; 3]))
            );
        }
        assert!(matches!(
            contour_clipped(&FnField(gyroid), element, usize::MAX, &|_| {}),
            Err(ContourError::TooManyVertices(_))
        ));
        // An undefined field is outside everywhere: nothing to draw, and no panic.
        let empty = clipped(|_| f64::NAN, element, 6);
        assert!(empty.is_empty());
    }
}

#[test]
fn element_signed_distance_signs_and_bbox() {
    for element in [Element3::Cube, Element3::Tetrahedron] {
        assert!(element.signed_distance([0.0; 3]) < 0.0);
        assert!(element.signed_distance([0.6, 0.0, 0.0]) > 0.0);
        let (min, max) = element.bbox();
        assert_eq!((min, max), ([-0.5; 3], [0.5; 3]));
    }
    for p in TETRAHEDRON_VERTICES {
        assert!(Element3::Tetrahedron.signed_distance(p).abs() < 1e-15);
    }
    // The other cube corners are outside the tetrahedron.
    assert!(Element3::Tetrahedron.signed_distance([0.5, 0.5, 0.5]) > 0.5);
    // Exact distances: to the cube's face, edge, and from its centre.
    let cube = Element3::Cube;
    assert!((cube.signed_distance([0.0; 3]) + 0.5).abs() < 1e-15);
    assert!((cube.signed_distance([0.7, 0.0, 0.0]) - 0.2).abs() < 1e-15);
    assert!((cube.signed_distance([0.8, 0.9, 0.0]) - 0.5).abs() < 1e-15);
    // Centroid to a tetrahedron face: the inradius.
    let tet = Element3::Tetrahedron.signed_distance([0.0; 3]);
    assert!((tet + 1.0 / (2.0 * 3f64.sqrt())).abs() < 1e-15);
}

/// The largest distance from an image of a vertex under `op` to the nearest vertex.
fn worst_image_gap(vertices: &[[f32; 3]], op: impl Fn([f64; 3]) -> [f64; 3]) -> f64 {
    let points: Vec<[f64; 3]> = vertices.iter().map(|v| v.map(f64::from)).collect();
    let mut sorted = points.clone();
    sorted.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let mut worst: f64 = 0.0;
    for &p in &points {
        let q = op(p);
        let from = sorted.partition_point(|s| s[0] < q[0] - 1e-5);
        let best = sorted[from..]
            .iter()
            .take_while(|s| s[0] <= q[0] + 1e-5)
            .map(|s| (0..3).map(|d| (s[d] - q[d]).powi(2)).sum::<f64>().sqrt())
            .fold(f64::INFINITY, f64::min);
        worst = worst.max(best);
    }
    worst
}

#[test]
fn element_cube_output_keeps_the_cube_s_symmetry() {
    // An Oh-symmetric field (offset so that no sample is zero to rounding, where the sign and
    // so the crossings would be decided by rounding): its clipped mesh maps onto itself under
    // the 48 signed permutations, to f32 rounding.
    let t = 2.0 * PI;
    let wavy = move |p: [f64; 3]| {
        let c = p.map(|x| (t * x).cos());
        c[0] + c[1] + c[2] - 0.4 * c[0] * c[1] * c[2] + 0.05
    };
    let perms = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    for samples in [17, 24] {
        let mesh = clipped(wavy, Element3::Cube, samples);
        assert_closed(&mesh, "wavy");
        for p in perms {
            for signs in 0..8 {
                let s = |a: usize| if (signs >> a) & 1 == 1 { -1.0 } else { 1.0 };
                let gap =
                    worst_image_gap(&mesh.vertices, |v| std::array::from_fn(|a| s(a) * v[p[a]]));
                assert!(gap < 1e-6, "{samples}: {p:?} signs {signs}: {gap}");
            }
        }
    }
}
