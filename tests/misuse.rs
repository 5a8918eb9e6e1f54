//! A build tool under misuse: results that are empty or broken fail the build (exit 1) with a
//! message that says why, instead of writing empty files and exiting 0.

mod common;

use common::Project;

/// `(exit code, stderr)` of `latticebuild build lattice.toml ARGS` in `p`.
fn build(p: &Project, extra: &[&str]) -> (Option<i32>, String) {
    let mut args = vec!["build", "lattice.toml"];
    args.extend_from_slice(extra);
    let out = p.run(&args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_field_that_never_crosses_zero_fails_and_says_its_range() {
    let p = Project::new(
        "[cells.one]\nexpr = \"1 + 0.5 * cos(tau * x)\"\n\n[outputs.blank]\ncell = \"one\"\n\
         domain = { min = [0, 0, 0], max = [1, 1, 1] }\nsamples = 9\n",
    );
    let (code, stderr) = build(&p, &[]);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(stderr.contains("the output is empty"), "{stderr}");
    assert!(stderr.contains("f ≤ 0 holds at no sample"), "{stderr}");
    assert!(stderr.contains("[0.500000, 1.500000]"), "{stderr}");
    // Nothing half-made is left for the user to mistake for a result.
    assert!(!p.out("blank.stl").exists());
    assert!(!p.out("blank.report.json").exists());
}

#[test]
fn a_crystal_surface_with_no_inside_fails() {
    let p = Project::new(&format!(
        "[cells.na]\ncrystal = \"{}/examples/crystals/NaCl.cif\"\nspecies = \"Na\"\n\n\
         [outputs.na]\ncell = \"na\"\ndomain = {{ min = [0, 0, 0], max = [1, 1, 1] }}\n\
         solid = \"inside\"\nsamples = 17\n",
        env!("CARGO_MANIFEST_DIR")
    ));
    let (code, stderr) = build(&p, &[]);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(stderr.contains("the output is empty"), "{stderr}");
    assert!(!p.out("na.stl").exists());
}
