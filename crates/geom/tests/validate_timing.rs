//! Validator throughput on a closed 16 M-triangle / 8 M-vertex torus.
//! Run with `cargo test --release -p latticebuild-geom --test validate_timing -- --ignored
//! --nocapture`. Target: ≤ 0.6 s on 2 cores (printed; the assertion only guards against gross
//! regressions).

use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::validate::check;
use std::f64::consts::TAU;
use std::time::Instant;

/// A torus with `n × m` vertices and `2 n m` triangles, outward winding.
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

#[test]
#[ignore = "timing; run in release"]
fn check_16m_triangles_timing() {
    let mesh = torus(4096, 2048);
    println!(
        "{} vertices, {} triangles, {} rayon threads",
        mesh.vertices.len(),
        mesh.triangles.len(),
        rayon::current_num_threads()
    );
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let start = Instant::now();
        let result = check(&mesh);
        let seconds = start.elapsed().as_secs_f64();
        best = best.min(seconds);
        println!("check: {seconds:.3} s");
        assert!(result.watertight && result.manifold, "{result:?}");
        assert_eq!(result.euler_characteristic, 0);
    }
    let verdict = if best <= 0.6 { "met" } else { "NOT met" };
    println!("best: {best:.3} s (target 0.6 s on 2 cores: {verdict})");
    // A regression guard, not the target: timings on shared machines vary by tens of percent.
    assert!(
        best <= 1.5,
        "validator far slower than expected: {best:.3} s"
    );
}
