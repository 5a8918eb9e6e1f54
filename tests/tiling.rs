//! Tiled outputs through the real binary: the summary's counts and volume fraction against
//! independent values, what each edit reruns (docs/method.md §2: a format change only rewrites,
//! the scaffold file is keyed by content), and the errors only the `tile` stage can find.

use crate::common;

use common::{Project, ran};

const GRID: &str = r#"
[cells.p]
tpms = "p"
symmetry = "Oh"
fit = { n = 16 }

[scaffolds.block]
grid = { min = [0, 0, 0], max = [8, 6, 4], divisions = [4, 3, 2], element = "hex" }

[outputs.a]
scaffold = "block"
cell = "p"
resolution = 12
"#;

fn only(reports: &serde_json::Value) -> &serde_json::Value {
    let all = reports.as_array().expect("array");
    assert_eq!(all.len(), 1);
    &all[0]
}

fn number(report: &serde_json::Value, key: &str) -> f64 {
    report[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key}: {report}"))
}

fn data(name: &str) -> Vec<u8> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("crates/geom/tests/data/scaffolds")
        .join(name);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn a_hex_grid_with_p_reports_its_faces_and_half_its_volume() {
    // P at offset 0 fills half of every cell (Φ(x + ½) = −Φ(x)); 4 × 3 × 2 hexes have 46
    // interior and 52 boundary faces.
    let p = Project::new(GRID);
    let report = p.build(&[]);
    let r = only(&report);
    assert_eq!(r["watertight"], true);
    assert_eq!(r["manifold"], true);
    let tiling = &r["tiling"];
    assert_eq!(tiling["element"], "hex8");
    assert_eq!(tiling["elements"], 24);
    assert_eq!(tiling["interior_faces"], 46);
    assert_eq!(tiling["boundary_faces"], 52);
    assert!((number(tiling, "scaffold_volume") - 192.0).abs() < 1e-9);
    let fraction = number(r, "volume_fraction");
    assert!((fraction - 0.5).abs() < 3e-3, "fraction {fraction}");
    assert!((number(r, "volume") / 192.0 - fraction).abs() < 1e-12);
}

#[test]
fn a_format_change_rewrites_without_retiling() {
    let p = Project::new(GRID);
    let first = p.build(&[]);
    assert_eq!(
        ran(&first),
        [
            "cell:p",
            "constrain:p",
            "fit:p",
            "sample:p",
            "tile:a",
            "write:a"
        ]
    );
    assert!(ran(&p.build(&[])).is_empty());
    let formats = p.build(&["--set", "outputs.a.formats=[\"stl\", \"ply\"]"]);
    assert_eq!(ran(&formats), ["write:a"]);
    assert!(p.out("a.ply").is_file());
    let resolution = p.build(&["--set", "outputs.a.resolution=8"]);
    assert_eq!(ran(&resolution), ["tile:a", "write:a"]);
    let skin = p.build(&["--set", "outputs.a.skin=0.2"]);
    assert_eq!(ran(&skin), ["tile:a", "write:a"]);
}

/// Files in the output directory that are not in place: temporaries of unused early writes.
fn temporaries(p: &Project) -> Vec<String> {
    let dir = p.out("a.stl");
    let dir = dir.parent().expect("out dir");
    std::fs::read_dir(dir)
        .expect("out dir")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|name| name.starts_with('.'))
        .collect()
}

#[test]
fn stl_written_while_tiling_is_the_file_written_from_the_cache() {
    // A tiling's STL is written from its chunks while the tiling runs; a write-only rerun
    // writes it from the cache entry. Both must be the same bytes, in both encodings.
    let p = Project::new(GRID);
    for (ascii, resolution) in [("false", "12"), ("true", "10")] {
        let ascii_key = format!("outputs.a.ascii={ascii}");
        let resolution = format!("outputs.a.resolution={resolution}");
        let first = p.build(&["--set", &ascii_key, "--set", &resolution]);
        assert!(ran(&first).contains(&"tile:a".to_string()), "{ascii}");
        let early = std::fs::read(p.out("a.stl")).expect("stl");
        let formats = p.build(&[
            "--set",
            &ascii_key,
            "--set",
            &resolution,
            "--set",
            "outputs.a.formats=[\"stl\", \"ply\"]",
        ]);
        assert_eq!(ran(&formats), ["write:a"], "{ascii}");
        let late = std::fs::read(p.out("a.stl")).expect("stl");
        assert!(early == late, "ascii = {ascii}: the early STL differs");
        assert!(temporaries(&p).is_empty(), "{:?}", temporaries(&p));
    }
}

