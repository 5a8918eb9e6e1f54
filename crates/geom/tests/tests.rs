//! The geometry crate's integration tests, one binary (`cargo test -p latticebuild-geom --test
//! integration`): each file of `tests/` is a module here, so cargo links one test executable
//! instead of one per file. The tests run as threads of one process: none may change
//! process-wide state (environment, current directory, global thread pools). Timings are not
//! tests: they are `cargo xtask bench geom`.
//!
//! A new test file must be listed here; `every_test_file_is_a_module` fails otherwise.

mod common;

mod contour2d_region;
mod element_clip;
mod expr_language;
mod expr_library;
mod mesh_io_roundtrip;
mod mesh_read_errors;
mod mesh_read_formats;
mod mesh_sdf_distance;
mod mesh_sdf_messy;
mod mesh_sdf_winding;
mod periodic_crystals;
mod periodic_phase;
mod scaffold_element;
mod scaffold_files;
mod scaffold_grid;
mod scaffold_read_errors;
mod scaffold_vtk_tools;
mod sdf_bounds;
mod sdf_errors;
mod sdf_paper;
mod sdf_pruning;
mod sdf_semantics;
mod symmetric_constrain;
mod symmetric_math;
mod symmetric_optimize;
mod symmetric_optimize_area;
mod tile_2d;
mod tile_gradient_jump;
mod tile_scaffolds;
mod tile_skin;
mod validate_properties;

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
