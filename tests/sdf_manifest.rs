//! SDF outputs in manifests (`sdf = "…"`) through the real binary: the same mesh as
//! `latticebuild sdf`, volumes against closed forms, and what each edit reruns.

use crate::common;

use std::f64::consts::PI;

use common::{Project, ran, sphere_stl};

fn number(report: &serde_json::Value, key: &str) -> f64 {
    report[key]
        .as_f64()
        .unwrap_or_else(|| panic!("no number `{key}`"))
}

fn only(reports: &serde_json::Value) -> &serde_json::Value {
    let all = reports.as_array().expect("array");
    assert_eq!(all.len(), 1);
    &all[0]
}

#[test]
fn a_program_gives_the_same_mesh_as_the_sdf_command() {
    let words = "cylinder orient 1,0,0 scale 1/2";
    let p = Project::new(&format!(
        "[outputs.rod]\nsdf = \"{words}\"\nsamples = \"50^3\"\nformats = [\"ply\"]\n"
    ));
    let reports = p.build(&[]);
    let rod = only(&reports);
    assert_eq!(rod["watertight"], true);
    assert_eq!(rod["manifold"], true);
    // A cylinder of radius 1/2 along x, cut by the box rule to [-1, 1] (length 2) — bounds
    // found automatically: ±1 along x, ±1/2 across.
    let volume = number(rod, "volume");
    assert!((volume - PI / 2.0).abs() < 0.02 * PI / 2.0, "{volume}");
    assert_eq!(rod["sdf_box"]["min"], serde_json::json!([-1.0, -0.5, -0.5]));
    assert_eq!(rod["sdf_box"]["max"], serde_json::json!([1.0, 0.5, 0.5]));

    let mut args = vec!["sdf"];
    args.extend(words.split_whitespace());
    args.extend(["-s", "50^3", "-o", "cli.ply", "-q"]);
    let out = p.run(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Header comments name the tool and the units (the command's its `--units`, default mm):
    // the rest must be the same bytes.
    let uncommented = |bytes: Vec<u8>| -> Vec<u8> {
        let end = bytes
            .windows(11)
            .position(|w| w == b"end_header\n")
            .expect("a PLY header");
        let header = String::from_utf8_lossy(&bytes[..end]).into_owned();
        let mut kept: Vec<u8> = header
            .lines()
            .filter(|l| !l.starts_with("comment "))
            .flat_map(|l| format!("{l}\n").into_bytes())
            .collect();
        kept.extend_from_slice(&bytes[end..]);
        kept
    };
    let built = uncommented(std::fs::read(p.out("rod.ply")).expect("built"));
    let cli = uncommented(std::fs::read(p.path().join("cli.ply")).expect("cli"));
    assert!(
        built == cli,
        "the manifest and the command wrote different meshes"
    );
}

#[test]
fn edits_rerun_only_what_they_change() {
    let p = Project::new(
        "[outputs.b]\nsdf = \"ball scale 2\"\nsamples = \"40^3\"\nformats = [\"stl\"]\n",
    );
    let first = p.build(&[]);
    assert_eq!(ran(&first), ["sdf:b", "write:b"]);
    let volume = number(only(&first), "volume");
    assert!(
        (volume - 32.0 * PI / 3.0).abs() < 0.02 * 32.0 * PI / 3.0,
        "{volume}"
    );
    assert!(ran(&p.build(&[])).is_empty());
    // Another spelling of the same program: nothing runs.
    assert!(ran(&p.build(&["--set", "outputs.b.sdf=BALL scale 4/2"])).is_empty());
    // Formats only: only the write.
    assert_eq!(
        ran(&p.build(&["--set", "outputs.b.formats=[\"stl\",\"obj\"]"])),
        ["write:b"]
    );
    // The program or the samples: the contour and the write.
    assert_eq!(
        ran(&p.build(&["--set", "outputs.b.sdf=ball scale 3"])),
        ["sdf:b", "write:b"]
    );
    assert_eq!(
        ran(&p.build(&["--set", "outputs.b.samples=30^3"])),
        ["sdf:b", "write:b"]
    );
}

#[test]
fn a_file_word_is_keyed_by_the_mesh_content() {
    let (stl, sphere) = sphere_stl(1.0, [0.0; 3], 24, 48);
    let p = Project::new(
        "[outputs.fill]\nsdf = \"tpms.gyroid scale 1/2 file meshes/part.stl intersection\"\n\
         samples = \"64^3\"\nbounds = { min = [-1.1, -1.1, -1.1], max = [1.1, 1.1, 1.1] }\n",
    );
    std::fs::create_dir(p.path().join("meshes")).unwrap();
    p.write("meshes/part.stl", &stl);
    let first = p.build(&[]);
    assert_eq!(
        ran(&first),
        ["file:meshes/part.stl", "sdf:fill", "write:fill"]
    );
    let fill = only(&first);
    assert_eq!(fill["watertight"], true);
    // The gyroid at offset 0 fills half of the ball.
    let fraction = number(fill, "volume") / sphere;
    assert!((fraction - 0.5).abs() < 0.03, "{fraction}");
    // Touched (same bytes, new time): nothing runs.
    std::thread::sleep(std::time::Duration::from_millis(20));
    p.write("meshes/part.stl", &stl);
    assert!(ran(&p.build(&[])).is_empty());
    // Edited: the file is read anew, the contour and the write run.
    let (smaller, _) = sphere_stl(0.8, [0.0; 3], 24, 48);
    p.write("meshes/part.stl", &smaller);
    assert_eq!(
        ran(&p.build(&[])),
        ["file:meshes/part.stl", "sdf:fill", "write:fill"]
    );
    // A missing mesh is a load error at the path's word.
    std::fs::remove_file(p.path().join("meshes/part.stl")).unwrap();
    let out = p.run(&["build", "lattice.toml"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("cannot read the mesh `meshes/part.stl` of `outputs.fill.sdf`"),
        "{err}"
    );
    assert!(err.contains("lattice.toml:2:35"), "{err}");
}

#[test]
fn a_solid_outside_its_bounds_is_a_build_error() {
    let p = Project::new(
        "[outputs.e]\nsdf = \"ball move 5,0,0\"\nbounds = { min = [-1, -1, -1], max = [1, 1, 1] }\n",
    );
    let out = p.run(&["build", "lattice.toml"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("the solid has no surface in the box [-1,1]×[-1,1]×[-1,1]"),
        "{err}"
    );
}
