//! Node data from VTK legacy files as VTK 9 and meshio write them (FIELD point data, a
//! `%20`-escaped name, METADATA blocks), through a real build: a shell graded by the file's
//! values gives the very mesh that the same grading written as an expression gives (the
//! fixture script computed the values from that expression), and a constant thickness not.

use crate::common;

use common::{Project, by_name, number};

const MANIFEST: &str = r#"
[cells.p]
tpms = "p"
symmetry = "Oh"
fit = { n = 16 }

[scaffolds.vtk9]
mesh = "vtk9.vtk"

[scaffolds.meshio]
mesh = "meshio.vtk"

[outputs.vtk9_file]
scaffold = "vtk9"
cell = "p"
solid = "shell"
thickness = "nodedata:wall thickness"
resolution = 8

[outputs.meshio_file]
scaffold = "meshio"
cell = "p"
solid = "shell"
thickness = "nodedata:thickness"
resolution = 8

[outputs.expression]
scaffold = "vtk9"
cell = "p"
solid = "shell"
thickness = "0.25 + z / 4"
resolution = 8

[outputs.constant]
scaffold = "meshio"
cell = "p"
solid = "shell"
thickness = 0.375
resolution = 8
"#;

fn fixture(name: &str) -> Vec<u8> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("crates/geom/tests/data/vtk")
        .join(name);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn nodedata_from_vtk_and_meshio_field_arrays_grades_a_shell_as_its_expression_does() {
    let p = Project::new(MANIFEST);
    // VTK 9's binary legacy file: `wall thickness` is a FIELD array after the SCALARS.
    std::fs::write(p.path().join("vtk9.vtk"), fixture("hex8_vtk9_binary.vtk")).expect("write");
    // meshio's: every point array is a FIELD array.
    std::fs::write(
        p.path().join("meshio.vtk"),
        fixture("hex8_meshio_binary.vtk"),
    )
    .expect("write");
    let reports = p.build(&[]);
    let expression = by_name(&reports, "expression");
    for name in ["vtk9_file", "meshio_file", "expression", "constant"] {
        let r = by_name(&reports, name);
        assert_eq!(r["watertight"], true, "{name}");
        assert_eq!(r["tiling"]["element"], "hex8", "{name}");
        assert_eq!(r["tiling"]["elements"], 4, "{name}");
    }
    for name in ["vtk9_file", "meshio_file"] {
        let r = by_name(&reports, name);
        assert_eq!(r["triangles"], expression["triangles"], "{name}");
        assert_eq!(
            number(r, "volume").to_bits(),
            number(expression, "volume").to_bits(),
            "{name}"
        );
    }
    let constant = number(by_name(&reports, "constant"), "volume");
    assert!(
        (constant - number(expression, "volume")).abs() > 1e-3 * constant,
        "the graded shell differs from a constant one"
    );
}
