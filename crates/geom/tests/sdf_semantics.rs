//! Each word of the SDF language against values computed by hand from the paper's equations.

use std::f64::consts::{FRAC_1_SQRT_2, PI};

use latticebuild_geom::field::{Grid, ScalarField};
use latticebuild_geom::stack_lang::{NoExternalSolids, Program, ProgramField};

fn field(program: &str) -> ProgramField {
    Program::parse_str(program)
        .unwrap_or_else(|e| panic!("{program}: {e}"))
        .field(&NoExternalSolids)
        .unwrap_or_else(|e| panic!("{program}: {e}"))
}

/// Checks `program` at each `(point, value)` to 1e-12.
fn check(program: &str, cases: &[([f64; 3], f64)]) {
    let f = field(program);
    for &(p, want) in cases {
        let got = f.eval(p);
        assert!(
            (got - want).abs() < 1e-12,
            "{program} at {p:?}: got {got}, want {want}"
        );
    }
}

#[test]
fn primitives() {
    check(
        "ball",
        &[
            ([0.0; 3], -1.0),
            ([2.0, 0.0, 0.0], 1.0),
            ([0.6, 0.8, 0.0], 0.0),
        ],
    );
    // Unit radius about z, infinitely long.
    check(
        "cylinder",
        &[([3.0, 4.0, 100.0], 4.0), ([0.0, 0.5, -7.0], -0.5)],
    );
    // Half-width 1, exact distance outside (to a face, an edge, a corner) and inside.
    check(
        "box",
        &[
            ([2.0, 0.0, 0.0], 1.0),
            ([2.0, 2.0, 0.0], 2f64.sqrt()),
            ([2.0, 3.0, 4.0], 14f64.sqrt()),
            ([0.5, 0.0, 0.0], -0.5),
            ([0.5, -0.8, 0.1], -0.2),
        ],
    );
}

#[test]
fn tpms_and_expressions() {
    // Gyroid C_x S_y + C_y S_z + C_z S_x with period 1.
    check(
        "tpms.gyroid",
        &[
            ([0.25, 0.0, 0.0], 1.0),
            ([0.0, 0.25, 0.0], 1.0),
            ([0.0; 3], 0.0),
        ],
    );
    // P: C_x + C_y + C_z, by an alias and in upper case.
    check(
        "tpms.Schwarz-P",
        &[([0.0; 3], 3.0), ([0.5, 0.5, 0.0], -1.0)],
    );
    check("TPMS.P", &[([0.5; 3], -3.0)]);
    check(
        "expression \"x*x + y - z\"",
        &[([2.0, 3.0, 1.0], 6.0), ([0.0, 0.0, 0.0], 0.0)],
    );
    check("expression sqrt(x^2+y^2)-2", &[([3.0, 4.0, 9.0], 3.0)]);
}

#[test]
fn value_transformations() {
    // eq. 8, 6, 7.
    check(
        "ball complement",
        &[([0.0; 3], 1.0), ([3.0, 0.0, 0.0], -2.0)],
    );
    check(
        "ball offset 0.5",
        &[([2.0, 0.0, 0.0], 0.5), ([0.0; 3], -1.5)],
    );
    check("ball offset -1/4", &[([2.0, 0.0, 0.0], 1.25)]);
    check(
        "ball shell 0.5",
        &[
            ([1.0, 0.0, 0.0], -0.25),
            ([0.0; 3], 0.75),
            ([3.0, 0.0, 0.0], 1.75),
        ],
    );
    // The eccentric shell |f − ξ| − Ξ/2 of eq. 15.
    check(
        "tpms.p offset 1 shell 2",
        &[([0.0; 3], 1.0), ([0.25, 0.25, 0.25], 0.0)],
    );
}

