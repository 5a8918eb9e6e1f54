//! At offset 0 the gyroid and P surfaces split space into two congruent halves, so the solid
//! `f ≤ 0` over whole periods has volume fraction exactly 1/2: an independent value to check
//! sampling, contouring, capping and the volume computation against.

use crate::common;

use common::Project;

fn fraction(tpms: &str) -> f64 {
    // Two periods per axis at 128 samples per period.
    let p = Project::new(&format!(
        r#"
[cells.c]
tpms = "{tpms}"

[outputs.o]
cell = "c"
domain = {{ min = [0, 0, 0], max = [2, 2, 2] }}
cell_size = 1
solid = "inside"
offset = 0
samples = 257
"#
    ));
    let reports = p.build(&[]);
    let report = &reports[0];
    assert_eq!(report["watertight"], true);
    assert_eq!(report["manifold"], true);
    report["volume_fraction"].as_f64().expect("fraction")
}

#[test]
fn gyroid_splits_space_in_half() {
    let f = fraction("gyroid");
    assert!((f - 0.5).abs() <= 0.003, "gyroid volume fraction {f}");
}

#[test]
fn p_splits_space_in_half() {
    let f = fraction("p");
    assert!((f - 0.5).abs() <= 0.003, "P volume fraction {f}");
}
