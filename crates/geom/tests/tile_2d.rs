//! Tiling 2D scaffolds (tri3, tri6, quad4, quad8, quad9; planar and curved surfaces): the
//! welded region is edge-manifold with closed boundary loops that run only along contours and
//! the scaffold boundary; area fractions match a quadrature of the cell; `extrude` and
//! `thickness_normal` close it into watertight, manifold, outward solids of the right volume;
//! quadratic elements are followed; output does not depend on the thread count.

use latticebuild_geom::field::{ScalarField, Solid};
use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::scaffold::{ElementKind, Scaffold, grid, read_scaffold};
use latticebuild_geom::tile::{
    RegionError, TiledRegion, TiledSolid, Transition, extrude, region_svg, thickness_normal,
    tile_surface_scaffold,
};
use latticebuild_geom::validate::check;
use std::collections::HashMap;
use std::path::PathBuf;

fn read(name: &str) -> Scaffold {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/scaffolds")
        .join(name);
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    read_scaffold(&bytes, name, None).unwrap_or_else(|e| panic!("{e}"))
}

const TAU: f64 = std::f64::consts::TAU;
const SQRT3: f64 = 1.732_050_807_568_877_2;

/// A D4 cell on the square: `cos 2πx + cos 2πy − 0.5`, solid along the element's edges with
/// a hole at its centre.
struct SquareCell;

impl ScalarField for SquareCell {
    fn eval_points(&self, xs: &[f64], ys: &[f64], _: &[f64], out: &mut [f64]) {
        for i in 0..out.len() {
            out[i] = square_cell([xs[i], ys[i]]);
        }
    }
}

fn square_cell(p: [f64; 2]) -> f64 {
    (TAU * p[0]).cos() + (TAU * p[1]).cos() - 0.5
}

/// A D3 cell on the centred triangle: `Σ_j cos(3π u_j·x) − 1` over the unit vectors `u_j` to
/// the triangle's corners (rotations by 120° permute them, the mirror x ↦ −x swaps two).
struct TriangleCell;

impl ScalarField for TriangleCell {
    fn eval_points(&self, xs: &[f64], ys: &[f64], _: &[f64], out: &mut [f64]) {
        for i in 0..out.len() {
            out[i] = triangle_cell([xs[i], ys[i]]);
        }
    }
}

fn triangle_cell(p: [f64; 2]) -> f64 {
    let u = [[0.0, 1.0], [-SQRT3 / 2.0, -0.5], [SQRT3 / 2.0, -0.5]];
    u.iter()
        .map(|u| (1.5 * TAU * (u[0] * p[0] + u[1] * p[1])).cos())
        .sum::<f64>()
        - 1.0
}

/// Solid everywhere: the region is the scaffold itself.
struct Everywhere;

impl ScalarField for Everywhere {
    fn eval_points(&self, _: &[f64], _: &[f64], _: &[f64], out: &mut [f64]) {
        out.fill(-1.0);
    }
}

fn cell_for(kind: ElementKind) -> &'static dyn ScalarField {
    if kind.is_simplex() {
        &TriangleCell
    } else {
        &SquareCell
    }
}

fn tile(scaffold: &Scaffold, cell: &dyn ScalarField, n: usize) -> TiledRegion {
    let solid = TiledSolid::of(cell, Solid::Inside { offset: 0.0 });
    tile_surface_scaffold(scaffold, &solid, n).unwrap_or_else(|e| panic!("{e}"))
}

