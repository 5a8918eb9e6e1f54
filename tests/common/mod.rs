//! Shared helpers for the integration tests: run the real binary in a scratch directory.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub const BIN: &str = env!("CARGO_BIN_EXE_latticebuild");

/// A scratch project directory holding one manifest.
pub struct Project {
    pub dir: tempfile::TempDir,
}

impl Project {
    pub fn new(manifest: &str) -> Project {
        let dir = tempfile::tempdir().expect("tempdir");
        std::fs::write(dir.path().join("lattice.toml"), manifest).expect("write manifest");
        Project { dir }
    }

    pub fn path(&self) -> &Path {
        self.dir.path()
    }

    pub fn write(&self, name: &str, text: &str) {
        std::fs::write(self.path().join(name), text).expect("write");
    }

    /// Runs `latticebuild ARGS` in the project directory (stderr plain, whatever this
    /// process's `CLICOLOR_FORCE`).
    pub fn run(&self, args: &[&str]) -> Output {
        Command::new(BIN)
            .args(args)
            .env_remove("CLICOLOR_FORCE")
            .current_dir(self.path())
            .output()
            .expect("run latticebuild")
    }

    /// Builds with `--report -` and returns the parsed reports; panics on failure.
    pub fn build(&self, extra: &[&str]) -> serde_json::Value {
        let mut args = vec!["build", "lattice.toml", "--report", "-", "-q"];
        args.extend_from_slice(extra);
        let out = self.run(&args);
        assert!(
            out.status.success(),
            "build failed: {}\n{}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).expect("report JSON")
    }

    pub fn out(&self, file: &str) -> PathBuf {
        self.path().join("out").join(file)
    }
}

/// The report of output `name` in a list of reports; panics when there is none.
pub fn by_name<'a>(reports: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    reports
        .as_array()
        .expect("array")
        .iter()
        .find(|r| r["name"] == name)
        .unwrap_or_else(|| panic!("no report {name}"))
}

/// A report's number at `key`; panics when it is not one.
pub fn number(report: &serde_json::Value, key: &str) -> f64 {
    report[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} in {report}"))
}

/// Names of the stages that ran (were not cached) in a list of reports, but for the
/// `preview:` nodes, which rerun with their write (`tests/previews.rs` checks them:
/// [`ran_all`]).
pub fn ran(reports: &serde_json::Value) -> Vec<String> {
    let mut names = ran_all(reports);
    names.retain(|n| !n.starts_with("preview:"));
    names
}

/// Names of every stage that ran, previews too.
pub fn ran_all(reports: &serde_json::Value) -> Vec<String> {
    let mut names: Vec<String> = reports
        .as_array()
        .expect("array")
        .iter()
        .flat_map(|r| r["stages"].as_array().expect("stages").clone())
        .filter(|s| s["cached"] == false)
        .map(|s| s["stage"].as_str().expect("stage").to_string())
        .collect();
    names.sort();
    names.dedup();
    names
}

/// Copies the files of directory `from` into `to` (created), recursively, except the names in
/// `skip`.
pub fn copy_dir(from: &Path, to: &Path, skip: &[&str]) {
    std::fs::create_dir_all(to).expect("mkdir");
    for entry in std::fs::read_dir(from).expect("read dir").flatten() {
        let path = entry.path();
        let name = entry.file_name();
        if name.to_str().is_some_and(|n| skip.contains(&n)) {
            continue;
        }
        if path.is_dir() {
            copy_dir(&path, &to.join(&name), skip);
        } else {
            std::fs::copy(&path, to.join(&name)).expect("copy");
        }
    }
}

/// A UV sphere of `radius` around `centre`: `(ASCII STL, enclosed volume)`, triangles
/// counter-clockwise seen from outside.
pub fn sphere_stl(radius: f64, centre: [f64; 3], rings: usize, segments: usize) -> (String, f64) {
    // Poles and the seam are exact, so the surface is closed (shared corners are equal).
    let point = |i: usize, j: usize| -> [f64; 3] {
        let theta = std::f64::consts::PI * i as f64 / rings as f64;
        let phi = 2.0 * std::f64::consts::PI * (j % segments) as f64 / segments as f64;
        let ring = if i == 0 || i == rings {
            0.0
        } else {
            radius * theta.sin()
        };
        let z = match i {
            0 => radius,
            _ if i == rings => -radius,
            _ => radius * theta.cos(),
        };
        [
            centre[0] + ring * phi.cos(),
            centre[1] + ring * phi.sin(),
            centre[2] + z,
        ]
    };
    let mut triangles = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let (a, b) = (point(i, j), point(i, j + 1));
            let (c, d) = (point(i + 1, j), point(i + 1, j + 1));
            // Rows go from the north pole down: (a, c, d) and (a, d, b) face outward.
            if i > 0 {
                triangles.push([a, c, b]);
            }
            if i + 1 < rings {
                triangles.push([b, c, d]);
            }
        }
    }
    let mut text = String::from("solid sphere\n");
    let mut volume = 0.0;
    for [p, q, r] in &triangles {
        let rel = |v: &[f64; 3]| [v[0] - centre[0], v[1] - centre[1], v[2] - centre[2]];
        let (p0, q0, r0) = (rel(p), rel(q), rel(r));
        volume += (p0[0] * (q0[1] * r0[2] - q0[2] * r0[1])
            - p0[1] * (q0[0] * r0[2] - q0[2] * r0[0])
            + p0[2] * (q0[0] * r0[1] - q0[1] * r0[0]))
            / 6.0;
        text.push_str(" facet normal 0 0 0\n  outer loop\n");
        for v in [p, q, r] {
            text.push_str(&format!("   vertex {} {} {}\n", v[0], v[1], v[2]));
        }
        text.push_str("  endloop\n endfacet\n");
    }
    text.push_str("endsolid sphere\n");
    (text, volume)
}

/// Checks a rendered diagnostic against `tests/golden/err/NAME.txt`; with `LATTICEBUILD_BLESS`
/// set (`cargo xtask golden --bless`), writes the file instead.
pub fn golden_err(name: &str, actual: &str) {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/golden/err/{name}.txt"));
    if std::env::var_os("LATTICEBUILD_BLESS").is_some() {
        std::fs::write(&file, actual).expect("bless a golden file");
        return;
    }
    let expected = std::fs::read_to_string(&file)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", file.display()));
    assert!(
        expected == actual,
        "the output differs from {}\n--- expected:\n{expected}--- actual:\n{actual}\
         (run `cargo xtask golden --bless` if the change is intended)",
        file.display()
    );
}
