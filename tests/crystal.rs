//! Periodic surfaces from crystals through the real binary: the `crystal` command's JSON
//! (checked against the atoms by evaluating its terms here), located errors for a malformed
//! CIF, and crystal and `ps` cells in a build (watertight, content-keyed).

use crate::common;

use std::f64::consts::TAU;

use common::Project;
use latticebuild_geom::periodic::{ExpandOptions, positions_of, read_crystal};

const FAU: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/crates/geom/tests/data/crystals/FAU.cif"
);
const NACL: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/crates/geom/tests/data/crystals/NaCl.cif"
);

/// ψ from the JSON terms, written out independently of the library's model.
fn psi(terms: &[serde_json::Value], p: [f64; 3]) -> f64 {
    terms
        .iter()
        .map(|t| {
            let v: Vec<f64> = t["vector"]
                .as_array()
                .expect("vector")
                .iter()
                .map(|x| x.as_f64().expect("number"))
                .collect();
            let phase = v[0] * p[0] + v[1] * p[1] + v[2] * p[2] + v[3];
            t["moment"].as_f64().expect("moment")
                * (TAU * t["scale"].as_f64().expect("scale") * phase).cos()
        })
        .sum()
}

#[test]
fn crystal_json_describes_a_surface_through_every_silicon() {
    let project = Project::new("");
    let out = project.run(&["crystal", FAU, "--species", "Si", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(json["atoms"], 192);
    assert_eq!(json["converged"], true);
    let terms = json["terms"].as_array().expect("terms");
    assert_eq!(json["dimension"].as_u64(), Some(terms.len() as u64));
    let max_error = json["max_error"].as_f64().expect("max_error");
    let porosity = json["porosity"].as_f64().expect("porosity");
    assert!(max_error <= 1e-9, "{max_error}");
    assert!(porosity > 0.0 && porosity <= 1.0, "{porosity}");
    // The terms vanish at every Si atom; max |ψ| on a 48³ grid is at most 1 (normalised).
    let bytes = std::fs::read(FAU).expect("FAU.cif");
    let crystal = read_crystal("FAU.cif", &bytes).expect("read");
    let atoms = positions_of(&crystal.atoms(&ExpandOptions::default()), Some("Si"));
    assert_eq!(atoms.len(), 192);
    let worst = atoms
        .iter()
        .map(|&p| psi(terms, p).abs())
        .fold(0.0, f64::max);
    assert!(worst <= 1e-9, "{worst}");
    let n = 48;
    let mut max: f64 = 0.0;
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = [i, j, k].map(|c| c as f64 / n as f64);
                max = max.max(psi(terms, p).abs());
            }
        }
    }
    assert!(max <= 1.0 + 1e-9 && max > 0.95, "{max}");

    // The table shows the same numbers.
    let out = project.run(&["crystal", FAU, "--species", "Si"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("192 atoms"), "{text}");
    assert!(text.contains("passes through every atom"), "{text}");
    assert!(text.contains("cos(2π(x+y+z))"), "{text}");
}

#[test]
fn crystal_command_reports_unconverged_searches_and_bad_files() {
    let project = Project::new("");
    // Faujasite's oxygens need scale 4: at scale 1 the report is printed and the exit code is 1.
    let out = project.run(&[
        "crystal",
        FAU,
        "--species",
        "O",
        "--max-scale",
        "1",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(json["converged"], false);
    assert!(json["max_error"].as_f64().expect("error") > 1e-3);

    let out = project.run(&["crystal", NACL, "--species", "K"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no `K` atoms") && err.contains("Na, Cl"),
        "{err}"
    );

    project.write(
        "bad.cif",
        "data_bad\n_cell_length_a 4\n_cell_length_b 4\n_cell_length_c 4\nloop_\n\
         _symmetry_equivalent_pos_as_xyz\n'x,y,z'\n'-y+1/2,q,z'\n",
    );
    let out = project.run(&["crystal", "bad.cif"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.cif:8:9: symmetry operation `-y+1/2,q,z`"),
        "{err}"
    );
}

const MANIFEST: &str = r#"
[cells.fau]
crystal = "FAU.cif"
species = "Si"

[cells.p]
ps = { terms = [
    { moment = 1, vector = [1, 0, 0, 0] },
    { moment = 1, vector = [0, 1, 0] },
    { moment = 1, scale = 1, vector = [0, 0, 1, 0] },
] }

[outputs.fau]
cell = "fau"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
solid = "shell"
thickness = 0.1
samples = 41

[outputs.p]
cell = "p"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 41
"#;

#[test]
fn crystal_and_ps_cells_build_closed_lattices_keyed_by_content() {
    let project = Project::new(MANIFEST);
    std::fs::copy(FAU, project.path().join("FAU.cif")).expect("copy");
    let reports = project.build(&[]);
    for r in reports.as_array().expect("reports") {
        assert_eq!(r["watertight"], true, "{r}");
        assert_eq!(r["manifold"], true, "{r}");
    }
    // Schwarz P (cos 2πx + cos 2πy + cos 2πz ≤ 0) fills half the cell.
    let p = reports
        .as_array()
        .expect("reports")
        .iter()
        .find(|r| r["name"] == "p")
        .expect("p");
    let fraction = p["volume_fraction"].as_f64().expect("fraction");
    assert!((fraction - 0.5).abs() < 0.01, "{fraction}");
    let ran = common::ran(&reports);
    assert!(
        ran.iter()
            .any(|s| s.contains("crystal") || s.contains("fau")),
        "{ran:?}"
    );
    // Touching the file (same bytes) rebuilds nothing; a malformed file is a located error.
    std::fs::copy(FAU, project.path().join("FAU.cif")).expect("copy");
    let again = project.build(&[]);
    assert!(common::ran(&again).is_empty(), "{:?}", common::ran(&again));
    project.write("FAU.cif", "data_x\n_cell_length_a 4\n_cell_length_b 4\n");
    let out = project.run(&["build", "lattice.toml", "-q"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("FAU.cif:1:0: missing `_cell_length_c`"),
        "{err}"
    );
}

#[test]
fn a_ps_cell_fits_onto_the_symmetric_basis() {
    // Schwarz P written as PS terms is Oh-symmetric and band-limited: fitted with `symmetry`,
    // it goes through sample → fit → constrain unchanged and still fills half the cell.
    let project = Project::new(
        r#"
[cells.p]
ps = { terms = [
    { moment = 1, vector = [1, 0, 0, 0] },
    { moment = 1, vector = [0, 1, 0, 0] },
    { moment = 1, vector = [0, 0, 1, 0] },
] }
symmetry = "Oh"
fit = { n = 16 }

[outputs.p]
cell = "p"
domain = { min = [0, 0, 0], max = [2, 2, 2] }
samples = 61
"#,
    );
    let reports = project.build(&[]);
    let r = &reports.as_array().expect("reports")[0];
    assert_eq!(r["watertight"], true, "{r}");
    let fraction = r["volume_fraction"].as_f64().expect("fraction");
    assert!((fraction - 0.5).abs() < 0.005, "{fraction}");
    let ran = common::ran(&reports);
    for stage in ["sample:p", "fit:p", "constrain:p"] {
        assert!(ran.iter().any(|s| s == stage), "{stage} not in {ran:?}");
    }
}