#[test]
fn point_transformations() {
    // eq. 2: f(x − δ).
    check(
        "ball move 1,2,3",
        &[([1.0, 2.0, 3.0], -1.0), ([3.0, 2.0, 3.0], 1.0)],
    );
    // eq. 3: |κ| f(x/κ), also for negative κ.
    check("ball scale 2", &[([3.0, 0.0, 0.0], 1.0), ([0.0; 3], -2.0)]);
    check("ball scale -2", &[([3.0, 0.0, 0.0], 1.0)]);
    check(
        "ball move 1,0,0 scale -2",
        &[([-2.0, 0.0, 0.0], -2.0), ([2.0, 0.0, 0.0], 2.0)],
    );
    check("ball scale 1/2", &[([1.0, 0.0, 0.0], 0.5)]);
    // eq. 4 as written: min over i of |κ_i| f(x/κ): the smallest factor outside, the largest
    // inside.
    check(
        "ball scale 2,1,1",
        &[
            ([4.0, 0.0, 0.0], 1.0),
            ([0.0; 3], -2.0),
            ([0.0, 2.0, 0.0], 1.0),
        ],
    );
    check(
        "ball scale 1,-3,1/2",
        &[([0.0, 6.0, 0.0], 0.5), ([0.0; 3], -3.0)],
    );
    // eq. 5: f(R x) with R the Rodrigues matrix; R about z by π/2 takes x to y, so the ball
    // at (2, 0, 0) is seen where R x = (2, 0, 0), at x = (0, −2, 0).
    check(
        "ball move 2,0,0 rotate 0,0,1 pi/2",
        &[([0.0, -2.0, 0.0], -1.0), ([0.0, 2.0, 0.0], 3.0)],
    );
    // About (1,1,1) by 2π/3, R cycles x → y → z, so the ball at (0, 0, 3) is seen at R⁻¹
    // (0,0,3) = (0, 3, 0).
    check(
        "ball move 0,0,3 rotate 1,1,1 2*pi/3",
        &[([0.0, 3.0, 0.0], -1.0)],
    );
    // orient: the solid's z axis turned onto v; the ball on the z axis follows it.
    check(
        "ball move 0,0,2 orient 1,0,0",
        &[([2.0, 0.0, 0.0], -1.0), ([-2.0, 0.0, 0.0], 3.0)],
    );
    let d = 2.0 * FRAC_1_SQRT_2;
    check(
        "ball move 0,0,2 orient 1,1,0",
        &[([d, d, 0.0], -1.0), ([0.0, 0.0, 2.0], 8f64.sqrt() - 1.0)],
    );
    check("ball move 0,0,2 orient 0,0,5", &[([0.0, 0.0, 2.0], -1.0)]);
    // A cylinder oriented along x with radius 1/2 (paper §4.3).
    check(
        "cylinder orient 1,0,0 scale 1/2",
        &[
            ([100.0, 0.0, 0.0], -0.5),
            ([0.0, 0.0, 1.0], 0.5),
            ([3.0, 0.3, 0.4], 0.0),
        ],
    );
}

#[test]
fn binary_operations() {
    let a = "ball move -1,0,0";
    let b = "ball move 1,0,0";
    check(
        &format!("{a} {b} union"),
        &[
            ([0.0; 3], 0.0),
            ([-1.0, 0.0, 0.0], -1.0),
            ([1.5, 0.0, 0.0], -0.5),
        ],
    );
    check(
        &format!("{a} {b} intersection"),
        &[
            ([0.0; 3], 0.0),
            ([-1.0, 0.0, 0.0], 1.0),
            ([0.0, 0.5, 0.0], (1.25f64).sqrt() - 1.0),
        ],
    );
    // A \ B = max(f_A, −f_B): order matters.
    check(
        &format!("{a} {b} difference"),
        &[
            ([-1.5, 0.0, 0.0], -0.5),
            ([1.0, 0.0, 0.0], 1.0),
            ([0.0; 3], 0.0),
        ],
    );
    check(&format!("{b} {a} difference"), &[([1.5, 0.0, 0.0], -0.5)]);
}

#[test]
fn arguments_are_expressions() {
    check("ball offset 2^-3", &[([1.0, 0.0, 0.0], -0.125)]);
    check(
        "ball move 1,0,0 rotate 0,0,1 pi/4",
        // The centre c with R c = (1, 0, 0): c = Rᵀ (1, 0, 0) = (cos π/4, −sin π/4, 0).
        &[([FRAC_1_SQRT_2, -FRAC_1_SQRT_2, 0.0], -1.0)],
    );
    check(
        "ball move min(1,2),-(1),sqrt(0)",
        &[([1.0, -1.0, 0.0], -1.0)],
    );
    check("ball scale tau/(2*pi)", &[([2.0, 0.0, 0.0], 1.0)]);
    let _ = PI;
}

/// The gyroid `C_x S_y + C_y S_z + C_z S_x` and P `C_x + C_y + C_z` of period 1, by hand.
fn gyroid(p: [f64; 3]) -> f64 {
    let (c, s) = (|v: f64| (2.0 * PI * v).cos(), |v: f64| (2.0 * PI * v).sin());
    c(p[0]) * s(p[1]) + c(p[1]) * s(p[2]) + c(p[2]) * s(p[0])
}

fn schwarz_p(p: [f64; 3]) -> f64 {
    p.iter().map(|&v| (2.0 * PI * v).cos()).sum()
}

