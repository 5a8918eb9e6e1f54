//! Imperfect meshes classified against the solid they are meant to bound: holes, duplicated
//! faces, flipped faces, slivers, soups read from STL, cavities. What "correct" means for each
//! is decided in the `mesh_sdf` module docs; these tests hold it.

use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::mesh_io::{self, Encoding, write_mesh};
use latticebuild_geom::mesh_read::{self, TriangleSoup};
use latticebuild_geom::mesh_sdf::{MeshSdf, SdfOptions};
use latticebuild_geom::synthetic::{Rng, box_sd, flip_some, icosphere, norm, sliver_cube};

fn sdf(soup: &TriangleSoup) -> MeshSdf {
    MeshSdf::new(soup, SdfOptions::default()).expect("valid mesh")
}

/// Random points of the ball of radius 1.6 whose distance to the unit sphere exceeds `margin`,
/// plus points at ±`margin`·(1.5, 3) from the surface.
fn sphere_points(rng: &mut Rng, margin: f64) -> Vec<([f64; 3], bool)> {
    let mut out = Vec::new();
    while out.len() < 2000 {
        let p = rng.point(-1.6, 1.6);
        let d = norm(p) - 1.0;
        if d.abs() > margin {
            out.push((p, d < 0.0));
        }
    }
    for _ in 0..1000 {
        let dir = rng.point(-1.0, 1.0);
        for s in [-3.0, -1.5, 1.5, 3.0] {
            let r = 1.0 + s * margin;
            out.push((dir.map(|c| c * r / norm(dir)), s < 0.0));
        }
    }
    out
}

/// The icosphere's vertices are on the sphere and it lies inside it, within 1e-2 (level 3).
const MARGIN: f64 = 0.02;

fn assert_classifies_the_sphere(mesh: &MeshSdf, points: &[([f64; 3], bool)], what: &str) {
    for &(p, inside) in points {
        assert_eq!(mesh.contains(p), inside, "{what}: {p:?}, |p| = {}", norm(p));
        assert_eq!(
            mesh.signed_distance(p) < 0.0,
            inside,
            "{what}: sign at {p:?}"
        );
    }
}

#[test]
fn a_mesh_with_a_hole_is_classified_away_from_the_hole() {
    let mut soup = icosphere(3, 1.0);
    // Remove a cap around +z: a hole of radius about 0.3.
    soup.triangles.retain(|t| {
        let c = t.map(|i| soup.positions[i as usize][2]);
        (c[0] + c[1] + c[2]) / 3.0 < 0.95
    });
    let mesh = sdf(&soup);
    assert!(!mesh.report().closed);
    let mut rng = Rng::new(31);
    let points: Vec<_> = sphere_points(&mut rng, MARGIN)
        .into_iter()
        // Away from the hole: below z = 0.6 inside, anywhere farther than 0.5 outside.
        .filter(|&(p, inside)| {
            if inside {
                p[2] < 0.6
            } else {
                norm(p) > 1.5 || p[2] < 0.6
            }
        })
        .collect();
    assert!(points.len() > 3000);
    assert_classifies_the_sphere(&mesh, &points, "hole");
    // Through the hole, w falls smoothly: the centre of the hole is about half inside.
    let w = mesh.winding_number([0.0, 0.0, 0.97]);
    assert!(w > 0.3 && w < 0.7, "w at the hole {w}");
}

