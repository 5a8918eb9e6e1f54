//! Writer throughput on a 16 M-triangle / 8 M-vertex mesh, written to `io::sink()`.
//! Run with `cargo test --release -p latticebuild-geom --test mesh_io_timing -- --ignored
//! --nocapture`. Targets: binary PLY ≤ 0.25 s, binary STL ≤ 0.5 s.

mod common;

use common::torus;
use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::mesh_io::{Encoding, Format, write_mesh};
use std::time::{Duration, Instant};

/// Best of `runs` timings, which filters out interference from other work on the machine.
fn best_of(runs: usize, mut f: impl FnMut()) -> Duration {
    (0..runs)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed()
        })
        .min()
        .unwrap_or_default()
}

fn time_write(mesh: &Mesh, format: Format, encoding: Encoding, runs: usize) -> f64 {
    let time = best_of(runs, || {
        write_mesh(mesh, format, encoding, &mut std::io::sink()).expect("sink never fails");
    });
    time.as_secs_f64()
}

fn big_mesh() -> Mesh {
    let mesh = torus(4096, 2048, 30.0, 10.0, [0.0; 3]);
    assert_eq!(mesh.triangles.len(), 16 << 20);
    println!(
        "{} vertices, {} triangles, {} rayon threads",
        mesh.vertices.len(),
        mesh.triangles.len(),
        rayon::current_num_threads()
    );
    mesh
}

#[test]
#[ignore = "timing; run in release"]
fn binary_ply_16m_triangles_within_0_25_s() {
    let mesh = big_mesh();
    let seconds = time_write(&mesh, Format::Ply, Encoding::Binary, 5);
    println!("binary PLY: {seconds:.3} s (target 0.25 s)");
    assert!(seconds <= 0.25);
}

#[test]
#[ignore = "timing; run in release"]
fn binary_stl_16m_triangles_within_0_5_s() {
    let mesh = big_mesh();
    let seconds = time_write(&mesh, Format::Stl, Encoding::Binary, 5);
    println!("binary STL: {seconds:.3} s (target 0.5 s)");
    assert!(seconds <= 0.5);
}

#[test]
#[ignore = "timing; run in release"]
fn other_encodings_16m_triangles() {
    let mesh = big_mesh();
    let cases = [
        (Format::Vtk, Encoding::Binary),
        (Format::Ply, Encoding::Ascii),
        (Format::Stl, Encoding::Ascii),
        (Format::Obj, Encoding::Ascii),
        (Format::Off, Encoding::Ascii),
        (Format::Vtk, Encoding::Ascii),
    ];
    for (format, encoding) in cases {
        let seconds = time_write(&mesh, format, encoding, 1);
        println!("{format:?} {encoding:?}: {seconds:.3} s");
    }
}
