//! Winding numbers of generated meshes against their analytic solids, and the hierarchical
//! evaluation against the exact sum over every triangle.

use latticebuild_geom::field::{Grid, ScalarField};
use latticebuild_geom::mesh_read::TriangleSoup;
use latticebuild_geom::mesh_sdf::{MeshSdf, Mode, SdfOptions};
use latticebuild_geom::synthetic::{
    Rng, chord_error, icosphere, longest_edge, norm, torus, torus_sd,
};

/// Hierarchical (β = 2, second order) against exact, over all our query sets: the stated
/// accuracy of the default options.
const FAST_TOLERANCE: f64 = 5e-3;

fn sdf(soup: &TriangleSoup, options: SdfOptions) -> MeshSdf {
    MeshSdf::new(soup, options).expect("valid mesh")
}

/// Random points of `[lo, hi]³` farther than `margin` from the analytic surface, each with
/// whether it is inside.
fn classified(
    rng: &mut Rng,
    n: usize,
    (lo, hi): (f64, f64),
    margin: f64,
    sd: impl Fn([f64; 3]) -> f64,
) -> Vec<([f64; 3], bool)> {
    let mut out = Vec::new();
    while out.len() < n {
        let p = rng.point(lo, hi);
        let d = sd(p);
        if d.abs() > margin {
            out.push((p, d < 0.0));
        }
    }
    out
}

#[test]
fn winding_number_is_one_inside_and_zero_outside_a_sphere_mesh() {
    let soup = icosphere(4, 1.0);
    let mesh = sdf(&soup, SdfOptions::default());
    assert!(mesh.report().closed);
    let margin = chord_error(&soup, 1.0);
    let mut rng = Rng::new(1);
    let points = classified(&mut rng, 3000, (-1.5, 1.5), margin, |p| norm(p) - 1.0);
    for (p, inside) in points {
        let w = mesh.winding_number(p);
        let expected = if inside { 1.0 } else { 0.0 };
        assert!((w - expected).abs() < FAST_TOLERANCE, "w({p:?}) = {w}");
        assert_eq!(mesh.contains(p), inside, "{p:?}");
    }
}

#[test]
fn winding_number_is_one_inside_and_zero_outside_a_torus_mesh() {
    let (big_r, r) = (1.0, 0.35);
    let soup = torus(96, 48, big_r, r);
    let mesh = sdf(&soup, SdfOptions::default());
    assert!(mesh.report().closed);
    // Every point of a triangle is within the longest edge of a vertex on the torus.
    let margin = longest_edge(&soup);
    let mut rng = Rng::new(2);
    let points = classified(&mut rng, 3000, (-1.6, 1.6), margin, |p| {
        torus_sd(p, big_r, r)
    });
    let mut insides = 0;
    for (k, (p, inside)) in points.into_iter().enumerate() {
        let w = mesh.winding_number(p);
        let expected = if inside { 1.0 } else { 0.0 };
        assert!((w - expected).abs() < FAST_TOLERANCE, "w({p:?}) = {w}");
        if k % 10 == 0 {
            let exact = mesh.winding_number_exact(p);
            assert!((exact - expected).abs() < 1e-9, "exact w({p:?}) = {exact}");
        }
        insides += usize::from(inside);
    }
    assert!(
        insides > 100,
        "the test must see the inside too ({insides})"
    );
}

/// Points at the given offsets along the outward normal from the centroids of some triangles.
fn near_surface(soup: &TriangleSoup, offsets: &[f64], rng: &mut Rng, n: usize) -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    for _ in 0..n {
        let t = soup.triangles[rng.below(soup.triangles.len())];
        let [a, b, c] = t.map(|i| soup.positions[i as usize]);
        // A random point of the triangle, not just its centroid.
        let (mut u, mut v) = (rng.unit(), rng.unit());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let p: [f64; 3] = std::array::from_fn(|k| a[k] + u * (b[k] - a[k]) + v * (c[k] - a[k]));
        let e1: [f64; 3] = std::array::from_fn(|k| b[k] - a[k]);
        let e2: [f64; 3] = std::array::from_fn(|k| c[k] - a[k]);
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let len = norm(n);
        for &o in offsets {
            out.push(std::array::from_fn(|k| p[k] + o * n[k] / len));
        }
    }
    out
}

