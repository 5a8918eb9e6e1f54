//! Symmetric cells through the real binary: `latticebuild cell` against independent values,
//! and the cache reusing fitted cells.

use crate::common;

use common::{Project, ran};

const MANIFEST: &str = r#"
[cells.p]
expr = "cos(tau*x) + cos(tau*y) + cos(tau*z)"
symmetry = "Oh"
fit = { n = 16 }

[cells.tsin]
expr = "sin(tau*x)*sin(tau*y)*sin(tau*z) + 0.25*cos(tau*x)*cos(tau*y)*cos(tau*z)"
symmetry = "Td"
extend = "none"     # sample the cube as is: mirroring would change this (symmetric) input
fit = { n = 16 }

[outputs.block]
cell = "p"
domain = { min = [0, 0, 0], max = [2, 2, 2] }
samples = 41

[outputs.tet]
cell = "tsin"
over = "element"
samples = 17
"#;

fn cell_json(p: &Project, name: &str) -> serde_json::Value {
    let out = p.run(&[
        "cell",
        "lattice.toml",
        name,
        "--json",
        "--points",
        "points.txt",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("json")
}

const POINTS: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [0.1, -0.2, 0.3],
    [0.45, 0.05, -0.33],
    [-0.25, 0.4, 0.125],
];

fn write_points(p: &Project) {
    let text: String = POINTS
        .iter()
        .map(|q| format!("{} {} {}\n", q[0], q[1], q[2]))
        .collect();
    p.write("points.txt", &format!("# x y z\n{text}"));
}

#[test]
fn cell_reproduces_band_limited_inputs_with_values_and_gradients() {
    use std::f64::consts::TAU;
    let p = Project::new(MANIFEST);
    write_points(&p);
    // A band-limited input is reproduced exactly (docs/method.md §4), so the values must be the
    // formula's own, computed here independently.
    let json = cell_json(&p, "p");
    assert_eq!(json["group"], "Oh");
    assert_eq!(json["n"], 16);
    for (row, q) in json["values"]
        .as_array()
        .expect("values")
        .iter()
        .zip(POINTS)
    {
        let expected = (TAU * q[0]).cos() + (TAU * q[1]).cos() + (TAU * q[2]).cos();
        assert!(
            (row["value"].as_f64().expect("value") - expected).abs() < 1e-12,
            "{row}"
        );
        for a in 0..3 {
            let g = row["gradient"][a].as_f64().expect("gradient");
            assert!((g + TAU * (TAU * q[a]).sin()).abs() < 1e-10, "{row}");
        }
    }
    // Oh coefficients are real; P has exactly one orbit, f = (1, 0, 0).
    let coefficients = json["coefficients"].as_array().expect("coefficients");
    let big: Vec<_> = coefficients
        .iter()
        .filter(|c| c["re"].as_f64().unwrap_or(0.0).abs() > 1e-9)
        .collect();
    assert_eq!(big.len(), 1, "{big:?}");
    assert_eq!(big[0]["f"], serde_json::json!([1, 0, 0]));

    // A Td-only input (fails if the projection lacks the conjugate).
    let json = cell_json(&p, "tsin");
    for (row, q) in json["values"]
        .as_array()
        .expect("values")
        .iter()
        .zip(POINTS)
    {
        let (s, c) = (|v: f64| (TAU * v).sin(), |v: f64| (TAU * v).cos());
        let expected = s(q[0]) * s(q[1]) * s(q[2]) + 0.25 * c(q[0]) * c(q[1]) * c(q[2]);
        assert!(
            (row["value"].as_f64().expect("value") - expected).abs() < 1e-12,
            "{row}"
        );
    }
    assert_eq!(json["constraint"]["applied"], false);
}

#[test]
fn cell_errors_name_the_cell() {
    let p = Project::new(&format!("{MANIFEST}\n[cells.plain]\ntpms = \"gyroid\"\n"));
    let out = p.run(&["cell", "lattice.toml", "plain"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cell `plain` has no `symmetry`"));
    let out = p.run(&["cell", "lattice.toml", "tsn"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("did you mean `tsin`?"));
}

#[test]
fn contour_resolution_changes_reuse_fitted_cells() {
    let p = Project::new(MANIFEST);
    let first = p.build(&[]);
    assert!(ran(&first).contains(&"fit:p".to_string()));
    let again = p.build(&["--set", "outputs.block.samples=33"]);
    assert_eq!(ran(&again), ["contour:block", "write:block"]);
    let offset = p.build(&["--set", "cells.p.offset=0.2"]);
    assert_eq!(
        ran(&offset),
        ["constrain:p", "contour:block", "write:block"]
    );
}

#[test]
fn fitted_outputs_are_watertight_and_td_element_is_closed() {
    let p = Project::new(MANIFEST);
    let reports = p.build(&[]);
    for r in reports.as_array().expect("array") {
        assert_eq!(r["watertight"], true, "{}", r["name"]);
        assert_eq!(r["manifold"], true, "{}", r["name"]);
    }
    // P at offset 0 over whole periods splits the box in half.
    let block = reports
        .as_array()
        .expect("array")
        .iter()
        .find(|r| r["name"] == "block")
        .expect("block");
    assert!((block["volume_fraction"].as_f64().expect("fraction") - 0.5).abs() < 0.003);
}

#[test]
fn a_2d_cell_over_a_planar_domain_gives_its_periodic_region() {
    // cos a + cos b + ½ cos a cos b is band-limited and D4-symmetric: the fit reproduces it, so
    // the area fraction over whole periods is that of the formula (midpoint quadrature below).
    let p = Project::new(
        r#"
[cells.sq]
expr = "cos(tau*x) + cos(tau*y) + 0.5*cos(tau*x)*cos(tau*y)"
symmetry = "D4"
fit = { n = 16 }

[outputs.panel]
cell = "sq"
domain = { min = [0, 0], max = [3, 2] }
cell_size = 0.5
samples = [241, 161]
formats = ["ply"]
"#,
    );
    let reports = p.build(&[]);
    let r = &reports[0];
    assert_eq!(r["planar"], true);
    assert_eq!(r["manifold"], true);
    let m = 1000;
    let cos: Vec<f64> = (0..m)
        .map(|i| (std::f64::consts::TAU * (i as f64 + 0.5) / m as f64).cos())
        .collect();
    let inside = cos
        .iter()
        .flat_map(|a| cos.iter().map(move |b| a + b + 0.5 * a * b))
        .filter(|&v| v <= 0.0)
        .count();
    let exact = inside as f64 / (m * m) as f64;
    let fraction = r["volume_fraction"].as_f64().expect("fraction");
    assert!((fraction - exact).abs() < 2e-3, "{fraction} vs {exact}");
    // The region lies in z = 0 and reaches the side x = 3 (there Φ = 1 + 1.5 cos b ≤ 0 where
    // cos b ≤ −⅔); the SVG is written next to the mesh.
    assert_eq!(r["bbox"]["max"][2], 0.0);
    assert!((r["bbox"]["max"][0].as_f64().unwrap() - 3.0).abs() < 1e-6);
    let svg = std::fs::read_to_string(p.out("panel.svg")).expect("svg");
    assert!(svg.starts_with("<svg") && svg.contains("<path"));
    assert!(p.out("panel.ply").exists());
}

const OPTIMIZED: &str = r#"
[cells.w]
expr = "cos(tau*x) + cos(tau*y) + cos(tau*z) - 0.4*cos(tau*x)*cos(tau*y)*cos(tau*z)"
symmetry = "Oh"
fit = { n = 16 }
optimize = { volume_fraction = 0.3 }

[outputs.cube]
cell = "w"
over = "element"
samples = 41
"#;

#[test]
fn an_optimize_that_stops_short_warns_in_the_build_report() {
    // One iteration cannot take the cell from ½ to 0.3 (the geometry crate's test of the same
    // run); the report says what was reached, on the fresh build and on the cached one.
    let p = Project::new(&OPTIMIZED.replace("0.3 }", "0.3, max_iterations = 1 }"));
    for pass in ["fresh", "cached"] {
        let reports = p.build(&[]);
        let warnings = common::by_name(&reports, "cube")["warnings"].to_string();
        assert!(
            warnings.contains("cell `w`: optimize did not converge in 1 iterations")
                && warnings.contains("not 0.3000"),
            "{pass}: {warnings}"
        );
    }
    let converged = Project::new(OPTIMIZED);
    let reports = converged.build(&[]);
    let warnings = common::by_name(&reports, "cube")["warnings"].to_string();
    assert!(!warnings.contains("optimize"), "{warnings}");
}

#[test]
fn an_unreachable_optimize_stops_early_and_the_report_says_so() {
    // An area density of 100 is out of reach for any field of frequencies at most 8 (the cell's
    // 16 samples, the change band 6): by Crofton's bound its zero set has area density at most
    // 6 · 8. The run stalls within a few steps instead of spending its 30.
    let p = Project::new(&OPTIMIZED.replace("volume_fraction = 0.3", "surface_area = 100"));
    let reports = p.build(&[]);
    let warnings = common::by_name(&reports, "cube")["warnings"].to_string();
    assert!(
        warnings.contains("cell `w`: optimize did not reach its target")
            && warnings.contains("out of reach")
            && warnings.contains("not 100.0000"),
        "{warnings}"
    );
    let out = p.run(&["cell", "lattice.toml", "w", "--json"]);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let o = &json["optimization"];
    assert_eq!(o["converged"], false, "{o}");
    assert_eq!(o["stalled"], true, "{o}");
    let steps = o["iterations"].as_array().expect("iterations").len() - 1;
    assert!(steps <= 6, "{o}");
}

#[test]
fn optimized_cell_fills_its_fraction_and_lists_its_iterations() {
    let p = Project::new(OPTIMIZED);
    let reports = p.build(&[]);
    let cube = common::by_name(&reports, "cube");
    // Independent of the optimiser's own count: the contoured mesh's volume.
    let fraction = common::number(cube, "volume_fraction");
    assert!((fraction - 0.3).abs() <= 0.01, "{fraction}");
    assert_eq!(cube["watertight"], true);
    assert_eq!(cube["components"], 1);

    let out = p.run(&["cell", "lattice.toml", "w", "--json"]);
    assert!(out.status.success());
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let o = &json["optimization"];
    assert_eq!(o["converged"], true, "{o}");
    let iterations = o["iterations"].as_array().expect("iterations");
    // Φ(x + ½) = −Φ(x) for this formula (each cosine changes sign), so it starts at ½.
    let first = iterations[0][0].as_f64().expect("fraction");
    assert!((first - 0.5).abs() <= 0.01, "{first}");
    assert!(iterations.len() >= 3, "{o}");
    let text = p.run(&["cell", "lattice.toml", "w"]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(text.contains("optimize: volume fraction 0.3000") && text.contains("converged"));

    // A new target reruns `constrain`, not the fit.
    p.write("lattice.toml", &OPTIMIZED.replace("0.3 }", "0.35 }"));
    let again = p.build(&[]);
    assert_eq!(ran(&again), ["constrain:w", "contour:cube", "write:cube"]);
    let fraction = common::number(common::by_name(&again, "cube"), "volume_fraction");
    assert!((fraction - 0.35).abs() <= 0.01, "{fraction}");
}
