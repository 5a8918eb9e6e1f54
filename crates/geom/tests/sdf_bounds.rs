//! Bounds of composite trees by interval reasoning, the box rule for unbounded solids, and a
//! check that bounds really contain their solids.

use std::f64::consts::SQRT_2;
use std::sync::Arc;

use latticebuild_geom::contour::ContourError;
use latticebuild_geom::field::ScalarField;
use latticebuild_geom::stack_lang::{
    self, Aabb, ExternalField, ExternalSolids, NoExternalSolids, Program,
};

const INF: f64 = f64::INFINITY;

/// A ball of radius `r` standing in for a mesh; a true distance or a squashed field.
struct Ball {
    r: f64,
    distance: bool,
}

impl ScalarField for Ball {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for i in 0..out.len() {
            let d = (xs[i] * xs[i] + ys[i] * ys[i] + zs[i] * zs[i]).sqrt() - self.r;
            // Not a distance: the same solid, with a field that grows too slowly outside.
            out[i] = if self.distance { d } else { d.tanh() };
        }
    }
}

impl ExternalField for Ball {
    fn bounds(&self) -> Aabb {
        Aabb::cube(self.r)
    }
    fn is_distance(&self) -> bool {
        self.distance
    }
}

struct Meshes;

impl ExternalSolids for Meshes {
    fn resolve(&self, path: &str, _from: Option<&str>) -> Result<Arc<dyn ExternalField>, String> {
        Ok(Arc::new(Ball {
            r: 2.0,
            distance: path == "distance.stl",
        }))
    }
}

fn bounds(program: &str) -> Aabb {
    Program::parse_str(program)
        .expect("the program parses")
        .field(&Meshes)
        .expect("its files resolve")
        .bounds()
}

fn domain(program: &str) -> Aabb {
    Program::parse_str(program)
        .expect("the program parses")
        .field(&NoExternalSolids)
        .expect("it names no file")
        .domain()
}

fn cube(h: f64) -> Aabb {
    Aabb::cube(h)
}

fn close(a: Aabb, b: Aabb) -> bool {
    let eq = |x: f64, y: f64| x == y || (x - y).abs() < 1e-12;
    (0..3).all(|i| eq(a.min[i], b.min[i]) && eq(a.max[i], b.max[i]))
}

fn assert_bounds(program: &str, want: Aabb) {
    let got = bounds(program);
    assert!(close(got, want), "{program}: got {got:?}, want {want:?}");
}

#[test]
fn primitives_and_transformations() {
    assert_bounds("ball", cube(1.0));
    assert_bounds("ball scale 5", cube(5.0));
    assert_bounds("box scale -3", cube(3.0));
    assert_bounds(
        "ball move 1,2,3",
        Aabb {
            min: [0.0, 1.0, 2.0],
            max: [2.0, 3.0, 4.0],
        },
    );
    assert_bounds(
        "ball scale 2,1,1/2",
        Aabb {
            min: [-2.0, -1.0, -0.5],
            max: [2.0, 1.0, 0.5],
        },
    );
    assert_bounds(
        "cylinder",
        Aabb {
            min: [-1.0, -1.0, -INF],
            max: [1.0, 1.0, INF],
        },
    );
    // The box turned by 45° about z: its corners reach √2 along x and y.
    assert_bounds(
        "box rotate 0,0,1 pi/4",
        Aabb {
            min: [-SQRT_2, -SQRT_2, -1.0],
            max: [SQRT_2, SQRT_2, 1.0],
        },
    );
    assert_bounds(
        "cylinder orient 1,0,0 scale 1/2",
        Aabb {
            min: [-INF, -0.5, -0.5],
            max: [INF, 0.5, 0.5],
        },
    );
    // Offsets and shells move the level: a distance grows by ξ.
    assert_bounds("ball offset 0.5", cube(1.5));
    assert_bounds("ball scale 2 offset -1/2", cube(1.5));
    assert_bounds("box shell 0.2", cube(1.1));
}

#[test]
fn combinations() {
    let pair = "ball move -1,0,0 ball move 1,0,0";
    assert_bounds(
        &format!("{pair} union"),
        Aabb {
            min: [-2.0, -1.0, -1.0],
            max: [2.0, 1.0, 1.0],
        },
    );
    assert_bounds(
        &format!("{pair} intersection"),
        Aabb {
            min: [0.0, -1.0, -1.0],
            max: [0.0, 1.0, 1.0],
        },
    );
    assert_bounds(&format!("{pair} difference"), bounds("ball move -1,0,0"));
    // A blend lies between its operands' values: inside only where one of them is.
    assert_bounds(
        &format!("{pair} sigmoid-blend 1,0,0 0 0.5"),
        bounds(&format!("{pair} union")),
    );
    // A TPMS is unbounded; intersected with a ball it has the ball's bounds (Figure 6).
    assert_bounds("tpms.gyroid", Aabb::EVERYTHING);
    assert_bounds(
        "ball scale 5 tpms.p scale 4 tpms.d scale 3.75 tpms.gyroid scale 1.25 intersection \
         intersection intersection",
        cube(5.0),
    );
    // Complement is unbounded, but reasoning on level sets undoes a double complement.
    assert_bounds("ball complement", Aabb::EVERYTHING);
    assert_bounds("ball complement complement", cube(1.0));
    // The box minus the ball of radius 2 is inside the box, whatever the ball.
    assert_bounds("box ball scale 2 difference", cube(1.0));
    // The hourglass of §6: grooves cut from the box.
    assert_bounds(
        "cylinder move 0,-2,0 cylinder move 0,2,0 union scale 1/2 orient 1,0,0 complement box \
         intersection",
        cube(1.0),
    );
    // A complement intersected with a bounded solid.
    assert_bounds("ball scale 3 box complement intersection", cube(3.0));
    // Everything is empty below the ball's centre depth.
    assert!(bounds("ball offset -2").is_empty());
}