#[test]
fn hierarchical_winding_number_agrees_with_the_exact_sum() {
    let soup = torus(128, 64, 1.0, 0.35);
    let mesh = sdf(&soup, SdfOptions::default());
    let mut rng = Rng::new(3);
    let mut points: Vec<[f64; 3]> = (0..1500).map(|_| rng.point(-1.6, 1.6)).collect();
    points.extend(near_surface(
        &soup,
        &[-1e-2, -1e-4, -1e-7, 0.0, 1e-7, 1e-4, 1e-2],
        &mut rng,
        200,
    ));
    let mut worst: f64 = 0.0;
    for p in points {
        let (fast, exact) = (mesh.winding_number(p), mesh.winding_number_exact(p));
        worst = worst.max((fast - exact).abs());
        assert!(
            (fast - exact).abs() < FAST_TOLERANCE,
            "{p:?}: fast {fast}, exact {exact}"
        );
    }
    // The samplers decide sides with β = 1.25 when that estimate is more than 0.2 from ½:
    // its error must stay well below 0.2.
    let coarse = sdf(
        &soup,
        SdfOptions {
            beta: 1.25,
            ..SdfOptions::default()
        },
    );
    let mut rng = Rng::new(4);
    let mut coarse_points: Vec<[f64; 3]> = (0..500).map(|_| rng.point(-1.6, 1.6)).collect();
    coarse_points.extend(near_surface(
        &soup,
        &[-1e-3, -1e-6, 1e-6, 1e-3],
        &mut rng,
        100,
    ));
    for p in coarse_points {
        let (fast, exact) = (coarse.winding_number(p), coarse.winding_number_exact(p));
        assert!(
            (fast - exact).abs() < 0.1,
            "β = 1.25 at {p:?}: fast {fast}, exact {exact}"
        );
    }
    // A larger β looks closer before approximating: more accurate.
    let tight = sdf(
        &soup,
        SdfOptions {
            beta: 4.0,
            ..SdfOptions::default()
        },
    );
    let mut rng = Rng::new(3);
    let tight_worst = (0..300)
        .map(|_| rng.point(-1.6, 1.6))
        .map(|p| (tight.winding_number(p) - tight.winding_number_exact(p)).abs())
        .fold(0.0, f64::max);
    assert!(
        tight_worst < worst.max(1e-12),
        "β=4: {tight_worst}, β=2: {worst}"
    );
}

#[test]
fn containment_mode_agrees_with_the_sign_of_the_signed_distance() {
    let soup = torus(64, 32, 1.0, 0.35);
    let distance = sdf(&soup, SdfOptions::default());
    let containment = sdf(
        &soup,
        SdfOptions {
            mode: Mode::Containment,
            ..SdfOptions::default()
        },
    );
    // A grid fine enough that many samples sit near the surface, through the samplers (which
    // carry the side along rows) and point by point.
    let grid = Grid::spanning([-1.5, -1.5, -0.5], [1.5, 1.5, 0.5], [61, 61, 21]);
    let (d_sampler, c_sampler) = (distance.sampler(&grid), containment.sampler(&grid));
    let mut d_plane = vec![0.0; grid.plane_len()];
    let mut c_plane = vec![0.0; grid.plane_len()];
    let mut inside = 0;
    for k in 0..grid.counts[2] {
        d_sampler.sample_plane(k, &mut d_plane);
        c_sampler.sample_plane(k, &mut c_plane);
        for (n, (&d, &c)) in d_plane.iter().zip(&c_plane).enumerate() {
            let p = [
                grid.coord(0, n % grid.counts[0]),
                grid.coord(1, n / grid.counts[0]),
                grid.coord(2, k),
            ];
            assert!(c == 1.0 || c == -1.0);
            let direct = containment.contains(p);
            assert_eq!(c < 0.0, direct, "containment sampler at {p:?}");
            if d != 0.0 {
                assert_eq!(
                    d < 0.0,
                    c < 0.0,
                    "sign of distance {d} vs containment at {p:?}"
                );
            }
            inside += usize::from(direct);
        }
    }
    assert!(inside > 1000, "{inside} inside samples");
}

/// The exact sum over every triangle adds fixed blocks in order: the same bits on any pool
/// (rayon's own `sum` splits where its scheduler does, so 1 and 3 threads disagreed).
#[test]
fn exact_winding_number_is_bitwise_equal_on_any_thread_count() {
    // 20 480 triangles: more than one block, so the sum runs in parallel.
    let soup = icosphere(5, 1.0);
    let mesh = sdf(&soup, SdfOptions::default());
    let mut rng = Rng::new(5);
    let points: Vec<[f64; 3]> = (0..40).map(|_| rng.point(-1.5, 1.5)).collect();
    let on = |threads: usize| -> Vec<u64> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            points
                .iter()
                .map(|&p| mesh.winding_number_exact(p).to_bits())
                .collect()
        })
    };
    let one = on(1);
    for threads in [2, 3, 5] {
        let other = on(threads);
        let differing = one.iter().zip(&other).filter(|(a, b)| a != b).count();
        assert_eq!(
            differing, 0,
            "{differing} of 40 points differ at {threads} threads"
        );
    }
    // And they are winding numbers: 1 inside the unit sphere, 0 outside (beyond its chords).
    let margin = chord_error(&soup, 1.0);
    for (p, &w) in points.iter().zip(&one) {
        let (w, r) = (f64::from_bits(w), norm(*p));
        if (r - 1.0).abs() > margin {
            let expected = if r < 1.0 { 1.0 } else { 0.0 };
            assert!((w - expected).abs() < 1e-9, "w({p:?}) = {w}");
        }
    }
}
