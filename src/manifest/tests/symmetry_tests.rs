//! Tests of symmetric cells, combinations and outputs over the reference element: invalid
//! manifests with their exact rendered diagnostics, then valid ones with what they must give.

use super::*;

const SYM_ERR_CASES: &[ErrCase] = &[
    ErrCase {
        name: "unknown group, with suggestion",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh2\"\n",
        sets: &[],
        expected: "\
error: unknown symmetry group `Oh2` in `cells.a.symmetry`
 --> lattice.toml:3:12
  |
3 | symmetry = \"Oh2\"
  |            ^^^^^ not a known group
  |
  = help: did you mean `Oh`?

error: could not load `lattice.toml` due to 1 previous error
",
    },
    ErrCase {
        name: "unknown group without a close one",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"C4v\"\n",
        sets: &[],
        expected: "\
error: unknown symmetry group `C4v` in `cells.a.symmetry`
 --> lattice.toml:3:12
  |
3 | symmetry = \"C4v\"
  |            ^^^^^ not a known group
  |
  = help: expected one of `D3`, `D4`, `Td`, `Oh`, or `{ generators = [...] }`

error: could not load `lattice.toml` due to 1 previous error
",
    },
    ErrCase {
        name: "generators that do not form a finite group",
        manifest: "[cells.a]\nexpr = \"x\"\nsymmetry = { generators = [[[0, -1, 0], [1, 0, 0], [0, 0, 1]], [[1, 1, 0], [0, 1, 0], [0, 0, 1]]] }\n",
        sets: &[],
        expected: "\
error: the generators in `cells.a.symmetry.generators` do not form a finite group
 --> lattice.toml:3:64
  |
3 | symmetry = { generators = [[[0, -1, 0], [1, 0, 0], [0, 0, 1]], [[1, 1, 0], [0, 1, 0], [0, 0, 1]]] }
  |                                                                ^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^ not orthogonal, so its powers never repeat
  |
  = help: each generator must be a rotation or reflection: a signed permutation matrix (an integer matrix M with Mᵀ·M = I)

error: could not load `lattice.toml` due to 1 previous error
",
    },
    ErrCase {
        name: "bad generator matrices",
        manifest: "[cells.a]\nexpr = \"x\"\nsymmetry = { generators = [[[0, -1], [1]], [[2, 0], [0, 1]], 3, [[1.5, 0], [0, 1]]], dimension = 2 }\n",
        sets: &[],
        expected: "\
error: a matrix in `cells.a.symmetry.generators` must be square
 --> lattice.toml:3:38
  |
3 | symmetry = { generators = [[[0, -1], [1]], [[2, 0], [0, 1]], 3, [[1.5, 0], [0, 1]]], dimension = 2 }
  |                                      ^^^ expected 2 entries, found 1

error: wrong type for `cells.a.symmetry.generators`
 --> lattice.toml:3:62
  |
3 | symmetry = { generators = [[[0, -1], [1]], [[2, 0], [0, 1]], 3, [[1.5, 0], [0, 1]]], dimension = 2 }
  |                                                              ^ expected a matrix (an array of rows of integers), found an integer

error: wrong type for `cells.a.symmetry.generators`
 --> lattice.toml:3:67
  |
3 | symmetry = { generators = [[[0, -1], [1]], [[2, 0], [0, 1]], 3, [[1.5, 0], [0, 1]]], dimension = 2 }
  |                                                                   ^^^ expected an integer, found a float

error: could not load `lattice.toml` due to 3 previous errors
",
    },
    ErrCase {
        name: "a 3D generator in a 2D group, and a tolerance with a fixed n",
        manifest: "[cells.a]\nexpr = \"x\"\nsymmetry = { generators = [[[0, -1, 0], [1, 0, 0], [0, 0, -1]]], dimension = 2 }\nfit = { n = 64, tolerance = 1e-3 }\n",
        sets: &[],
        expected: "\
error: a 3D matrix in the 2D group of `cells.a.symmetry`
 --> lattice.toml:3:28
  |
3 | symmetry = { generators = [[[0, -1, 0], [1, 0, 0], [0, 0, -1]]], dimension = 2 }
  |                            ^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^ outside the upper-left 2×2 block it must equal the identity
  |
  = help: write 2×2 matrices for `dimension = 2`

error: `cells.a.fit.tolerance` applies only to `n = \"auto\"`
 --> lattice.toml:4:17
  |
4 | fit = { n = 64, tolerance = 1e-3 }
  |                 ^^^^^^^^^ `n` is fixed at `64`
  |
  = help: remove `tolerance`, or set `n = \"auto\"`

error: could not load `lattice.toml` due to 2 previous errors
",
    },
    ErrCase {
        name: "odd and too large fit resolutions",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\nfit = { n = 63 }\n\n[cells.b]\ntpms = \"p\"\nsymmetry = \"Oh\"\nfit = { n = 1024 }\n\n[cells.c]\nexpr = \"x\"\nsymmetry = \"D4\"\nfit = { n = \"atuo\" }\n",
        sets: &[],
        expected: "\
error: `cells.a.fit.n` must be even and at least 4
 --> lattice.toml:4:13
  |
4 | fit = { n = 63 }
  |             ^^ found `63`
  |
  = help: N is the number of samples per axis of the fit, like `n = 64`

error: `cells.b.fit.n` must be at most 512 for a 3D group
 --> lattice.toml:9:13
  |
9 | fit = { n = 1024 }
  |             ^^^^ found `1024`
  |
  = help: the fit samples N^3 points; use `n = \"auto\"` to choose N by a tolerance

error: unknown value `atuo` in `cells.c.fit.n`
  --> lattice.toml:14:13
   |
14 | fit = { n = \"atuo\" }
   |             ^^^^^^ expected an even integer or `\"auto\"`
   |
   = help: did you mean `auto`?

error: could not load `lattice.toml` due to 3 previous errors
",
    },
    ErrCase {
        name: "fit and other keys without symmetry",
        manifest: "[cells.a]\ntpms = \"p\"\nfit = { n = 64 }\ninvert = true\n",
        sets: &[],
        expected: "\
error: `cells.a.fit` applies only to cells with a `symmetry`
 --> lattice.toml:3:1
  |
3 | fit = { n = 64 }
  | ^^^ cell `a` has no `symmetry`
  |
  = help: add `symmetry = \"Oh\"` (or `\"D3\"`, `\"D4\"`, `\"Td\"`), or remove `fit`

error: `cells.a.invert` applies only to cells with a `symmetry`
 --> lattice.toml:4:1
  |
4 | invert = true
  | ^^^^^^ cell `a` has no `symmetry`
  |
  = help: add `symmetry = \"Oh\"` (or `\"D3\"`, `\"D4\"`, `\"Td\"`), or remove `invert`

error: could not load `lattice.toml` due to 2 previous errors
",
    },
    ErrCase {
        name: "blend of cells with different groups",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\n\n[cells.b]\ntpms = \"d\"\nsymmetry = \"Td\"\n\n[cells.m]\nblend = { cells = [\"a\", \"b\"], weights = [0.7, 0.3] }\n",
        sets: &[],
        expected: "\
error: blend of cells with different groups in `cells.m.blend.cells`
  --> lattice.toml:10:19
   |
10 | blend = { cells = [\"a\", \"b\"], weights = [0.7, 0.3] }
   |                   ^^^^^^^^^^ `a` has group `Oh`, `b` has group `Td`
   |
   = help: combine cells of one group: different groups have different bases

error: could not load `lattice.toml` due to 1 previous error
",
    },
    ErrCase {
        name: "blend of a missing cell and of a cell without symmetry",
        manifest: "[cells.prim]\ntpms = \"p\"\nsymmetry = \"Oh\"\n\n[cells.plain]\ntpms = \"p\"\n\n[cells.m]\nblend = { cells = [\"prin\", \"prim\"], weights = [1, 1] }\n\n[cells.n]\nminkowski = { op = \"difference\", cells = [\"prim\", \"plain\"] }\n",
        sets: &[],
        expected: "\
error: unknown cell `prin` in `cells.m.blend.cells`
 --> lattice.toml:9:20
  |
9 | blend = { cells = [\"prin\", \"prim\"], weights = [1, 1] }
  |                    ^^^^^^ no cell with this name
  |
  = help: did you mean `prim`?

error: cell `plain` in `cells.n.minkowski.cells` has no `symmetry`
  --> lattice.toml:12:51
   |
12 | minkowski = { op = \"difference\", cells = [\"prim\", \"plain\"] }
   |                                                   ^^^^^^^ a Minkowski combination combines symmetric cells
   |
   = help: add `symmetry = \"Oh\"` (or its group) to `[cells.plain]`

error: could not load `lattice.toml` due to 2 previous errors
",
    },
    ErrCase {
        name: "blend weights of the wrong length",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\n\n[cells.m]\nblend = { cells = [\"a\", \"a\"], weights = [0.7, 0.2, 0.1] }\n",
        sets: &[],
        expected: "\
error: `cells.m.blend.weights` must have one weight per cell
 --> lattice.toml:6:41
  |
6 | blend = { cells = [\"a\", \"a\"], weights = [0.7, 0.2, 0.1] }
  |                                         ^^^^^^^^^^^^^^^ found 3 weights for 2 cells

error: could not load `lattice.toml` due to 1 previous error
",
    },
    ErrCase {
        name: "minkowski with three cells",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\n\n[cells.m]\nminkowski = { op = \"sum\", cells = [\"a\", \"a\", \"a\"] }\n",
        sets: &[],
        expected: "\
error: `cells.m.minkowski.cells` must name exactly 2 cells
 --> lattice.toml:6:35
  |
6 | minkowski = { op = \"sum\", cells = [\"a\", \"a\", \"a\"] }
  |                                   ^^^^^^^^^^^^^^^ found 3
  |
  = help: a Minkowski sum or difference combines two cells

error: could not load `lattice.toml` due to 1 previous error
",
    },
    ErrCase {
        name: "blend cycle and a cell using itself",
        manifest: "[cells.a]\nblend = { cells = [\"b\"], weights = [1] }\n\n[cells.b]\nminkowski = { op = \"sum\", cells = [\"a\", \"a\"] }\n\n[cells.c]\nblend = { cells = [\"c\"], weights = [1] }\n",
        sets: &[],
        expected: "\
error: reference cycle between cells: `a` → `b` → `a`
 --> lattice.toml:2:20
  |
2 | blend = { cells = [\"b\"], weights = [1] }
  |                    ^^^ `a` uses `b` here
  |
  = help: a blend or Minkowski combination cannot use itself, directly or through other cells

error: cell `c` refers to itself in `cells.c.blend.cells`
 --> lattice.toml:8:20
  |
8 | blend = { cells = [\"c\"], weights = [1] }
  |                    ^^^ a cell cannot use itself
  |
  = help: name other cells

error: could not load `lattice.toml` due to 2 previous errors
",
    },
    ErrCase {
        name: "z in the expression of a 2D cell",
        manifest: "[cells.a]\nexpr = \"cos(tau*x) + 2e-3*cos(tau*z)\"\nsymmetry = \"d4\"\n",
        sets: &[],
        expected: "\
error: invalid expression in `cells.a.expr`
 --> lattice.toml:2:35
  |
2 | expr = \"cos(tau*x) + 2e-3*cos(tau*z)\"
  |                                   ^ `z` in a cell of the 2D group `D4`
  |
  = help: a 2D cell is a function of x and y only

error: could not load `lattice.toml` due to 1 previous error
",
    },
    ErrCase {
        name: "tpms with a 2D group",
        manifest: "[cells.a]\ntpms = \"gyroid\"\nsymmetry = \"D4\"\n",
        sets: &[],
        expected: "\
error: 2D group for a TPMS cell in `cells.a.symmetry`
 --> lattice.toml:3:12
  |
3 | symmetry = \"D4\"
  |            ^^^^ `D4` is a 2D group, but the TPMS library's surfaces are 3D
  |
  = help: use `symmetry = \"Oh\"` or `\"Td\"`, or write the cell as an `expr` in x and y

error: could not load `lattice.toml` due to 1 previous error
",
    },
    ErrCase {
        name: "domain with over = element",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\n\n[outputs.o]\ncell = \"a\"\nover = \"element\"\ndomain = { min = [0, 0, 0], max = [1, 1, 1] }\ncell_size = 2\nsamples = 32\n",
        sets: &[],
        expected: "\
error: `outputs.o.domain` does not apply with `over = \"element\"`
 --> lattice.toml:8:1
  |
8 | domain = { min = [0, 0, 0], max = [1, 1, 1] }
  | ^^^^^^ the element is the reference cell
  |
  = help: remove `domain`, or remove `over` to fill a box

error: `outputs.o.cell_size` does not apply with `over = \"element\"`
 --> lattice.toml:9:1
  |
9 | cell_size = 2
  | ^^^^^^^^^ the element is one cell of size 1
  |
  = help: remove `cell_size`, or remove `over` to fill a box

error: could not load `lattice.toml` due to 2 previous errors
",
    },
    ErrCase {
        name: "planar domain of a 3D cell, and corners of different lengths",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\n\n[outputs.o]\ncell = \"a\"\ndomain = { min = [0, 0], max = [1, 1] }\nsamples = 32\n\n[outputs.q]\ncell = \"a\"\ndomain = { min = [0, 0], max = [1, 1, 1] }\nsamples = 32\n",
        sets: &[],
        expected: "\
error: the planar `outputs.o.domain` needs a 2D cell
 --> lattice.toml:7:10
  |
7 | domain = { min = [0, 0], max = [1, 1] }
  |          ^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^ cell `a` has a 3D group
  |
  = help: give the corners as [x, y, z] to fill a box, or use a cell with a 2D `symmetry` (`\"D3\"`, `\"D4\"` or generators with `dimension = 2`)

error: `outputs.q.domain.min` and `outputs.q.domain.max` differ in length
  --> lattice.toml:12:10
   |
12 | domain = { min = [0, 0], max = [1, 1, 1] }
   |          ^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^^ `min` has 2 values, `max` has 3
   |
   = help: give both corners as [x, y] for a planar domain, or both as [x, y, z]

error: could not load `lattice.toml` due to 2 previous errors
",
    },
    ErrCase {
        name: "misspelled over, and over a cell without symmetry",
        manifest: "[cells.a]\ntpms = \"p\"\n\n[outputs.o]\ncell = \"a\"\nover = \"elemnt\"\nsamples = 32\n\n[outputs.q]\ncell = \"a\"\nover = \"element\"\nsamples = 32\n",
        sets: &[],
        expected: "\
error: unknown value `elemnt` in `outputs.o.over`
 --> lattice.toml:6:8
  |
6 | over = \"elemnt\"
  |        ^^^^^^^^ expected `\"element\"`
  |
  = help: did you mean `element`?

error: `outputs.q.over = \"element\"` needs a reference element
  --> lattice.toml:11:8
   |
11 | over = \"element\"
   |        ^^^^^^^^^ cell `a` has no `symmetry`, so it has no reference element
   |
   = help: give `[cells.a]` a `symmetry` of `\"D3\"`, `\"D4\"`, `\"Td\"` or `\"Oh\"`, or remove `over`

error: could not load `lattice.toml` due to 2 previous errors
",
    },
    ErrCase {
        name: "keys that do not apply to a blend",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\n\n[cells.m]\nblend = { cells = [\"a\"], weights = [1] }\nsymmetry = \"Oh\"\nextend = \"none\"\n",
        sets: &[],
        expected: "\
error: `cells.m.symmetry` does not apply to a blend
 --> lattice.toml:7:1
  |
7 | symmetry = \"Oh\"
  | ^^^^^^^^ it takes the group of the cells it combines
  |
  = help: remove `symmetry`

error: `cells.m.extend` does not apply to a blend
 --> lattice.toml:8:1
  |
8 | extend = \"none\"
  | ^^^^^^ it combines fitted cells: nothing is sampled
  |
  = help: set `extend` on the cells it combines

error: could not load `lattice.toml` due to 2 previous errors
",
    },
];

#[test]
fn invalid_symmetric_manifests_render_exactly() {
    let mut failures = Vec::new();
    for case in SYM_ERR_CASES {
        let actual = render_errors(case.manifest, case.sets);
        if actual != case.expected {
            failures.push(format!(
                "--- case `{}`\n--- expected:\n{}--- actual:\n{}",
                case.name, case.expected, actual
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} case(s) differ:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

// ---- valid manifests --------------------------------------------------------------------------

fn symmetric(group: GroupSpec, n: FitResolution) -> Symmetric {
    Symmetric {
        group,
        n,
        mirror: true,
        symmetrize: false,
        normal_to_faces: false,
        offset: 0.0,
        invert: false,
    }
}

fn named(name: &str) -> GroupSpec {
    GroupSpec::Named(name.into())
}

#[test]
fn defaults_are_filled_in_for_each_group() {
    let text = "\
[cells.tri]
expr = \"cos(tau*x) + cos(tau*y)\"
symmetry = \"d3\"

[cells.square]
expr = \"cos(tau*x) + cos(tau*y)\"
symmetry = \"D4\"

[cells.tet]
tpms = \"d\"
symmetry = \"TD\"

[cells.cube]
tpms = \"p\"
symmetry = \"oh\"
";
    let manifest = parse_ok(text, &[]);
    let groups: Vec<_> = manifest
        .cells
        .values()
        .map(|c| c.symmetric.clone())
        .collect();
    let fixed = FitResolution::Fixed;
    assert_eq!(
        groups,
        vec![
            Some(symmetric(named("Oh"), fixed(128))),
            Some(symmetric(named("D4"), fixed(256))),
            Some(symmetric(named("Td"), fixed(128))),
            Some(symmetric(named("D3"), fixed(256))),
        ]
    );
}

#[test]
fn every_symmetric_key_given_explicitly() {
    let text = "\
[cells.bone]
tpms = \"gyroid\"
symmetry = \"Td\"
fit = { n = \"auto\", tolerance = 2e-4 }
extend = \"none\"
symmetrize = true
normal_to_faces = true
offset = -0.1
invert = true

[cells.auto]
tpms = \"p\"
symmetry = \"Oh\"
fit = { n = \"AUTO\" }

[cells.big]
expr = \"cos(tau*x) * cos(tau*y)\"
symmetry = \"D4\"
fit = { n = 8192 }
";
    let manifest = parse_ok(text, &[]);
    assert_eq!(
        manifest.cells["bone"].symmetric,
        Some(Symmetric {
            group: named("Td"),
            n: FitResolution::Auto { tolerance: 2e-4 },
            mirror: false,
            symmetrize: true,
            normal_to_faces: true,
            offset: -0.1,
            invert: true,
        })
    );
    let n = |name: &str| manifest.cells[name].symmetric.as_ref().map(|s| s.n);
    assert_eq!(n("auto"), Some(FitResolution::Auto { tolerance: 1e-3 }));
    assert_eq!(n("big"), Some(FitResolution::Fixed(8192)));
}

#[test]
fn generators_are_stored_as_3x3_matrices() {
    let text = "\
[cells.c4]
expr = \"cos(tau*x) + cos(tau*y) + cos(tau*z)\"
symmetry = { generators = [[[0, -1, 0], [1, 0, 0], [0, 0, 1]], [[1, 0, 0], [0, 1, 0], [0, 0, -1]]], dimension = 3 }
fit = { n = 64 }

[cells.flat]
expr = \"cos(tau*x) + cos(tau*y)\"
symmetry = { generators = [[[0, -1], [1, 0]]] }
";
    let manifest = parse_ok(text, &[]);
    assert_eq!(
        manifest.cells["c4"].symmetric,
        Some(symmetric(
            GroupSpec::Generators {
                dimension: 3,
                generators: vec![
                    [[0, -1, 0], [1, 0, 0], [0, 0, 1]],
                    [[1, 0, 0], [0, 1, 0], [0, 0, -1]],
                ],
            },
            FitResolution::Fixed(64),
        ))
    );
    // 2×2 matrices: the dimension is inferred, the matrix embedded, and the 2D default N used.
    assert_eq!(
        manifest.cells["flat"].symmetric,
        Some(symmetric(
            GroupSpec::Generators {
                dimension: 2,
                generators: vec![[[0, -1, 0], [1, 0, 0], [0, 0, 1]]],
            },
            FitResolution::Fixed(256),
        ))
    );
}

#[test]
fn combinations_take_their_members_group() {
    let text = "\
[cells.mix]
blend = { cells = [\"p\", \"wavy\"], weights = [0.7, 0.3] }
offset = 0.05

[cells.p]
tpms = \"p\"
symmetry = \"Oh\"
fit = { n = 64 }

[cells.wavy]
expr = \"cos(tau*x) + cos(tau*y) + cos(tau*z)\"
symmetry = { generators = [[[0, 1, 0], [1, 0, 0], [0, 0, 1]], [[-1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 0, 1], [0, 1, 0], [1, 0, 0]]] }

[cells.sum]
minkowski = { op = \"sum\", cells = [\"mix\", \"p\"] }
fit = { n = \"auto\" }
invert = true

[cells.flat]
expr = \"cos(tau*x) + cos(tau*y)\"
symmetry = \"D3\"

[cells.flat-mix]
blend = { cells = [\"flat\"], weights = [2] }
";
    let manifest = parse_ok(text, &[]);
    // `wavy`'s generators give Oh itself (the same matrices), so it blends with `p`.
    let mix = &manifest.cells["mix"];
    assert_eq!(
        mix.source,
        CellSource::Blend {
            cells: vec!["p".into(), "wavy".into()],
            weights: vec![0.7, 0.3],
        }
    );
    let mut expected = symmetric(named("Oh"), FitResolution::Fixed(128));
    expected.offset = 0.05;
    assert_eq!(mix.symmetric, Some(expected));
    let sum = &manifest.cells["sum"];
    assert_eq!(
        sum.source,
        CellSource::Minkowski {
            op: MinkowskiOp::Sum,
            cells: ["mix".into(), "p".into()],
        }
    );
    let mut expected = symmetric(named("Oh"), FitResolution::Auto { tolerance: 1e-3 });
    expected.invert = true;
    assert_eq!(sum.symmetric, Some(expected));
    assert_eq!(
        manifest.cells["flat-mix"].symmetric,
        Some(symmetric(named("D3"), FitResolution::Fixed(256)))
    );
}

#[test]
fn outputs_over_the_element_take_its_bounding_box() {
    let r3 = 3f64.sqrt();
    let cases = [
        (
            "D3",
            "expr = \"cos(tau*x)\"",
            [-0.5, -r3 / 6.0, 0.0],
            [0.5, r3 / 3.0, 0.0],
        ),
        (
            "D4",
            "expr = \"cos(tau*x)\"",
            [-0.5, -0.5, 0.0],
            [0.5, 0.5, 0.0],
        ),
        ("Td", "tpms = \"d\"", [-0.5; 3], [0.5; 3]),
        ("Oh", "tpms = \"p\"", [-0.5; 3], [0.5; 3]),
    ];
    for (group, source, min, max) in cases {
        let text = format!(
            "[cells.a]\n{source}\nsymmetry = \"{group}\"\n\n[cells.m]\nblend = {{ cells = [\"a\"], weights = [1] }}\n\n\
             [outputs.o]\ncell = \"m\"\nover = \"element\"\nvoxel = 0.25\n"
        );
        let manifest = parse_ok(&text, &[]);
        let out = &manifest.outputs["o"];
        assert!(out.over_element, "{group}");
        assert_eq!((out.domain_min, out.domain_max), (min, max), "{group}");
        assert_eq!(out.cell_size, [1.0; 3], "{group}");
        // A 2D element has no extent in z, and still gets the 2 samples every axis has.
        let z = if min[2] == max[2] { 2 } else { 5 };
        assert_eq!((out.samples[0], out.samples[2]), (5, z), "{group}");
    }
}

#[test]
fn planar_domains_take_pairs_and_fix_z() {
    let text = "[cells.a]\nexpr = \"cos(tau*x) + cos(tau*y)\"\nsymmetry = \"D4\"\n\n\
                [outputs.o]\ncell = \"a\"\ndomain = { min = [0, -1], max = [3, 1] }\n\
                cell_size = [0.5, 0.25]\nsamples = [61, 41]\n\n\
                [outputs.v]\ncell = \"a\"\ndomain = { min = [0, 0], max = [2, 1] }\ncell_size = 3\nvoxel = 0.1\n";
    let manifest = parse_ok(text, &[]);
    let o = &manifest.outputs["o"];
    assert!(o.planar_domain && !o.over_element);
    assert_eq!(
        (o.domain_min, o.domain_max),
        ([0.0, -1.0, 0.0], [3.0, 1.0, 0.0])
    );
    assert_eq!(o.cell_size, [0.5, 0.25, 1.0]);
    assert_eq!(o.samples, [61, 41, 2]);
    let v = &manifest.outputs["v"];
    assert!(v.planar_domain);
    assert_eq!(v.cell_size, [3.0, 3.0, 1.0]);
    assert_eq!(v.samples, [21, 11, 2]);
}

#[test]
fn symmetric_keys_can_be_set_from_the_command_line() {
    // Group names, `extend`, `n = "auto"` and `over` are strings without quotes.
    let manifest = parse_ok(
        "[cells.gyroid]\ntpms = \"gyroid\"\n",
        &[
            "cells.gyroid.symmetry=Td",
            "cells.gyroid.extend=none",
            "cells.gyroid.fit.n=auto",
            "outputs.e.cell=gyroid",
            "outputs.e.over=element",
            "outputs.e.samples=16",
        ],
    );
    let mut expected = symmetric(named("Td"), FitResolution::Auto { tolerance: 1e-3 });
    expected.mirror = false;
    assert_eq!(manifest.cells["gyroid"].symmetric, Some(expected));
    let out = &manifest.outputs["e"];
    assert!(out.over_element);
    assert_eq!((out.domain_min, out.domain_max), ([-0.5; 3], [0.5; 3]));
}

/// Every prefix of a manifest using every new key must give a manifest or diagnostics with
/// locations, never a panic.
#[test]
fn no_symmetric_input_panics() {
    let text = "\
[cells.a]
expr = \"cos(tau*x) + 1e+3*z\"
symmetry = { generators = [[[0, -1], [1, 0]], [[2147483648, 0], [0, 1]]], dimension = 2 }
fit = { n = 9223372036854775807, tolerance = -nan }
extend = \"mirror\"
[cells.b]
blend = { cells = [\"a\", \"b\", \"c\"], weights = [1, inf] }
symmetrize = 1
[cells.c]
minkowski = { op = \"sum\", cells = [\"b\", \"a\"] }
[outputs.o]
cell = \"b\"
over = \"element\"
samples = 8
";
    for end in (0..=text.len()).filter(|&i| text.is_char_boundary(i)) {
        if let Err(diags) = parse(&text[..end], Path::new("m.toml"), &[]) {
            assert!(!diags.is_empty());
            assert!(
                diags.iter().all(|d| d.location.is_some()),
                "{}",
                render(&diags)
            );
        }
    }
}

/// The symmetric example in the user's reference must stay a valid manifest.
#[test]
fn symmetric_reference_example_is_valid() {
    let doc = include_str!("../../../docs/manifest.md");
    let example = doc
        .split("## Symmetric cells")
        .nth(1)
        .and_then(|rest| rest.split("```toml\n").nth(1))
        .and_then(|rest| rest.split("```").next())
        .unwrap_or_default();
    let manifest = parse_ok(example, &[]);
    let group = |name: &str| {
        manifest.cells[name]
            .symmetric
            .as_ref()
            .map(|s| s.group.clone())
    };
    assert_eq!(group("mix"), Some(named("Oh")));
    assert_eq!(group("thick"), Some(named("Oh")));
    assert_eq!(group("triangle"), Some(named("D3")));
    assert_eq!(manifest.cells.len(), 8);
}
