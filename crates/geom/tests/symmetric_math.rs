//! Tests of the symmetric Fourier cells (docs/method.md). Every check compares against a value the
//! test derives on its own (matrices written out, brute-force orbits, quadrature, known
//! inputs), never against the code's own output.
//!
//! `cargo test -p latticebuild-geom symmetric`

mod symmetric {
    use latticebuild_geom::symmetric::{
        Complex64, Extend, FitError, FitOptions, Frame, Group, GroupError, Matrix,
        ReferenceElement, SampleOptions, Side, Source, fit, from_fn, minkowski_difference,
        minkowski_sum, sample, weighted_average,
    };
    use std::f64::consts::{PI, TAU};

    // ---------- helpers written independently of the library ----------

    /// SplitMix64: deterministic pseudo-random numbers in [0, 1).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            (z >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, a: f64, b: f64) -> f64 {
            a + (b - a) * self.next()
        }
        fn int(&mut self, lo: i32, hi: i32) -> i32 {
            lo + (self.next() * (hi - lo + 1) as f64) as i32
        }
    }

    fn all_groups() -> Vec<Group> {
        vec![Group::d3(), Group::d4(), Group::td(), Group::oh()]
    }

    fn mul(a: &Matrix, b: &Matrix) -> Matrix {
        let mut m = [[0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    m[i][j] += a[i][k] * b[k][j];
                }
            }
        }
        m
    }

    fn tr(a: &Matrix) -> Matrix {
        let mut m = [[0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] = a[j][i];
            }
        }
        m
    }

    fn apply(m: &Matrix, v: [i32; 3]) -> [i32; 3] {
        let mut o = [0; 3];
        for i in 0..3 {
            for j in 0..3 {
                o[i] += m[i][j] * v[j];
            }
        }
        o
    }

    fn apply_f(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
        let mut o = [0.0; 3];
        for i in 0..3 {
            for j in 0..3 {
                o[i] += m[i][j] * v[j];
            }
        }
        o
    }

    const R3: f64 = 1.732_050_807_568_877_2;

    /// Skew (s1, s2) to Cartesian: x = s1·(1,0) + s2·(½, √3/2).
    fn skew_to_cart(s: [f64; 3]) -> [f64; 3] {
        [s[0] + s[1] / 2.0, s[1] * R3 / 2.0, s[2]]
    }

    fn cart_to_skew(x: [f64; 3]) -> [f64; 3] {
        let s2 = 2.0 * x[1] / R3;
        [x[0] - s2 / 2.0, s2, x[2]]
    }

    /// The Cartesian matrix of a group element: M itself, or B M B⁻¹ for the skew frame.
    fn cartesian(g: &Group, m: &Matrix) -> [[f64; 3]; 3] {
        let mf = m.map(|r| r.map(f64::from));
        if g.frame() == Frame::Cartesian {
            return mf;
        }
        let b = [[1.0, 0.5, 0.0], [0.0, R3 / 2.0, 0.0], [0.0, 0.0, 1.0]];
        let binv = [[1.0, -1.0 / R3, 0.0], [0.0, 2.0 / R3, 0.0], [0.0, 0.0, 1.0]];
        let mut out = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    for l in 0..3 {
                        out[i][j] += b[i][k] * mf[k][l] * binv[l][j];
                    }
                }
            }
        }
        out
    }

    fn random_point(rng: &mut Rng, dim: usize) -> [f64; 3] {
        let z = if dim == 3 { rng.range(-0.6, 0.6) } else { 0.0 };
        [rng.range(-0.6, 0.6), rng.range(-0.6, 0.6), z]
    }

    /// A random real trigonometric polynomial in frame coordinates, with frequencies
    /// |k_i| ≤ kmax, as (k, amplitude, phase) triples.
    fn random_poly(
        rng: &mut Rng,
        dim: usize,
        terms: usize,
        kmax: i32,
    ) -> Vec<([i32; 3], f64, f64)> {
        (0..terms)
            .map(|_| {
                let k = [
                    rng.int(-kmax, kmax),
                    rng.int(-kmax, kmax),
                    if dim == 3 { rng.int(-kmax, kmax) } else { 0 },
                ];
                (k, rng.range(0.2, 1.0), rng.range(0.0, TAU))
            })
            .collect()
    }

    fn eval_poly(p: &[([i32; 3], f64, f64)], s: [f64; 3]) -> f64 {
        p.iter()
            .map(|(k, a, ph)| {
                a * (TAU * (k[0] as f64 * s[0] + k[1] as f64 * s[1] + k[2] as f64 * s[2]) + ph)
                    .cos()
            })
            .sum()
    }

    /// `(1/|S|) Σ_Q h(Q s)`: a symmetric version of `h`, in frame coordinates.
    fn symmetrized(g: &Group, p: &[([i32; 3], f64, f64)], s: [f64; 3]) -> f64 {
        let sum: f64 = g
            .elements()
            .iter()
            .map(|m| {
                let mf = m.map(|r| r.map(f64::from));
                eval_poly(p, apply_f(&mf, s))
            })
            .sum();
        sum / g.order() as f64
    }

    fn to_frame(g: &Group, x: [f64; 3]) -> [f64; 3] {
        if g.frame() == Frame::Hexagonal {
            cart_to_skew(x)
        } else {
            x
        }
    }

    fn no_check() -> FitOptions {
        FitOptions {
            sample: SampleOptions {
                extend: Extend::None,
                symmetrize: false,
            },
            check_vanishing: false,
        }
    }

    // ---------- groups ----------

    #[test]
    fn symmetric_group_orders_closure_inverses() {
        for (g, order) in all_groups().into_iter().zip([6, 8, 24, 48]) {
            let els = g.elements();
            assert_eq!(els.len(), order, "{}", g.name());
            let id = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
            assert!(els.contains(&id));
            for a in els {
                assert!(els.iter().any(|b| mul(a, b) == id), "inverse missing");
                for b in els {
                    assert!(els.contains(&mul(a, b)), "{} not closed", g.name());
                }
            }
            // Orthogonal in Cartesian coordinates.
            for m in els {
                let q = cartesian(&g, m);
                for i in 0..3 {
                    for j in 0..3 {
                        let d: f64 = (0..3).map(|k| q[k][i] * q[k][j]).sum();
                        assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12);
                    }
                }
            }
        }
    }

    #[test]
    fn symmetric_group_d3_matrices_are_methods() {
        let m = |a: [[i32; 2]; 2]| [[a[0][0], a[0][1], 0], [a[1][0], a[1][1], 0], [0, 0, 1]];
        let mut expected = vec![
            m([[1, 0], [0, 1]]),
            m([[-1, -1], [1, 0]]),
            m([[0, 1], [-1, -1]]),
            m([[-1, -1], [0, 1]]),
            m([[0, 1], [1, 0]]),
            m([[1, 0], [-1, -1]]),
        ];
        expected.sort();
        let mut got = Group::d3().elements().to_vec();
        got.sort();
        assert_eq!(got, expected);
    }

    #[test]
    fn symmetric_group_td_is_even_sign_signed_permutations() {
        let td = Group::td();
        let minus = [[-1, 0, 0], [0, -1, 0], [0, 0, -1]];
        assert!(!td.elements().contains(&minus));
        assert!(Group::oh().elements().contains(&minus));
        for m in td.elements() {
            let prod: i32 = m.iter().flatten().filter(|&&v| v != 0).product();
            assert_eq!(prod, 1);
        }
    }

    #[test]
    fn symmetric_group_maps_reference_element_onto_itself() {
        for g in all_groups() {
            let r = g.reference_element().expect("named groups have one");
            // Vertices written out here, from docs/method.md §1.
            let h = R3 / 6.0;
            let verts: Vec<[f64; 3]> = match r {
                ReferenceElement::Square => vec![
                    [-0.5, -0.5, 0.0],
                    [0.5, -0.5, 0.0],
                    [0.5, 0.5, 0.0],
                    [-0.5, 0.5, 0.0],
                ],
                ReferenceElement::Cube => {
                    let mut v = Vec::new();
                    for a in [-0.5, 0.5] {
                        for b in [-0.5, 0.5] {
                            for c in [-0.5, 0.5] {
                                v.push([a, b, c]);
                            }
                        }
                    }
                    v
                }
                ReferenceElement::Tetrahedron => vec![
                    [-0.5, -0.5, -0.5],
                    [0.5, 0.5, -0.5],
                    [-0.5, 0.5, 0.5],
                    [0.5, -0.5, 0.5],
                ],
                ReferenceElement::Triangle => {
                    vec![[-0.5, -h, 0.0], [0.5, -h, 0.0], [0.0, 2.0 * h, 0.0]]
                }
            };
            let lib = r.vertices();
            assert_eq!(lib.len(), verts.len());
            for v in &verts {
                assert!(
                    lib.iter()
                        .any(|w| (0..3).all(|a| (v[a] - w[a]).abs() < 1e-12))
                );
            }
            for m in g.elements() {
                let q = cartesian(&g, m);
                let mut hit = vec![false; verts.len()];
                for v in &verts {
                    let w = apply_f(&q, *v);
                    let i = verts
                        .iter()
                        .position(|u| (0..3).all(|a| (u[a] - w[a]).abs() < 1e-12))
                        .unwrap_or_else(|| panic!("{}: vertex {v:?} maps off", g.name()));
                    hit[i] = true;
                }
                assert!(hit.iter().all(|&b| b), "not a bijection of vertices");
            }
        }
        // Td is exactly the subgroup of Oh fixing the tetrahedron.
        let tet = ReferenceElement::Tetrahedron.vertices();
        let fixing = Group::oh()
            .elements()
            .iter()
            .filter(|m| {
                let q = m.map(|r| r.map(f64::from));
                tet.iter().all(|v| {
                    let w = apply_f(&q, *v);
                    tet.iter()
                        .any(|u| (0..3).all(|a| (u[a] - w[a]).abs() < 1e-12))
                })
            })
            .count();
        assert_eq!(fixing, 24);
    }

    #[test]
    fn symmetric_group_from_generators() {
        // D4 from a 90° rotation and a mirror.
        let rot = [[0, -1, 0], [1, 0, 0], [0, 0, 1]];
        let mir = [[1, 0, 0], [0, -1, 0], [0, 0, 1]];
        let g = Group::from_generators(2, &[rot, mir]).expect("D4 generators");
        assert_eq!(g, Group::d4());
        // Oh from three generators; Td from a 3-fold axis and a diagonal mirror and S4.
        let c3 = [[0, 0, 1], [1, 0, 0], [0, 1, 0]];
        let c4 = [[0, -1, 0], [1, 0, 0], [0, 0, 1]];
        let inv = [[-1, 0, 0], [0, -1, 0], [0, 0, -1]];
        assert_eq!(
            Group::from_generators(3, &[c3, c4, inv]).expect("Oh"),
            Group::oh()
        );
        let swap = [[0, 1, 0], [1, 0, 0], [0, 0, 1]];
        let c2 = [[1, 0, 0], [0, -1, 0], [0, 0, -1]];
        assert_eq!(
            Group::from_generators(3, &[c3, swap, c2]).expect("Td"),
            Group::td()
        );
        // A cyclic group and a hexagonal group (C6 in skew coordinates: 60° rotation).
        assert_eq!(Group::from_generators(2, &[rot]).expect("C4").order(), 4);
        let c6 = [[0, -1, 0], [1, 1, 0], [0, 0, 1]];
        let g6 = Group::from_generators_in(2, Frame::Hexagonal, &[c6]).expect("C6");
        assert_eq!(g6.order(), 6);
        assert_eq!(Group::from_generators(3, &[]).expect("trivial").order(), 1);
    }

    #[test]
    fn symmetric_group_bad_input() {
        assert!(matches!(
            Group::by_name("D5"),
            Err(GroupError::UnknownName(_))
        ));
        assert!(matches!(
            Group::by_name(""),
            Err(GroupError::UnknownName(_))
        ));
        assert_eq!(Group::by_name("oh").expect("case-insensitive"), Group::oh());
        assert_eq!(Group::by_name("D3").expect("D3"), Group::d3());
        let shear = [[1, 1, 0], [0, 1, 0], [0, 0, 1]];
        assert!(matches!(
            Group::from_generators(2, &[shear]),
            Err(GroupError::NotOrthogonal { index: 0, .. })
        ));
        let twice = [[2, 0, 0], [0, 1, 0], [0, 0, 1]];
        assert!(matches!(
            Group::from_generators(3, &[IDENTITY_M, twice]),
            Err(GroupError::NotInvertible { index: 1, det: 2 })
        ));
        let big = [[i32::MAX, 0, 0], [0, 1, 0], [0, 0, 1]];
        assert!(Group::from_generators(3, &[big]).is_err());
        let not2d = [[1, 0, 0], [0, 1, 0], [0, 0, -1]];
        assert!(matches!(
            Group::from_generators(2, &[not2d]),
            Err(GroupError::NotEmbedded { .. })
        ));
        assert!(matches!(
            Group::from_generators(4, &[]),
            Err(GroupError::Dimension(4))
        ));
        // A 60° rotation is not orthogonal in the Cartesian frame.
        let c6 = [[0, -1, 0], [1, 1, 0], [0, 0, 1]];
        assert!(Group::from_generators(2, &[c6]).is_err());
    }

    const IDENTITY_M: Matrix = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];

    // ---------- frequencies ----------

    /// Brute force: every integer vector of a box lies in the orbit of exactly one member of F
    /// when its whole orbit is in band, and of none otherwise.
    fn check_frequency_set(g: &Group, n: usize) {
        let f = g.frequency_set(n);
        let set: std::collections::HashSet<[i32; 3]> = f.iter().copied().collect();
        assert_eq!(set.len(), f.len(), "duplicates");
        let d = g.dimension();
        let h = n as i32; // a box well beyond the band
        let zr = if d == 3 { h } else { 0 };
        let transposes: Vec<Matrix> = g.elements().iter().map(tr).collect();
        let mut covered = std::collections::HashSet::new();
        for a in -h..=h {
            for b in -h..=h {
                for c in -zr..=zr {
                    let k = [a, b, c];
                    let mut orbit: Vec<[i32; 3]> = transposes.iter().map(|t| apply(t, k)).collect();
                    orbit.sort();
                    orbit.dedup();
                    let in_band = orbit
                        .iter()
                        .all(|q| (0..d).all(|i| 2 * q[i].abs() < n as i32));
                    let reps: Vec<_> = orbit.iter().filter(|q| set.contains(*q)).collect();
                    assert_eq!(
                        reps.len(),
                        usize::from(in_band),
                        "{}: k = {k:?} has reps {reps:?}",
                        g.name()
                    );
                    if let Some(r) = reps.first() {
                        covered.insert(**r);
                    }
                }
            }
        }
        assert_eq!(covered.len(), f.len(), "F has members outside the box");
    }

    #[test]
    fn symmetric_frequency_sets_one_representative_per_orbit() {
        for g in all_groups() {
            for n in [4, 8, 10] {
                check_frequency_set(&g, n);
            }
        }
        let rot = [[0, -1, 0], [1, 0, 0], [0, 0, 1]];
        check_frequency_set(&Group::from_generators(2, &[rot]).expect("C4"), 10);
        let c3 = [[0, 0, 1], [1, 0, 0], [0, 1, 0]];
        check_frequency_set(&Group::from_generators(3, &[c3]).expect("C3"), 8);
        let c6 = [[0, -1, 0], [1, 1, 0], [0, 0, 1]];
        check_frequency_set(
            &Group::from_generators_in(2, Frame::Hexagonal, &[c6]).expect("C6"),
            12,
        );
    }

    #[test]
    fn symmetric_frequency_sets_follow_method_inequalities() {
        for g in all_groups() {
            let set = g.frequency_set(12);
            for f in &set {
                let ok = match g.name() {
                    "Oh" => f[0] >= f[1] && f[1] >= f[2] && f[2] >= 0,
                    "Td" => f[0] >= f[1] && f[1] >= f[2].abs(),
                    "D4" | "D3" => f[0] >= f[1] && f[1] >= 0 && f[2] == 0,
                    _ => unreachable!(),
                };
                assert!(ok, "{}: {f:?}", g.name());
            }
            // Cubic groups: the band is max|f_i| ≤ N/2 − 1, so all such vectors are present.
            let expected = match g.name() {
                "Oh" => (0..=5).map(|a| (a + 1) * (a + 2) / 2).sum::<i32>() as usize,
                "Td" => (0..=5)
                    .map(|a: i32| (0..=a).map(|b| 2 * b + 1).sum::<i32>())
                    .sum::<i32>() as usize,
                "D4" => 21,
                _ => set.len(),
            };
            assert_eq!(set.len(), expected, "{}", g.name());
        }
    }

    #[test]
    fn symmetric_partners_and_stabilizers() {
        let td = Group::td();
        assert_eq!(td.partner([3, 2, 1]), [3, 2, -1]);
        assert_eq!(td.partner([3, 2, 0]), [3, 2, 0]);
        let d3 = Group::d3();
        assert_eq!(d3.partner([5, 2, 0]), [5, 3, 0]);
        assert_eq!(d3.partner([4, 2, 0]), [4, 2, 0]);
        assert_eq!(Group::oh().partner([3, 2, 1]), [3, 2, 1]);
        // |orbit|·|Stab| = |S|, counted by brute force.
        for g in all_groups() {
            for f in g.frequency_set(8) {
                let ts: Vec<Matrix> = g.elements().iter().map(tr).collect();
                let stab = ts.iter().filter(|t| apply(t, f) == f).count();
                assert_eq!(g.stabilizer_order(f), stab);
                assert_eq!(g.orbit(f).len() * stab, g.order());
                let k = 1.0 / ((g.order() * stab) as f64).sqrt();
                assert!((g.normalization(f) - k).abs() < 1e-15);
            }
        }
    }

    // ---------- basis ----------

    /// φ_f by its definition, written here.
    fn phi(g: &Group, f: [i32; 3], s: [f64; 3]) -> Complex64 {
        let ts: Vec<Matrix> = g.elements().iter().map(tr).collect();
        let stab = ts.iter().filter(|t| apply(t, f) == f).count();
        let k = 1.0 / ((g.order() * stab) as f64).sqrt();
        let mut sum = Complex64::new(0.0, 0.0);
        for t in &ts {
            let q = apply(t, f);
            let a = TAU * (q[0] as f64 * s[0] + q[1] as f64 * s[1] + q[2] as f64 * s[2]);
            sum += Complex64::new(a.cos(), a.sin());
        }
        sum * k
    }

    #[test]
    fn symmetric_basis_orthonormal_by_quadrature() {
        for g in all_groups() {
            let d = g.dimension();
            let n = if d == 3 { 8 } else { 16 };
            let fs = g.frequency_set(n);
            let origin = g.domain().origin();
            // Grid in frame coordinates (lattice measure): exact for in-band products.
            let pts: Vec<[f64; 3]> = (0..n.pow(d as u32))
                .map(|i| {
                    let idx = [i % n, (i / n) % n, i / (n * n)];
                    std::array::from_fn(|a| {
                        if a < d {
                            origin[a] + idx[a] as f64 / n as f64
                        } else {
                            0.0
                        }
                    })
                })
                .collect();
            let vals: Vec<Vec<Complex64>> = fs
                .iter()
                .map(|&f| pts.iter().map(|&s| phi(&g, f, s)).collect())
                .collect();
            // The library's φ agrees with the definition.
            for (i, &f) in fs.iter().enumerate().step_by(3) {
                for (p, &s) in pts.iter().enumerate().step_by(7) {
                    assert!((g.basis_value(f, s) - vals[i][p]).norm() < 1e-12);
                }
            }
            let w = 1.0 / pts.len() as f64;
            for i in 0..fs.len() {
                for j in 0..fs.len() {
                    let ip: Complex64 = vals[i]
                        .iter()
                        .zip(&vals[j])
                        .map(|(a, b)| a * b.conj())
                        .sum::<Complex64>()
                        * w;
                    let expect = if i == j { 1.0 } else { 0.0 };
                    assert!(
                        (ip - expect).norm() < 1e-12,
                        "{}: <φ{:?}, φ{:?}> = {ip}",
                        g.name(),
                        fs[i],
                        fs[j]
                    );
                }
            }
        }
    }

    // ---------- exactness ----------

    /// Fits a symmetric band-limited input and compares Φ with it at random points.
    #[test]
    fn symmetric_fit_reproduces_band_limited_inputs() {
        let mut rng = Rng(7);
        for g in all_groups() {
            let d = g.dimension();
            let n = 16;
            // |k_i| ≤ 3 keeps every orbit member within |k| ≤ 6 < N/2 (D3 sums components).
            let poly = random_poly(&mut rng, d, 6, 3);
            let gg = g.clone();
            let input = move |x: [f64; 3]| symmetrized(&gg, &poly, to_frame(&gg, x));
            let cell = fit(&g, n, &from_fn(&input), &no_check()).expect("fit");
            let mut worst: f64 = 0.0;
            for _ in 0..100 {
                let x = random_point(&mut rng, d);
                worst = worst.max((cell.value(x) - input(x)).abs());
            }
            assert!(worst <= 1e-12, "{}: error {worst:e}", g.name());
        }
    }

    /// The fit sums the spectrum's bins into its coefficients in parallel: the same bits on
    /// any pool. (Its ranges once followed the thread count, and every coefficient of an
    /// n = 32 cell could change in its last bits between 1 and 3 threads.)
    #[test]
    fn symmetric_fit_is_bitwise_equal_on_any_thread_count() {
        // Not band-limited, so every bin carries rounding-sized values to sum.
        let input = |x: [f64; 3]| {
            (TAU * x[0]).sin() * (TAU * x[1]).sin() * (TAU * x[2]).sin()
                + 0.3 * ((TAU * x[0]).cos() + (TAU * x[1]).cos() + (TAU * x[2]).cos())
                + 0.05 * (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt()
        };
        for g in all_groups() {
            let bits = |threads: usize| -> Vec<([i32; 3], u64, u64)> {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("pool");
                let cell = pool
                    .install(|| fit(&g, 32, &from_fn(input), &no_check()))
                    .expect("fit");
                cell.coefficients()
                    .iter()
                    .map(|c| (c.f, c.c.re.to_bits(), c.c.im.to_bits()))
                    .collect()
            };
            let one = bits(1);
            assert!(one.len() > 10, "{}: {} coefficients", g.name(), one.len());
            for threads in [2, 3, 5] {
                let other = bits(threads);
                let differing = one.iter().zip(&other).filter(|(a, b)| a != b).count();
                assert!(
                    one.len() == other.len() && differing == 0,
                    "{}: {differing} of {} coefficients differ at {threads} threads",
                    g.name(),
                    one.len()
                );
            }
        }
    }

    #[test]
    fn symmetric_fit_td_only_input_needs_the_conjugate() {
        let g = Group::td();
        let input = |x: [f64; 3]| (TAU * x[0]).sin() * (TAU * x[1]).sin() * (TAU * x[2]).sin();
        let cell = fit(&g, 16, &from_fn(input), &no_check()).expect("fit");
        let mut rng = Rng(11);
        for _ in 0..200 {
            let x = random_point(&mut rng, 3);
            let e = (cell.value(x) - input(x)).abs();
            assert!(e <= 1e-12, "Φ({x:?}) off by {e:e}: the inverted cell?");
        }
        // Its coefficients: sin·sin·sin = −(1/8) Σ_{signs} s1s2s3 e(±x±y±z) puts weight on
        // (1,1,1) and (1,1,−1) with opposite imaginary parts.
        let a = cell.coefficient([1, 1, 1]);
        let b = cell.coefficient([1, 1, -1]);
        assert!((a - b.conj()).norm() < 1e-13, "partners must be conjugate");
        assert!(a.re.abs() < 1e-13 && a.im.abs() > 0.1);
    }

    #[test]
    fn symmetric_fit_d3_complex_coefficient() {
        // Φ = Re(c φ_f) + 0.3 Re φ_(1,0) with f = (3,1), whose partner is (3,2).
        let g = Group::d3();
        let c = Complex64::new(0.7, 0.4);
        let gg = g.clone();
        let input = move |x: [f64; 3]| {
            let s = cart_to_skew(x);
            (c * phi(&gg, [3, 1, 0], s)).re + 0.3 * phi(&gg, [1, 0, 0], s).re
        };
        let cell = fit(&g, 16, &from_fn(&input), &no_check()).expect("fit");
        // Re(cφ) = (cφ + c̄ φ̄)/2 and φ̄_f = φ_partner.
        assert!((cell.coefficient([3, 1, 0]) - c / 2.0).norm() < 1e-13);
        assert!((cell.coefficient([3, 2, 0]) - c.conj() / 2.0).norm() < 1e-13);
        assert!((cell.coefficient([1, 0, 0]) - 0.15).norm() < 1e-13);
        assert!((cell.coefficient([1, 1, 0]) - 0.15).norm() < 1e-13);
        let rest: f64 = cell
            .coefficients()
            .iter()
            .filter(|k| ![[3, 1, 0], [3, 2, 0], [1, 0, 0], [1, 1, 0]].contains(&k.f))
            .map(|k| k.c.norm())
            .sum();
        assert!(rest < 1e-12);
        let mut rng = Rng(5);
        for _ in 0..200 {
            let x = random_point(&mut rng, 2);
            assert!((cell.value(x) - input(x)).abs() <= 1e-12);
        }
    }

    #[test]
    fn symmetric_coefficients_real_or_conjugate_partners() {
        // Real input: Oh and D4 coefficients are real; Td and D3 partners are conjugate.
        let mut rng = Rng(31);
        for g in all_groups() {
            let d = g.dimension();
            let poly = random_poly(&mut rng, d, 5, 5);
            let input = move |x: [f64; 3]| eval_poly(&poly, x) + (x[0] - 0.1).abs() - 0.2;
            let cell = fit(&g, 16, &from_fn(input), &no_check()).expect("fit");
            let has_inversion = g.elements().contains(&[
                [-1, 0, 0],
                [0, -1, 0],
                [0, 0, if d == 3 { -1 } else { 1 }],
            ]);
            assert_eq!(has_inversion, matches!(g.name(), "Oh" | "D4"));
            let mut complex = 0;
            for c in cell.coefficients() {
                // The partner, found by brute force: the F member in the orbit of −f.
                let neg = [-c.f[0], -c.f[1], -c.f[2]];
                let ts: Vec<Matrix> = g.elements().iter().map(tr).collect();
                let p = ts
                    .iter()
                    .map(|t| apply(t, neg))
                    .find(|q| cell.coefficients().iter().any(|k| k.f == *q))
                    .expect("partner in F");
                assert!((cell.coefficient(p) - c.c.conj()).norm() < 1e-14);
                if has_inversion {
                    assert!(c.c.im.abs() < 1e-14);
                } else if c.c.im.abs() > 1e-6 {
                    complex += 1;
                }
            }
            if !has_inversion {
                assert!(
                    complex > 0,
                    "{}: expected genuinely complex coefficients",
                    g.name()
                );
            }
        }
    }

    // ---------- symmetry ----------

    #[test]
    fn symmetric_fit_of_non_symmetric_input_is_symmetric() {
        let mut rng = Rng(3);
        for g in all_groups() {
            let d = g.dimension();
            for extend in [Extend::Mirror, Extend::None] {
                // An off-centre ball (not symmetric, not band-limited) plus a random wave.
                let poly = random_poly(&mut rng, d, 3, 4);
                let c = [0.13, -0.07, if d == 3 { 0.05 } else { 0.0 }];
                let input = move |x: [f64; 3]| {
                    let r = ((x[0] - c[0]).powi(2) + (x[1] - c[1]).powi(2) + (x[2] - c[2]).powi(2))
                        .sqrt();
                    r - 0.3 + 0.05 * eval_poly(&poly, x)
                };
                let opts = FitOptions {
                    sample: SampleOptions {
                        extend,
                        symmetrize: false,
                    },
                    check_vanishing: true,
                };
                let cell = fit(&g, 16, &from_fn(input), &opts).expect("fit");
                for _ in 0..30 {
                    let x = random_point(&mut rng, d);
                    let v = cell.value(x);
                    for m in g.elements() {
                        let qx = apply_f(&cartesian(&g, m), x);
                        let e = (cell.value(qx) - v).abs();
                        assert!(e <= 1e-12, "{}: |Φ(Qx) − Φ(x)| = {e:e}", g.name());
                    }
                }
            }
        }
    }

    #[test]
    fn symmetric_symmetrize_is_union_of_images() {
        // A ball off the centre; symmetrized, every image of its centre is inside.
        let g = Group::d4();
        let c = [0.2, 0.1, 0.0];
        let input =
            move |x: [f64; 3]| ((x[0] - c[0]).powi(2) + (x[1] - c[1]).powi(2)).sqrt() - 0.08;
        let opts = SampleOptions {
            extend: Extend::Mirror,
            symmetrize: true,
        };
        let n = 20;
        let s = sample(&g, n, &from_fn(input), opts).expect("sample");
        for (img, expect) in [
            ([0.2, 0.1], true),
            ([-0.1, 0.2], true),
            ([0.1, -0.2], true),
            ([0.0, 0.0], false),
        ] {
            let i = ((img[0] + 0.5) * n as f64).round() as usize;
            let j = ((img[1] + 0.5) * n as f64).round() as usize;
            assert_eq!(s[i + n * j] < 0.0, expect, "{img:?}");
        }
    }

    // ---------- extension ----------

    #[test]
    fn symmetric_triangle_mirror_is_continuous_across_rhombus_edges() {
        let g = Group::d3();
        let n = 48;
        // D3-symmetric and smooth, but not periodic: x³ − 3xy² is the 3-fold harmonic.
        let sym = |x: [f64; 3]| {
            let r2 = x[0] * x[0] + x[1] * x[1];
            r2 - 0.06 + 0.8 * (x[1].powi(3) - 3.0 * x[1] * x[0] * x[0])
        };
        let jump = |s: &[f64]| {
            let mut edge: f64 = 0.0;
            let mut inner: f64 = 0.0;
            for j in 0..n {
                edge = edge.max((s[j * n] - s[n - 1 + j * n]).abs());
                edge = edge.max((s[j] - s[j + n * (n - 1)]).abs());
                inner = inner.max((s[1 + j * n] - s[j * n]).abs());
                inner = inner.max((s[j + n] - s[j]).abs());
            }
            (edge, inner)
        };
        let mirrored = sample(&g, n, &from_fn(sym), SampleOptions::default()).expect("sample");
        let (edge, inner) = jump(&mirrored);
        assert!(edge <= 2.0 * inner, "jump {edge} vs neighbour step {inner}");
        let plain = sample(
            &g,
            n,
            &from_fn(sym),
            SampleOptions {
                extend: Extend::None,
                symmetrize: false,
            },
        )
        .expect("sample");
        let (edge_plain, _) = jump(&plain);
        assert!(
            edge_plain > 5.0 * inner,
            "the unmirrored domain should jump: {edge_plain} vs {inner}"
        );

        // Each triangle edge becomes a mirror line of the fitted cell: the mirror across
        // s1 + s2 = ⅓ is (s1, s2) ↦ (⅓ − s2, ⅓ − s1).
        let opts = FitOptions::default();
        let cell = fit(&g, 32, &from_fn(sym), &opts).expect("fit");
        let mut rng = Rng(9);
        for _ in 0..100 {
            let s = [rng.range(-0.4, 0.7), rng.range(-0.4, 0.7), 0.0];
            let m = [1.0 / 3.0 - s[1], 1.0 / 3.0 - s[0], 0.0];
            let e = (cell.value(skew_to_cart(s)) - cell.value(skew_to_cart(m))).abs();
            assert!(e < 1e-12, "not a mirror line: {e:e}");
        }
    }

    #[test]
    fn symmetric_tetrahedron_mirror_samples_reflected_points() {
        // A field that records the point it was evaluated at.
        let g = Group::td();
        let n = 8;
        let probe = |x: [f64; 3]| x[0] + 10.0 * x[1] + 100.0 * x[2];
        let s = sample(&g, n, &from_fn(probe), SampleOptions::default()).expect("sample");
        let normals = [
            [1.0, 1.0, 1.0],
            [-1.0, -1.0, 1.0],
            [1.0, -1.0, -1.0],
            [-1.0, 1.0, -1.0],
        ];
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let x = [i, j, k].map(|c| -0.5 + c as f64 / n as f64);
                    let mut p = x;
                    for nr in &normals {
                        let t: f64 = nr.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>() - 0.5;
                        if t > 1e-12 {
                            p = std::array::from_fn(|a| x[a] - 2.0 * t / 3.0 * nr[a]);
                            // The image lies in the tetrahedron.
                            for m in &normals {
                                let u: f64 = m.iter().zip(&p).map(|(a, b)| a * b).sum();
                                assert!(u <= 0.5 + 1e-12);
                            }
                        }
                    }
                    assert!((s[i + n * (j + n * k)] - probe(p)).abs() < 1e-12);
                }
            }
        }
    }

    // ---------- evaluation ----------

    #[test]
    fn symmetric_direct_sum_matches_inverse_fft_grid() {
        for g in all_groups() {
            let d = g.dimension();
            let n = if d == 3 { 16 } else { 32 };
            let ball = |x: [f64; 3]| (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt() - 0.3;
            let cell = fit(&g, n, &from_fn(ball), &FitOptions::default()).expect("fit");
            let origin = g.domain().origin();
            for m in [n, 2 * n, n / 2 + 2] {
                let grid = cell.grid(m).expect("grid");
                assert_eq!(grid.len(), m.pow(d as u32));
                let mut worst: f64 = 0.0;
                for (i, &v) in grid.iter().enumerate().step_by(3) {
                    let idx = [i % m, (i / m) % m, i / (m * m)];
                    let s: [f64; 3] = std::array::from_fn(|a| {
                        if a < d {
                            origin[a] + idx[a] as f64 / m as f64
                        } else {
                            0.0
                        }
                    });
                    let x = if g.frame() == Frame::Hexagonal {
                        skew_to_cart(s)
                    } else {
                        s
                    };
                    worst = worst.max((cell.value(x) - v).abs());
                }
                assert!(worst <= 1e-10, "{} m={m}: {worst:e}", g.name());
            }
        }
    }

    #[test]
    fn symmetric_direct_sum_matches_grid_for_explicit_coefficients() {
        use latticebuild_geom::symmetric::FittedCell;
        // Sparse sets, including an f without its partner (Td, D3): the grid must still be
        // Re Σ c_f φ_f, read through both k and −k.
        type Case = (Group, Vec<([i32; 3], Complex64)>);
        let cases: Vec<Case> = vec![
            (
                Group::td(),
                vec![
                    ([2, 1, -1], Complex64::new(0.3, 0.8)),
                    ([0, 0, 0], Complex64::new(0.1, 0.0)),
                ],
            ),
            (
                Group::d3(),
                vec![
                    ([3, 1, 0], Complex64::new(-0.4, 0.5)),
                    ([2, 2, 0], Complex64::new(0.2, -0.1)),
                ],
            ),
            (
                Group::oh(),
                vec![
                    ([3, 2, 1], Complex64::new(0.7, 0.0)),
                    ([1, 0, 0], Complex64::new(0.0, 0.3)),
                ],
            ),
            (Group::d4(), vec![([3, 1, 0], Complex64::new(0.5, 0.2))]),
        ];
        for (g, cs) in cases {
            let d = g.dimension();
            let cell = FittedCell::from_coefficients(g.clone(), 8, cs.clone()).expect("cell");
            let origin = g.domain().origin();
            for m in [8, 12, 6] {
                let grid = cell.grid(m).expect("grid");
                for (i, &v) in grid.iter().enumerate() {
                    let idx = [i % m, (i / m) % m, i / (m * m)];
                    let s: [f64; 3] = std::array::from_fn(|a| {
                        if a < d {
                            origin[a] + idx[a] as f64 / m as f64
                        } else {
                            0.0
                        }
                    });
                    // Independent value: Re Σ c_f φ_f(s) with φ from the definition.
                    let expect: f64 = cs.iter().map(|(f, c)| (c * phi(&g, *f, s)).re).sum();
                    assert!(
                        (v - expect).abs() < 1e-12,
                        "{} m={m}: {v} vs {expect}",
                        g.name()
                    );
                    let x = if g.frame() == Frame::Hexagonal {
                        skew_to_cart(s)
                    } else {
                        s
                    };
                    assert!((cell.value(x) - expect).abs() < 1e-12);
                }
            }
        }
    }

    #[test]
    fn symmetric_gradient_matches_finite_differences() {
        let mut rng = Rng(21);
        for g in all_groups() {
            let d = g.dimension();
            let poly = random_poly(&mut rng, d, 4, 3);
            let input = move |x: [f64; 3]| eval_poly(&poly, x) + 0.1;
            let cell = fit(&g, 16, &from_fn(input), &no_check()).expect("fit");
            for _ in 0..20 {
                let x = random_point(&mut rng, d);
                let (v, grad) = cell.value_gradient(x);
                assert!((v - cell.value(x)).abs() < 1e-12);
                for a in 0..d {
                    let h = 1e-6;
                    let mut p = x;
                    let mut q = x;
                    p[a] += h;
                    q[a] -= h;
                    let fd = (cell.value(p) - cell.value(q)) / (2.0 * h);
                    assert!(
                        (fd - grad[a]).abs() < 1e-6 * (1.0 + grad[a].abs()),
                        "{} axis {a}: {fd} vs {}",
                        g.name(),
                        grad[a]
                    );
                }
            }
        }
    }

    #[test]
    fn symmetric_cell_is_a_scalar_field() {
        use latticebuild_geom::field::{Grid, ScalarField};
        let g = Group::oh();
        let p = |x: [f64; 3]| (TAU * x[0]).cos() + (TAU * x[1]).cos() + (TAU * x[2]).cos();
        let cell = fit(&g, 8, &from_fn(p), &FitOptions::default()).expect("fit");
        let grid = Grid::spanning([-0.5; 3], [0.5; 3], [9, 7, 5]);
        let sampler = cell.sampler(&grid);
        let mut plane = vec![0.0; grid.plane_len()];
        for k in 0..5 {
            sampler.sample_plane(k, &mut plane);
            for j in 0..7 {
                for i in 0..9 {
                    let x = [grid.coord(0, i), grid.coord(1, j), grid.coord(2, k)];
                    assert!((plane[i + 9 * j] - p(x)).abs() < 1e-12);
                }
            }
        }
        let mut out = [0.0; 2];
        cell.eval_points(&[0.1, 0.2], &[0.3, -0.1], &[0.0, 0.4], &mut out);
        assert!((out[0] - p([0.1, 0.3, 0.0])).abs() < 1e-12);
        assert!((out[1] - p([0.2, -0.1, 0.4])).abs() < 1e-12);
        // Offsets and inversion act on c_0 and the sign.
        let e = cell.offset(-0.25);
        assert!((e.value([0.1, 0.2, 0.3]) - (p([0.1, 0.2, 0.3]) - 0.25)).abs() < 1e-12);
        assert!((cell.negated().value([0.1, 0.2, 0.3]) + p([0.1, 0.2, 0.3])).abs() < 1e-12);
    }

    #[test]
    fn symmetric_grid_sampler_matches_direct_sum() {
        use latticebuild_geom::field::{Grid, ScalarField};
        for g in all_groups() {
            let d = g.dimension();
            let ball = |x: [f64; 3]| (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt() - 0.3;
            let cell = fit(&g, 16, &from_fn(ball), &FitOptions::default()).expect("fit");
            // A grid unrelated to the FFT grid, reaching beyond one period.
            let grid = Grid::spanning([-0.7, -0.55, -0.6], [0.8, 0.6, 0.65], [13, 11, 9]);
            let sampler = cell.sampler(&grid);
            let mut plane = vec![0.0; grid.plane_len()];
            for k in [0, 4, 8, 4] {
                sampler.sample_rows(k, 2..7, &mut plane[2 * 13..7 * 13]);
                for j in 2..7 {
                    for i in 0..13 {
                        let z = if d == 3 { grid.coord(2, k) } else { 0.0 };
                        let x = [grid.coord(0, i), grid.coord(1, j), z];
                        let e = (plane[i + 13 * j] - cell.value(x)).abs();
                        assert!(e < 1e-12, "{}: {e:e}", g.name());
                    }
                }
            }
        }
    }

    #[test]
    fn symmetric_fit_from_expression_field() {
        // A ScalarField source (the expression compiler's separable sampler path).
        let expr =
            latticebuild_geom::expr::compile("sin(tau*x)*sin(tau*y)*sin(tau*z)").expect("expr");
        let direct = |x: [f64; 3]| (TAU * x[0]).sin() * (TAU * x[1]).sin() * (TAU * x[2]).sin();
        for extend in [Extend::None] {
            let opts = FitOptions {
                sample: SampleOptions {
                    extend,
                    symmetrize: false,
                },
                check_vanishing: true,
            };
            let cell = fit(&Group::td(), 16, &expr, &opts).expect("fit");
            let mut rng = Rng(1);
            for _ in 0..50 {
                let x = random_point(&mut rng, 3);
                assert!((cell.value(x) - direct(x)).abs() < 1e-12);
            }
        }
        // Mirrored Td samples from the field agree with mirrored samples from a closure.
        let a = sample(&Group::td(), 8, &expr, SampleOptions::default()).expect("sample");
        let b =
            sample(&Group::td(), 8, &from_fn(direct), SampleOptions::default()).expect("sample");
        for (u, v) in a.iter().zip(&b) {
            assert!((u - v).abs() < 1e-12);
        }
        let _ = PI;
    }

    // ---------- blends ----------

    #[test]
    fn symmetric_weighted_average_is_linear() {
        let mut rng = Rng(17);
        for g in all_groups() {
            let d = g.dimension();
            let p1 = random_poly(&mut rng, d, 3, 5);
            let p2 = random_poly(&mut rng, d, 3, 5);
            let g1 = move |x: [f64; 3]| {
                (x[0] * x[0] + x[1] * x[1]).sqrt() - 0.2 + 0.1 * eval_poly(&p1, x)
            };
            let g2 = move |x: [f64; 3]| {
                x[0].abs() + x[1].abs() + x[2].abs() - 0.4 + 0.1 * eval_poly(&p2, x)
            };
            let opts = FitOptions::default();
            let n = if d == 3 { 16 } else { 32 };
            let a = fit(&g, n, &from_fn(&g1), &opts).expect("a");
            let b = fit(&g, n, &from_fn(&g2), &opts).expect("b");
            let blend = weighted_average(&[(&a, 0.6), (&b, 1.4)]).expect("blend");
            let mix = |x: [f64; 3]| 0.3 * g1(x) + 0.7 * g2(x);
            let direct = fit(&g, n, &from_fn(mix), &opts).expect("mix");
            assert_eq!(blend.coefficients().len(), direct.coefficients().len());
            for (u, v) in blend.coefficients().iter().zip(direct.coefficients()) {
                assert_eq!(u.f, v.f);
                assert!((u.c - v.c).norm() < 1e-12, "{}: {:?}", g.name(), u.f);
            }
            let x = random_point(&mut rng, d);
            assert!((blend.value(x) - (0.3 * a.value(x) + 0.7 * b.value(x))).abs() < 1e-12);
        }
        // Different groups, no cells, bad weights.
        let ball = |x: [f64; 3]| (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt() - 0.3;
        let o = fit(&Group::oh(), 8, &from_fn(ball), &FitOptions::default()).expect("oh");
        let t = fit(&Group::td(), 8, &from_fn(ball), &FitOptions::default()).expect("td");
        assert!(matches!(
            weighted_average(&[(&o, 1.0), (&t, 1.0)]),
            Err(FitError::GroupMismatch(..))
        ));
        assert!(matches!(weighted_average(&[]), Err(FitError::NoCells)));
        assert!(matches!(
            weighted_average(&[(&o, 1.0), (&o, -1.0)]),
            Err(FitError::BadWeights)
        ));
        assert!(matches!(
            weighted_average(&[(&o, f64::NAN)]),
            Err(FitError::BadWeights)
        ));
        assert!(minkowski_sum(&o, &t, 8).is_err());
    }

    /// Radius of the zero set of Φ along direction `u` by bisection from the centre.
    fn radius(cell: &latticebuild_geom::symmetric::FittedCell, u: [f64; 3]) -> f64 {
        let (mut lo, mut hi) = (0.0, 0.49);
        assert!(cell.value([0.0; 3]) < 0.0 && cell.value(u.map(|c| c * hi)) > 0.0);
        for _ in 0..50 {
            let mid = 0.5 * (lo + hi);
            if cell.value(u.map(|c| c * mid)) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }

    #[test]
    fn symmetric_minkowski_sum_of_balls() {
        let n = 48;
        let step = 1.0 / n as f64;
        let g = Group::oh();
        let ball = |r: f64| {
            move |x: [f64; 3]| {
                if x[0] * x[0] + x[1] * x[1] + x[2] * x[2] <= r * r {
                    -1.0
                } else {
                    1.0
                }
            }
        };
        let opts = FitOptions::default();
        let a = fit(&g, n, &from_fn(ball(0.12)), &opts).expect("a");
        let b = fit(&g, n, &from_fn(ball(0.2)), &opts).expect("b");
        let sum = minkowski_sum(&a, &b, n).expect("sum");
        let mut rng = Rng(4);
        let mut worst: f64 = 0.0;
        for _ in 0..40 {
            let mut u = [
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ];
            let l = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
            u = u.map(|c| c / l);
            worst = worst.max((radius(&sum, u) - 0.32).abs());
        }
        println!("Minkowski sum radius error {worst:.4} (grid step {step:.4})");
        assert!(worst <= step, "radius off by {worst} (grid step {step})");
        // Difference: (A ⊕ B) ⊖ B for balls is A again.
        let diff = minkowski_difference(&sum, &b, n).expect("difference");
        let mut worst: f64 = 0.0;
        for _ in 0..40 {
            let mut u = [
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ];
            let l = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
            u = u.map(|c| c / l);
            worst = worst.max((radius(&diff, u) - 0.12).abs());
        }
        println!("Minkowski difference radius error {worst:.4} (grid step {step:.4})");
        assert!(worst <= 2.0 * step, "difference radius off by {worst}");
    }

    #[test]
    fn symmetric_minkowski_uses_point_reflection_d3() {
        // D3 does not contain −I, so −B ≠ B: the sum must contain a + b (not a − b) and the
        // difference must erode by −B.
        let g = Group::d3();
        let n = 64;
        // B: the triangle scaled by 0.3 (pointing to +y), as an indicator.
        let tri = |scale: f64| {
            move |x: [f64; 3]| {
                let s = cart_to_skew(x);
                let t = scale / 3.0;
                if s[0] >= -t && s[1] >= -t && s[0] + s[1] <= t {
                    -1.0
                } else {
                    1.0
                }
            }
        };
        let opts = FitOptions::default();
        let small = fit(&g, n, &from_fn(tri(0.3)), &opts).expect("small");
        let sum = minkowski_sum(&small, &small, n).expect("sum");
        // T(0.3) ⊕ T(0.3) = T(0.6): its top vertex is at y = 0.6·√3/3 ≈ 0.346, its bottom edge
        // at y = −0.6·√3/6 ≈ −0.173. The reflected sum would point down instead.
        assert!(sum.value([0.0, 0.3, 0.0]) < 0.0);
        assert!(sum.value([0.0, -0.25, 0.0]) > 0.0);
        // A ⊖ B with A = T(0.6), B = T(0.3) is T(0.3) (triangles are summands of each other).
        let big = fit(&g, n, &from_fn(tri(0.6)), &opts).expect("big");
        let diff = minkowski_difference(&big, &small, n).expect("diff");
        assert!(diff.value([0.0, 0.0, 0.0]) < 0.0);
        assert!(diff.value([0.0, 0.25, 0.0]) > 0.0);
        assert!(diff.value([0.0, -0.15, 0.0]) > 0.0);
    }

    // ---------- bad input ----------

    #[test]
    fn symmetric_fit_bad_input() {
        let ball = |x: [f64; 3]| (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt() - 0.3;
        let g = Group::oh();
        let opts = FitOptions::default();
        assert_eq!(
            fit(&g, 15, &from_fn(ball), &opts).unwrap_err(),
            FitError::Odd(15)
        );
        assert_eq!(
            fit(&g, 2, &from_fn(ball), &opts).unwrap_err(),
            FitError::TooSmall(2)
        );
        assert_eq!(
            fit(&g, 0, &from_fn(ball), &opts).unwrap_err(),
            FitError::TooSmall(0)
        );
        assert!(matches!(
            fit(&g, 1 << 20, &from_fn(ball), &opts),
            Err(FitError::TooLarge { .. })
        ));
        // No surface in the input.
        assert_eq!(
            fit(&g, 8, &from_fn(|_| 1.0), &opts).unwrap_err(),
            FitError::EmptyInput {
                side: Side::Outside
            }
        );
        assert_eq!(
            fit(&g, 8, &from_fn(|_| -1.0), &opts).unwrap_err(),
            FitError::EmptyInput { side: Side::Inside }
        );
        // A surface, but its Oh-symmetric part is zero (odd in x) or one-signed.
        let odd = |x: [f64; 3]| (TAU * x[0]).sin();
        assert_eq!(
            fit(&g, 8, &from_fn(odd), &opts).unwrap_err(),
            FitError::Vanishes { side: Side::Zero }
        );
        let shifted = |x: [f64; 3]| 0.5 + (TAU * x[0]).sin();
        assert_eq!(
            fit(&g, 8, &from_fn(shifted), &opts).unwrap_err(),
            FitError::Vanishes {
                side: Side::Outside
            }
        );
        // Non-finite samples are reported with the point.
        let bad = |x: [f64; 3]| if x[0] > 0.2 { f64::NAN } else { x[0] };
        assert!(matches!(
            fit(&g, 8, &from_fn(bad), &opts),
            Err(FitError::NonFinite { .. })
        ));
        let sym = SampleOptions {
            extend: Extend::Mirror,
            symmetrize: true,
        };
        assert!(matches!(
            sample(&g, 8, &from_fn(bad), sym),
            Err(FitError::NonFinite { .. })
        ));
        // Grids.
        let cell = fit(&g, 8, &from_fn(ball), &opts).expect("fit");
        assert_eq!(cell.grid(7).unwrap_err(), FitError::Odd(7));
        assert!(minkowski_sum(&cell, &cell, 3).is_err());
        // Messages name the problem.
        assert!(FitError::Odd(15).to_string().contains("odd"));
        assert!(
            FitError::Vanishes { side: Side::Zero }
                .to_string()
                .contains("vanishes")
        );
        // Overflowing generators and frequencies are rejected, not wrapped.
        let huge = [[i32::MAX, 1, 0], [i32::MAX, i32::MAX, 0], [0, 7, i32::MAX]];
        assert!(Group::from_generators(3, &[huge]).is_err());
        assert!(matches!(
            FittedCell::from_coefficients(
                Group::td(),
                8,
                [([i32::MAX, i32::MIN, 0], Complex64::new(1.0, 0.0))]
            ),
            Err(FitError::OutOfBand { .. })
        ));
        // Explicit coefficients are checked.
        use latticebuild_geom::symmetric::FittedCell;
        assert!(matches!(
            FittedCell::from_coefficients(Group::oh(), 8, [([1, 2, 0], Complex64::new(1.0, 0.0))]),
            Err(FitError::NotRepresentative { .. })
        ));
        assert!(matches!(
            FittedCell::from_coefficients(Group::oh(), 8, [([4, 0, 0], Complex64::new(1.0, 0.0))]),
            Err(FitError::OutOfBand { .. })
        ));
        let ok = FittedCell::from_coefficients(
            Group::oh(),
            8,
            [
                ([1, 0, 0], Complex64::new(1.0, 0.0)),
                ([0, 0, 0], Complex64::new(0.5, 0.0)),
            ],
        )
        .expect("valid");
        // φ_(1,0,0) = (2/√6)(cos 2πx + cos 2πy + cos 2πz) for Oh: K = 1/√(48·8).
        let x = [0.1, 0.2, 0.3];
        let expect =
            0.5 + 16.0 / (48.0f64 * 8.0).sqrt() * x.iter().map(|c| (TAU * c).cos()).sum::<f64>();
        assert!((ok.value(x) - expect).abs() < 1e-12);
    }

    #[allow(dead_code)]
    fn assert_source<S: Source>(_: &S) {}
}
