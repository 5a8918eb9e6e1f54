//! Signed distances of generated meshes against analytic solids; samplers against point
//! queries; the band; contouring the field of a mesh.

use latticebuild_geom::contour::contour;
use latticebuild_geom::field::{Grid, ScalarField};
use latticebuild_geom::mesh_read::TriangleSoup;
use latticebuild_geom::mesh_sdf::{MeshSdf, MeshSdfError, SdfOptions};
use latticebuild_geom::synthetic::{Rng, box_sd, chord_error, icosphere, norm, sliver_cube};
use latticebuild_geom::validate;

fn sdf(soup: &TriangleSoup, options: SdfOptions) -> MeshSdf {
    MeshSdf::new(soup, options).expect("valid mesh")
}

/// The mesh and the sphere are within the chord error ε of each other (every mesh point is
/// within ε of the sphere radially, and every sphere point's ray meets the mesh within ε), so
/// their signed distances differ by at most ε everywhere.
#[test]
fn sphere_mesh_signed_distance_is_within_the_chord_error_of_the_sphere() {
    let soup = icosphere(4, 1.0);
    let eps = chord_error(&soup, 1.0);
    assert!(eps > 1e-4 && eps < 1e-2, "chord error {eps}");
    let mesh = sdf(&soup, SdfOptions::default());
    let mut rng = Rng::new(21);
    let mut worst: f64 = 0.0;
    for k in 0..4000 {
        // Half the points in a thin shell about the surface, where it matters most.
        let p = if k % 2 == 0 {
            rng.point(-2.0, 2.0)
        } else {
            let dir = rng.point(-1.0, 1.0);
            let r = 1.0 + rng.range(-0.05, 0.05);
            dir.map(|c| c * r / norm(dir))
        };
        let d = mesh.signed_distance(p);
        let exact = norm(p) - 1.0;
        worst = worst.max((d - exact).abs());
        assert!((d - exact).abs() <= eps + 1e-12, "at {p:?}: {d} vs {exact}");
    }
    assert!(
        worst > 0.1 * eps,
        "the test should come near the bound ({worst} vs {eps})"
    );
}

/// Slivers of aspect ratio 1e6 along every edge of a cube: distances are the cube's to
/// rounding, including right next to the slivers.
#[test]
fn sliver_triangles_give_exact_distances() {
    let h = 0.5;
    let soup = sliver_cube(h, 1e-6);
    let mesh = sdf(&soup, SdfOptions::default());
    assert!(mesh.report().closed);
    let mut rng = Rng::new(22);
    for k in 0..3000 {
        let p = match k % 3 {
            0 => rng.point(-1.0, 1.0),
            // Next to a face, near the middle of an edge where the slivers are.
            1 => {
                let mut p = [rng.range(-1e-3, 1e-3), h - rng.range(0.0, 2e-6), 0.0];
                p[2] = h + rng.range(-1e-5, 1e-5);
                p
            }
            _ => {
                let mut p = rng.point(-h, h);
                p[rng.below(3)] = h + rng.range(-1e-6, 1e-6);
                p
            }
        };
        let d = mesh.signed_distance(p);
        let exact = box_sd(p, h);
        assert!((d - exact).abs() < 1e-12, "at {p:?}: {d} vs {exact}");
    }
}