/// The region's directed boundary edges, after checking it is edge-manifold (each edge used
/// once, or twice in opposite directions) and that its loops are closed chains of exactly
/// those edges.
fn boundary_edges(region: &TiledRegion, what: &str) -> Vec<(u32, u32)> {
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &region.mesh.triangles {
        for k in 0..3 {
            *uses.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    let mut boundary = Vec::new();
    for (&(a, b), &count) in &uses {
        assert_eq!(count, 1, "{what}: edge {a}→{b} used {count} times one way");
        if !uses.contains_key(&(b, a)) {
            boundary.push((a, b));
        }
    }
    let mut in_loops: Vec<(u32, u32)> = region
        .loops
        .iter()
        .flat_map(|lp| (0..lp.len()).map(move |k| (lp[k], lp[(k + 1) % lp.len()])))
        .collect();
    in_loops.sort_unstable();
    boundary.sort_unstable();
    assert_eq!(
        in_loops, boundary,
        "{what}: loops are not the boundary edges"
    );
    let mut used = vec![false; region.mesh.vertices.len()];
    region
        .mesh
        .triangles
        .iter()
        .flatten()
        .for_each(|&v| used[v as usize] = true);
    assert!(used.iter().all(|&u| u), "{what}: unused vertices");
    boundary
}

fn signed_area(region: &TiledRegion, lp: &[u32]) -> f64 {
    let p = |v: u32| region.mesh.vertices[v as usize].map(f64::from);
    (0..lp.len())
        .map(|k| {
            let (a, b) = (p(lp[k]), p(lp[(k + 1) % lp.len()]));
            0.5 * (a[0] * b[1] - a[1] * b[0])
        })
        .sum()
}

/// (file, interior edges, boundary edges, area, whether corners-only (straight) area)
const SURFACES: [(&str, usize, usize, f64); 10] = [
    ("plate_hole_tri3.msh", 1017, 96, 722.7457514),
    ("plate_hole_tri6.msh", 1017, 96, 721.4617728),
    ("plate_hole_quad4.msh", 1242, 140, 722.1176731),
    ("plate_hole_quad8.msh", 1242, 140, 721.4605979),
    ("plate_hole_quad9.msh", 1242, 140, 721.4605979),
    ("sphere_surface_tri3.msh", 1347, 0, 1248.020297),
    ("sphere_surface_tri6.msh", 1347, 0, 1256.621077),
    ("cylinder_side_quad4.msh", 1632, 64, 627.361299),
    ("cylinder_side_quad8.msh", 1632, 64, 628.3209893),
    ("cylinder_side_quad9.msh", 1632, 64, 628.3178799),
];

#[test]
fn every_surface_scaffold_tiles_edge_manifold_with_closed_loops() {
    for (file, interior, boundary, area) in SURFACES {
        let scaffold = read(file);
        let region = tile(&scaffold, cell_for(scaffold.kind), 6);
        assert_eq!(region.stats.interior_faces, interior, "{file}");
        assert_eq!(region.stats.boundary_faces, boundary, "{file}");
        let edges = boundary_edges(&region, file);
        assert!(!edges.is_empty() && !region.loops.is_empty(), "{file}");
        assert!(
            region.area > 0.1 * area && region.area < 0.9 * area,
            "{file}: {}",
            region.area
        );

        // The full cell is the scaffold itself: its boundary and its area.
        let full = tile(&scaffold, &Everywhere, 4);
        let edges = boundary_edges(&full, file);
        let expected_loops = match file {
            f if f.starts_with("sphere") => 0,
            _ => 2,
        };
        assert_eq!(full.loops.len(), expected_loops, "{file}");
        // Each scaffold boundary edge is cut into 3 segments (4 samples per edge).
        assert_eq!(edges.len(), 3 * boundary, "{file}");
        // Flat elements (tri3, planar quad4): the exact area; curved ones (quadratic, or
        // bilinear quads off a plane) to the chords' O(h²).
        let flat =
            scaffold.kind == ElementKind::Tri3 || (full.planar && scaffold.kind.order() == 1);
        let tolerance = if flat { 1e-6 } else { 2e-3 };
        assert!(
            (full.area - area).abs() < tolerance * area,
            "{file}: area {} vs {area}",
            full.area
        );
        if full.planar {
            let mut signs: Vec<f64> = full.loops.iter().map(|lp| signed_area(&full, lp)).collect();
            signs.sort_by(f64::total_cmp);
            // Outer boundary counter-clockwise (40 × 20), the hole (r = 5) clockwise.
            assert!((signs[1] - 800.0).abs() < 1e-3, "{file}: {signs:?}");
            assert!(signs[0] < -70.0 && signs[0] > -80.0, "{file}: {signs:?}");
        }
    }
}

/// The reference point of a model point in a generated grid (found by the element holding
/// it) and the element's kind: for checking contour vertices against the cell itself.
fn reference_point(scaffold: &Scaffold, x: [f64; 2]) -> [f64; 2] {
    for e in 0..scaffold.element_count() {
        let nodes: Vec<[f64; 3]> = scaffold
            .element(e)
            .iter()
            .map(|&n| scaffold.nodes[n as usize])
            .collect();
        match scaffold.kind {
            ElementKind::Quad4 => {
                let (lo, hi) = (nodes[0], nodes[2]);
                let t = [0, 1].map(|a| (x[a] - lo[a]) / (hi[a] - lo[a]));
                if t.iter().all(|&t| (-1e-9..=1.0 + 1e-9).contains(&t)) {
                    return t.map(|t| t - 0.5);
                }
            }
            _ => {
                let (p0, p1, p2) = (nodes[0], nodes[1], nodes[2]);
                let det = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p2[0] - p0[0]) * (p1[1] - p0[1]);
                let l1 =
                    ((x[0] - p0[0]) * (p2[1] - p0[1]) - (p2[0] - p0[0]) * (x[1] - p0[1])) / det;
                let l2 =
                    ((p1[0] - p0[0]) * (x[1] - p0[1]) - (x[0] - p0[0]) * (p1[1] - p0[1])) / det;
                let l = [1.0 - l1 - l2, l1, l2];
                if l.iter().all(|&l| l >= -1e-9) {
                    let q = (0..3).map(|i| ElementKind::Tri3.reference_node(i));
                    let mut xi = [0.0; 2];
                    for (l, q) in l.iter().zip(q) {
                        xi[0] += l * q[0];
                        xi[1] += l * q[1];
                    }
                    return xi;
                }
            }
        }
    }
    panic!("{x:?} is in no element");
}

#[test]
fn region_boundary_edges_are_contour_or_scaffold_boundary_edges() {
    let (max, d) = ([4.0, 3.0, 0.0], [4, 3, 0]);
    for (kind, cell, phi) in [
        (
            ElementKind::Quad4,
            &SquareCell as &dyn ScalarField,
            square_cell as fn([f64; 2]) -> f64,
        ),
        (ElementKind::Tri3, &TriangleCell, triangle_cell),
    ] {
        let scaffold = grid([0.0; 3], max, d, kind).unwrap_or_else(|e| panic!("{e}"));
        let region = tile(&scaffold, cell, 16);
        let on_box = |p: [f64; 2]| {
            [
                p[0].abs(),
                (p[0] - 4.0).abs(),
                p[1].abs(),
                (p[1] - 3.0).abs(),
            ]
            .map(|d| d < 1e-6)
        };
        let (mut on_scaffold, mut contour) = (0, 0);
        for (a, b) in boundary_edges(&region, kind.name()) {
            let [pa, pb] = [a, b].map(|v| {
                let p = region.mesh.vertices[v as usize];
                [f64::from(p[0]), f64::from(p[1])]
            });
            let (sa, sb) = (on_box(pa), on_box(pb));
            if (0..4).any(|s| sa[s] && sb[s]) {
                on_scaffold += 1;
                continue;
            }
            // Off the scaffold boundary, only the cell's zero set may bound the region
            // (linear interpolation error at 15 segments per edge: well below 0.05).
            for p in [pa, pb] {
                let value = phi(reference_point(&scaffold, p));
                assert!(
                    value.abs() < 0.05,
                    "{kind}: boundary edge at {p:?}, Φ = {value}"
                );
            }
            contour += 1;
        }
        assert!(
            on_scaffold > 0 && contour > 0,
            "{kind}: {on_scaffold} {contour}"
        );
    }
}

/// Fraction of the reference element where `phi < 0`, by the midpoint rule on a fine grid
/// (points outside the triangle skipped for it).
fn quadrature_fraction(phi: fn([f64; 2]) -> f64, triangle: bool) -> f64 {
    let n = 2000;
    let (mut inside, mut total) = (0usize, 0usize);
    for j in 0..n {
        for i in 0..n {
            let p = [
                (i as f64 + 0.5) / n as f64 - 0.5,
                (j as f64 + 0.5) / n as f64 - 0.5,
            ];
            let p = if triangle {
                // The triangle's bounding box: x in [-½, ½], y in [-√3/6, √3/3].
                let p = [p[0], -SQRT3 / 6.0 + (p[1] + 0.5) * SQRT3 / 2.0];
                let edges = [
                    p[1] + SQRT3 / 6.0,
                    SQRT3 / 3.0 - p[1] - SQRT3 * p[0],
                    SQRT3 / 3.0 - p[1] + SQRT3 * p[0],
                ];
                if edges.iter().any(|&e| e < 0.0) {
                    continue;
                }
                p
            } else {
                p
            };
            total += 1;
            inside += usize::from(phi(p) < 0.0);
        }
    }
    inside as f64 / total as f64
}

#[test]
fn structured_grids_match_a_quadrature_of_the_cell() {
    for (kind, cell, phi) in [
        (
            ElementKind::Quad4,
            &SquareCell as &dyn ScalarField,
            square_cell as fn([f64; 2]) -> f64,
        ),
        (ElementKind::Tri3, &TriangleCell, triangle_cell),
    ] {
        let scaffold =
            grid([0.0; 3], [3.0, 2.0, 0.0], [3, 2, 0], kind).unwrap_or_else(|e| panic!("{e}"));
        let region = tile(&scaffold, cell, 40);
        let fraction = region.area / 6.0;
        let expected = quadrature_fraction(phi, kind == ElementKind::Tri3);
        assert!(expected > 0.2 && expected < 0.8, "{kind}: {expected}");
        eprintln!("{kind} grid: tiled fraction {fraction:.6}, quadrature {expected:.6}");
        assert!(
            (fraction - expected).abs() < 2e-3,
            "{kind}: tiled {fraction} vs quadrature {expected}"
        );
    }
}

fn closed(mesh: &Mesh, what: &str) -> f64 {
    let c = check(mesh);
    assert!(c.watertight && c.manifold, "{what}: {c:?}");
    assert!(c.volume > 0.0, "{what}: volume {} (inward?)", c.volume);
    c.volume
}

#[test]
fn extruded_regions_are_closed_with_volume_area_times_height() {
    let quad_grid = grid([0.0; 3], [4.0, 3.0, 0.0], [4, 3, 0], ElementKind::Quad4)
        .unwrap_or_else(|e| panic!("{e}"));
    for (what, scaffold) in [
        ("plate_hole_quad4", read("plate_hole_quad4.msh")),
        ("plate_hole_tri6", read("plate_hole_tri6.msh")),
        ("quad grid", quad_grid),
    ] {
        let region = tile(&scaffold, cell_for(scaffold.kind), 8);
        for h in [0.75, 2.0] {
            let solid = extrude(&region, h).unwrap_or_else(|e| panic!("{e}"));
            let volume = closed(&solid, what);
            let expected = region.area * h;
            eprintln!("extrude {what} h={h}: volume {volume:.9} vs area × h {expected:.9}");
            assert!(
                ((volume - expected) / expected).abs() < 1e-9,
                "{what}: volume {volume} vs area × h {expected}"
            );
        }
    }
}

#[test]
fn thickness_normal_makes_closed_shells_of_volume_area_times_h() {
    // On a surface of radius R, ±h/2 offsets enclose area × h × (1 + h²/(12 R²)) per area
    // of the mid-surface: 1e-4 here; the rest is the chords of the linear elements and the
    // averaged nodal normals, within 1 %.
    for (file, h) in [
        ("sphere_surface_tri3.msh", 0.3),
        ("sphere_surface_tri6.msh", 0.3),
        ("cylinder_side_quad4.msh", 0.4),
        ("cylinder_side_quad9.msh", 0.4),
        ("plate_hole_quad8.msh", 0.5),
    ] {
        let scaffold = read(file);
        let solid = TiledSolid::of(cell_for(scaffold.kind), Solid::Inside { offset: 0.0 });
        let shell =
            thickness_normal(&scaffold, &solid, 6, h).unwrap_or_else(|e| panic!("{file}: {e}"));
        let volume = closed(&shell.mesh, file);
        let expected = shell.mid.area * h;
        eprintln!("thickness_normal {file} h={h}: volume {volume:.6} vs area × h {expected:.6}");
        assert!(
            ((volume - expected) / expected).abs() < 1e-2,
            "{file}: volume {volume} vs area × h {expected}"
        );
    }
}

#[test]
fn thickness_beyond_the_curvature_radius_is_refused() {
    let scaffold = read("sphere_surface_tri3.msh");
    let solid = TiledSolid::of(&TriangleCell, Solid::Inside { offset: 0.0 });
    let err = thickness_normal(&scaffold, &solid, 5, 25.0)
        .map(|_| ())
        .unwrap_err();
    assert!(
        matches!(err, RegionError::SelfOverlap { triangles, .. } if triangles > 0),
        "{err}"
    );
    for h in [0.0, -1.0, f64::NAN] {
        let err = thickness_normal(&scaffold, &solid, 5, h)
            .map(|_| ())
            .unwrap_err();
        assert!(matches!(err, RegionError::Length { .. }), "{err}");
    }
    let curved = tile(&scaffold, &TriangleCell, 5);
    assert_eq!(
        extrude(&curved, 1.0).map(|_| ()).unwrap_err().to_string(),
        "extrude needs a planar scaffold (every node at one z)"
    );
    let volume = read("box_4x3x2_hex8.msh");
    let err = tile_surface_scaffold(&volume, &solid, 5)
        .map(|_| ())
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "hex8 scaffolds are volumes: tile them with tile_scaffold"
    );
}

