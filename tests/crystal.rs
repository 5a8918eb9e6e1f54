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

/// The `crystal` command's JSON `terms` as a model.
fn model_of(terms: &[serde_json::Value]) -> latticebuild_geom::periodic::PsModel {
    let number = |v: &serde_json::Value| v.as_f64().expect("number");
    latticebuild_geom::periodic::PsModel::new(
        terms
            .iter()
            .map(|t| {
                let v: Vec<f64> = t["vector"]
                    .as_array()
                    .expect("vector")
                    .iter()
                    .map(number)
                    .collect();
                latticebuild_geom::periodic::PsTerm {
                    moment: number(&t["moment"]),
                    scale: number(&t["scale"]),
                    vector: [v[0], v[1], v[2], v[3]],
                }
            })
            .collect(),
    )
}

fn crystal_json(project: &Project, args: &[&str]) -> serde_json::Value {
    let out = project.run(&[&["crystal"], args, &["--json"]].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("json")
}

/// `--scale 2,0.5,-1.5 --rotate 1,2,2,30 --translate 0.3,-0.2,0.7` prints
/// `PsModel::transformed` of the untransformed terms, and that model at p is the
/// untransformed one at S⁻¹ Rᵀ (p − t), with R built here from a quaternion.
#[test]
fn crystal_transform_flags_print_the_transformed_terms() {
    let project = Project::new("");
    let plain = crystal_json(&project, &[FAU, "--species", "Si"]);
    let moved = crystal_json(
        &project,
        &[
            FAU,
            "--species",
            "Si",
            "--scale",
            "2,0.5,-1.5",
            "--rotate",
            "1,2,2,30",
            "--translate",
            "0.3,-0.2,0.7",
        ],
    );
    assert_eq!(moved["max_error"], plain["max_error"]);
    let half = 30f64.to_radians() / 2.0;
    let (w, x, y, z) = (
        half.cos(),
        half.sin() / 3.0,
        2.0 * half.sin() / 3.0,
        2.0 * half.sin() / 3.0,
    );
    let r = [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - z * w),
            2.0 * (x * z + y * w),
        ],
        [
            2.0 * (x * y + z * w),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - x * w),
        ],
        [
            2.0 * (x * z - y * w),
            2.0 * (y * z + x * w),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ];
    let (s, t) = ([2.0, 0.5, -1.5], [0.3, -0.2, 0.7]);
    let linear: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| r[i][j] * s[j]));
    let untransformed = model_of(plain["terms"].as_array().expect("terms"));
    let expected = untransformed.transformed(linear, t).expect("invertible");
    let got = model_of(moved["terms"].as_array().expect("terms"));
    assert_eq!(got.terms.len(), expected.terms.len());
    for (g, e) in got.terms.iter().zip(&expected.terms) {
        assert_eq!((g.moment, g.scale), (e.moment, e.scale));
        for i in 0..4 {
            assert!((g.vector[i] - e.vector[i]).abs() <= 1e-12, "{g:?} vs {e:?}");
        }
    }
    let plain_terms = plain["terms"].as_array().expect("terms");
    for i in 0..100 {
        let p = [
            i as f64 * 0.031 - 1.0,
            (i * 13 % 17) as f64 * 0.11,
            0.5 - i as f64 * 0.017,
        ];
        let d = [p[0] - t[0], p[1] - t[1], p[2] - t[2]];
        let inverse: [f64; 3] =
            std::array::from_fn(|j| (0..3).map(|i| r[i][j] * d[i]).sum::<f64>() / s[j]);
        let (a, b) = (got.value(p), psi(plain_terms, inverse));
        assert!((a - b).abs() <= 1e-12, "at {p:?}: {a} vs {b}");
    }
    // Bad flags are usage errors naming the flag.
    let out = project.run(&["crystal", FAU, "--rotate", "0,0,0,90"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--rotate needs a non-zero axis"));
    let out = project.run(&["crystal", FAU, "--scale", "1,2"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--scale takes 3"));
}

/// The JSON's Chebyshev form, evaluated here as Σ c_k cos(k arccos s) per basis vector,
/// equals the cosine terms (the optimised Faujasite surface has scales 1 and 2 on the same
/// vectors, so some polynomials have two degrees). The same run's optimisation numbers agree:
/// the phase kept is 0, the plain search's porosity at 0 is "before", "after" is the surface's
/// porosity, and the printed terms vanish at every Si atom (evaluated here).
#[test]
fn crystal_chebyshev_form_equals_the_cosine_terms() {
    let project = Project::new("");
    let json = crystal_json(&project, &[FAU, "--species", "Si", "--optimize"]);
    let o = &json["optimization"];
    let phase = &o["phase"];
    assert_eq!(phase["theta"].as_f64(), Some(0.0), "{o}");
    assert!(
        phase["evaluations"].as_u64().is_some_and(|n| n >= 24),
        "{o}"
    );
    assert_eq!(phase["porosity_at_zero"], o["before"]["porosity"], "{o}");
    assert_eq!(o["after"]["porosity"], json["porosity"], "{o}");
    assert_eq!(o["after"]["dimension"], json["dimension"], "{o}");
    assert!(
        o["domain"]
            .as_str()
            .is_some_and(|d| d.contains("unit cell")),
        "{o}"
    );
    let bytes = std::fs::read(FAU).expect("FAU.cif");
    let crystal = read_crystal("FAU.cif", &bytes).expect("read");
    let atoms = positions_of(&crystal.atoms(&ExpandOptions::default()), Some("Si"));
    let terms = json["terms"].as_array().expect("terms");
    assert!(terms.iter().all(|t| t["vector"][3].as_f64() == Some(0.0)));
    for a in &atoms {
        assert!(psi(terms, *a).abs() <= 1e-9, "{a:?}");
    }
    let terms = json["terms"].as_array().expect("terms");
    let form = &json["chebyshev"];
    let planes = form["planes"].as_array().expect("planes");
    assert!(
        planes
            .iter()
            .any(|p| p["coefficients"].as_array().is_some_and(|c| c.len() == 3))
    );
    let optimization = &json["optimization"];
    let (before, after) = (
        optimization["before"]["porosity"].as_f64().expect("before"),
        optimization["after"]["porosity"].as_f64().expect("after"),
    );
    assert!(after > before + 0.1, "{optimization}");
    for i in 0..100 {
        let p = [
            i as f64 * 0.0123,
            (i * 7 % 11) as f64 * 0.09,
            1.0 - i as f64 * 0.007,
        ];
        let chebyshev: f64 = form["constant"].as_f64().expect("constant")
            + planes
                .iter()
                .map(|plane| {
                    let v: Vec<f64> = plane["vector"]
                        .as_array()
                        .expect("vector")
                        .iter()
                        .map(|x| x.as_f64().expect("number"))
                        .collect();
                    let s = (TAU * (v[0] * p[0] + v[1] * p[1] + v[2] * p[2] + v[3])).cos();
                    plane["coefficients"]
                        .as_array()
                        .expect("coefficients")
                        .iter()
                        .enumerate()
                        .map(|(k, c)| c.as_f64().expect("number") * (k as f64 * s.acos()).cos())
                        .sum::<f64>()
                })
                .sum::<f64>();
        let cosine = psi(terms, p);
        assert!(
            (chebyshev - cosine).abs() <= 1e-12,
            "{p:?}: {chebyshev} vs {cosine}"
        );
    }
}

/// Rock salt's ions lie on a six-dimensional family of scale-1 surfaces. The command says so,
/// and gives the same surface for the symmetric CIF, for its P1 expansion written here (the
/// face-centred translations of Na at 0 and Cl at ½, worked out by hand) and for that list
/// shuffled.
#[test]
fn rock_salt_gives_one_surface_however_its_atoms_are_listed() {
    let project = Project::new("");
    let fcc = [
        [0.0, 0.0, 0.0],
        [0.0, 0.5, 0.5],
        [0.5, 0.0, 0.5],
        [0.5, 0.5, 0.0],
    ];
    let mut sites: Vec<(String, [f64; 3])> = Vec::new();
    for (n, t) in fcc.iter().enumerate() {
        sites.push((format!("Na{n}"), *t));
        sites.push((format!("Cl{n}"), t.map(|c| (c + 0.5) % 1.0)));
    }
    let cif = |sites: &[(String, [f64; 3])]| {
        let mut text = String::from(
            "data_NaCl_P1\n_cell_length_a 5.6402\n_cell_length_b 5.6402\n_cell_length_c 5.6402\n\
             _cell_angle_alpha 90\n_cell_angle_beta 90\n_cell_angle_gamma 90\n\
             loop_\n_atom_site_label\n_atom_site_type_symbol\n_atom_site_fract_x\n\
             _atom_site_fract_y\n_atom_site_fract_z\n",
        );
        for (label, p) in sites {
            let species = &label[..2];
            text.push_str(&format!("{label} {species} {} {} {}\n", p[0], p[1], p[2]));
        }
        text
    };
    project.write("p1.cif", &cif(&sites));
    let shuffled: Vec<_> = [5, 2, 7, 0, 3, 6, 1, 4]
        .iter()
        .map(|&i| sites[i].clone())
        .collect();
    project.write("shuffled.cif", &cif(&shuffled));
    let p1 = project.path().join("p1.cif").display().to_string();
    let shuffled = project.path().join("shuffled.cif").display().to_string();
    let runs: Vec<serde_json::Value> = [NACL, &p1, &shuffled]
        .iter()
        .map(|f| crystal_json(&project, &[f]))
        .collect();
    for json in &runs {
        assert_eq!(json["atoms"], 8);
        assert_eq!(json["multiplicity"], 6, "{json}");
        assert_eq!(json["unique"], false);
    }
    let reference = model_of(runs[0]["terms"].as_array().expect("terms"));
    for json in &runs[1..] {
        let model = model_of(json["terms"].as_array().expect("terms"));
        assert_eq!(model.terms.len(), reference.terms.len(), "{json}");
        for (a, b) in model.terms.iter().zip(&reference.terms) {
            assert_eq!((a.scale, a.vector), (b.scale, b.vector));
            assert!((a.moment - b.moment).abs() <= 1e-9, "{a:?} vs {b:?}");
        }
    }
    let out = project.run(&["crystal", &shuffled]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("not unique"));
}

#[test]
fn a_build_warns_when_several_surfaces_pass_through_the_atoms() {
    // NaCl's 8 ions lie on 6 independent surfaces of the basis (the `crystal` command's JSON
    // above says so); FAU's Si atoms on one. The report says which, built fresh and cached.
    let project = Project::new(
        r#"
[cells.salt]
crystal = "NaCl.cif"

[cells.fau]
crystal = "FAU.cif"
species = "Si"

[outputs.salt]
cell = "salt"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 25

[outputs.fau]
cell = "fau"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 25
"#,
    );
    std::fs::copy(NACL, project.path().join("NaCl.cif")).expect("copy");
    std::fs::copy(FAU, project.path().join("FAU.cif")).expect("copy");
    let multiplicity = crystal_json(&project, &[NACL])["multiplicity"]
        .as_u64()
        .expect("multiplicity");
    assert_eq!(multiplicity, 6);
    for pass in ["fresh", "cached"] {
        let reports = project.build(&[]);
        let warnings = |name: &str| {
            reports
                .as_array()
                .expect("reports")
                .iter()
                .find(|r| r["name"] == name)
                .expect("report")["warnings"]
                .to_string()
        };
        let salt = warnings("salt");
        assert!(
            salt.contains("cell `salt`: not unique: 6 independent surfaces"),
            "{pass}: {salt}"
        );
        let fau = warnings("fau");
        assert!(!fau.contains("not unique"), "{pass}: {fau}");
    }
}
