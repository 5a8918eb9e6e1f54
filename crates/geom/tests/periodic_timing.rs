//! Timing of loci-surface reconstruction. Ignored by default; run in release:
//! `cargo test --release -p latticebuild-geom --test periodic_timing -- --ignored --nocapture`.
//!
//! Target (issue 7): Faujasite reconstruction up to scale 4 in ≤ 1 s. The search is forced
//! through scales 1, 2 and 4 (tolerance 0), on the Si atoms and on all 600 atoms with images.

use std::time::Instant;

use latticebuild_geom::periodic::reconstruct::{ReconstructOptions, reconstruct};
use latticebuild_geom::periodic::{ExpandOptions, positions_of, read_crystal};

#[test]
#[ignore = "timing; run in release with --ignored --nocapture"]
fn faujasite_up_to_scale_4() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/crystals/FAU.cif");
    let bytes = std::fs::read(path).expect("FAU.cif");
    let options = ReconstructOptions {
        tolerance: 0.0,
        max_scale: 4,
        ..ReconstructOptions::default()
    };
    for (species, images) in [(Some("Si"), false), (None, true)] {
        let start = Instant::now();
        let crystal = read_crystal("FAU.cif", &bytes).expect("read");
        let atoms = crystal.atoms(&ExpandOptions {
            include_images: images,
            ..ExpandOptions::default()
        });
        let points = positions_of(&atoms, species);
        let r = reconstruct(&points, &options).expect("reconstruct");
        let s = start.elapsed().as_secs_f64();
        println!(
            "FAU {:>3} atoms, scales 1-4, read + expand + reconstruct: {s:.4} s (target ≤ 1 s); \
             dimension {}, error {:.2e}, porosity {:.4}",
            points.len(),
            r.metrics.dimension,
            r.metrics.max_error,
            r.metrics.porosity
        );
        assert_eq!(r.steps.len(), 3);
        assert!(s < 4.0, "{s} s");
    }
}