/// Largest distance of a region vertex from the sphere of radius 10.
fn sphere_deviation(region: &TiledRegion) -> f64 {
    region
        .mesh
        .vertices
        .iter()
        .map(|v| (v.iter().map(|&c| f64::from(c).powi(2)).sum::<f64>().sqrt() - 10.0).abs())
        .fold(0.0, f64::max)
}

#[test]
fn quadratic_elements_follow_the_curved_surface() {
    let linear = tile(&read("sphere_surface_tri3.msh"), &TriangleCell, 7);
    let quadratic = tile(&read("sphere_surface_tri6.msh"), &TriangleCell, 7);
    let (dl, dq) = (sphere_deviation(&linear), sphere_deviation(&quadratic));
    eprintln!("sphere surface: max |r − 10| tri3 {dl:.5}, tri6 {dq:.5}");
    // Flat triangles of side ≈ 1.3 sag up to ≈ h²/(8R) ≈ 0.03 below the sphere; the quadratic
    // map's own error is an order smaller.
    assert!(dl > 0.01, "tri3 deviation {dl}");
    assert!(
        dq < 0.2 * dl && dq < 5e-3,
        "tri6 deviation {dq} vs tri3 {dl}"
    );

    // The plate's hole (r = 5 about (15, 10), 10 from the outer edges): boundary vertices of
    // the full region on it.
    let hole = |file: &str| {
        let full = tile(&read(file), &Everywhere, 5);
        full.loops
            .iter()
            .flatten()
            .map(|&v| full.mesh.vertices[v as usize])
            .map(|v| (f64::from(v[0]) - 15.0).hypot(f64::from(v[1]) - 10.0))
            .filter(|&r| r < 7.0)
            .map(|r| (r - 5.0).abs())
            .fold(0.0, f64::max)
    };
    let (dl, dq) = (hole("plate_hole_quad4.msh"), hole("plate_hole_quad9.msh"));
    eprintln!("plate hole: max |r − 5| quad4 {dl:.5}, quad9 {dq:.5}");
    assert!(dq < 0.2 * dl, "quad9 hole deviation {dq} vs quad4 {dl}");
}