#[test]
fn duplicated_faces_are_dropped_and_change_nothing() {
    let clean = icosphere(3, 1.0);
    let mut soup = clean.clone();
    // Every third face again, some of them twice more.
    let extra: Vec<[u32; 3]> = soup.triangles.iter().step_by(3).copied().collect();
    soup.triangles.extend(&extra);
    soup.triangles.extend(extra.iter().step_by(2));
    let mesh = sdf(&soup);
    assert_eq!(
        mesh.report().duplicates,
        extra.len() + extra.len().div_ceil(2)
    );
    assert!(mesh.report().closed);
    let mut rng = Rng::new(32);
    let points = sphere_points(&mut rng, MARGIN);
    assert_classifies_the_sphere(&mesh, &points, "duplicates");
    // Without repair a doubled face counts twice: just outside it w is about −½ (the face
    // from its front, twice, against +½ from the rest), which is why repeats are dropped
    // rather than classified by |w|.
    let mut once = clean.clone();
    once.triangles.push(clean.triangles[3]);
    let raw = MeshSdf::new(
        &once,
        SdfOptions {
            repair: false,
            ..SdfOptions::default()
        },
    )
    .expect("valid");
    let t = clean.triangles[3].map(|i| clean.positions[i as usize]);
    let c: [f64; 3] = std::array::from_fn(|a| (t[0][a] + t[1][a] + t[2][a]) / 3.0);
    let outside = c.map(|x| x * (1.0 + 1e-4));
    let w = raw.winding_number(outside);
    assert!(
        (w + 0.5).abs() < 0.01,
        "raw w just outside a doubled face: {w}"
    );
    assert!(sdf(&once).winding_number(outside).abs() < 0.01);
}

#[test]
fn flipped_faces_are_turned_back() {
    let mut soup = icosphere(3, 1.0);
    let mut rng = Rng::new(33);
    let flipped = flip_some(&mut soup, |_| rng.unit() < 0.3);
    let mesh = sdf(&soup);
    assert_eq!(mesh.report().flipped, flipped);
    assert!(mesh.report().closed);
    let points = sphere_points(&mut Rng::new(34), MARGIN);
    assert_classifies_the_sphere(&mesh, &points, "30% flipped");

    // All faces flipped: the solid it bounds, not its complement.
    let mut inverted = icosphere(3, 1.0);
    let all = flip_some(&mut inverted, |_| true);
    let mesh = sdf(&inverted);
    assert_eq!(mesh.report().flipped, all);
    assert_classifies_the_sphere(&mesh, &points, "all flipped");
}

/// A hollow ball: an outer sphere facing out and an inner one facing in (the cavity), each
/// with some faces flipped. Repair must keep the cavity a cavity.
#[test]
fn a_cavity_stays_a_cavity_when_faces_are_flipped() {
    let outer = icosphere(3, 1.0);
    let mut inner = icosphere(3, 0.5);
    flip_some(&mut inner, |_| true);
    let offset = outer.positions.len() as u32;
    let mut soup = outer.clone();
    soup.positions.extend(&inner.positions);
    soup.triangles
        .extend(inner.triangles.iter().map(|t| t.map(|i| i + offset)));
    let mut rng = Rng::new(35);
    flip_some(&mut soup, |k| k % 7 == 0 || rng.unit() < 0.1);
    let mesh = sdf(&soup);
    assert!(mesh.report().closed);
    assert_eq!(mesh.report().components, 2);
    let mut rng = Rng::new(36);
    for _ in 0..3000 {
        let p = rng.point(-1.3, 1.3);
        let r = norm(p);
        if (r - 1.0).abs() < MARGIN || (r - 0.5).abs() < MARGIN {
            continue;
        }
        let inside = r < 1.0 && r > 0.5;
        assert_eq!(mesh.contains(p), inside, "{p:?}, |p| = {r}");
    }
}

#[test]
fn sliver_triangles_are_classified_correctly() {
    let h = 0.5;
    let soup = sliver_cube(h, 1e-6);
    // Aspect ratio of the thinnest triangle: longest edge over height.
    let aspect = soup
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| soup.positions[i as usize]);
            let e = |p: [f64; 3], q: [f64; 3]| norm([p[0] - q[0], p[1] - q[1], p[2] - q[2]]);
            let longest = e(a, b).max(e(b, c)).max(e(c, a));
            let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let ac = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let cross = [
                ab[1] * ac[2] - ab[2] * ac[1],
                ab[2] * ac[0] - ab[0] * ac[2],
                ab[0] * ac[1] - ab[1] * ac[0],
            ];
            longest * longest / norm(cross)
        })
        .fold(0.0, f64::max);
    assert!(aspect > 0.9e6, "aspect ratio {aspect}");
    let mesh = sdf(&soup);
    let mut rng = Rng::new(37);
    for k in 0..4000 {
        let p = if k % 2 == 0 {
            rng.point(-0.8, 0.8)
        } else {
            // Within 1e-5 of a face, where the slivers are thinnest relative to the distance.
            let mut p = rng.point(-h, h);
            p[rng.below(3)] = (if rng.unit() < 0.5 { -h } else { h }) + rng.range(-1e-5, 1e-5);
            p
        };
        let d = box_sd(p, h);
        if d.abs() < 1e-9 {
            continue;
        }
        assert_eq!(mesh.contains(p), d < 0.0, "{p:?}");
    }
}

