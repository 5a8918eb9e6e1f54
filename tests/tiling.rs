//! Tiled outputs through the real binary: the summary's counts and volume fraction against
//! independent values, what each edit reruns (DESIGN.md §2: a format change only rewrites,
//! the scaffold file is keyed by content), and the errors only the `tile` stage can find.

mod common;

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

#[test]
fn two_dimensional_scaffolds_are_refused_clearly() {
    let manifest = r#"
[cells.s]
expr = "cos(tau*x) + cos(tau*y)"
symmetry = "D4"
fit = { n = 16 }

[scaffolds.plate]
grid = { min = [0, 0], max = [4, 2], divisions = [4, 2], element = "quad" }

[outputs.a]
scaffold = "plate"
cell = "s"
"#;
    let p = Project::new(manifest);
    let err = build_error(&p);
    assert!(
        err.contains("the grid `plate` has quad4 elements: tiling 2D scaffolds"),
        "{err}"
    );
}