#[test]
fn graded_and_transition_regions_stay_edge_manifold() {
    for file in ["plate_hole_tri6.msh", "cylinder_side_quad8.msh"] {
        let scaffold = read(file);
        let weight: Vec<f64> = scaffold
            .nodes
            .iter()
            .map(|x| (0.1 * x[0]).sin().abs())
            .collect();
        let offset: Vec<f64> = scaffold
            .nodes
            .iter()
            .map(|x| 0.3 * (0.2 * x[1]).cos())
            .collect();
        let solid = TiledSolid {
            transition: Some(Transition {
                to: &Everywhere,
                weight: &weight,
            }),
            offset: Some(&offset),
            ..TiledSolid::of(cell_for(scaffold.kind), Solid::Inside { offset: 0.0 })
        };
        let region = tile_surface_scaffold(&scaffold, &solid, 7).unwrap_or_else(|e| panic!("{e}"));
        boundary_edges(&region, file);
        let shell = thickness_normal(&scaffold, &solid, 7, 0.3).unwrap_or_else(|e| panic!("{e}"));
        closed(&shell.mesh, file);
    }
}

#[test]
fn thread_count_does_not_change_the_output() {
    let scaffold = read("cylinder_side_quad9.msh");
    // Graded, so every element is contoured on its own (the per-element path).
    let offset: Vec<f64> = scaffold.nodes.iter().map(|x| 0.02 * x[2]).collect();
    let solid = TiledSolid {
        offset: Some(&offset),
        ..TiledSolid::of(&SquareCell, Solid::Inside { offset: 0.0 })
    };
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map(|p| {
                p.install(|| {
                    (
                        tile_surface_scaffold(&scaffold, &solid, 6),
                        thickness_normal(&scaffold, &solid, 6, 0.3),
                    )
                })
            })
    };
    let (one, three) = (run(1), run(3));
    assert!(matches!((&one, &three), (Ok((Ok(a), Ok(b))), Ok((Ok(c), Ok(d)))) if a == c && b == d));
}