#[test]
fn an_early_stl_of_an_unchanged_mesh_is_dropped() {
    // The scaffold's bytes change but not its mesh (a comment section): the tiling reruns
    // and writes an STL early, the write stage is cached, and the early file is removed
    // without touching the one in place.
    let p = Project::new(FILE);
    let bytes = data("box_4x3x2_hex8.msh");
    std::fs::write(p.path().join("box.msh"), &bytes).expect("write");
    p.build(&[]);
    let placed = std::fs::metadata(p.out("a.stl")).expect("stl");
    let text = String::from_utf8(bytes).expect("ascii");
    let commented = text.replacen(
        "$EndMeshFormat\n",
        "$EndMeshFormat\n$Comments\nsame mesh\n$EndComments\n",
        1,
    );
    assert_ne!(commented, text);
    p.write("box.msh", &commented);
    assert_eq!(ran(&p.build(&[])), ["file:box.msh", "tile:a"]);
    let after = std::fs::metadata(p.out("a.stl")).expect("stl");
    assert_eq!(
        after.modified().expect("mtime"),
        placed.modified().expect("mtime")
    );
    assert!(temporaries(&p).is_empty(), "{:?}", temporaries(&p));
}

const FILE: &str = r#"
[cells.p]
tpms = "p"
symmetry = "Oh"
fit = { n = 16 }

[scaffolds.box]
mesh = "box.msh"

[outputs.a]
scaffold = "box"
cell = "p"
offset = 0.5
resolution = 8
"#;

#[test]
fn a_scaffold_file_is_keyed_by_its_content() {
    let p = Project::new(FILE);
    let bytes = data("box_4x3x2_hex8.msh");
    std::fs::write(p.path().join("box.msh"), &bytes).expect("write");
    let r = p.build(&[]);
    assert_eq!(only(&r)["tiling"]["elements"], 24);
    assert_eq!(only(&r)["watertight"], true);
    // Rewriting the same bytes: nothing to do.
    std::thread::sleep(std::time::Duration::from_millis(20));
    std::fs::write(p.path().join("box.msh"), &bytes).expect("write");
    assert!(ran(&p.build(&[])).is_empty());
    // Renamed: the file is read under its new name, but its content is known.
    std::fs::rename(p.path().join("box.msh"), p.path().join("renamed.msh")).expect("rename");
    p.write("lattice.toml", &FILE.replace("box.msh", "renamed.msh"));
    assert_eq!(ran(&p.build(&[])), ["file:renamed.msh"]);
    // Moving one node changes the content: the tiling reruns.
    let text = String::from_utf8(bytes).expect("ascii");
    let moved = text.replacen("\n4 3 2\n", "\n4.2 3.1 2.1\n", 1);
    assert_ne!(moved, text, "the box's corner node is written as `4 3 2`");
    p.write("renamed.msh", &moved);
    assert_eq!(
        ran(&p.build(&[])),
        ["file:renamed.msh", "tile:a", "write:a"]
    );
}

