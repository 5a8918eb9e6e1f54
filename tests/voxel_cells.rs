//! Voxel-image cells through the real binary: an analytic ball voxelised in the test (as
//! occupancy and as signed distance, in `.npy` and raw form) must build the ball's volume
//! fraction within the voxel resolution, the forms must agree, and malformed files must be
//! errors naming the file and what is wrong (golden files).

use crate::common;

use common::{Project, by_name, number};
use std::f64::consts::PI;

const N: usize = 32;
const RADIUS: f64 = 0.3;

/// A `.npy` file of `shape` (a Python tuple, C order) holding `data`'s bytes, of NumPy type
/// `descr`.
fn npy(descr: &str, shape: &str, data: &[u8]) -> Vec<u8> {
    let mut dict = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    // NumPy pads the header with spaces and a newline to a multiple of 64 bytes.
    while (10 + dict.len() + 1) % 64 != 0 {
        dict.push(' ');
    }
    dict.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend((dict.len() as u16).to_le_bytes());
    out.extend(dict.as_bytes());
    out.extend(data);
    out
}

/// The centre of voxel `i` of `N` in cell coordinates.
fn centre(i: usize) -> f64 {
    (i as f64 + 0.5) / N as f64 - 0.5
}

/// The ball's signed distance at voxel `(i, j, k)`.
fn ball(i: usize, j: usize, k: usize) -> f64 {
    let (x, y, z) = (centre(i), centre(j), centre(k));
    (x * x + y * y + z * z).sqrt() - RADIUS
}

/// The ball as u8 occupancy (255 inside) in C order and in x-fastest (raw) order, and as
/// f32 signed distance in C order.
fn images() -> (Vec<u8>, Vec<u8>, Vec<u8>) {
    let (mut c, mut raw, mut distance) = (Vec::new(), Vec::new(), Vec::new());
    let occupied = |i, j, k| if ball(i, j, k) < 0.0 { 255u8 } else { 0 };
    for i in 0..N {
        for j in 0..N {
            for k in 0..N {
                c.push(occupied(i, j, k));
                distance.extend((ball(i, j, k) as f32).to_le_bytes());
                raw.push(occupied(k, j, i));
            }
        }
    }
    (c, raw, distance)
}

fn project() -> Project {
    let outputs = ["occupancy", "raw", "distance", "unfitted"]
        .map(|cell| {
            format!(
                "[outputs.{cell}]\ncell = \"{cell}\"\n\
                 domain = {{ min = [-0.5, -0.5, -0.5], max = [0.5, 0.5, 0.5] }}\n\
                 samples = 49\n"
            )
        })
        .join("\n");
    let p = Project::new(&format!(
        "[cells.occupancy]\nvoxels = \"ball.npy\"\nsymmetry = \"Oh\"\nfit = {{ n = 32 }}\n\n\
         [cells.raw]\nvoxels = \"ball.raw\"\nshape = [{N}, {N}, {N}]\ndtype = \"uint8\"\n\
         symmetry = \"Oh\"\nfit = {{ n = 32 }}\n\n\
         [cells.distance]\nvoxels = \"ball_distance.npy\"\nvalues = \"distance\"\n\
         symmetry = \"Oh\"\nfit = {{ n = 32 }}\n\n\
         [cells.unfitted]\nvoxels = \"ball.npy\"\nthreshold = 127.5\n\n{outputs}"
    ));
    let (c, raw, distance) = images();
    let write = |name: &str, bytes: &[u8]| {
        std::fs::write(p.path().join(name), bytes).expect("write");
    };
    write("ball.npy", &npy("|u1", &format!("({N}, {N}, {N})"), &c));
    write("ball.raw", &raw);
    write(
        "ball_distance.npy",
        &npy("<f4", &format!("({N}, {N}, {N})"), &distance),
    );
    p
}

/// The box [-½, ½]³ holds the ball centred at the cell's origin, one piece, so every
/// form's volume fraction is the ball's, within the voxel resolution; the occupancy and
/// distance forms agree, and the raw form is the `.npy` form byte for byte.
#[test]
fn a_voxelised_ball_builds_the_balls_volume_fraction_in_every_form() {
    let p = project();
    let reports = p.build(&[]);
    let exact = 4.0 / 3.0 * PI * RADIUS.powi(3);
    let mut fractions = Vec::new();
    for name in ["occupancy", "raw", "distance", "unfitted"] {
        let report = by_name(&reports, name);
        assert_eq!(report["watertight"], true, "{name}");
        assert_eq!(report["components"], 1, "{name}");
        let fraction = number(report, "volume_fraction");
        // A binary image moves the surface by at most half a voxel: |ΔV| ≤ area · h / 2.
        let bound = 4.0 * PI * RADIUS * RADIUS / N as f64 / 2.0;
        assert!(
            (fraction - exact).abs() < 0.25 * bound,
            "{name}: {fraction} vs {exact} (voxel bound {bound})"
        );
        fractions.push(fraction);
    }
    assert!((fractions[0] - fractions[2]).abs() < 0.002, "{fractions:?}");
    let read = |name: &str| std::fs::read(p.out(&format!("{name}.stl"))).expect("output");
    assert_eq!(read("occupancy"), read("raw"));
}

/// A malformed file is a build error naming the file and what is wrong with it.
#[test]
fn malformed_voxel_files_are_errors_naming_the_file() {
    let cases: [(&str, &str, Vec<u8>); 4] = [
        (
            "voxel_npy_of_a_2d_array",
            "[cells.a]\nvoxels = \"scan.npy\"\nsymmetry = \"Oh\"\n",
            npy("<f4", "(32, 32)", &[0; 4 * 32 * 32]),
        ),
        (
            "voxel_raw_one_byte_short",
            "[cells.a]\nvoxels = \"scan.raw\"\nshape = [32, 32, 32]\ndtype = \"uint8\"\n",
            vec![0; 32767],
        ),
        (
            "voxel_npy_of_an_unsupported_type",
            "[cells.a]\nvoxels = \"scan.npy\"\n",
            npy("<c8", "(2, 2, 2)", &[0; 64]),
        ),
        (
            "voxel_image_with_no_surface",
            "[cells.a]\nvoxels = \"scan.npy\"\n",
            npy("|u1", "(2, 2, 2)", &[3; 8]),
        ),
    ];
    for (name, cell, bytes) in cases {
        let file = if cell.contains(".raw") {
            "scan.raw"
        } else {
            "scan.npy"
        };
        let p = Project::new(&format!(
            "{cell}\n[outputs.o]\ncell = \"a\"\ndomain = {{ min = [0, 0, 0], max = [1, 1, 1] }}\n\
             samples = 9\n"
        ));
        std::fs::write(p.path().join(file), &bytes).expect("write");
        let out = p.run(&["build", "lattice.toml", "-q"]);
        assert_eq!(out.status.code(), Some(1), "{name}");
        common::golden_err(name, &String::from_utf8_lossy(&out.stderr));
    }
}
