//! The TPMS library through the expression language, checked against an independent
//! transcription of Table 2 of the Cesogen paper, and the separable sampler checked against
//! pointwise evaluation.

mod expr {
    use std::f64::consts::TAU;

    use latticebuild_geom::expr::{CompiledExpr, compile};
    use latticebuild_geom::field::{Grid, PlaneSampler, PointwiseSampler, ScalarField};
    use latticebuild_geom::tpms::{LIBRARY, lookup};

    fn c(f: f64) -> f64 {
        (TAU * f).cos()
    }
    fn s(f: f64) -> f64 {
        (TAU * f).sin()
    }

    type Formula = fn(f64, f64, f64) -> f64;

    /// Table 2 of patience-2025-cesogen.md, row by row, with `C_f = cos(2πf)`,
    /// `S_f = sin(2πf)`. P+C(P) is completed with `+ 0.1(C_x C_y + C_y C_z + C_z C_x)`.
    #[rustfmt::skip]
    const TABLE_2: [(&str, Formula); 27] = [
        ("Gyroid", |x, y, z| c(x) * s(y) + c(y) * s(z) + c(z) * s(x)),
        ("D", |x, y, z| {
            s(x) * s(y) * s(z) + c(x) * s(y) * c(z) + c(y) * s(z) * c(x) + c(z) * s(x) * c(y)
        }),
        ("P", |x, y, z| c(x) + c(y) + c(z)),
        ("IWP", |x, y, z| {
            2.0 * (c(x) * c(y) + c(y) * c(z) + c(z) * c(x)) - (c(2.0 * x) + c(2.0 * y) + c(2.0 * z))
        }),
        ("Neovius", |x, y, z| 4.0 * c(x) * c(y) * c(z) + 3.0 * (c(x) + c(y) + c(z))),
        ("C(Y)", |x, y, z| {
            -s(x) * s(y) * s(z) + s(2.0 * x) * s(y) + s(2.0 * y) * s(z) + s(2.0 * z) * s(x)
                - c(x) * c(y) * c(z) + c(x) * s(2.0 * y) + c(y) * s(2.0 * z) + c(z) * s(2.0 * x)
        }),
        ("Lidinoid", |x, y, z| {
            s(2.0 * x) * c(y) * s(z) + s(2.0 * y) * c(z) * s(x) + s(2.0 * z) * c(x) * s(y)
                - (c(2.0 * x) * c(2.0 * y) + c(2.0 * y) * c(2.0 * z) + c(2.0 * z) * c(2.0 * x))
                + 0.3
        }),
        ("OCTO", |x, y, z| {
            0.6 * (c(x) * c(y) + c(y) * c(z) + c(z) * c(x)) - 0.4 * (c(x) + c(y) + c(z)) + 0.25
        }),
        ("FRD", |x, y, z| {
            8.0 * c(x) * c(y) * c(z) + c(2.0 * x) * c(2.0 * y) * c(2.0 * z)
                - (c(2.0 * x) * c(2.0 * y) + c(2.0 * y) * c(2.0 * z) + c(2.0 * z) * c(2.0 * x))
        }),
        ("S", |x, y, z| {
            c(2.0 * x) * s(y) * c(z) + c(2.0 * y) * s(z) * c(x) + c(2.0 * z) * s(x) * c(y)
        }),
        ("P+C(P)", |x, y, z| {
            0.3 * c(x) * c(y) * c(z) + 0.1 * c(2.0 * x) * c(2.0 * y) * c(2.0 * z)
                + 0.2 * (c(x) + c(y) + c(z)) + 0.1 * (c(2.0 * x) + c(2.0 * y) + c(2.0 * z))
                + 0.05 * (c(3.0 * x) + c(3.0 * y) + c(3.0 * z))
                + 0.1 * (c(x) * c(y) + c(y) * c(z) + c(z) * c(x))
        }),
        ("Split P", |x, y, z| {
            1.1 * (s(2.0 * x) * c(y) * s(z) + s(2.0 * y) * c(z) * s(x) + s(2.0 * z) * c(x) * s(y))
                - 0.2 * (c(2.0 * x) * c(2.0 * y) + c(2.0 * y) * c(2.0 * z) + c(2.0 * z) * c(2.0 * x))
                - 0.4 * (c(2.0 * x) + c(2.0 * y) + c(2.0 * z))
        }),
        ("F", |x, y, z| c(x) * c(y) * c(z)),
        ("C(D)", |x, y, z| {
            c(3.0 * x + y) * c(z) - s(3.0 * x - y) * s(z) + c(x + 3.0 * y) * c(z)
                + s(x - 3.0 * y) * s(z) + c(x - y) * c(3.0 * z) - s(x + y) * s(3.0 * z)
        }),
        ("G'", |x, y, z| {
            s(2.0 * x) * c(y) * s(z) + s(2.0 * y) * c(z) * s(x) + s(2.0 * z) * c(x) * s(y) + 0.32
        }),
        ("G'₂", |x, y, z| {
            5.0 * (s(2.0 * x) * c(y) * s(z) + s(2.0 * y) * c(z) * s(x) + s(2.0 * z) * c(x) * s(y))
                + c(2.0 * x) * c(2.0 * y) + c(2.0 * y) * c(2.0 * z) + c(2.0 * z) * c(2.0 * x)
        }),
        ("D'", |x, y, z| {
            0.5 * (c(x) * c(y) * c(z) + s(x) * c(y) * s(z) + s(y) * c(z) * s(x) + s(z) * c(x) * s(y))
                - 0.5 * (s(2.0 * x) * s(2.0 * y) + s(2.0 * y) * s(2.0 * z) + s(2.0 * z) * s(2.0 * x))
                - 0.2
        }),
        ("K", |x, y, z| {
            0.3 * (c(x) + c(y) + c(z) + c(x) * c(y) + c(y) * c(z) + c(z) * c(x))
                - 0.4 * (c(2.0 * x) + c(2.0 * y) + c(2.0 * z)) + 0.2
        }),
        ("C(S)", |x, y, z| {
            c(2.0 * x) + c(2.0 * y) + c(2.0 * z)
                + 2.0 * (s(2.0 * x) * c(y) * s(3.0 * z) + s(2.0 * y) * c(z) * s(3.0 * x)
                    + s(2.0 * z) * c(x) * s(3.0 * y))
                + 2.0 * (s(2.0 * x) * c(3.0 * y) * s(z) + s(2.0 * y) * c(3.0 * z) * s(x)
                    + s(2.0 * z) * c(3.0 * x) * s(y))
        }),
        ("Y", |x, y, z| {
            s(x) * s(y) * s(z) + c(x) * s(2.0 * y) + c(y) * s(2.0 * z) + c(z) * s(2.0 * x)
                + c(x) * c(y) * c(z) + s(2.0 * x) * s(y) + s(2.0 * y) * s(z) + s(2.0 * z) * s(x)
        }),
        ("±Y", |x, y, z| {
            2.0 * c(x) * c(y) * c(z) + s(2.0 * x) * s(y) + s(2.0 * y) * s(z) + s(2.0 * z) * s(x)
        }),
        ("C(±Y)", |x, y, z| {
            -2.0 * c(x) * c(y) * c(z) + s(2.0 * x) * s(y) + s(2.0 * y) * s(z) + s(2.0 * z) * s(x)
        }),
        ("C(I2-Y**)", |x, y, z| {
            2.0 * (s(2.0 * x) * c(y) * s(z) + s(2.0 * y) * c(z) * s(x) + s(2.0 * z) * c(x) * s(y))
                + c(2.0 * x) * c(2.0 * y) + c(2.0 * y) * c(2.0 * z) + c(2.0 * z) * c(2.0 * x)
        }),
        ("W", |x, y, z| {
            c(2.0 * x) * c(y) + c(2.0 * y) * c(z) + c(2.0 * z) * c(x)
                - (c(x) * c(2.0 * y) + c(y) * c(2.0 * z) + c(z) * c(2.0 * x))
        }),
        ("Q*", |x, y, z| {
            (c(x) - 2.0 * c(y)) * c(z) - 3f64.sqrt() * s(z) * (c(x - y) - c(x)) + c(x - y) * c(z)
        }),
        ("C(G)", |x, y, z| {
            3.0 * (s(x) * c(y) + s(y) * c(z) + s(z) * c(x))
                + 2.0 * (s(3.0 * x) * c(y) + s(3.0 * y) * c(z) + s(3.0 * z) * c(x))
                - 2.0 * (s(x) * c(3.0 * y) + s(y) * c(3.0 * z) + s(z) * c(3.0 * x))
        }),
        ("Slotted P", |x, y, z| {
            -2.0 * (c(x) * c(y) + c(y) * c(z) + c(z) * c(x))
                - 2.0 * (c(2.0 * x) + c(2.0 * y) + c(2.0 * z))
                + c(2.0 * x) * c(y) + c(2.0 * y) * c(z) + c(2.0 * z) * c(x)
                - (c(x) * c(2.0 * y) + c(y) * c(2.0 * z) + c(z) * c(2.0 * x))
        }),
    ];

