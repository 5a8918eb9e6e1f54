//! Writer throughput on a 16 M-triangle / 8 M-vertex mesh, written to `io::sink()`.
//! Run with `cargo test --release -p latticebuild-geom --test mesh_io_timing -- --ignored
//! --nocapture`. Targets: binary PLY ≤ 0.25 s, binary STL ≤ 0.5 s.

use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::mesh_io::{Encoding, Format, write_mesh};
use std::f64::consts::TAU;
use std::time::{Duration, Instant};

/// A torus with `n × m` vertices and `2 n m` triangles.
fn torus(n: u32, m: u32) -> Mesh {
    let (big_r, r) = (30.0, 10.0);
    let mut vertices = Vec::with_capacity((n * m) as usize);
    for i in 0..n {
        let theta = TAU * f64::from(i) / f64::from(n);
        for j in 0..m {
            let phi = TAU * f64::from(j) / f64::from(m);
            let rho = big_r + r * phi.cos();
            vertices.push([
                (rho * theta.cos()) as f32,
                (rho * theta.sin()) as f32,
                (r * phi.sin()) as f32,
            ]);
        }
    }
    let id = |i: u32, j: u32| (i % n) * m + (j % m);
    let mut triangles = Vec::with_capacity(2 * (n * m) as usize);
    for i in 0..n {
        for j in 0..m {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    Mesh {
        vertices,
        triangles,
    }
}

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
    let mesh = torus(4096, 2048);
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
