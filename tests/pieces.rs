//! Solid pieces through the real binary: every report counts them, with the largest one's
//! share, and more than one is a warning in the report and on stderr. The expected counts are
//! the geometry's: Schwarz P's `f ≤ −2` is one ball about each cell's centre (where
//! `cos 2πx = cos 2πy = cos 2πz = −1`), `f ≤ 0` one connected network; a hollow sphere's
//! inner surface is a cavity, not a piece.

use crate::common;

use common::{Project, by_name};

const BALLS_AND_NETWORK: &str = r#"
[cells.p]
tpms = "p"

[cells.p_oh]
tpms = "p"
symmetry = "Oh"

[cells.hollow]
expr = "abs(sqrt(x*x + y*y + z*z) - 0.3) - 0.05"

[scaffolds.cubes]
grid = { min = [0, 0, 0], max = [3, 2, 2], divisions = [3, 2, 2], element = "hex" }

[outputs.balls]
cell = "p"
domain = { min = [0, 0, 0], max = [2, 3, 2] }
offset = -2
samples = 49
formats = ["ply"]

[outputs.network]
cell = "p"
domain = { min = [0, 0, 0], max = [2, 3, 2] }
samples = 49
formats = ["ply"]

[outputs.hollow_ball]
cell = "hollow"
domain = { min = [-0.5, -0.5, -0.5], max = [0.5, 0.5, 0.5] }
samples = 41
formats = ["ply"]

[outputs.tiled_balls]
scaffold = "cubes"
cell = "p_oh"
offset = 2
solid = "outside"
resolution = 12
formats = ["ply"]
"#;

fn pieces(report: &serde_json::Value) -> (u64, f64) {
    (
        report["components"].as_u64().expect("components"),
        report["largest_component_fraction"]
            .as_f64()
            .expect("largest_component_fraction"),
    )
}

fn warnings(report: &serde_json::Value) -> Vec<String> {
    report["warnings"]
        .as_array()
        .map(|w| {
            w.iter()
                .map(|w| w.as_str().expect("text").to_string())
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn reports_count_solid_pieces_and_warn_about_more_than_one() {
    let project = Project::new(BALLS_AND_NETWORK);
    let reports = project.build(&[]);

    // 2 × 3 × 2 cells, a ball inside each: 12 equal pieces.
    let balls = by_name(&reports, "balls");
    let (count, largest) = pieces(balls);
    assert_eq!(count, 12);
    // Equal balls, sampled at slightly different places in their cells.
    assert!((largest - 1.0 / 12.0).abs() < 1e-4, "{largest}");
    let warned = warnings(balls);
    assert!(
        warned
            .iter()
            .any(|w| w.starts_with("the mesh is 12 separate pieces")),
        "{warned:?}"
    );

    // The network is one piece: no warning.
    let network = by_name(&reports, "network");
    assert_eq!(pieces(network), (1, 1.0));
    assert!(warnings(network).is_empty());

    // A hollow ball: two surfaces, one solid, and its hollow is a sealed cavity (the one
    // warning: powder or resin stays in it).
    let hollow = by_name(&reports, "hollow_ball");
    assert_eq!(pieces(hollow), (1, 1.0));
    assert_eq!(hollow["cavities"], 1);
    let warned = warnings(hollow);
    assert!(
        warned.len() == 1 && warned[0].starts_with("1 sealed cavity"),
        "{warned:?}"
    );

    // Tiled (streamed): P over the reference cube `[−½, ½]³` is 3 at its centre, so
    // `f ≥ 2` is a ball about each element's centre: 3 × 2 × 2 pieces.
    let tiled = by_name(&reports, "tiled_balls");
    let (count, largest) = pieces(tiled);
    assert_eq!(count, 12);
    assert!((largest - 1.0 / 12.0).abs() < 1e-4, "{largest}");

    // On stderr, with the summary line.
    let out = project.run(&["build", "lattice.toml", "balls"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("12 pieces (the largest 8.3 %)"), "{stderr}");
    assert!(
        stderr.contains("warning: balls: the mesh is 12 separate pieces"),
        "{stderr}"
    );
}
