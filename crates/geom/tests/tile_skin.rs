//! The skin along a scaffold's boundary (`tile/skin.rs`): closed and manifold on generated and
//! real scaffolds, its volume against the box's shell `V − Π(Lᵢ − 2t)`, and the lattice far
//! from the boundary untouched by it.

use latticebuild_geom::field::{ScalarField, Solid};
use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::scaffold::{ElementKind, Scaffold, grid, read_scaffold};
use latticebuild_geom::tile::{TiledSolid, tile_scaffold, tile_scaffold_with_skin};
use latticebuild_geom::validate::check;
use std::path::PathBuf;

/// Never inside: with a skin, the output is the skin alone.
struct Void;

impl ScalarField for Void {
    fn eval_points(&self, _: &[f64], _: &[f64], _: &[f64], out: &mut [f64]) {
        out.fill(1.0);
    }
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

fn closed(mesh: &Mesh, what: &str) -> f64 {
    let c = check(mesh);
    assert!(c.watertight && c.manifold, "{what}: {c:?}");
    assert!(c.volume > 0.0, "{what}: volume {}", c.volume);
    c.volume
}

fn skinned(scaffold: &Scaffold, cell: &dyn ScalarField, t: f64, n: usize) -> Mesh {
    let solid = TiledSolid::of(cell, Solid::Inside { offset: 0.0 });
    tile_scaffold_with_skin(scaffold, &solid, Some(t), n)
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}

#[test]
fn a_skin_alone_on_a_box_has_the_volume_of_the_box_shell() {
    // The region within t of the box's faces is the box minus the box shrunk by t: an
    // independent value, exact up to marching cubes cutting the inner box's edges.
    let (size, t) = ([3.0, 2.0, 1.0], 0.2);
    let shell = size.iter().product::<f64>() - size.iter().map(|l| l - 2.0 * t).product::<f64>();
    for kind in [ElementKind::Hex8, ElementKind::Tet4] {
        let scaffold = grid([0.0; 3], size, [6, 4, 2], kind).expect("grid");
        let volume = closed(&skinned(&scaffold, &Void, t, 16), kind.name());
        assert!(
            (volume / shell - 1.0).abs() < 1e-2,
            "{kind}: skin volume {volume} vs box shell {shell}"
        );
    }
}

#[test]
fn a_thin_skin_is_boundary_area_times_thickness() {
    let (size, t) = ([2.0, 2.0, 2.0], 0.05);
    let scaffold = grid([0.0; 3], size, [4, 4, 4], ElementKind::Hex8).expect("grid");
    let volume = closed(&skinned(&scaffold, &Void, t, 24), "hex8");
    let area = 6.0 * 4.0;
    // Area × t over-counts the twelve edges' overlaps by O(t²): within 5 %.
    assert!(
        (volume / (area * t) - 1.0).abs() < 5e-2,
        "{volume} vs {}",
        area * t
    );
}

#[test]
fn a_skin_around_a_lattice_is_closed_and_joins_it() {
    let (size, t) = ([3.0, 2.0, 2.0], 0.15);
    for kind in [ElementKind::Hex8, ElementKind::Tet4] {
        let scaffold = grid([0.0; 3], size, [3, 2, 2], kind).expect("grid");
        let cell = SchwarzP(0.6);
        let lattice = {
            let solid = TiledSolid::of(&cell, Solid::Inside { offset: 0.0 });
            tile_scaffold(&scaffold, &solid, 16).expect("tile").0
        };
        let lattice = closed(&lattice, "lattice");
        let skin = closed(&skinned(&scaffold, &Void, t, 16), "skin");
        let both = closed(&skinned(&scaffold, &cell, t, 16), kind.name());
        // A union: more than either part, less than both (they overlap along the boundary).
        assert!(
            both > lattice.max(skin) && both < lattice + skin,
            "{kind}: union {both}, lattice {lattice}, skin {skin}"
        );
    }
}

#[test]
fn far_from_the_boundary_the_lattice_is_untouched() {
    // A thin skin on a big grid: every triangle not within the skin's reach is a triangle of
    // the plain tiling, at the same position bit for bit.
    let scaffold = grid([0.0; 3], [6.0, 6.0, 6.0], [6, 6, 6], ElementKind::Hex8).expect("grid");
    let cell = SchwarzP(0.3);
    let plain = {
        let solid = TiledSolid::of(&cell, Solid::Inside { offset: 0.0 });
        tile_scaffold(&scaffold, &solid, 12).expect("tile").0
    };
    let with_skin = skinned(&scaffold, &cell, 0.1, 12);
    let inner = |m: &Mesh| -> Vec<[u32; 3]> {
        let mut v: Vec<[u32; 3]> = m
            .vertices
            .iter()
            .filter(|p| p.iter().all(|&c| (1.5..=4.5).contains(&c)))
            .map(|p| p.map(f32::to_bits))
            .collect();
        v.sort_unstable();
        v
    };
    let (a, b) = (inner(&plain), inner(&with_skin));
    assert!(!a.is_empty());
    assert_eq!(a, b, "interior vertices differ");
}

fn read(name: &str) -> Scaffold {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/scaffolds")
        .join(name);
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    read_scaffold(&bytes, name, None).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn skins_on_real_scaffolds_are_closed() {
    // Curved quadratic elements included (the skin term uses the corner positions).
    for (file, t) in [
        ("sphere_r10_tet4.msh", 0.5),
        ("sphere_r10_tet10.msh", 0.5),
        ("cylinder_r5h20_hex27.msh", 0.4),
    ] {
        let scaffold = read(file);
        let mesh = skinned(&scaffold, &SchwarzP(0.8), t, 6);
        closed(&mesh, file);
    }
}

#[test]
fn a_bad_thickness_is_an_error() {
    let scaffold = grid([0.0; 3], [1.0; 3], [1, 1, 1], ElementKind::Hex8).expect("grid");
    let solid = TiledSolid::of(&Void, Solid::Inside { offset: 0.0 });
    for t in [0.0, -1.0, f64::NAN] {
        let err = tile_scaffold_with_skin(&scaffold, &solid, Some(t), 4)
            .err()
            .map(|e| e.to_string());
        assert!(
            err.as_deref().is_some_and(|e| e.contains("positive")),
            "{t}: {err:?}"
        );
    }
}
