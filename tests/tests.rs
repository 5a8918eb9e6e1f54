//! The root crate's integration tests, one binary (`cargo test --test integration`): each
//! file of `tests/` is a module here, so cargo links one test executable instead of one per
//! file. The tests run as threads of one process: none may change process-wide state
//! (environment, current directory, signal dispositions, global thread pools); each works in
//! its own temporary directory and passes what a child needs through its `Command`.
//!
//! A new test file must be listed here; `every_test_file_is_a_module` fails otherwise.

mod common;

mod codegen;
mod command_line_edges;
mod contract;
mod conventions;
mod crystal;
mod determinism;
mod examples;
mod far_from_origin;
mod formats;
mod golden;
mod incremental;
mod islands;
mod measure_report;
mod mesh_inputs;
mod misuse;
mod model_units;
mod pieces;
mod point_cells;
mod previews;
mod sdf_cli;
mod sdf_manifest;
mod serve;
mod shells;
mod symmetric;
mod tiling;
mod tiling_cache;
mod volume_fraction;
mod voxel_cells;
mod vtk_scaffolds;
mod watch;

/// Cargo no longer discovers `tests/*.rs` (`autotests = false`), so a file not declared
/// above would silently never compile or run.
#[test]
fn every_test_file_is_a_module() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let this = std::fs::read_to_string(dir.join("tests.rs")).expect("tests.rs");
    for entry in std::fs::read_dir(&dir).expect("tests dir") {
        let path = entry.expect("entry").path();
        let Some(stem) = path.file_stem().and_then(|s| s.to_str()) else {
            continue;
        };
        if path.extension().is_some_and(|e| e == "rs") && stem != "tests" {
            assert!(
                this.lines().any(|l| l == format!("mod {stem};")),
                "tests/{stem}.rs is not declared as a module of tests/tests.rs"
            );
        }
    }
}
