//! Every bundled example builds, and every output is manifold, and watertight unless it is the
//! planar region of a 2D cell. Every output is also one solid piece, with no thin-wall warning
//! and every shell wall at least two spacings thick, except the few listed in `MANY_PIECES`,
//! whose manifests say why: the examples are meant to be printed. And none seals a cavity
//! (trapped powder or resin) but those listed in `CAVITIES`, skins and crystal cages. Each
//! example's reports validate against `docs/report.schema.json`, and its manifest against
//! `docs/manifest.schema.json`.

use crate::common;

use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;

/// The outputs that are more than one piece on purpose, as (manifest, output, why).
const MANY_PIECES: &[(&str, &str, &str)] = &[
    (
        "cesogen.toml",
        "two_rods",
        "§4.3's two rods, 4 apart, joined by `union` without touching",
    ),
    (
        "crystals.toml",
        "rock_salt",
        "the surface through rock salt's ions is a stack of sheets: the solid is layers",
    ),
];

/// The outputs that seal cavities on purpose, as (manifest, output, why).
const CAVITIES: &[(&str, &str, &str)] = &[
    (
        "cesogen.toml",
        "filled_part",
        "the part's shell closes the lattice in",
    ),
    (
        "mesh_inputs.toml",
        "ring",
        "`skin` closes the torus round its gyroid",
    ),
    (
        "tiling.toml",
        "box",
        "`skin` closes the box round its lattice",
    ),
    (
        "tiling.toml",
        "curved_sphere",
        "`skin` closes the ball round its struts",
    ),
    (
        "crystals.toml",
        "framework",
        "the framework's cages, closed by the surface and the caps on the box faces",
    ),
    (
        "crystals.toml",
        "paper_model",
        "voids of the reconstructed surface closed by the caps on the box faces",
    ),
];

/// Walls thinner than this many sample (or lattice) spacings get a warning.
const THIN_WALL: f64 = 2.0;

/// One test per bundled example, named after its manifest (`examples/NAME.toml`), and
/// `EXAMPLES`, the list `every_example_is_tested` holds against the directory.
macro_rules! examples {
    ($($name:ident),* $(,)?) => {
        const EXAMPLES: &[&str] = &[$(concat!(stringify!($name), ".toml")),*];
        $(
            #[test]
            fn $name() {
                check_example(concat!(stringify!($name), ".toml"));
            }
        )*
    };
}

examples!(
    cesogen,
    crystals,
    expression,
    gyroid,
    mesh_inputs,
    optimizer_loop,
    sources,
    symmetric_cells,
    tiling,
    tiling_2d,
    tpms_gallery,
);

/// A new example cannot be forgotten: every `examples/*.toml` has its test above, and every
/// exception names a listed example.
#[test]
fn every_example_is_tested() {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut found = BTreeSet::new();
    for entry in std::fs::read_dir(&examples).expect("examples") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "toml") {
            found.insert(
                path.file_name()
                    .expect("name")
                    .to_string_lossy()
                    .to_string(),
            );
        }
    }
    let listed: BTreeSet<String> = EXAMPLES.iter().map(|s| s.to_string()).collect();
    assert_eq!(
        found, listed,
        "examples/*.toml and the list of `examples!` in tests/examples.rs differ"
    );
    assert!(
        found.len() >= 3,
        "expected the bundled examples, found {}",
        found.len()
    );
    for (file, name, _) in MANY_PIECES.iter().chain(CAVITIES) {
        assert!(
            listed.contains(*file),
            "{file}: {name} is an exception but {file} is not a listed example"
        );
    }
}

/// Builds `examples/FILE` in a scratch copy and checks every output.
fn check_example(file: &str) {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut excepted_seen = BTreeSet::new();
    let path = examples.join(file);
    let scratch = tempfile::tempdir().expect("tempdir");
    let manifest = scratch.path().join(path.file_name().expect("name"));
    std::fs::copy(&path, &manifest).expect("copy");
    // The meshes, crystals, scaffolds, images and points examples read, at the same place.
    for dir in ["meshes", "crystals", "scaffolds", "voxels", "points"] {
        common::copy_dir(&examples.join(dir), &scratch.path().join(dir), &[]);
    }
    let out = Command::new(common::BIN)
        .args(["build", "--report", "-", "-q"])
        .arg(&manifest)
        .output()
        .expect("run");
    assert!(
        out.status.success(),
        "{}: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let reports: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    // The automation contract: the reports and the manifest validate against their schemas.
    crate::contract::assert_valid("report.schema.json", &reports, file);
    let text = std::fs::read_to_string(&path).expect("manifest text");
    crate::contract::assert_valid(
        "manifest.schema.json",
        &crate::contract::manifest_json(&text),
        file,
    );
    for r in reports.as_array().expect("array") {
        // Planar regions of 2D cells are open by nature; every solid must be closed.
        if r["planar"] != true {
            assert_eq!(
                r["watertight"],
                true,
                "{}: {} is not watertight",
                path.display(),
                r["name"]
            );
        }
        assert_eq!(
            r["manifold"],
            true,
            "{}: {} is not manifold",
            path.display(),
            r["name"]
        );
        assert!(r["triangles"].as_u64().expect("count") > 0);
        let file = path
            .file_name()
            .expect("name")
            .to_string_lossy()
            .to_string();
        let name = r["name"].as_str().expect("name");
        let pieces = r["components"].as_u64().expect("components");
        match MANY_PIECES
            .iter()
            .find(|(m, o, _)| *m == file && *o == name)
        {
            // Kept honest: an exception that has become one piece leaves the list.
            Some((_, _, why)) => {
                assert!(
                    pieces > 1,
                    "{file}: {name} is one piece now, listed as not: {why}"
                );
                excepted_seen.insert((file.clone(), name.to_string()));
            }
            None => assert_eq!(
                pieces, 1,
                "{file}: {name} is {pieces} pieces (the largest {}): a printed example must \
                 be one, or be listed in MANY_PIECES with the reason its manifest gives",
                r["largest_component_fraction"]
            ),
        }
        let cavities = r["cavities"].as_u64().expect("cavities");
        let sealed = CAVITIES.iter().any(|(m, o, _)| *m == file && *o == name);
        assert!(
            sealed == (cavities > 0),
            "{file}: {name} seals {cavities} cavities; a printed example must seal none, or \
             be listed in CAVITIES with the reason its manifest gives"
        );
        if let Some(wall) = r["thinnest_wall"].as_f64() {
            assert!(
                wall >= THIN_WALL,
                "{file}: {name}'s thinnest wall is {wall} spacings, under {THIN_WALL}"
            );
        }
        for w in r["warnings"].as_array().into_iter().flatten() {
            let w = w.as_str().expect("warning text");
            assert!(
                !w.contains("shell wall"),
                "{file}: {name} warns of a thin wall: {w}"
            );
        }
        for f in r["files"].as_array().expect("files") {
            assert!(
                Path::new(f.as_str().expect("path")).is_file(),
                "{f} missing"
            );
        }
    }
    for (m, name, _) in MANY_PIECES {
        assert!(
            *m != file || excepted_seen.contains(&(file.to_string(), name.to_string())),
            "{file}: {name} is listed in MANY_PIECES but was not built"
        );
    }
}