/// The samplers (which reuse work along rows) give the point queries' values, and the band
/// clamps them.
#[test]
fn samplers_agree_with_point_queries_and_the_band_clamps() {
    let soup = icosphere(3, 1.0);
    let exact = sdf(&soup, SdfOptions::default());
    let band = 0.1;
    let banded = sdf(
        &soup,
        SdfOptions {
            band: Some(band),
            ..SdfOptions::default()
        },
    );
    let grid = Grid::spanning([-1.3, -1.2, -1.1], [1.2, 1.3, 1.25], [41, 37, 29]);
    let (sampler, band_sampler) = (exact.sampler(&grid), banded.sampler(&grid));
    let mut plane = vec![0.0; grid.plane_len()];
    let mut band_plane = vec![0.0; grid.plane_len()];
    let (mut xs, mut ys, mut zs) = (Vec::new(), Vec::new(), Vec::new());
    let mut from_sampler = Vec::new();
    for k in 0..grid.counts[2] {
        sampler.sample_plane(k, &mut plane);
        band_sampler.sample_plane(k, &mut band_plane);
        for (n, (&v, &b)) in plane.iter().zip(&band_plane).enumerate() {
            let p = [
                grid.coord(0, n % grid.counts[0]),
                grid.coord(1, n / grid.counts[0]),
                grid.coord(2, k),
            ];
            let d = exact.signed_distance(p);
            assert!((v - d).abs() < 1e-12, "sampler {v} vs point {d} at {p:?}");
            assert!(
                (b - d.clamp(-band, band)).abs() < 1e-12,
                "band {b} vs {d} at {p:?}"
            );
            xs.push(p[0]);
            ys.push(p[1]);
            zs.push(p[2]);
            from_sampler.push(v);
        }
    }
    let mut batch = vec![0.0; xs.len()];
    exact.eval_points(&xs, &ys, &zs, &mut batch);
    for (a, b) in batch.iter().zip(&from_sampler) {
        assert!((a - b).abs() < 1e-12);
    }
    // A plane sampled twice is bit-identical (the contourer relies on it).
    let mut again = vec![0.0; grid.plane_len()];
    sampler.sample_plane(7, &mut plane);
    sampler.sample_plane(7, &mut again);
    assert!(
        plane
            .iter()
            .zip(&again)
            .all(|(a, b)| a.to_bits() == b.to_bits())
    );
}

/// The streaming contourer meshes the zero set directly: closed, manifold, with the volume of
/// the sphere mesh up to the grid's resolution.
#[test]
fn contouring_the_field_of_a_sphere_mesh_gives_a_closed_sphere() {
    let soup = icosphere(3, 1.0);
    let mesh = sdf(&soup, SdfOptions::default());
    let grid = Grid::spanning([-1.2; 3], [1.2; 3], [49; 3]);
    let sampler = mesh.sampler(&grid);
    let surface = contour(sampler.as_ref(), &grid, &|_| {}).expect("contour");
    let check = validate::check(&surface);
    assert!(check.watertight && check.manifold);
    let sphere = 4.0 / 3.0 * std::f64::consts::PI;
    assert!(
        (check.volume - sphere).abs() < 0.02 * sphere,
        "volume {}",
        check.volume
    );
}

#[test]
fn invalid_soups_and_options_are_errors() {
    let tri = |triangles: Vec<[u32; 3]>| TriangleSoup {
        positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        triangles,
    };
    let new = |soup: &TriangleSoup, options| MeshSdf::new(soup, options).err();
    let d = SdfOptions::default();
    assert_eq!(new(&tri(vec![]), d), Some(MeshSdfError::Empty));
    assert_eq!(
        new(&tri(vec![[0, 1, 3]]), d),
        Some(MeshSdfError::IndexOutOfRange {
            triangle: 0,
            index: 3,
            count: 3
        })
    );
    assert_eq!(
        new(&tri(vec![[0, 1, 1]]), d),
        Some(MeshSdfError::Degenerate)
    );
    let mut nan = tri(vec![[0, 1, 2]]);
    nan.positions[1][2] = f64::NAN;
    assert_eq!(new(&nan, d), Some(MeshSdfError::NonFinite { vertex: 1 }));
    let beta = SdfOptions { beta: 0.5, ..d };
    assert!(matches!(
        new(&tri(vec![[0, 1, 2]]), beta),
        Some(MeshSdfError::BadOption { .. })
    ));
    let band = SdfOptions {
        band: Some(0.0),
        ..d
    };
    assert!(matches!(
        new(&tri(vec![[0, 1, 2]]), band),
        Some(MeshSdfError::BadOption { .. })
    ));
}

#[test]
fn mesh_sdf_is_send_sync_and_owns_its_data() {
    fn shared<T: Send + Sync + 'static>(_: &T) {}
    let mesh = sdf(&icosphere(1, 1.0), SdfOptions::default());
    shared(&mesh);
    let (lo, hi) = mesh.bounds();
    assert!(lo.iter().chain(&hi).all(|c| (c.abs() - 1.0).abs() < 0.2));
}
