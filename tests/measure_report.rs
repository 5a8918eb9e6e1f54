//! What the report measures of a built mesh, through the real binary: local thickness of the
//! solid and the void (`[build] report = "full"`, the default), topology only with
//! `"basic"`, and a clear error for any other level. References are independent of the
//! measure: the self-complementary Schwarz P (its solid and its void are congruent), and
//! what a basic build leaves out.

use crate::common;

use common::{Project, by_name};

const P_BLOCK: &str = r#"
[cells.p]
tpms = "p"

[outputs.p]
cell = "p"
domain = { min = [0, 0, 0], max = [20, 20, 20] }
cell_size = 10
samples = 97
formats = ["ply"]
"#;

/// Schwarz P at level 0 is its own complement (a half-period shift swaps solid and void),
/// so in a box of whole periods its wall thickness and pore size agree. The largest ball in
/// a node of `cos x + cos y + cos z < 0` touches the surface along the body diagonals, at
/// `√3·π/2` of a period `2π`: a diameter of `√3/2` periods, 8.660 mm in 10 mm cells. The
/// solid is one piece with no cavity.
#[test]
fn schwarz_p_walls_and_pores_are_congruent() {
    let reports = Project::new(P_BLOCK).build(&[]);
    let p = by_name(&reports, "p");
    let wall = &p["wall_thickness"];
    let pore = &p["pore_size"];
    let (w, v) = (
        wall["median"].as_f64().expect("wall median"),
        pore["median"].as_f64().expect("pore median"),
    );
    assert!((w - v).abs() < 0.04 * w, "wall {wall} vs pore {pore}");
    // (Only the solid's largest ball is checked: the void's pores that the box cuts open
    // have no wall beyond it, so their balls there may be larger than the periodic ones.)
    let node = 10.0 * 3f64.sqrt() / 2.0;
    let max = wall["max"].as_f64().expect("max");
    assert!((max - node).abs() < 0.02 * node, "{wall} vs {node}");
    // Ordered figures, none beyond the box.
    for s in [wall, pore] {
        let f = |k: &str| s[k].as_f64().expect(k);
        assert!(f("min") <= f("p05") && f("p05") <= f("median") && f("median") <= f("max"));
        assert!(f("voxel") > 0.0 && f("voxel") < 1.0, "{s}");
    }
    assert_eq!(p["cavities"], 0);
    assert_eq!(p["genus"].as_array().map(Vec::len), Some(1), "{p}");
}

/// `report = "basic"` keeps the topology and leaves out the distance-transform figures; the
/// choice is part of the write stage's key, so switching levels remeasures.
#[test]
fn a_basic_report_leaves_out_local_thickness() {
    let project = Project::new(&format!("[build]\nreport = \"basic\"\n{P_BLOCK}"));
    let basic = project.build(&[]);
    let p = by_name(&basic, "p");
    assert!(
        p.get("wall_thickness").is_none() && p.get("pore_size").is_none(),
        "{p}"
    );
    assert_eq!(p["genus"].as_array().map(Vec::len), Some(1), "{p}");
    let full = project.build(&["--set", "build.report=full"]);
    assert!(by_name(&full, "p")["wall_thickness"]["median"].is_f64());
}

/// An unknown level names the key's place in the file and the levels there are.
#[test]
fn an_unknown_report_level_is_an_error_at_its_value() {
    let project = Project::new(&format!("[build]\nreport = \"everything\"\n{P_BLOCK}"));
    let out = project.run(&["build", "lattice.toml"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("lattice.toml:2:10"), "{stderr}");
    assert!(
        stderr.contains("unknown report level `everything`"),
        "{stderr}"
    );
    assert!(stderr.contains("\"basic\""), "{stderr}");
}