fn build_error(p: &Project) -> String {
    let out = p.run(&["build", "lattice.toml", "-q"]);
    assert!(!out.status.success(), "the build succeeded");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn a_file_of_the_wrong_element_is_an_error_naming_both() {
    let p = Project::new(&FILE.replace("\"Oh\"", "\"Td\""));
    std::fs::write(p.path().join("box.msh"), data("box_4x3x2_hex8.msh")).expect("write");
    let err = build_error(&p);
    assert!(
        err.contains(
            "`box.msh` has hex8 elements, which need a cell of group `Oh`, but `p` of \
             `outputs.a` has group `Td`"
        ),
        "{err}"
    );
}

#[test]
fn a_missing_node_data_view_lists_the_views_the_file_has() {
    let manifest = r#"
[cells.t]
tpms = "p"
symmetry = "Td"
fit = { n = 16 }

[scaffolds.sphere]
mesh = "sphere.msh"

[outputs.a]
scaffold = "sphere"
cell = "t"
solid = "shell"
thickness = "nodedata:thicknes"
resolution = 8
"#;
    let p = Project::new(manifest);
    std::fs::write(
        p.path().join("sphere.msh"),
        data("sphere_r10_tet4_thickness.msh"),
    )
    .expect("write");
    let err = build_error(&p);
    assert!(
        err.contains(
            "`outputs.a.thickness` reads node data `thicknes`, but `sphere.msh` has no such \
             view: its views are `thickness`"
        ),
        "{err}"
    );
    // With the right name, the graded shell builds closed.
    p.write(
        "lattice.toml",
        &manifest.replace("thicknes\"", "thickness\""),
    );
    let r = p.build(&[]);
    assert_eq!(only(&r)["watertight"], true);
    assert_eq!(only(&r)["tiling"]["element"], "tet4");
}

const PLATE: &str = r#"
[cells.s]
expr = "cos(tau*x) + cos(tau*y)"
symmetry = "D4"
fit = { n = 16 }

[scaffolds.plate]
grid = { min = [0, 0], max = [4, 2], divisions = [4, 2], element = "quad" }

[outputs.a]
scaffold = "plate"
cell = "s"
resolution = 16
"#;

#[test]
fn a_quad_grid_region_covers_half_and_extrudes_to_area_times_h() {
    // cos 2πx + cos 2πy changes sign under a shift by (½, ½), which maps the element (one
    // period) onto itself: Φ < 0 covers half of every element, so half of the 4 × 2 plate.
    let p = Project::new(PLATE);
    let r = p.build(&[]);
    let r = only(&r);
    let tiling = &r["tiling"];
    assert_eq!(tiling["element"], "quad4");
    assert_eq!(tiling["elements"], 8);
    // 3 interior vertical lines of 2 edges and 1 horizontal of 4; 2 × (4 + 2) on the border.
    assert_eq!(tiling["interior_faces"], 10);
    assert_eq!(tiling["boundary_faces"], 12);
    assert!((number(tiling, "scaffold_volume") - 8.0).abs() < 1e-12);
    assert_eq!(r["planar"], true);
    assert_eq!(r["manifold"], true);
    let fraction = number(r, "volume_fraction");
    println!("quad grid area fraction {fraction}");
    assert!((fraction - 0.5).abs() < 3e-3, "fraction {fraction}");
    let region_area = number(tiling, "region_area");
    assert!((number(r, "area") - region_area).abs() < 1e-4 * region_area);
    // The SVG holds the filled region and the scaffold's edges, drawn faintly.
    let svg = std::fs::read_to_string(p.out("a.svg")).expect("a.svg");
    assert!(svg.contains("fill-rule=\"evenodd\"") && svg.contains("stroke=\"#808080\""));
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));

    let h = 0.5;
    let extruded = p.build(&["--set", "outputs.a.extrude=0.5"]);
    let e = only(&extruded);
    assert_eq!(e["watertight"], true);
    assert_eq!(e["manifold"], true);
    let volume = number(e, "volume");
    let area = number(&e["tiling"], "region_area");
    println!("extruded volume {volume}, region area × h {}", area * h);
    assert!(
        (volume - area * h).abs() < 1e-5 * volume,
        "{volume} vs {}",
        area * h
    );
    assert!((volume - 0.5 * 8.0 * h).abs() < 3e-3 * 8.0 * h);
    assert!((number(&e["tiling"], "scaffold_volume") - 8.0 * h).abs() < 1e-12);
    // A solid is written as a mesh only: no drawing.
    let files = e["files"].as_array().expect("files");
    assert!(
        files
            .iter()
            .all(|f| !f.as_str().unwrap_or("").ends_with(".svg")),
        "{files:?}"
    );
}

