//! Timings of the expression evaluators. Ignored by default; run in release:
//! `cargo test --release -p latticebuild-geom --test expr_timing -- --ignored --nocapture`.
//!
//! Targets: separable gyroid ≤ 1.0 ns/sample over an 800³ grid (one thread), pointwise
//! compiled gyroid ≤ 150 ns/point. The assertions are looser than the targets because the
//! machine is shared; the printed numbers are what to compare against the targets.

mod expr {
    use std::hint::black_box;
    use std::time::Instant;

    use latticebuild_geom::expr::compile;
    use latticebuild_geom::field::{Grid, PlaneSampler, PointwiseSampler, ScalarField};
    use latticebuild_geom::tpms::LIBRARY;

    #[test]
    #[ignore = "timing; run in release with --ignored --nocapture"]
    fn expr_timing_gyroid() {
        let gyroid = compile(LIBRARY[0].formula).expect("library formula compiles");
        assert!(gyroid.is_separable());
        let n = 800;
        let grid = Grid::spanning([0.0; 3], [4.0; 3], [n; 3]);
        let mut plane = vec![0.0; grid.plane_len()];

        let start = Instant::now();
        let sampler = gyroid.sampler(&grid);
        let setup = start.elapsed();
        let start = Instant::now();
        let mut checksum = 0.0;
        for k in 0..n {
            sampler.sample_plane(k, &mut plane);
            checksum += plane[(k * 7919) % plane.len()];
        }
        let separable = start.elapsed();
        black_box(checksum);
        let samples = (n * n * n) as f64;
        let ns_sample = separable.as_secs_f64() * 1e9 / samples;

        // Spot-check the last plane against pointwise evaluation.
        for idx in (0..plane.len()).step_by(9973) {
            let p = [
                grid.coord(0, idx % n),
                grid.coord(1, idx / n),
                grid.coord(2, n - 1),
            ];
            assert!((plane[idx] - gyroid.eval(p)).abs() < 1e-12);
        }

        let planes = 6;
        let pointwise = PointwiseSampler {
            field: &gyroid,
            grid,
        };
        let start = Instant::now();
        for k in 0..planes {
            pointwise.sample_plane(k, &mut plane);
            black_box(&plane);
        }
        let ns_point = start.elapsed().as_secs_f64() * 1e9 / (planes * n * n) as f64;

        println!(
            "separable gyroid, {n}^3 grid: setup {:.3} ms, {:.3} s total, {ns_sample:.3} ns/sample",
            setup.as_secs_f64() * 1e3,
            separable.as_secs_f64()
        );
        println!("pointwise compiled gyroid: {ns_point:.1} ns/point");
        assert!(
            ns_sample < 3.0,
            "separable path too slow: {ns_sample:.3} ns/sample"
        );
        assert!(
            ns_point < 400.0,
            "pointwise path too slow: {ns_point:.1} ns/point"
        );
    }

    #[test]
    #[ignore = "timing; run in release with --ignored --nocapture"]
    fn expr_timing_library() {
        // Per-sample cost of every library surface on the separable path.
        let n = 200;
        let grid = Grid::spanning([0.0; 3], [2.0; 3], [n; 3]);
        let mut plane = vec![0.0; grid.plane_len()];
        for surface in &LIBRARY {
            let field = compile(surface.formula).expect("library formula compiles");
            let start = Instant::now();
            let sampler = field.sampler(&grid);
            for k in 0..n {
                sampler.sample_plane(k, &mut plane);
                black_box(&plane);
            }
            let ns = start.elapsed().as_secs_f64() * 1e9 / (n * n * n) as f64;
            let form = field.separable_form().expect("library surfaces separate");
            println!(
                "{:>10}: {:>2} terms, {} x factors, {ns:.3} ns/sample",
                surface.name,
                form.term_count(),
                form.factor_count(0)
            );
        }
    }
}
