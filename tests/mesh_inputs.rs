//! Mesh inputs through the real binary: cells made from triangle meshes, parts filled with a
//! lattice (`within`, `skin`), caching keyed on the file's content, and errors naming the file.
//! Meshes are generated here as ASCII STL text (an independent writer).

use crate::common;

use common::{Project, ran, sphere_stl};
use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::{mesh_read, validate};
use std::f64::consts::PI;

/// A gyroid in a sphere of radius 10 (`ball.stl`), over the sphere's box.
const BALL: &str = r#"
[cells.g]
tpms = "gyroid"

[outputs.ball]
cell = "g"
within = "ball.stl"
domain = { min = [-10.5, -10.5, -10.5], max = [10.5, 10.5, 10.5] }
cell_size = 4
samples = 128
formats = ["ply"]
"#;

fn number(report: &serde_json::Value, key: &str) -> f64 {
    report[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} in {report}"))
}

#[test]
fn a_sphere_filled_with_a_gyroid_keeps_the_gyroids_volume_fraction() {
    let (stl, sphere_volume) = sphere_stl(10.0, [0.0; 3], 48, 96);
    let p = Project::new(BALL);
    p.write("ball.stl", &stl);
    let reports = p.build(&[]);
    let r = &reports[0];
    assert_eq!(r["watertight"], true, "{r}");
    assert_eq!(r["manifold"], true, "{r}");
    // The gyroid at offset 0 fills half of any region many cells across.
    let fraction = number(r, "volume") / sphere_volume;
    assert!((fraction - 0.5).abs() < 0.01, "fraction {fraction}");
    // It stays inside the sphere (up to a sample spacing).
    let h = 21.0 / 127.0;
    for axis in 0..3 {
        assert!(r["bbox"]["max"][axis].as_f64().unwrap() <= 10.0 + h);
        assert!(r["bbox"]["min"][axis].as_f64().unwrap() >= -10.0 - h);
    }
}

#[test]
fn a_skin_closes_the_part_and_adds_its_shell() {
    let (stl, sphere_volume) = sphere_stl(10.0, [0.0; 3], 48, 96);
    let p = Project::new(BALL);
    p.write("ball.stl", &stl);
    let r = &p.build(&["--set", "outputs.ball.skin=1.0"])[0];
    assert_eq!(r["watertight"], true, "{r}");
    assert_eq!(r["manifold"], true, "{r}");
    // The skin (radii 9 to 10) is solid, and the gyroid fills half of the ball inside it.
    let scale = sphere_volume / (4.0 / 3.0 * PI * 1000.0);
    let shell = scale * 4.0 / 3.0 * PI * (1000.0 - 729.0);
    let core = scale * 4.0 / 3.0 * PI * 729.0;
    let expected = shell + 0.5 * core;
    let volume = number(r, "volume");
    assert!(
        (volume - expected).abs() < 0.015 * expected,
        "volume {volume}, expected {expected}"
    );
}

#[test]
fn a_mesh_cell_repeats_its_solid_and_fits_through_the_fourier_stages() {
    // A ball of radius 0.3 in the reference cell: repeated over 2×2×2 cells, and fitted with
    // Oh symmetry (the ball is symmetric, so the fit changes it only by its band limit).
    let (stl, ball_volume) = sphere_stl(0.3, [0.0; 3], 32, 64);
    let p = Project::new(
        r#"
[cells.ball]
mesh = "ball.stl"

[cells.fitted]
mesh = "ball.stl"
symmetry = "Oh"
fit = { n = 32 }

[cells.placed]
mesh = "big.stl"
placement = "fit"
sample = "containment"

[outputs.balls]
cell = "ball"
domain = { min = [0, 0, 0], max = [2, 2, 2] }
samples = 81

[outputs.fitted]
cell = "fitted"
domain = { min = [0, 0, 0], max = [2, 2, 2] }
samples = 81

[outputs.placed]
cell = "placed"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 61
"#,
    );
    p.write("ball.stl", &stl);
    // A sphere of radius 5 far from the origin: `placement = "fit"` scales it to radius ½.
    let (big, big_volume) = sphere_stl(5.0, [20.0, -3.0, 7.0], 32, 64);
    p.write("big.stl", &big);
    let reports = p.build(&[]);
    let by_name = |name: &str| {
        reports
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["name"] == name)
            .unwrap_or_else(|| panic!("{name}"))
            .clone()
    };
    let balls = by_name("balls");
    assert_eq!(balls["watertight"], true);
    let fraction = number(&balls, "volume_fraction");
    assert!(
        (fraction - ball_volume).abs() < 0.004,
        "{fraction} vs {ball_volume}"
    );
    let fitted = by_name("fitted");
    assert_eq!(fitted["watertight"], true);
    let fitted_fraction = number(&fitted, "volume_fraction");
    assert!(
        (fitted_fraction - ball_volume).abs() < 0.01,
        "{fitted_fraction} vs {ball_volume}"
    );
    // Placed: one ball of radius ½ centred in the unit cell (its corners are the cell's, so
    // the box [0, 1]³ holds eight eighths of balls: the same volume).
    let placed = by_name("placed");
    let expected = big_volume / 1000.0;
    let placed_fraction = number(&placed, "volume_fraction");
    assert!(
        (placed_fraction - expected).abs() < 0.01,
        "{placed_fraction} vs {expected}"
    );
}