#[test]
fn svg_draws_the_region_and_every_element_edge() {
    let scaffold = read("plate_hole_quad8.msh");
    let region = tile(&scaffold, &SquareCell, 6);
    let svg = region_svg(&region, &scaffold).unwrap_or_else(|e| panic!("{e}"));
    let paths: Vec<&str> = svg.lines().filter(|l| l.starts_with("<path")).collect();
    assert_eq!(paths.len(), 2, "{}", &svg[..200]);
    assert!(paths[0].contains("fill=\"#4a7ab5\""));
    assert_eq!(paths[0].matches('M').count(), region.loops.len());
    assert_eq!(paths[0].matches('Z').count(), region.loops.len());
    // Every element edge once, as an 8-segment polyline (quadratic).
    assert_eq!(paths[1].matches('M').count(), 1242 + 140);
    assert_eq!(paths[1].matches('L').count(), 8 * (1242 + 140));
    // The frame is the plate (40 × 20) with a 2 % margin, y flipped.
    assert!(
        svg.starts_with(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"-0.8 -20.8 41.6 21.6\">"
        ),
        "{}",
        &svg[..120]
    );
    let curved = tile(&read("cylinder_side_quad4.msh"), &SquareCell, 4);
    assert!(region_svg(&curved, &scaffold).is_err());
}