    /// Deterministic pseudo-random numbers in `[lo, hi)` (splitmix64).
    struct Rng(u64);
    impl Rng {
        fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^= z >> 31;
            lo + (hi - lo) * (z >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    fn compiled(text: &str) -> CompiledExpr {
        compile(text).unwrap_or_else(|e| panic!("{text}: {e:?}"))
    }

    #[test]
    fn every_library_surface_matches_table_2() {
        let mut rng = Rng(2025);
        for (surface, (title, formula)) in LIBRARY.iter().zip(TABLE_2) {
            assert_eq!(surface.title, title, "library order differs from Table 2");
            let field = compiled(surface.formula);
            assert!(field.is_separable(), "{title} must take the separable path");
            for _ in 0..20 {
                let p = [
                    rng.uniform(-1.5, 1.5),
                    rng.uniform(-1.5, 1.5),
                    rng.uniform(-1.5, 1.5),
                ];
                let got = field.eval(p);
                let want = formula(p[0], p[1], p[2]);
                assert!(
                    (got - want).abs() <= 1e-12,
                    "{title} at {p:?}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn known_values() {
        let at = |name: &str, p: [f64; 3]| {
            let surface = lookup(name).unwrap_or_else(|| panic!("{name} is in the library"));
            compiled(surface.formula).eval(p)
        };
        let close = |got: f64, want: f64| (got - want).abs() < 1e-15;
        assert!(close(at("gyroid", [0.0, 0.0, 0.0]), 0.0));
        // cos(π/2)·sin 0 + cos 0·sin 0 + cos 0·sin(π/2) = 1
        assert!(close(at("gyroid", [0.25, 0.0, 0.0]), 1.0));
        assert!(close(at("gyroid", [0.0, 0.25, 0.0]), 1.0));
        assert!(close(at("p", [0.0, 0.0, 0.0]), 3.0));
        assert!(close(at("p", [0.5, 0.5, 0.5]), -3.0));
        assert!(close(at("p", [0.25, 0.25, 0.25]), 0.0));
        assert!(close(at("d", [0.0, 0.0, 0.0]), 0.0));
        assert!(close(at("iwp", [0.0, 0.0, 0.0]), 3.0));
        assert!(close(at("neovius", [0.0, 0.0, 0.0]), 13.0));
        assert!(close(at("f", [0.0, 0.0, 0.0]), 1.0));
        assert!(close(
            at("octo", [0.0, 0.0, 0.0]),
            0.6 * 3.0 - 0.4 * 3.0 + 0.25
        ));
        // Period 1 along every axis.
        let g = compiled(LIBRARY[0].formula);
        let p = [0.123, -0.456, 0.789];
        for axis in 0..3 {
            let mut q = p;
            q[axis] += 1.0;
            assert!((g.eval(p) - g.eval(q)).abs() < 1e-14);
        }
        assert!(
            (g.eval(p) - (c(p[0]) * s(p[1]) + c(p[1]) * s(p[2]) + c(p[2]) * s(p[0]))).abs() < 1e-15
        );
    }

    fn random_grid(rng: &mut Rng) -> Grid {
        let counts = [
            2 + (rng.uniform(0.0, 1.0) * 30.0) as usize,
            2 + (rng.uniform(0.0, 1.0) * 20.0) as usize,
            2 + (rng.uniform(0.0, 1.0) * 12.0) as usize,
        ];
        let min = [
            rng.uniform(-1.5, 0.0),
            rng.uniform(-1.5, 0.0),
            rng.uniform(-1.5, 0.0),
        ];
        let max = [
            rng.uniform(0.0, 1.5),
            rng.uniform(0.0, 1.5),
            rng.uniform(0.0, 1.5),
        ];
        Grid::spanning(min, max, counts)
    }

    /// Every plane of the field's sampler against pointwise evaluation of the same field at
    /// the same coordinates, within `tol`.
    fn assert_sampler_matches(field: &CompiledExpr, grid: &Grid, tol: f64, label: &str) {
        let fast = field.sampler(grid);
        let slow = PointwiseSampler { field, grid: *grid };
        assert_eq!(fast.grid(), grid);
        let n = grid.plane_len();
        let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
        for k in 0..grid.counts[2] {
            fast.sample_plane(k, &mut a);
            slow.sample_plane(k, &mut b);
            for (idx, (&u, &v)) in a.iter().zip(&b).enumerate() {
                assert!(
                    (u - v).abs() <= tol,
                    "{label}: plane {k}, sample {idx}: {u} vs {v}"
                );
            }
            // And against single-point evaluation at the documented coordinates.
            let (i, j) = ((k * 7 + 3) % grid.counts[0], (k * 5 + 1) % grid.counts[1]);
            let p = [grid.coord(0, i), grid.coord(1, j), grid.coord(2, k)];
            assert!(
                (a[i + grid.counts[0] * j] - field.eval(p)).abs() <= tol,
                "{label} at {p:?}"
            );
        }
    }

    fn tolerance(field: &CompiledExpr, scale: f64) -> f64 {
        let sum = field.separable_form().map_or(0.0, |f| f.coefficient_sum());
        1e-12 * (1.0 + sum) * scale
    }

    #[test]
    fn library_sampler_matches_pointwise_on_random_grids() {
        let mut rng = Rng(77);
        for surface in &LIBRARY {
            let field = compiled(surface.formula);
            for _ in 0..3 {
                let grid = random_grid(&mut rng);
                assert_sampler_matches(&field, &grid, tolerance(&field, 1.0), surface.name);
            }
        }
    }

    #[test]
    fn user_expressions_sampler_matches_pointwise() {
        let mut rng = Rng(5);
        // Factors stay below ~e² on these grids, hence the scale of 10.
        for text in [
            "x*y + exp(z)",
            "cos(tau*(x-2*y+z))",
            "sin(x + y)*cos(z - x) + 0.5",
            "(x + y + z)^3 - x*y*z",
            "x*y/(1 + z^2)",
            "exp(x - y + 0.5)*(1 + z^2)",
            "(cos(tau*x) + sin(tau*y))^2/3",
            "-(x - y)^2 + 2*cos(2*x + 3*y - z + 1)",
            "x",
            "2.5",
        ] {
            let field = compiled(text);
            assert!(field.is_separable(), "{text} should be separable");
            for _ in 0..3 {
                let grid = random_grid(&mut rng);
                assert_sampler_matches(&field, &grid, tolerance(&field, 10.0), text);
            }
        }
    }

    #[test]
    fn non_separable_expressions_fall_back_and_stay_right() {
        let field = compiled("sqrt(x^2+y^2)-0.3");
        assert!(!field.is_separable());
        let grid = Grid::spanning([-1.0, -0.5, 0.0], [1.0, 0.5, 2.0], [9, 6, 4]);
        let sampler = field.sampler(&grid);
        let mut plane = vec![0.0; grid.plane_len()];
        for k in 0..4 {
            sampler.sample_plane(k, &mut plane);
            for j in 0..6 {
                for i in 0..9 {
                    let (x, y) = (grid.coord(0, i), grid.coord(1, j));
                    let want = (x * x + y * y).sqrt() - 0.3;
                    assert!((plane[i + 9 * j] - want).abs() <= 1e-15, "({i}, {j}, {k})");
                }
            }
        }
        for text in ["min(x, y) + z", "abs(x*y*z)", "sin(x*y)", "x/(y + z + 3)"] {
            let field = compiled(text);
            assert!(!field.is_separable(), "{text}");
            assert_sampler_matches(&field, &grid, 0.0, text);
        }
    }

    #[test]
    fn planes_are_pure_functions_of_k() {
        let field = compiled(LIBRARY[5].formula);
        let grid = Grid::spanning([-0.3, 0.1, -1.0], [1.7, 0.9, 1.0], [37, 23, 11]);
        let sampler = field.sampler(&grid);
        let n = grid.plane_len();
        let forward: Vec<Vec<f64>> = (0..11)
            .map(|k| {
                let mut p = vec![0.0; n];
                sampler.sample_plane(k, &mut p);
                p
            })
            .collect();
        // Reverse order, on other threads, from a second sampler: identical bits.
        let again = field.sampler(&grid);
        std::thread::scope(|scope| {
            let handles: Vec<_> = (0..11)
                .rev()
                .map(|k| {
                    let again = &again;
                    scope.spawn(move || {
                        let mut p = vec![f64::NAN; n];
                        again.sample_plane(k, &mut p);
                        (k, p)
                    })
                })
                .collect();
            for h in handles {
                let (k, p) = h.join().expect("sampling thread");
                let same = p
                    .iter()
                    .zip(&forward[k])
                    .all(|(a, b)| a.to_bits() == b.to_bits());
                assert!(same, "plane {k} differs between calls");
            }
        });
    }

    #[test]
    fn compiled_fields_are_send_and_sync() {
        fn check<T: Send + Sync + Clone + std::fmt::Debug>() {}
        check::<CompiledExpr>();
        check::<latticebuild_geom::expr::Expr>();
    }
}

/// Contouring samples a few rows at a time: any block of rows must equal the same rows of the
/// whole plane, bit for bit, for both the separable and the pointwise paths.
#[test]
fn row_blocks_equal_whole_planes() {
    use latticebuild_geom::field::{Grid, ScalarField};
    let grid = Grid::spanning([-0.3, 0.1, 0.0], [1.2, 0.9, 0.7], [23, 17, 5]);
    for text in [
        latticebuild_geom::tpms::LIBRARY[0].formula,
        "sqrt(x^2 + y^2) - 0.3*z",
    ] {
        let field = latticebuild_geom::expr::compile(text).expect("compiles");
        let sampler = field.sampler(&grid);
        let nx = grid.counts[0];
        let mut plane = vec![0.0; grid.plane_len()];
        sampler.sample_plane(3, &mut plane);
        for rows in [0..1, 2..9, 9..17, 16..17] {
            let mut block = vec![0.0; rows.len() * nx];
            sampler.sample_rows(3, rows.clone(), &mut block);
            assert_eq!(
                block,
                plane[rows.start * nx..rows.end * nx],
                "{text} rows {rows:?}"
            );
        }
    }
}
