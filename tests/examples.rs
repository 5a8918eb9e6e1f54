//! Every bundled example builds, and every output is manifold, and watertight unless it is the
//! planar region of a 2D cell.

mod common;

use std::path::Path;
use std::process::Command;

#[test]
fn every_example_builds_watertight_manifold_outputs() {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut count = 0;
    for entry in std::fs::read_dir(&examples).expect("examples") {
        let path = entry.expect("entry").path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let scratch = tempfile::tempdir().expect("tempdir");
        let manifest = scratch.path().join(path.file_name().expect("name"));
        std::fs::copy(&path, &manifest).expect("copy");
        // The meshes, crystals and scaffolds examples read, at the same relative place.
        for dir in ["meshes", "crystals", "scaffolds"] {
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
            for f in r["files"].as_array().expect("files") {
                assert!(
                    Path::new(f.as_str().expect("path")).is_file(),
                    "{f} missing"
                );
            }
        }
        count += 1;
    }
    assert!(count >= 3, "expected the bundled examples, found {count}");
}
