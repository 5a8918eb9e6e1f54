//! Timings of symmetric Fourier cells. Ignored by default; run in release:
//! `cargo test --release -p latticebuild-geom --test symmetric_timing -- --ignored --nocapture`.
//!
//! Targets (2 cores): Oh fit from an expression at N = 128 ≤ 0.5 s and N = 256 ≤ 4 s; Td fit at
//! N = 128 ≤ 0.5 s; inverse-FFT evaluation on a 256³ grid ≤ 1 s. The assertions are looser
//! than the targets because the machine is shared; the printed numbers are what to compare.

mod symmetric {
    use std::time::Instant;

    use latticebuild_geom::expr::compile;
    use latticebuild_geom::symmetric::{FitOptions, Group, fit};

    fn time<T>(label: &str, target: f64, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        let s = start.elapsed().as_secs_f64();
        println!("{label:<48} {s:>7.3} s   (target ≤ {target} s)");
        assert!(s < 4.0 * target, "{label}: {s} s");
        out
    }

    #[test]
    #[ignore = "timing; run in release with --ignored --nocapture"]
    fn symmetric_timing() {
        println!("rayon threads: {}", rayon::current_num_threads());
        let opts = FitOptions::default();
        let schwarz = compile("cos(tau*x) + cos(tau*y) + cos(tau*z)").expect("expr");
        // Not separable: the pointwise evaluator runs for every sample.
        let ball =
            compile("sqrt(x*x + y*y + z*z) - 0.3 + 0.05*cos(tau*x)*cos(tau*y)").expect("expr");
        let tet = compile("sin(tau*x)*sin(tau*y)*sin(tau*z) + 0.2").expect("expr");

        let oh = Group::oh();
        let td = Group::td();
        let _ = time("Oh fit, Schwarz P expression, N = 128", 0.5, || {
            fit(&oh, 128, &schwarz, &opts).expect("fit")
        });
        let _ = time("Oh fit, ball expression (pointwise), N = 128", 0.5, || {
            fit(&oh, 128, &ball, &opts).expect("fit")
        });
        let big = time("Oh fit, Schwarz P expression, N = 256", 4.0, || {
            fit(&oh, 256, &schwarz, &opts).expect("fit")
        });
        let _ = time("Oh fit, ball expression (pointwise), N = 256", 4.0, || {
            fit(&oh, 256, &ball, &opts).expect("fit")
        });
        let _ = time("Td fit, mirrored expression, N = 128", 0.5, || {
            fit(&td, 128, &tet, &opts).expect("fit")
        });
        let _ = time("Td fit, ball expression (pointwise), N = 128", 0.5, || {
            fit(&td, 128, &ball, &opts).expect("fit")
        });
        let grid = time("inverse-FFT grid 256³ of the N = 256 Oh fit", 1.0, || {
            big.grid(256).expect("grid")
        });
        assert_eq!(grid.len(), 256 * 256 * 256);
        let x = [0.1, 0.2, 0.3];
        let p = (x[0] * std::f64::consts::TAU).cos()
            + (x[1] * std::f64::consts::TAU).cos()
            + (x[2] * std::f64::consts::TAU).cos();
        let v = time(
            "first direct evaluation (builds the expansion)",
            0.5,
            || big.value(x),
        );
        assert!((v - p).abs() < 1e-12);
        println!("terms after pruning: {}", big.term_count());

        // Contour-style sampling of a rich fit (no target; for the integrator's planning).
        use latticebuild_geom::field::{Grid, ScalarField};
        let rich = fit(&oh, 64, &ball, &opts).expect("fit");
        let grid = Grid::spanning([-0.5; 3], [0.5; 3], [160; 3]);
        let sampled = time(
            "separable sampler, N = 64 ball fit on a 160³ grid",
            2.0,
            || {
                let sampler = rich.sampler(&grid);
                let mut plane = vec![0.0; grid.plane_len()];
                let mut acc = 0.0;
                for k in 0..160 {
                    sampler.sample_plane(k, &mut plane);
                    acc += plane[k * 7];
                }
                acc
            },
        );
        println!("({} terms, checksum {sampled:.3})", rich.term_count());
    }
}