#[test]
fn a_sphere_surface_thickened_along_its_normals_is_closed_with_volume_area_times_h() {
    let manifest = r#"
[cells.t]
expr = "cos(2*tau*x) + cos(2*tau*y) - 0.3"
symmetry = "D3"
fit = { n = 16 }

[scaffolds.sphere]
mesh = "sphere.msh"

[outputs.a]
scaffold = "sphere"
cell = "t"
thickness_normal = 0.2
resolution = 6
"#;
    let p = Project::new(manifest);
    std::fs::write(p.path().join("sphere.msh"), data("sphere_surface_tri3.msh")).expect("write");
    let r = p.build(&[]);
    let r = only(&r);
    assert_eq!(r["watertight"], true);
    assert_eq!(r["manifold"], true);
    assert_eq!(r["tiling"]["element"], "tri3");
    assert_eq!(r["tiling"]["elements"], 898);
    // A closed surface: every edge interior.
    assert_eq!(r["tiling"]["boundary_faces"], 0);
    let (volume, area) = (number(r, "volume"), number(&r["tiling"], "region_area"));
    println!("shell volume {volume}, mid area × h {}", area * 0.2);
    assert!(
        (volume / (area * 0.2) - 1.0).abs() < 5e-3,
        "{volume} vs {}",
        area * 0.2
    );
}

#[test]
fn two_dimensional_keys_on_the_wrong_scaffold_name_the_file_and_element() {
    // `extrude` on a curved surface, and on a hexahedral file; `skin` on a planar file.
    let p = Project::new(
        r#"
[cells.t]
expr = "cos(2*tau*x) + cos(2*tau*y) - 0.3"
symmetry = "D3"
fit = { n = 16 }

[scaffolds.sphere]
mesh = "sphere.msh"

[outputs.a]
scaffold = "sphere"
cell = "t"
extrude = 1
resolution = 4
"#,
    );
    std::fs::write(p.path().join("sphere.msh"), data("sphere_surface_tri3.msh")).expect("write");
    let err = build_error(&p);
    assert!(
        err.contains(
            "`outputs.a.extrude` needs a planar scaffold (every node at one z), but \
             `sphere.msh` is a curved surface of tri3 elements"
        ),
        "{err}"
    );
    let p = Project::new(&FILE.replace("offset = 0.5", "extrude = 2"));
    std::fs::write(p.path().join("box.msh"), data("box_4x3x2_hex8.msh")).expect("write");
    let err = build_error(&p);
    assert!(
        err.contains(
            "`outputs.a.extrude` applies only to 2D scaffolds (quad, tri), but `box.msh` has \
             hex8 elements"
        ),
        "{err}"
    );
    let p = Project::new(
        &PLATE
            .replace(
                "grid = { min = [0, 0], max = [4, 2], divisions = [4, 2], element = \"quad\" }",
                "mesh = \"plate.msh\"",
            )
            .replace("resolution = 16", "skin = 0.1"),
    );
    std::fs::write(p.path().join("plate.msh"), data("plate_hole_quad4.msh")).expect("write");
    let err = build_error(&p);
    assert!(
        err.contains(
            "`outputs.a.skin` does not apply to 2D scaffolds, but `plate.msh` has quad4 elements"
        ),
        "{err}"
    );
    // A triangle file under a D4 cell: the group check names the file, element and groups.
    std::fs::write(p.path().join("plate.msh"), data("plate_hole_tri3.msh")).expect("write");
    let err = build_error(&p);
    assert!(
        err.contains(
            "`plate.msh` has tri3 elements, which need a cell of group `D3`, but `s` of \
             `outputs.a` has group `D4`"
        ),
        "{err}"
    );
}
