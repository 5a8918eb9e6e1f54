//! Point-cloud cells through the real binary: points sampled from an analytic ball with their
//! normals (PLY and six-column text, written in the test) must build the ball's volume
//! fraction, and a zero normal must be an error naming the point (a golden file).

use crate::common;

use common::{Project, by_name, number};
use std::f64::consts::PI;

const RADIUS: f64 = 0.3;

/// `count` points spread over the ball's sphere (a Fibonacci lattice) with outward normals.
fn sphere(count: usize) -> Vec<[f64; 6]> {
    let golden = PI * (3.0 - 5f64.sqrt());
    (0..count)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / count as f64;
            let r = (1.0 - z * z).sqrt();
            let (s, c) = (golden * i as f64).sin_cos();
            let n = [r * c, r * s, z];
            [
                RADIUS * n[0],
                RADIUS * n[1],
                RADIUS * n[2],
                n[0],
                n[1],
                n[2],
            ]
        })
        .collect()
}

/// A binary little-endian PLY of the points (float32 coordinates and normals).
fn ply(points: &[[f64; 6]]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\nend_header\n",
        points.len()
    )
    .into_bytes();
    for p in points {
        for v in p {
            out.extend((*v as f32).to_le_bytes());
        }
    }
    out
}

fn xyz(points: &[[f64; 6]]) -> String {
    points
        .iter()
        .map(|p| p.map(|v| format!("{v:.9}")).join(" ") + "\n")
        .collect()
}

/// The box [-½, ½]³ holds the ball; inside/outside from the oriented points gives its volume
/// within the points' spacing, fitted or not, from PLY or text alike.
#[test]
fn an_oriented_point_cloud_of_a_ball_builds_the_balls_volume_fraction() {
    let outputs = ["fitted", "unfitted", "text"]
        .map(|cell| {
            format!(
                "[outputs.{cell}]\ncell = \"{cell}\"\n\
                 domain = {{ min = [-0.5, -0.5, -0.5], max = [0.5, 0.5, 0.5] }}\n\
                 samples = 41\n"
            )
        })
        .join("\n");
    let p = Project::new(&format!(
        "[cells.fitted]\npoints = \"ball.ply\"\nsymmetry = \"Oh\"\nfit = {{ n = 24 }}\n\n\
         [cells.unfitted]\npoints = \"ball.ply\"\n\n[cells.text]\npoints = \"ball.xyz\"\n\n\
         {outputs}"
    ));
    let points = sphere(2000);
    std::fs::write(p.path().join("ball.ply"), ply(&points)).expect("write");
    p.write("ball.xyz", &xyz(&points));
    let reports = p.build(&[]);
    let exact = 4.0 / 3.0 * PI * RADIUS.powi(3);
    for name in ["fitted", "unfitted", "text"] {
        let report = by_name(&reports, name);
        assert_eq!(report["watertight"], true, "{name}");
        assert_eq!(report["components"], 1, "{name}");
        let fraction = number(report, "volume_fraction");
        assert!(
            (fraction - exact).abs() < 0.03 * exact,
            "{name}: {fraction} vs {exact}"
        );
    }
    let fractions = ["unfitted", "text"].map(|n| number(by_name(&reports, n), "volume_fraction"));
    assert!((fractions[0] - fractions[1]).abs() < 1e-4, "{fractions:?}");
}

/// A zero normal is a build error naming the file and the point.
#[test]
fn a_zero_normal_is_an_error_naming_the_point() {
    let mut points = sphere(50);
    points[17][3..].copy_from_slice(&[0.0; 3]);
    let p = Project::new(
        "[cells.a]\npoints = \"scan.ply\"\n\n[outputs.o]\ncell = \"a\"\n\
         domain = { min = [0, 0, 0], max = [1, 1, 1] }\nsamples = 9\n",
    );
    std::fs::write(p.path().join("scan.ply"), ply(&points)).expect("write");
    let out = p.run(&["build", "lattice.toml", "-q"]);
    assert_eq!(out.status.code(), Some(1));
    common::golden_err(
        "point_cloud_with_a_zero_normal",
        &String::from_utf8_lossy(&out.stderr),
    );
}
