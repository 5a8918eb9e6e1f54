//! Validator throughput on a closed 16 M-triangle / 8 M-vertex torus.
//! Run with `cargo test --release -p latticebuild-geom --test validate_timing -- --ignored
//! --nocapture`. Target: ≤ 0.6 s on 2 cores (printed; the assertion only guards against gross
//! regressions).

mod common;

use common::torus;
use latticebuild_geom::validate::check;
use std::time::Instant;

#[test]
#[ignore = "timing; run in release"]
fn check_16m_triangles_timing() {
    let mesh = torus(4096, 2048, 30.0, 10.0, [0.0; 3]);
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
