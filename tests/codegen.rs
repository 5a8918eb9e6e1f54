//! Generated files are current: the TPMS table in docs/manifest.md is produced by
//! `cargo xtask codegen` from `latticebuild_geom::tpms`.

#[test]
fn tpms_table_in_docs_is_current() {
    let status = std::process::Command::new(env!("CARGO"))
        .args([
            "run",
            "--quiet",
            "--package",
            "xtask",
            "--",
            "codegen",
            "--check",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .status()
        .expect("run xtask");
    assert!(
        status.success(),
        "docs/manifest.md is stale: run `cargo xtask codegen`"
    );
}