#[test]
fn file_solids_grow_only_when_they_are_distances() {
    assert_bounds("file distance.stl", cube(2.0));
    assert_bounds("file distance.stl offset 1", cube(3.0));
    assert_bounds("file squashed.stl offset -1", cube(2.0));
    assert_bounds("file squashed.stl offset 1", Aabb::EVERYTHING);
    assert_bounds(
        "tpms.neovius scale 0.065 file squashed.stl intersection",
        cube(2.0),
    );
}

#[test]
fn the_box_rule() {
    // Unbounded solids are contoured in [-1, 1]³, the box of `box` (paper §4.2).
    assert_eq!(domain("tpms.gyroid"), cube(1.0));
    assert_eq!(domain("expression \"x + y + z - 1\""), cube(1.0));
    assert_eq!(
        domain("cylinder orient 1,0,0 scale 1/2"),
        Aabb {
            min: [-1.0, -0.5, -0.5],
            max: [1.0, 0.5, 0.5]
        }
    );
    // One-sided sides keep their finite end and are never inverted.
    let half = Aabb {
        min: [3.0, -INF, -5.0],
        max: [INF, -4.0, 2.0],
    };
    assert_eq!(
        half.box_rule(),
        Aabb {
            min: [3.0, -6.0, -5.0],
            max: [5.0, -4.0, 2.0]
        }
    );
    assert_eq!(domain("ball offset -2"), cube(1.0));
}

/// Samples a box larger than the bounds: every point inside the solid lies in the bounds.
#[test]
fn bounds_contain_their_solids() {
    let programs = [
        "ball scale 2,1,1/2 rotate 1,2,3 0.7 move 0.3,-0.2,0.5",
        "box shell 0.3 offset 0.1 ball move 1,1,0 difference",
        "cylinder scale 0.4 orient 1,1,1 ball scale 1.5 intersection",
        "ball move 1,0,0 complement box scale 1.2 intersection tpms.gyroid scale 0.5 \
         intersection",
        "ball scale 0.5,1,1.5 offset 0.2 complement offset -0.5 complement",
        "box scale 0.7 move 0.5,0,0 rotate 0,1,0 1 orient 1,-1,2",
        "ball move -1,0,0 box scale 0.5 move 1,0.5,0 sigmoid-blend 1,0.2,0 0.1 0.3 complement \
         offset 0.2 complement rotate 0,0,1 0.5",
    ];
    for program in programs {
        let p = Program::parse_str(program).unwrap();
        let f = p.field(&NoExternalSolids).unwrap();
        let b = f.bounds();
        assert!(b.is_bounded(), "{program}: {b:?}");
        let n = 40;
        let (lo, hi) = (-3.5, 3.5);
        let mut inside = 0;
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    let t = |v: usize| lo + (hi - lo) * (v as f64 + 0.5) / n as f64;
                    let p = [t(i), t(j), t(k)];
                    if f.eval(p) < 0.0 {
                        inside += 1;
                        assert!(
                            (0..3).all(|a| b.min[a] - 1e-9 <= p[a] && p[a] <= b.max[a] + 1e-9),
                            "{program}: {p:?} is inside but outside {b:?}"
                        );
                    }
                }
            }
        }
        assert!(inside > 0, "{program}: no sample inside");
    }
}

/// Found by `cargo xtask fuzz` (tests/fuzz_corpus/sdf): `offset 1e308` gives a box whose sides
/// overflow; it was sampled at inf and NaN, and pruning changed the resulting mesh.
#[test]
fn a_box_whose_sides_overflow_is_an_error_not_a_mesh() {
    let field = Program::parse_str("box shell 3 offset 1e308 ball move 1,1,0 difference")
        .expect("parses")
        .field(&NoExternalSolids)
        .expect("compiles");
    let domain = field.domain();
    assert_eq!(domain.max[0], 1e308 + 2.5);
    let e = stack_lang::mesh(&field, &domain, [6, 6, 6]).expect_err("no spacing");
    assert!(
        matches!(e, ContourError::BadBox(ref b) if b.starts_with("[-1e308,1e308]×")),
        "{e}"
    );
    // Wide sides within `f32` still sample, and give a mesh of finite vertices; beyond it
    // (1e307) the written positions could not hold them, which is the contourer's refusal.
    let wide = Aabb {
        min: [-1e30; 3],
        max: [1e30; 3],
    };
    let mesh = stack_lang::mesh(&field, &wide, [6, 6, 6]).expect("finite spacing");
    assert!(mesh.vertices.iter().flatten().all(|c| c.is_finite()));
    let beyond = Aabb {
        min: [-1e307; 3],
        max: [1e307; 3],
    };
    let e = stack_lang::mesh(&field, &beyond, [6, 6, 6]).expect_err("beyond f32");
    assert!(matches!(e, ContourError::BeyondF32 { .. }), "{e}");
}
