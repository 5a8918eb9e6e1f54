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

    /// Runs `latticebuild ARGS` in the project directory.
    pub fn run(&self, args: &[&str]) -> Output {
        Command::new(BIN)
            .args(args)
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

/// Names of the stages that ran (were not cached) in a list of reports.
pub fn ran(reports: &serde_json::Value) -> Vec<String> {
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
