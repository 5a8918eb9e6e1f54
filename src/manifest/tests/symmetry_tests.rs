//! Tests of symmetric cells, combinations and outputs over the reference element: invalid
//! manifests with their exact rendered diagnostics, then valid ones with what they must give.

use super::*;

pub(super) const SYM_ERR_CASES: &[ErrCase] = &[
    ErrCase {
        name: "unknown group, with suggestion",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh2\"\n",
        sets: &[],
    },
    ErrCase {
        name: "unknown group without a close one",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"C4v\"\n",
        sets: &[],
    },
    ErrCase {
        name: "generators that do not form a finite group",
        manifest: "[cells.a]\nexpr = \"x\"\nsymmetry = { generators = [[[0, -1, 0], [1, 0, 0], [0, 0, 1]], [[1, 1, 0], [0, 1, 0], [0, 0, 1]]] }\n",
        sets: &[],
    },
    ErrCase {
        name: "bad generator matrices",
        manifest: "[cells.a]\nexpr = \"x\"\nsymmetry = { generators = [[[0, -1], [1]], [[2, 0], [0, 1]], 3, [[1.5, 0], [0, 1]]], dimension = 2 }\n",
        sets: &[],
    },
    ErrCase {
        name: "a 3D generator in a 2D group, and a tolerance with a fixed n",
        manifest: "[cells.a]\nexpr = \"x\"\nsymmetry = { generators = [[[0, -1, 0], [1, 0, 0], [0, 0, -1]]], dimension = 2 }\nfit = { n = 64, tolerance = 1e-3 }\n",
        sets: &[],
    },
    ErrCase {
        name: "odd and too large fit resolutions",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\nfit = { n = 63 }\n\n[cells.b]\ntpms = \"p\"\nsymmetry = \"Oh\"\nfit = { n = 1024 }\n\n[cells.c]\nexpr = \"x\"\nsymmetry = \"D4\"\nfit = { n = \"atuo\" }\n",
        sets: &[],
    },
    ErrCase {
        name: "max_n not a power of two, too large, below 64 and with a fixed n",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\nfit = { n = \"auto\", max_n = 100 }\n\n[cells.b]\ntpms = \"p\"\nsymmetry = \"Oh\"\nfit = { n = \"auto\", max_n = 1024 }\n\n[cells.c]\nexpr = \"x\"\nsymmetry = \"D4\"\nfit = { n = \"auto\", max_n = 32 }\n\n[cells.d]\ntpms = \"p\"\nsymmetry = \"Oh\"\nfit = { n = 64, max_n = 128 }\n",
        sets: &[],
    },
    ErrCase {
        name: "fit and other keys without symmetry",
        manifest: "[cells.a]\ntpms = \"p\"\nfit = { n = 64 }\ninvert = true\n",
        sets: &[],
    },
    ErrCase {
        name: "blend of cells with different groups",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\n\n[cells.b]\ntpms = \"d\"\nsymmetry = \"Td\"\n\n[cells.m]\nblend = { cells = [\"a\", \"b\"], weights = [0.7, 0.3] }\n",
        sets: &[],
    },
    ErrCase {
        name: "blend of a missing cell and of a cell without symmetry",
        manifest: "[cells.prim]\ntpms = \"p\"\nsymmetry = \"Oh\"\n\n[cells.plain]\ntpms = \"p\"\n\n[cells.m]\nblend = { cells = [\"prin\", \"prim\"], weights = [1, 1] }\n\n[cells.n]\nminkowski = { op = \"difference\", cells = [\"prim\", \"plain\"] }\n",
        sets: &[],
    },
    ErrCase {
        name: "blend weights of the wrong length",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\n\n[cells.m]\nblend = { cells = [\"a\", \"a\"], weights = [0.7, 0.2, 0.1] }\n",
        sets: &[],
    },
    ErrCase {
        name: "minkowski with three cells",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\n\n[cells.m]\nminkowski = { op = \"sum\", cells = [\"a\", \"a\", \"a\"] }\n",
        sets: &[],
    },
    ErrCase {
        name: "blend cycle and a cell using itself",
        manifest: "[cells.a]\nblend = { cells = [\"b\"], weights = [1] }\n\n[cells.b]\nminkowski = { op = \"sum\", cells = [\"a\", \"a\"] }\n\n[cells.c]\nblend = { cells = [\"c\"], weights = [1] }\n",
        sets: &[],
    },
    ErrCase {
        name: "z in the expression of a 2D cell",
        manifest: "[cells.a]\nexpr = \"cos(tau*x) + 2e-3*cos(tau*z)\"\nsymmetry = \"d4\"\n",
        sets: &[],
    },
    ErrCase {
        name: "tpms with a 2D group",
        manifest: "[cells.a]\ntpms = \"gyroid\"\nsymmetry = \"D4\"\n",
        sets: &[],
    },
    ErrCase {
        name: "domain with over = element",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\n\n[outputs.o]\ncell = \"a\"\nover = \"element\"\ndomain = { min = [0, 0, 0], max = [1, 1, 1] }\ncell_size = 2\nsamples = 32\n",
        sets: &[],
    },
    ErrCase {
        name: "planar domain of a 3D cell, and corners of different lengths",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\n\n[outputs.o]\ncell = \"a\"\ndomain = { min = [0, 0], max = [1, 1] }\nsamples = 32\n\n[outputs.q]\ncell = \"a\"\ndomain = { min = [0, 0], max = [1, 1, 1] }\nsamples = 32\n",
        sets: &[],
    },
    ErrCase {
        name: "misspelled over, and over a cell without symmetry",
        manifest: "[cells.a]\ntpms = \"p\"\n\n[outputs.o]\ncell = \"a\"\nover = \"elemnt\"\nsamples = 32\n\n[outputs.q]\ncell = \"a\"\nover = \"element\"\nsamples = 32\n",
        sets: &[],
    },
    ErrCase {
        name: "optimize: a fraction out of reach, a misspelled key, too many iterations, a missing fraction and a loose tolerance",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\noptimize = { volume_fraction = 1.2, max_iteration = 5 }\n\n[cells.b]\ntpms = \"p\"\nsymmetry = \"Oh\"\noptimize = { max_iterations = 0, tolerance = 0.5 }\n\n[cells.c]\ntpms = \"p\"\noptimize = { volume_fraction = 0.3 }\n\n[cells.d]\ntpms = \"p\"\nsymmetry = \"Oh\"\noptimize = 0.3\n",
        sets: &[],
    },
    ErrCase {
        name: "optimize: a negative surface area and an infinite one",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\noptimize = { surface_area = -1.5 }\n\n[cells.b]\ntpms = \"p\"\nsymmetry = \"Oh\"\noptimize = { volume_fraction = 0.3, surface_area = inf }\n",
        sets: &[],
    },
    ErrCase {
        name: "keys that do not apply to a blend",
        manifest: "[cells.a]\ntpms = \"p\"\nsymmetry = \"Oh\"\n\n[cells.m]\nblend = { cells = [\"a\"], weights = [1] }\nsymmetry = \"Oh\"\nextend = \"none\"\n",
        sets: &[],
    },
];

#[test]
fn invalid_symmetric_manifests_render_exactly() {
    check_err_cases(SYM_ERR_CASES);
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
        optimize: None,
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
fit = { n = \"auto\", tolerance = 2e-4, max_n = 128 }
extend = \"none\"
symmetrize = true
normal_to_faces = true
offset = -0.1
invert = true
optimize = { volume_fraction = 0.25, max_iterations = 12 }

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
            n: FitResolution::Auto {
                tolerance: 2e-4,
                max_n: 128,
            },
            mirror: false,
            symmetrize: true,
            normal_to_faces: true,
            offset: -0.1,
            invert: true,
            optimize: Some(Optimize {
                volume_fraction: Some(0.25),
                surface_area: None,
                max_iterations: 12,
                tolerance: 1e-4,
            }),
        })
    );
    let n = |name: &str| manifest.cells[name].symmetric.as_ref().map(|s| s.n);
    assert_eq!(
        n("auto"),
        Some(FitResolution::Auto {
            tolerance: 1e-3,
            max_n: 256,
        })
    );
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
    let mut expected = symmetric(
        named("Oh"),
        FitResolution::Auto {
            tolerance: 1e-3,
            max_n: 256,
        },
    );
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
    let mut expected = symmetric(
        named("Td"),
        FitResolution::Auto {
            tolerance: 1e-3,
            max_n: 256,
        },
    );
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
