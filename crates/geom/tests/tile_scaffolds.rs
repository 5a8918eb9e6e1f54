//! Tiling the real Gmsh scaffolds of `tests/data/scaffolds` (tet4, tet10, hex8, hex20, hex27):
//! closed, manifold output with the files' facet counts; curved (quadratic) faces followed;
//! graded and transition fields from the files' node data closed too.

use latticebuild_geom::field::{ScalarField, Solid};
use latticebuild_geom::scaffold::{Scaffold, read_scaffold};
use latticebuild_geom::tile::{TiledSolid, Transition, tile_scaffold};
use latticebuild_geom::validate::check;
use std::path::PathBuf;

fn read(name: &str) -> Scaffold {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/scaffolds")
        .join(name);
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    read_scaffold(&bytes, name, None).unwrap_or_else(|e| panic!("{e}"))
}

/// Schwarz P, `cos 2πx + cos 2πy + cos 2πz − offset` (Oh, hence Td).
struct SchwarzP(f64);

impl ScalarField for SchwarzP {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        let tau = std::f64::consts::TAU;
        for i in 0..out.len() {
            out[i] = (tau * xs[i]).cos() + (tau * ys[i]).cos() + (tau * zs[i]).cos() - self.0;
        }
    }
}

/// Solid everywhere: the tiling is the scaffold itself, capped on its boundary.
struct Everywhere;

impl ScalarField for Everywhere {
    fn eval_points(&self, _: &[f64], _: &[f64], _: &[f64], out: &mut [f64]) {
        out.fill(-1.0);
    }
}

fn closed(mesh: &latticebuild_geom::mesh::Mesh, what: &str) -> f64 {
    let c = check(mesh);
    assert!(c.watertight && c.manifold, "{what}: {c:?}");
    assert!(c.volume > 0.0, "{what}: volume {}", c.volume);
    c.volume
}

#[test]
fn every_volume_scaffold_tiles_closed_with_its_facet_counts() {
    // (file, interior facets, boundary facets) from the data README.
    let files = [
        ("box_4x3x2_hex8.msh", 46, 52),
        ("sphere_r10_tet4.msh", 4047, 710),
        ("sphere_r10_tet10.msh", 4047, 710),
        ("sphere_r10_hex8.msh", 5775, 762),
        ("cylinder_r5h20_hex8.msh", 4788, 792),
        ("cylinder_r5h20_hex20.msh", 4788, 792),
        ("cylinder_r5h20_hex27.msh", 4788, 792),
        ("cylinder_r5h20_hex8.inp", 4788, 792),
        ("bracket_tet4.msh", 17348, 3812),
    ];
    for (file, interior, boundary) in files {
        let scaffold = read(file);
        let solid = TiledSolid::of(&SchwarzP(0.0), Solid::Shell { thickness: 1.0 });
        let (mesh, stats) =
            tile_scaffold(&scaffold, &solid, 6).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(
            (stats.interior_faces, stats.boundary_faces),
            (interior, boundary),
            "{file}"
        );
        let v = closed(&mesh, file);
        // A shell of P takes a fair share of every element, never all of it.
        let fraction = v / scaffold.measure();
        assert!(
            fraction > 0.05 && fraction < 0.6,
            "{file}: fraction {fraction}"
        );
    }
}

#[test]
fn a_full_cell_reproduces_the_scaffold_volume_and_curved_faces() {
    // V from the data README: the isoparametric (curved) volume for quadratic elements, which
    // the lattice's flat triangles follow to O(h²): at 6 samples per edge about 6e-4.
    for (file, volume, tolerance) in [
        ("sphere_r10_tet4.msh", 4122.907041, 1e-5),
        ("box_4x3x2_hex8.msh", 24.0, 1e-6),
        ("sphere_r10_tet10.msh", 4188.661609, 1e-3),
        ("cylinder_r5h20_hex20.msh", 1570.793293, 1e-3),
    ] {
        let scaffold = read(file);
        let solid = TiledSolid::of(&Everywhere, Solid::Inside { offset: 0.0 });
        let (mesh, _) = tile_scaffold(&scaffold, &solid, 6).unwrap_or_else(|e| panic!("{e}"));
        let v = closed(&mesh, file);
        assert!(
            (v / volume - 1.0).abs() < tolerance,
            "{file}: {v} vs {volume}"
        );
    }
    // On the tet10 sphere every boundary vertex is on a curved face: it lies on the sphere to
    // the map's own accuracy, far closer than the flat tet4 faces.
    let off_sphere = |file: &str| {
        let scaffold = read(file);
        let solid = TiledSolid::of(&Everywhere, Solid::Inside { offset: 0.0 });
        let (mesh, _) = tile_scaffold(&scaffold, &solid, 6).unwrap_or_else(|e| panic!("{e}"));
        mesh.vertices
            .iter()
            .map(|v| (v.iter().map(|c| f64::from(*c).powi(2)).sum::<f64>().sqrt() - 10.0).abs())
            .fold(0.0, f64::max)
    };
    let (curved, flat) = (
        off_sphere("sphere_r10_tet10.msh"),
        off_sphere("sphere_r10_tet4.msh"),
    );
    assert!(
        curved < 0.2 * flat && curved < 0.05,
        "tet10 {curved} vs tet4 {flat}"
    );
}

#[test]
fn node_data_grades_and_blends_without_cracks() {
    let scaffold = read("sphere_r10_tet4_thickness.msh");
    // The view holds 0.1..0.3; P's values span ±3, so a shell 8 times thicker is visible at
    // this resolution.
    let thickness: Vec<f64> = scaffold
        .node_data("thickness")
        .map(|d| d.values.iter().map(|t| 8.0 * t).collect())
        .unwrap_or_else(|| panic!("no thickness view"));
    let p = SchwarzP(0.0);
    let graded = TiledSolid {
        thickness: Some(&thickness),
        ..TiledSolid::of(&p, Solid::Shell { thickness: 0.0 })
    };
    let (mesh, _) = tile_scaffold(&scaffold, &graded, 6).unwrap_or_else(|e| panic!("{e}"));
    closed(&mesh, "graded shell");

    let scaffold = read("bracket_tet4_weight.msh");
    let weight = scaffold
        .node_data("weight")
        .map(|d| d.values.clone())
        .unwrap_or_else(|| panic!("no weight view"));
    let (a, b) = (SchwarzP(0.6), SchwarzP(-0.6));
    let blend = TiledSolid {
        transition: Some(Transition {
            to: &b,
            weight: &weight,
        }),
        ..TiledSolid::of(&a, Solid::Inside { offset: 0.0 })
    };
    let (mesh, _) = tile_scaffold(&scaffold, &blend, 4).unwrap_or_else(|e| panic!("{e}"));
    closed(&mesh, "transition");
}

#[test]
fn surface_scaffolds_are_refused_with_their_kind() {
    let scaffold = read("plate_hole_quad4.msh");
    let solid = TiledSolid::of(&Everywhere, Solid::Inside { offset: 0.0 });
    let err = tile_scaffold(&scaffold, &solid, 4).map(|_| ()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "quad4 scaffolds are surfaces: tile them with tile_surface_scaffold"
    );
}