#[test]
fn the_mesh_content_not_its_path_or_time_decides_what_rebuilds() {
    let (stl, _) = sphere_stl(0.3, [0.0; 3], 16, 32);
    let p = Project::new(
        "[cells.ball]\nmesh = \"ball.stl\"\n\n[outputs.o]\ncell = \"ball\"\n\
         domain = { min = [0, 0, 0], max = [1, 1, 1] }\nsamples = 33\n",
    );
    p.write("ball.stl", &stl);
    p.build(&[]);
    // Rewritten with the same bytes (a new modification time): nothing runs.
    std::thread::sleep(std::time::Duration::from_millis(20));
    p.write("ball.stl", &stl);
    assert!(ran(&p.build(&[])).is_empty());
    // Another mesh: the cell and everything after it run.
    let (bigger, _) = sphere_stl(0.35, [0.0; 3], 16, 32);
    p.write("ball.stl", &bigger);
    assert_eq!(
        ran(&p.build(&[])),
        ["cell:ball", "contour:o", "file:ball.stl", "write:o"]
    );
}

#[test]
fn bad_mesh_files_are_errors_naming_the_file() {
    let p = Project::new(
        "[cells.ball]\nmesh = \"missing.stl\"\n\n[outputs.o]\ncell = \"ball\"\n\
         domain = { min = [0, 0, 0], max = [1, 1, 1] }\nsamples = 9\n",
    );
    let out = p.run(&["build", "lattice.toml"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("cannot read the mesh `missing.stl` of `cells.ball.mesh`"),
        "{err}"
    );
    assert!(err.contains("lattice.toml:2:8"), "{err}");

    // Half-written: the ASCII STL stops inside a facet.
    let (stl, _) = sphere_stl(0.3, [0.0; 3], 8, 16);
    let cut = &stl[..stl.len() / 2];
    p.write("missing.stl", cut);
    let out = p.run(&["build", "lattice.toml"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("cannot read `missing.stl`"), "{err}");
    assert!(err.contains("line"), "{err}");
}

/// `examples/mesh_inputs.toml`'s struts (a mesh cell whose struts end in caps on the cell's
/// faces) come out as one body over 3 × 3 × 3 cells: the caps of neighbouring copies meet
/// and bound nothing, so there is no gap at the cell faces.
#[test]
fn the_example_struts_are_one_connected_body() {
    let examples = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let manifest = std::fs::read_to_string(examples.join("mesh_inputs.toml")).expect("example");
    let p = Project::new(&manifest);
    common::copy_dir(&examples.join("meshes"), &p.path().join("meshes"), &[]);
    let reports = p.build(&["--set", "outputs.struts.formats=[\"ply\"]", "struts"]);
    let r = &reports[0];
    assert_eq!(
        (r["watertight"].clone(), r["manifold"].clone()),
        (true.into(), true.into())
    );
    let bytes = std::fs::read(p.out("struts.ply")).expect("struts.ply");
    let soup = mesh_read::read(&bytes, mesh_read::Format::Ply).expect("PLY");
    let mesh = Mesh {
        vertices: soup.positions.iter().map(|p| p.map(|c| c as f32)).collect(),
        triangles: soup.triangles,
    };
    assert_eq!(validate::components(&mesh), 1);
}

/// `n = "auto"` that cannot meet its tolerance by `max_n` builds with the fit at `max_n` and
/// warns, naming the movement reached and the tolerance, on a cached rebuild too; one that
/// meets it does not warn.
#[test]
fn an_automatic_n_stopped_at_max_n_is_a_warning_not_a_failure() {
    let (stl, _) = sphere_stl(0.3, [0.0; 3], 16, 32);
    let p = Project::new(
        r#"
[cells.ball]
mesh = "ball.stl"
symmetry = "Oh"
fit = { n = "auto", tolerance = 1e-9, max_n = 64 }

[outputs.ball]
cell = "ball"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 33
"#,
    );
    p.write("ball.stl", &stl);
    for _ in 0..2 {
        let r = &p.build(&[])[0];
        assert_eq!(r["watertight"], true, "{r}");
        let warnings: Vec<&str> = r["warnings"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|w| w.as_str())
            .collect();
        assert!(
            warnings.iter().any(|w| w.contains("cell `ball`")
                && w.contains("max_n = 64")
                && w.contains("from N = 32 to N = 64")
                && w.contains("tolerance 1.0e-9")),
            "{warnings:?}"
        );
    }
    // `latticebuild cell` says how N was chosen, also through a `constrain` stage (an offset).
    for set in [None, Some("cells.ball.offset=0.01")] {
        let mut args = vec!["cell", "lattice.toml", "ball"];
        args.extend(set.iter().flat_map(|s| ["--set", s]));
        let out = p.run(&[args.as_slice(), &["--json"]].concat());
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
        assert_eq!(json["n"], 64, "{json}");
        assert_eq!(json["auto"]["n"], 64, "{json}");
        assert_eq!(json["auto"]["converged"], false, "{json}");
        let text = String::from_utf8_lossy(&p.run(&args).stdout).to_string();
        assert!(
            text.contains("N = 64 reached max_n: automatic N stopped at max_n = 64"),
            "{text}"
        );
    }
    let loose = [
        "cell",
        "lattice.toml",
        "ball",
        "--set",
        "cells.ball.fit.tolerance=1",
    ];
    let text = String::from_utf8_lossy(&p.run(&loose).stdout).to_string();
    assert!(
        text.contains("N = 32 chosen automatically: doubling it to 64 moves the surface"),
        "{text}"
    );
    let r = &p.build(&["--set", "cells.ball.fit.tolerance=1"])[0];
    let warned = r["warnings"].as_array().into_iter().flatten();
    assert!(
        !warned
            .filter_map(|w| w.as_str())
            .any(|w| w.contains("max_n")),
        "{r}"
    );
}