/// `f g sigmoid-blend d x0 width`: `f` far on the −d side, `g` far on the +d side, their
/// average on the plane `d̂·x = x0`, and the logistic weight in between.
#[test]
fn sigmoid_blend_grades_between_two_solids() {
    let f = field("tpms.gyroid tpms.p sigmoid-blend 1,0,0 0 0.1");
    let points = [[0.13, 0.71, -0.4], [0.0, 0.25, 0.3], [0.37, -0.05, 0.9]];
    for q in points {
        // 30 widths away the weight is e^-30 ≈ 1e-13 from its limit.
        let far_low = [q[0] - 3.0, q[1], q[2]];
        let far_high = [q[0] + 3.0, q[1], q[2]];
        assert!((f.eval(far_low) - gyroid(far_low)).abs() < 1e-11);
        assert!((f.eval(far_high) - schwarz_p(far_high)).abs() < 1e-11);
        let mid = [0.0, q[1], q[2]];
        let average = 0.5 * (gyroid(mid) + schwarz_p(mid));
        assert!((f.eval(mid) - average).abs() < 1e-12);
        // One width past the plane: w = 1/(1 + e^-1).
        let one = [0.1, q[1], q[2]];
        let w = 1.0 / (1.0 + (-1.0f64).exp());
        let want = (1.0 - w) * gyroid(one) + w * schwarz_p(one);
        assert!((f.eval(one) - want).abs() < 1e-12);
    }
    // The direction is made a unit vector, and the blend moves with what follows it: the plane
    // x0 = 0.5 of `2,0,0` lies at world x = 1.5 after `move 1,0,0`; `scale 2` doubles lengths
    // and values.
    check(
        "ball box sigmoid-blend 2,0,0 0.5 0.25 move 1,0,0",
        &[([1.5, 0.2, 0.0], 0.5 * (0.29f64.sqrt() - 1.0 - 0.5))],
    );
    let scaled = field("tpms.gyroid tpms.p sigmoid-blend 0,0,1 0.5 0.1 scale 2");
    let at = [0.3, -0.2, 1.0];
    let half = at.map(|v| v / 2.0);
    let want = 2.0 * 0.5 * (gyroid(half) + schwarz_p(half));
    assert!((scaled.eval(at) - want).abs() < 1e-12);
}

/// The grid sampler (separable tables, tiles) agrees with point evaluation, with pruning off;
/// with pruning on, every sample keeps its sign.
#[test]
fn sampler_agrees_with_points() {
    let programs = [
        "ball scale 5 tpms.p scale 4 tpms.d scale 3.75 tpms.gyroid scale 1.25 intersection \
         intersection intersection",
        "tpms.gyroid rotate 1,2,3 0.4 scale 0.7 ball scale 2 move 0.1,0,0 intersection",
        "box expression \"sin(3*x)*y - z\" offset 0.1 union cylinder orient 1,1,0 difference",
        "tpms.iwp scale 0.5,0.8,1.3 offset 0.3 shell 0.4 complement",
        "tpms.gyroid tpms.p offset 0.5 sigmoid-blend 1,1,0 0.2 0.3 scale 1.5 ball scale 1.8 \
         intersection",
    ];
    let grid = Grid::spanning([-2.1, -1.9, -2.0], [2.0, 2.2, 1.7], [45, 38, 41]);
    let [nx, ny, nz] = grid.counts;
    for program in programs {
        let mut f = field(program);
        f.set_pruning(false);
        let exact = f.sampler(&grid);
        let mut plane = vec![0.0; nx * ny];
        let (mut xs, mut ys, mut zs) = (Vec::new(), Vec::new(), Vec::new());
        for k in [0, 7, nz - 1] {
            exact.sample_plane(k, &mut plane);
            xs.clear();
            ys.clear();
            zs.clear();
            for j in 0..ny {
                for i in 0..nx {
                    xs.push(grid.coord(0, i));
                    ys.push(grid.coord(1, j));
                    zs.push(grid.coord(2, k));
                }
            }
            let mut points = vec![0.0; nx * ny];
            f.eval_points(&xs, &ys, &zs, &mut points);
            for (s, p) in plane.iter().zip(&points) {
                assert!(
                    (s - p).abs() < 1e-9,
                    "{program}: sampled {s}, evaluated {p}"
                );
            }
        }
        let mut pruned_field = field(program);
        pruned_field.set_pruning(true);
        let pruned = pruned_field.sampler(&grid);
        let mut pruned_plane = vec![0.0; nx * ny];
        for k in 0..nz {
            exact.sample_plane(k, &mut plane);
            pruned.sample_plane(k, &mut pruned_plane);
            for (a, b) in plane.iter().zip(&pruned_plane) {
                assert_eq!(*a < 0.0, *b < 0.0, "{program}: plane {k}: {a} vs {b}");
            }
        }
    }
}

/// Long programs parse, compile and evaluate without deep recursion.
#[test]
fn long_programs() {
    // 100 001 complements: an odd number negates.
    let program = format!("ball{}", " complement".repeat(100_001));
    check(&program, &[([0.0; 3], 1.0)]);
    // 10 000 small moves add up.
    let program = format!("ball{}", " move 0.001,0,0".repeat(10_000));
    let f = field(&program);
    assert!((f.eval([10.0, 0.0, 0.0]) + 1.0).abs() < 1e-9);
    // A chain of 2 000 unions.
    let mut program = String::from("ball");
    for i in 1..2000 {
        program.push_str(&format!(" ball move {},0,0 union", 3 * i));
    }
    check(
        &program,
        &[([3000.0, 0.0, 0.0], -1.0), ([1.5, 0.0, 0.0], 0.5)],
    );
    assert_eq!(field(&program).bounds().max, [5998.0, 1.0, 1.0]);
}