/// A binary STL repeats each position per facet: welding gives the mesh back, closed.
#[test]
fn an_stl_soup_welds_into_the_closed_mesh() {
    let ico = icosphere(3, 1.0);
    let mesh = Mesh {
        vertices: ico.positions.iter().map(|p| p.map(|c| c as f32)).collect(),
        triangles: ico.triangles.clone(),
    };
    let mut bytes = Vec::new();
    write_mesh(&mesh, mesh_io::Format::Stl, Encoding::Binary, &mut bytes).expect("memory");
    let soup = mesh_read::read(&bytes, mesh_read::Format::Stl).expect("own STL");
    assert_eq!(soup.positions.len(), 3 * soup.triangles.len());
    let sdf = sdf(&soup);
    assert_eq!(sdf.report().vertices, ico.positions.len());
    assert!(sdf.report().closed);
    let points = sphere_points(&mut Rng::new(38), MARGIN);
    assert_classifies_the_sphere(&sdf, &points, "STL soup");
}

/// A lone open square is nowhere inside, and its winding number stays within ±½.
#[test]
fn an_open_sheet_is_nowhere_inside() {
    let soup = TriangleSoup {
        positions: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    };
    let mesh = sdf(&soup);
    let mut rng = Rng::new(39);
    for _ in 0..500 {
        let p = rng.point(-0.5, 1.5);
        let w = mesh.winding_number(p);
        assert!(w.abs() <= 0.5 + 1e-9, "w({p:?}) = {w}");
        assert!(!mesh.contains(p));
    }
}

/// On an open surface the samplers cannot carry the side along rows; they must still agree
/// with point queries wherever the side is not a near tie (`w` within 0.05 of ½).
#[test]
fn samplers_of_an_open_mesh_agree_with_point_queries() {
    use latticebuild_geom::field::{Grid, ScalarField};
    use latticebuild_geom::mesh_sdf::Mode;
    let mut soup = icosphere(3, 1.0);
    soup.triangles.retain(|t| {
        let c = t.map(|i| soup.positions[i as usize][2]);
        (c[0] + c[1] + c[2]) / 3.0 < 0.8
    });
    let exact = sdf(&soup);
    assert!(!exact.report().closed);
    let grid = Grid::spanning([-1.2; 3], [1.2; 3], [33; 3]);
    for mode in [Mode::SignedDistance, Mode::Containment] {
        let mesh = MeshSdf::new(
            &soup,
            SdfOptions {
                mode,
                ..SdfOptions::default()
            },
        )
        .expect("mesh");
        let sampler = mesh.sampler(&grid);
        let mut plane = vec![0.0; grid.plane_len()];
        let mut checked = 0;
        for k in 0..grid.counts[2] {
            sampler.sample_plane(k, &mut plane);
            for (n, &v) in plane.iter().enumerate() {
                let p = [
                    grid.coord(0, n % 33),
                    grid.coord(1, n / 33),
                    grid.coord(2, k),
                ];
                if (exact.winding_number_exact(p) - 0.5).abs() < 0.05 || v == 0.0 {
                    continue;
                }
                assert_eq!(v < 0.0, exact.contains(p), "{mode:?} at {p:?}");
                checked += 1;
            }
        }
        assert!(checked > 30_000);
    }
}