#[test]
fn orientation_problems_are_errors_naming_elements() {
    let solid = TiledSolid::of(&SquareCell, Solid::Inside { offset: 0.0 });
    // One quad of the cylinder's side turned over: its edges run with its neighbours'.
    let mut surface = read("cylinder_side_quad4.msh");
    surface.connectivity[..4].reverse();
    let err = tile_surface_scaffold(&surface, &solid, 4)
        .map(|_| ())
        .unwrap_err();
    assert!(
        matches!(err, RegionError::Inconsistent { a, b, .. } if a == surface.element_tags[0] || b == surface.element_tags[0]),
        "{err}"
    );
    assert!(thickness_normal(&surface, &solid, 4, 0.1).is_err());
    // The same in the plane: counter-clockwise and clockwise elements mixed.
    let mut plate = read("plate_hole_quad4.msh");
    plate.connectivity[4..8].reverse();
    let err = tile_surface_scaffold(&plate, &solid, 4)
        .map(|_| ())
        .unwrap_err();
    assert_eq!(
        err,
        RegionError::MixedOrientation {
            ccw: plate.element_tags[0],
            cw: plate.element_tags[1]
        }
    );
    // All clockwise: flipped as a whole, so the region is the same, counter-clockwise.
    let ccw = tile(&read("plate_hole_quad4.msh"), &SquareCell, 5);
    let mut all_cw = read("plate_hole_quad4.msh");
    for element in all_cw.connectivity.chunks_exact_mut(4) {
        element.swap(1, 3);
    }
    let cw = tile(&all_cw, &SquareCell, 5);
    assert!(
        (cw.area - ccw.area).abs() < 1e-9 * ccw.area && cw.area > 0.0,
        "{} {}",
        cw.area,
        ccw.area
    );
    boundary_edges(&cw, "clockwise plate");
}

