//! Golden cases, one driver for all (see `tests/golden/README.md`):
//! - `ok/NNNN_name/lattice.toml` must build without diagnostics; a normalized summary of every
//!   output (counts, validity, bbox, volume and area at fixed precision, warnings) must equal
//!   `summary.txt`.
//! - `err/NNNN_name/lattice.toml` must fail with exit code 2 and print exactly `expected.txt`.
//!
//! An optional `args` file adds command-line arguments, one per line.
//! `cargo xtask golden --bless` (or `LATTICEBUILD_BLESS=1`) rewrites the expectations.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

fn cases(kind: &str) -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(kind);
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&root)
        .expect("golden dir")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.join("lattice.toml").is_file())
        .collect();
    dirs.sort();
    dirs
}

fn blessing() -> bool {
    std::env::var_os("LATTICEBUILD_BLESS").is_some()
}

/// Runs the case in a scratch copy, so neither outputs nor cache land in the source tree.
fn run_case(case: &Path, extra: &[&str]) -> std::process::Output {
    let scratch = tempfile::tempdir().expect("tempdir");
    // The manifest and every file it may read (meshes), not the expected results.
    common::copy_dir(
        case,
        scratch.path(),
        &["summary.txt", "expected.txt", "args"],
    );
    let mut args: Vec<String> = vec!["build".into(), "lattice.toml".into()];
    if let Ok(text) = std::fs::read_to_string(case.join("args")) {
        args.extend(
            text.lines()
                .filter(|l| !l.trim().is_empty())
                .map(str::to_string),
        );
    }
    args.extend(extra.iter().map(|s| s.to_string()));
    Command::new(common::BIN)
        .args(&args)
        .env_remove("CLICOLOR_FORCE")
        .current_dir(scratch.path())
        .output()
        .expect("run")
}

fn check(expected_file: &Path, actual: &str, case: &Path) -> Result<(), String> {
    if blessing() {
        std::fs::write(expected_file, actual).expect("bless");
        return Ok(());
    }
    let expected = std::fs::read_to_string(expected_file).unwrap_or_default();
    if expected == actual {
        Ok(())
    } else {
        Err(format!(
            "{}: output differs from {}\n--- expected\n{expected}\n--- actual\n{actual}\n(run `cargo xtask golden --bless` if the change is intended)",
            case.display(),
            expected_file.display()
        ))
    }
}

/// The summary of one report, at a precision that is stable across runs.
fn summarize(report: &serde_json::Value) -> String {
    let num = |v: &serde_json::Value| v.as_f64().expect("number");
    let vec3 = |v: &serde_json::Value| {
        let a = v.as_array().expect("array");
        format!("[{:.6}, {:.6}, {:.6}]", num(&a[0]), num(&a[1]), num(&a[2]))
    };
    format!(
        "output {}\n  triangles {}\n  vertices {}\n  watertight {}\n  manifold {}\n  euler_characteristic {}\n  volume {:.6e}\n  area {:.6e}\n  volume_fraction {:.6}\n  components {} (largest {:.6})\n  bbox {} {}\n",
        report["name"].as_str().expect("name"),
        report["triangles"],
        report["vertices"],
        report["watertight"],
        report["manifold"],
        report["euler_characteristic"],
        num(&report["volume"]),
        num(&report["area"]),
        num(&report["volume_fraction"]),
        report["components"],
        num(&report["largest_component_fraction"]),
        vec3(&report["bbox"]["min"]),
        vec3(&report["bbox"]["max"]),
    ) + &tiling(report)
        + &measures(report)
        + &warnings(report)
}

/// The measured topology and local thickness (medians, four significant digits).
fn measures(report: &serde_json::Value) -> String {
    let spread = |key: &str| match report[key]["median"].as_f64() {
        Some(m) => format!(
            "  {key} median {m:.4e} voxel {:.4e}\n",
            report[key]["voxel"].as_f64().expect("voxel")
        ),
        None => String::new(),
    };
    format!(
        "  genus {} cavities {}\n",
        report["genus"], report["cavities"]
    ) + &spread("wall_thickness")
        + &spread("pore_size")
}

/// A shell's measured wall, and a line per warning of the report (loose pieces, a thin wall).
fn warnings(report: &serde_json::Value) -> String {
    let wall = report["thinnest_wall"]
        .as_f64()
        .map_or(String::new(), |wall| format!("  thinnest_wall {wall:.4}\n"));
    let Some(warnings) = report["warnings"].as_array() else {
        return wall;
    };
    wall + &warnings
        .iter()
        .map(|w| format!("  warning {}\n", w.as_str().expect("text")))
        .collect::<String>()
}

/// The tiling line of a tiled output's report (nothing for other outputs).
fn tiling(report: &serde_json::Value) -> String {
    let t = &report["tiling"];
    if t.is_null() {
        return String::new();
    }
    // 2D scaffolds also report the tiled region's area.
    let region = match t["region_area"].as_f64() {
        Some(area) => format!(" region_area {area:.6e}"),
        None => String::new(),
    };
    format!(
        "  tiling {} elements {} interior_faces {} boundary_faces {} scaffold_volume {:.6e}{region}\n",
        t["element"].as_str().expect("element"),
        t["elements"],
        t["interior_faces"],
        t["boundary_faces"],
        t["scaffold_volume"].as_f64().expect("volume"),
    )
}

#[test]
fn golden_ok_cases() {
    let mut failures = Vec::new();
    for case in cases("ok") {
        let out = run_case(&case, &["--report", "-", "-q"]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        if !out.status.success() || !stderr.is_empty() {
            failures.push(format!(
                "{}: expected a clean build, got {}\n{stderr}",
                case.display(),
                out.status
            ));
            continue;
        }
        let reports: serde_json::Value = serde_json::from_slice(&out.stdout).expect("report");
        let summary: String = reports
            .as_array()
            .expect("array")
            .iter()
            .map(summarize)
            .collect();
        if let Err(e) = check(&case.join("summary.txt"), &summary, &case) {
            failures.push(e);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn golden_err_cases() {
    let mut failures = Vec::new();
    for case in cases("err") {
        let out = run_case(&case, &[]);
        if out.status.code() != Some(2) {
            failures.push(format!(
                "{}: expected exit code 2, got {}",
                case.display(),
                out.status
            ));
        }
        if !out.stdout.is_empty() {
            failures.push(format!("{}: expected nothing on stdout", case.display()));
        }
        let stderr = String::from_utf8_lossy(&out.stderr);
        if let Err(e) = check(&case.join("expected.txt"), &stderr, &case) {
            failures.push(e);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
