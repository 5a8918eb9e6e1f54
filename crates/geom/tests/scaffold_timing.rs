//! Reading and preparing the ~100k-tet bracket scaffold (MSH 4.1 binary, not shipped with the
//! tests: set `SCAFFOLD_100K` to its path, default the shared data folder). Run with
//! `cargo test --release -p latticebuild-geom --test scaffold_timing -- --ignored --nocapture`.
//! No target of its own: it is the first step of tiling (≥ 10 M output triangles/s end to end),
//! so it should cost a small fraction of a second.

use latticebuild_geom::scaffold::{check, read_scaffold};
use std::time::Instant;

#[test]
#[ignore = "timing; run in release"]
fn read_100k_tets_timing() {
    let path = std::env::var("SCAFFOLD_100K")
        .unwrap_or_else(|_| "/work/shared/data/scaffolds/bracket_tet4_100k_msh41bin.msh".into());
    let Ok(bytes) = std::fs::read(&path) else {
        println!("{path} not found: skipped");
        return;
    };
    let mut best = [f64::INFINITY; 4];
    for _ in 0..5 {
        let t = Instant::now();
        let s = read_scaffold(&bytes, "bracket_100k.msh", Some("msh")).expect("reads");
        let read = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let facets = s.facets();
        let facet_time = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let v = s.measure();
        let measure = t.elapsed().as_secs_f64();
        let t = Instant::now();
        check(&s).expect("valid");
        let check_time = t.elapsed().as_secs_f64();
        assert_eq!(s.element_count(), 98228);
        assert_eq!(facets.interior.len(), 187256);
        assert_eq!(facets.boundary.len(), 18400);
        assert!((v - 20658.91579).abs() < 1e-4);
        for (b, x) in best.iter_mut().zip([read, facet_time, measure, check_time]) {
            *b = b.min(x);
        }
    }
    println!(
        "{} bytes: read {:.3} s, facets {:.3} s, measure {:.3} s, check {:.3} s (best of 5)",
        bytes.len(),
        best[0],
        best[1],
        best[2],
        best[3]
    );
    assert!(best[0] < 2.0, "reading far slower than expected");
}