/// 2D tilings far from the origin: a lattice whose margin (1/256 of a lattice edge) is below
/// the `f32` step where the scaffold lies is refused, for the region and for
/// `thickness_normal` (whose offset surfaces reach h/2 farther); the highest resolution it
/// names tiles into a manifold region with distinct positions.
#[test]
fn lattices_too_fine_for_f32_where_a_2d_scaffold_lies_are_refused() {
    for kind in [ElementKind::Quad4, ElementKind::Tri3] {
        // 0.25-unit elements at 1000, where an f32 step is 2⁻¹⁴: at most 0.25 / 2⁻⁶ + 1 = 17.
        let far = grid(
            [1000.0, 1000.0, 0.0],
            [1001.0, 1001.0, 0.0],
            [4, 4, 0],
            kind,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let solid = TiledSolid::of(cell_for(kind), Solid::Inside { offset: 0.0 });
        let err = tile_surface_scaffold(&far, &solid, 24).expect_err("refused");
        assert!(
            err.to_string().contains("resolution of at most 17"),
            "{kind:?}: {err}"
        );
        let err = thickness_normal(&far, &solid, 24, 0.1).expect_err("refused");
        assert!(matches!(err, RegionError::Tile(_)), "{kind:?}: {err}");
        let region = tile(&far, cell_for(kind), 17);
        let c = check(&region.mesh);
        assert!(c.manifold, "{kind:?}: {c:?}");
        assert_eq!((c.duplicate_positions, c.degenerate_triangles), (0, 0));
    }
}

/// Width of the thin 2D shells below, in field values: under a third of a lattice spacing at 7
/// points per edge (both cells are steeper than 2π per unit on their zero sets).
const THIN: f64 = 0.3;

fn square_band(p: [f64; 2]) -> f64 {
    square_cell(p).abs() - 0.5 * THIN
}

fn triangle_band(p: [f64; 2]) -> f64 {
    triangle_cell(p).abs() - 0.5 * THIN
}

/// A shell of a 2D cell, tiled as the band between its two levels, keeps a wall thinner than
/// the lattice spacing (sampled as `|f| − w/2` it vanished between samples), stays
/// edge-manifold with closed loops, and its area converges to the quadrature's.
#[test]
fn thin_2d_shells_keep_their_area() {
    for (kind, cell, phi) in [
        (
            ElementKind::Quad4,
            &SquareCell as &dyn ScalarField,
            square_band as fn([f64; 2]) -> f64,
        ),
        (ElementKind::Tri3, &TriangleCell, triangle_band),
    ] {
        let scaffold =
            grid([0.0; 3], [3.0, 2.0, 0.0], [3, 2, 0], kind).unwrap_or_else(|e| panic!("{e}"));
        let expected = quadrature_fraction(phi, kind == ElementKind::Tri3);
        let shell = TiledSolid::of(cell, Solid::Shell { thickness: THIN });
        let errors: Vec<f64> = [7, 13, 25]
            .iter()
            .map(|&n| {
                let region =
                    tile_surface_scaffold(&scaffold, &shell, n).unwrap_or_else(|e| panic!("{e}"));
                boundary_edges(&region, &format!("{kind} at {n}"));
                (region.area / 6.0 / expected - 1.0).abs()
            })
            .collect();
        eprintln!("{kind}: quadrature {expected:.5}, relative errors {errors:?}");
        // The triangle's lattice is coarser for its points per edge (6 cells at 7).
        let coarse = if kind == ElementKind::Tri3 { 0.25 } else { 0.1 };
        assert!(errors[0] < coarse, "{kind}: relative errors {errors:?}");
        assert!(errors[2] < 0.015, "{kind}: relative errors {errors:?}");
    }
}
