//! Manifest tests: a table of invalid manifests whose exact rendered diagnostics are files of
//! `tests/golden/err/` (one per case, named after it), and valid manifests with the
//! [`Manifest`] they must produce. One driver per table, so a change of API edits one function.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use latticebuild_geom::expr::ParseError;
use latticebuild_geom::field::Solid;
use latticebuild_geom::mesh_io::{Encoding, Format};

use super::source::{Report, Sources};
use super::*;
use crate::diagnostics::render;

fn strings(sets: &[&str]) -> Vec<String> {
    sets.iter().map(|s| s.to_string()).collect()
}

fn parse_ok(text: &str, sets: &[&str]) -> Manifest {
    match parse(text, Path::new("lattice.toml"), &strings(sets)) {
        Ok(manifest) => manifest,
        Err(diags) => panic!("expected a valid manifest, got:\n{}", render(&diags)),
    }
}

fn render_errors(text: &str, sets: &[&str]) -> String {
    match parse(text, Path::new("lattice.toml"), &strings(sets)) {
        Ok(manifest) => format!("unexpectedly valid: {manifest:?}"),
        Err(diags) => render(&diags),
    }
}

/// The manifest with every name's span removed, for comparing manifests whose text differs
/// only in layout.
fn without_spans(mut manifest: Manifest) -> Manifest {
    for cell in manifest.cells.values_mut() {
        cell.name.span = None;
    }
    for output in manifest.outputs.values_mut() {
        output.name.span = None;
    }
    manifest
}

// ---- invalid manifests ------------------------------------------------------------------------

/// An invalid manifest (and `--set` arguments); its exact rendered diagnostics are the file
/// [`golden_file`] names, which `cargo xtask golden --bless` rewrites.
pub(super) struct ErrCase {
    name: &'static str,
    manifest: &'static str,
    sets: &'static [&'static str],
}

/// `tests/golden/err/NAME.txt`, NAME the case's name in lower case with every run of other
/// characters than letters and digits one underscore.
fn golden_file(name: &str) -> PathBuf {
    let mut stem = String::new();
    for c in name.chars() {
        if c.is_ascii_alphanumeric() {
            stem.push(c.to_ascii_lowercase());
        } else if !stem.is_empty() && !stem.ends_with('_') {
            stem.push('_');
        }
    }
    let stem = stem.trim_end_matches('_');
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/golden/err/{stem}.txt"))
}

/// Renders every case and compares it with its golden file; with `LATTICEBUILD_BLESS` set
/// (`cargo xtask golden --bless`), writes the files instead.
pub(super) fn check_err_cases(cases: &[ErrCase]) {
    let bless = std::env::var_os("LATTICEBUILD_BLESS").is_some();
    let mut failures = Vec::new();
    for case in cases {
        let actual = render_errors(case.manifest, case.sets);
        let file = golden_file(case.name);
        if bless {
            std::fs::write(&file, &actual).expect("bless a golden file");
            continue;
        }
        let expected = std::fs::read_to_string(&file)
            .unwrap_or_else(|e| format!("(cannot read {}: {e})\n", file.display()));
        if actual != expected {
            failures.push(format!(
                "--- case `{}` ({})\n--- expected:\n{}--- actual:\n{}",
                case.name,
                file.display(),
                expected,
                actual
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} case(s) differ:\n{}\n(run `cargo xtask golden --bless` if the change is intended)",
        failures.len(),
        failures.join("\n")
    );
}

/// A small valid manifest that the `--set` cases start from (output `g` starts on line 4).
const VALID: &str = "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.g]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 32
";

const ERR_CASES: &[ErrCase] = &[
    ErrCase {
        name: "malformed toml",
        manifest: "[outputs.g]\nsamples = [64,\n",
        sets: &[],
    },
    ErrCase {
        name: "several toml syntax errors at once",
        manifest: "a = 1\nb = \n[x\n",
        sets: &[],
    },
    ErrCase {
        name: "unknown top-level table",
        manifest: "[cells.a]\ntpms = \"gyroid\"\n\n[ouputs.g]\ncell = \"a\"\n",
        sets: &[],
    },
    ErrCase {
        name: "unknown top-level key without a close name",
        manifest: "version = 1\n",
        sets: &[],
    },
    ErrCase {
        // The misspelling is the only error: `samples` is not also reported missing.
        name: "unknown key in an output, with suggestion",
        manifest: "\
# A gyroid block.
[cells.a]
tpms = \"gyroid\"

[outputs.g]
cell = \"a\"
domain = { min = [0, 0, 0], max = [10, 10, 10] }
cell_size = 5
solid = \"shell\"
thickness = 0.3
formats = [\"stl\", \"ply\"]
sampels = 64
",
        sets: &[],
    },
    ErrCase {
        name: "misspelled tpms name",
        manifest: "[cells.a]\ntpms = \"gyroyd\"\n",
        sets: &[],
    },
    ErrCase {
        name: "unknown tpms name without a close one",
        manifest: "[cells.a]\ntpms = \"banana\"\n",
        sets: &[],
    },
    ErrCase {
        name: "cell with neither and with both sources",
        manifest: "[cells.a]\n\n[cells.b]\ntpms = \"p\"\nexpr = \"x\"\n",
        sets: &[],
    },
    ErrCase {
        name: "missing referenced cell, with suggestion",
        manifest: "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.g]
cell = \"gyriod\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 32
",
        sets: &[],
    },
    ErrCase {
        name: "output missing every required key",
        manifest: "[outputs.g]\n",
        sets: &[],
    },
    ErrCase {
        name: "wrong type",
        manifest: "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.g]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = \"big\"
",
        sets: &[],
    },
    ErrCase {
        name: "float where an integer is expected",
        manifest: "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.g]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 64.5
",
        sets: &[],
    },
    ErrCase {
        name: "samples out of range",
        manifest: "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.g]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 1
",
        sets: &[],
    },
    ErrCase {
        name: "one axis of samples out of range",
        manifest: "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.g]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = [32, 200000, 32]
",
        sets: &[],
    },
    ErrCase {
        name: "negative thickness",
        manifest: "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.g]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 32
solid = \"shell\"
thickness = -1
",
        sets: &[],
    },
    ErrCase {
        name: "domain min not below max",
        manifest: "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.g]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 0, -1] }
samples = 32
",
        sets: &[],
    },
    ErrCase {
        name: "both samples and voxel",
        manifest: "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.g]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 32
voxel = 0.1
",
        sets: &[],
    },
    ErrCase {
        name: "voxel too small for the domain",
        manifest: "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.g]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
voxel = 1e-6
",
        sets: &[],
    },
    ErrCase {
        name: "thickness with an inside solid",
        manifest: "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.g]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 32
thickness = 0.2
",
        sets: &[],
    },
    ErrCase {
        name: "offset with a shell",
        manifest: "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.g]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 32
solid = \"shell\"
thickness = 0.2
offset = 0.1
",
        sets: &[],
    },
    ErrCase {
        name: "shell without thickness",
        manifest: "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.g]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 32
solid = \"shell\"
",
        sets: &[],
    },
    ErrCase {
        name: "unknown solid, formats, path and a non-finite offset",
        manifest: "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.g]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 32
solid = \"shel\"
offset = nan
formats = \"stl\"
path = \"/tmp/x\"
",
        sets: &[],
    },
    ErrCase {
        name: "array lengths, a bad format, bad cell sizes, bool type, name and path",
        manifest: "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.\"my part\"]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = [2, 3]
formats = [3]
cell_size = [1, 0, \"a\"]
ascii = 1
path = \"a/../../b\"
",
        sets: &[],
    },
    ErrCase {
        name: "wrong table types",
        manifest: "[[outputs]]\ncell = 1\n\n[build]\nout_dir = 3\nout = 1\n",
        sets: &[],
    },
    ErrCase {
        // Two bad outputs, written out of alphabetical order: errors come in source order.
        name: "multiple errors at once",
        manifest: "\
[cells.gyroid]
tpms = \"gyroyd\"

[outputs.b]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 1

[outputs.a]
cell = \"schwarz\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
voxel = 0
formats = [\"stl\", \"stp\"]
",
        sets: &[],
    },
    ErrCase {
        name: "malformed --set",
        manifest: VALID,
        sets: &["outputs.g.offset", "=3", "outputs..x=1"],
    },
    ErrCase {
        name: "type errors in --set values",
        manifest: VALID,
        sets: &["outputs.g.samples=big", "cells.gyroid.tpms=gyroyd"],
    },
    ErrCase {
        name: "--set values that are not TOML or not in a table",
        manifest: VALID,
        sets: &["outputs.g.formats=[\"ply\",", "outputs.g.cell.name=x"],
    },
    ErrCase {
        // The file's errors come first, then each `--set` argument's, in command-line order.
        name: "errors in the file and in --set together",
        manifest: "[cells.a]\ntpms = \"gyroyd\"\n",
        sets: &["cells.b.tpms=p", "cells.c.shape=1"],
    },
];

#[test]
fn invalid_manifests_render_exactly() {
    check_err_cases(ERR_CASES);
}

/// Two cases cannot share a golden file.
#[test]
fn every_invalid_case_has_its_own_golden_file() {
    let tables = [
        ERR_CASES,
        mesh_tests::MESH_ERR_CASES,
        program_tests::SDF_ERR_CASES,
        symmetry_tests::SYM_ERR_CASES,
        transform_tests::TRANSFORM_ERR_CASES,
    ];
    let mut files = std::collections::BTreeSet::new();
    for case in tables.iter().copied().flatten() {
        assert!(
            files.insert(golden_file(case.name)),
            "two cases named like `{}`",
            case.name
        );
    }
}

#[test]
fn unreadable_file_is_a_diagnostic_naming_the_path() {
    let dir = tempfile::tempdir().expect("temporary directory");
    let path = dir.path().join("missing.toml");
    let diags = load(&path, &[]).expect_err("a missing file cannot load");
    let shown = path.display().to_string();
    let text = render(&diags);
    assert!(
        text.starts_with(&format!("error: could not read `{shown}`\n  |\n  = note: ")),
        "{text}"
    );
    assert!(text.ends_with(&format!(
        "error: could not load `{shown}` due to 1 previous error\n"
    )));
}

// ---- valid manifests --------------------------------------------------------------------------

fn output(name: &str, span: Option<std::ops::Range<usize>>) -> Output {
    Output {
        name: Name {
            text: name.into(),
            span,
        },
        cell: "gyroid".into(),
        over_element: false,
        planar_domain: false,
        domain_min: [0.0; 3],
        domain_max: [1.0; 3],
        cell_size: [1.0; 3],
        solid: Solid::Inside { offset: 0.0 },
        sizing: Sizing::Field,
        samples: [32; 3],
        formats: vec![Format::Stl],
        encoding: Encoding::Binary,
        stem: name.into(),
        within: None,
        skin: None,
        islands: Default::default(),
    }
}

#[test]
fn empty_manifest_is_valid() {
    let manifest = parse_ok("", &[]);
    assert!(manifest.cells.is_empty() && manifest.outputs.is_empty() && manifest.inputs.is_empty());
    assert_eq!(manifest.root, PathBuf::from("."));
    assert_eq!(manifest.out_dir, PathBuf::from("out"));
}

#[test]
fn defaults_are_filled_in() {
    let text = "[cells.gyroid]\ntpms = \"gyroid\"\n\n[outputs.g]\ncell = \"gyroid\"\n\
                domain = { min = [0, 0, 0], max = [1, 1, 1] }\nsamples = 32\n";
    let manifest = match parse(text, Path::new("parts/lattice.toml"), &[]) {
        Ok(manifest) => manifest,
        Err(diags) => panic!("{}", render(&diags)),
    };
    let expected = Manifest {
        path: PathBuf::from("parts/lattice.toml"),
        root: PathBuf::from("parts"),
        out_dir: PathBuf::from("parts/out"),
        units: "mm".into(),
        report: crate::stages::measure::ReportLevel::Full,
        previews: true,
        preview_size: [1024, 768],
        cells: BTreeMap::from([(
            "gyroid".to_string(),
            Cell {
                name: Name {
                    text: "gyroid".into(),
                    span: Some(7..13),
                },
                source: CellSource::Tpms("gyroid".into()),
                symmetric: None,
            },
        )]),
        outputs: BTreeMap::from([("g".to_string(), output("g", Some(41..42)))]),
        program_outputs: BTreeMap::new(),
        scaffolds: BTreeMap::new(),
        tiled_outputs: BTreeMap::new(),
        inputs: Vec::new(),
        parameters: BTreeMap::from([(
            "g".to_string(),
            serde_json::json!({
                "cell": "gyroid",
                "domain": { "min": [0, 0, 0], "max": [1, 1, 1] },
                "samples": 32
            }),
        )]),
        cell_tables: BTreeMap::from([(
            "gyroid".to_string(),
            serde_json::json!({ "tpms": "gyroid" }),
        )]),
        scaffold_tables: BTreeMap::new(),
        cache_max_size: 4_000_000_000,
    };
    assert_eq!(manifest, expected);
}

#[test]
fn every_key_given_explicitly() {
    let text = r#"
[build]
out_dir = "meshes"

[cells.wavy]
expr = "cos(x) + cos(y) + cos(z)"

[outputs.part]
cell = "wavy"
domain = { min = [-1, -2.5, 0], max = [1, 2.5, 0.5] }
cell_size = [0.5, 1, 2]
solid = "eccentric_shell"
offset = -0.25
thickness = 0.3
samples = [2, 3, 100000]
formats = ["vtk", "stl", "vtk", "obj"]
ascii = true
path = "sub/part-1"
"#;
    let manifest = parse_ok(text, &[]);
    assert_eq!(manifest.out_dir, PathBuf::from("meshes"));
    assert_eq!(
        manifest.cells["wavy"].source,
        CellSource::Expr("cos(x) + cos(y) + cos(z)".into())
    );
    let out = &manifest.outputs["part"];
    assert_eq!(
        (out.domain_min, out.domain_max),
        ([-1.0, -2.5, 0.0], [1.0, 2.5, 0.5])
    );
    assert_eq!(out.cell_size, [0.5, 1.0, 2.0]);
    assert_eq!(
        out.solid,
        Solid::EccentricShell {
            offset: -0.25,
            thickness: 0.3
        }
    );
    assert_eq!(out.samples, [2, 3, 100000]);
    assert_eq!(out.formats, vec![Format::Stl, Format::Obj, Format::Vtk]);
    assert_eq!(out.encoding, Encoding::Ascii);
    assert_eq!(out.stem, "sub/part-1");
}

#[test]
fn scalar_cell_size_and_voxel_resolve_per_axis() {
    let text = "[cells.gyroid]\ntpms = \"gyroid\"\n[outputs.g]\ncell = \"gyroid\"\n\
                domain = { min = [0, 0, 0], max = [1.1, 2, 0.25] }\ncell_size = 0.5\nvoxel = 0.1\n\
                solid = \"outside\"\noffset = 0.2\n";
    let out = &parse_ok(text, &[]).outputs["g"];
    assert_eq!(out.cell_size, [0.5; 3]);
    // 1.1 / 0.1 is 11.000000000000002 in floating point: still 11 intervals, so 12 samples.
    // 0.25 / 0.1 = 2.5 rounds up to 3 intervals, so 4 samples.
    assert_eq!(out.samples, [12, 21, 4]);
    assert_eq!(out.solid, Solid::Outside { offset: 0.2 });
}

#[test]
fn tpms_aliases_store_the_canonical_name() {
    let text = "[cells.a]\ntpms = \"schwarz-p\"\n[cells.b]\ntpms = \"Gyroid\"\n[cells.c]\ntpms = 'diamond'\n";
    let manifest = parse_ok(text, &[]);
    let names: Vec<_> = manifest.cells.values().map(|c| c.source.clone()).collect();
    assert_eq!(
        names,
        ["p", "gyroid", "d"]
            .map(|n| CellSource::Tpms(n.to_string()))
            .to_vec()
    );
}

#[test]
fn reordering_tables_and_comments_gives_an_equal_manifest() {
    let a = "\
[cells.gyroid]
tpms = \"gyroid\"

[outputs.g]
cell = \"gyroid\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 32

[outputs.h]
cell = \"gyroid\"
domain.min = [0, 0, 0]
domain.max = [1, 1, 1]
samples = 32
";
    let b = "\
# Outputs first, keys shuffled, comments everywhere.
[outputs.h]   # the second output
samples = 32
cell = \"gyroid\"
[outputs.h.domain]
max = [1, 1, 1]
min = [0, 0, 0]

[outputs.g]
samples = 32  # per axis
domain = { max = [1, 1, 1], min = [0, 0, 0] }
cell = \"gyroid\"

[cells]
gyroid = { tpms = \"gyroid\" }
";
    let (a, b) = (parse_ok(a, &[]), parse_ok(b, &[]));
    // Names keep their spans for late errors; only the spans may differ.
    assert_ne!(a, b);
    assert_eq!(without_spans(a), without_spans(b));
}

#[test]
fn set_changes_only_the_overridden_field() {
    let base = parse_ok(VALID, &[]);
    let changed = parse_ok(VALID, &["outputs.g.offset=0.12"]);
    let mut expected = base.clone();
    if let Some(out) = expected.outputs.get_mut("g") {
        out.solid = Solid::Inside { offset: 0.12 };
    }
    if let Some(serde_json::Value::Object(table)) = expected.parameters.get_mut("g") {
        table.insert("offset".into(), serde_json::json!(0.12));
    }
    assert_eq!(changed, expected);
}

fn parse_unset(text: &str, sets: &[&str], unsets: &[&str]) -> Result<Manifest, String> {
    crate::manifest::parse_edited(
        text,
        Path::new("lattice.toml"),
        &strings(sets),
        &strings(unsets),
    )
    .map_err(|diags| render(&diags))
}

#[test]
fn unset_then_set_switches_samples_to_voxel() {
    let switched = parse_unset(VALID, &["outputs.g.voxel=0.05"], &["outputs.g.samples"])
        .unwrap_or_else(|e| panic!("{e}"));
    let by_voxel = parse_ok(&VALID.replace("samples = 32", "voxel = 0.05"), &[]);
    assert_eq!(without_spans(switched.clone()), without_spans(by_voxel));
    assert_eq!(switched.outputs["g"].samples, [21, 21, 21]);
    assert_eq!(switched.parameters["g"].get("samples"), None);
    // Without the unset, both are given: an error, as in a file.
    let both = render_errors(VALID, &["outputs.g.voxel=0.05"]);
    assert!(both.contains("voxel"), "{both}");
    // A whole table goes too.
    let gone = parse_unset(VALID, &[], &["outputs.g"]).unwrap_or_else(|e| panic!("{e}"));
    assert!(gone.outputs.is_empty());
}

#[test]
fn unset_of_a_key_that_is_not_there_is_an_error_at_the_argument() {
    let err = parse_unset(VALID, &[], &["outputs.g.sample"]).expect_err("no such key");
    assert!(
        err.contains("error: cannot unset `outputs.g.sample`"),
        "{err}"
    );
    assert!(err.contains("--> --unset:1:11"), "{err}");
    assert!(err.contains("did you mean `samples`?"), "{err}");
    let err = parse_unset(VALID, &[], &["outputs.h.voxel"]).expect_err("no such table");
    assert!(err.contains("`outputs.h` is not in the manifest"), "{err}");
    assert!(err.contains("--> --unset:1:9"), "{err}");
    let err = parse_unset(VALID, &[], &["outputs.g.domain.min.x"]).expect_err("not a table");
    assert!(
        err.contains("`outputs.g.domain.min` is an array, not a table"),
        "{err}"
    );
    let err = parse_unset(VALID, &[], &["outputs.g.samples=3"]).expect_err("a value");
    assert!(
        err.contains("`--unset` takes a key, not `key=value`"),
        "{err}"
    );
    // After a `--set` argument, the unset's columns are still its own.
    let err = parse_unset(VALID, &["outputs.g.offset=0.1"], &["x"]).expect_err("no key x");
    assert!(err.contains("--> --unset:1:1"), "{err}");
}

#[test]
fn set_replaces_values_and_creates_keys_and_tables() {
    let manifest = parse_ok(
        VALID,
        &[
            "outputs.g.formats=[\"ply\",\"stl\"]",
            "outputs.g.ascii=true",
            "outputs.g.domain.max=[2, 2, 2]",
            "cells.b.tpms=diamond",
            "cells.c.expr = cos(x) + sin(y)",
            "cells.gyroid.tpms=\"schwarz-d\"",
            "build.out_dir=build dir",
            "outputs.h.cell=b",
            "outputs.h.domain={ min = [0, 0, 0], max = [1, 1, 1] }",
            "outputs.h.voxel=0.5",
        ],
    );
    assert_eq!(manifest.out_dir, PathBuf::from("build dir"));
    assert_eq!(
        manifest.cells["gyroid"].source,
        CellSource::Tpms("d".into())
    );
    assert_eq!(manifest.cells["b"].source, CellSource::Tpms("d".into()));
    assert_eq!(
        manifest.cells["c"].source,
        CellSource::Expr("cos(x) + sin(y)".into())
    );
    // Names created by `--set` have no span in the manifest file.
    assert_eq!(
        manifest.cells["b"].name,
        Name {
            text: "b".into(),
            span: None
        }
    );
    let g = &manifest.outputs["g"];
    assert_eq!(g.formats, vec![Format::Stl, Format::Ply]);
    assert_eq!(g.encoding, Encoding::Ascii);
    assert_eq!(g.domain_max, [2.0; 3]);
    let h = &manifest.outputs["h"];
    assert_eq!((h.cell.as_str(), h.samples), ("b", [3; 3]));
}

#[test]
fn later_set_wins() {
    let manifest = parse_ok(
        VALID,
        &["outputs.g.samples=8", "outputs.g.samples=[4, 5, 6]"],
    );
    assert_eq!(manifest.outputs["g"].samples, [4, 5, 6]);
}

// ---- expressions ------------------------------------------------------------------------------

/// Renders the diagnostic for a parser error at `span` (in the decoded string `decoded`) in the
/// expression whose source text is at bytes `value` of the combined sources.
fn expression_error(
    manifest: &str,
    sets: &[&str],
    value: std::ops::Range<usize>,
    decoded: &str,
    span: std::ops::Range<usize>,
) -> String {
    let sets = strings(sets);
    let sources = Sources::new("lattice.toml".into(), manifest, &sets);
    let err = ParseError {
        span,
        message: "expected `)`".into(),
        help: Some("close the parenthesis".into()),
    };
    let (at, diag) = expression::error_at(&sources, "cells.a.expr", &value, decoded, err);
    let mut report = Report::new(&sources);
    report.at(&at, diag);
    render(&report.finish())
}

#[test]
fn expression_errors_map_into_plain_strings() {
    let expected = |location: &str, line: &str, marker: &str| {
        format!(
            "error: invalid expression in `cells.a.expr`\n --> {location}\n  |\n1 | {line}\n  | \
             {marker} expected `)`\n  |\n  = help: close the parenthesis\n\n\
             error: could not load `lattice.toml` due to 1 previous error\n"
        )
    };
    // A basic and a literal string without escapes: the parser's offset plus the quote.
    for text in ["expr = \"sin(x\"", "expr = 'sin(x'"] {
        let actual = expression_error(text, &[], 7..14, "sin(x", 3..4);
        assert_eq!(actual, expected("lattice.toml:1:12", text, "           ^"));
    }
    // An escape shifts offsets, so the whole string is underlined instead.
    let text = "expr = \"\\tsin(x\"";
    let actual = expression_error(text, &[], 7..16, "\tsin(x", 4..5);
    assert_eq!(
        actual,
        expected("lattice.toml:1:8", text, "       ^^^^^^^^^")
    );
    // A raw `--set` value: the offset within the argument's value.
    let set = "cells.a.expr=sin(x";
    let actual = expression_error("", &[set], 14..19, "sin(x", 3..4);
    assert_eq!(actual, expected("--set:1:17", set, "                ^"));
    // A parser span past the end of the text is clamped to the end of the string.
    let actual = expression_error("expr = 'sin(x'", &[], 7..14, "sin(x", 40..50);
    assert_eq!(
        actual,
        expected("lattice.toml:1:14", "expr = 'sin(x'", "             ^")
    );
}

#[test]
fn empty_expressions_are_rejected() {
    let diags = parse("[cells.a]\nexpr = \"  \"\n", Path::new("lattice.toml"), &[])
        .expect_err("an empty expression is invalid");
    let loc = diags
        .first()
        .and_then(|d| d.location.clone())
        .map(|l| (l.line, l.column));
    assert_eq!(loc, Some((2, 9)), "{}", render(&diags));
}

#[test]

fn expression_syntax_errors_point_inside_the_string() {
    let text = "[cells.a]\nexpr = \"sin(x\"\n";
    let diags = parse(text, Path::new("lattice.toml"), &[]).expect_err("`sin(x` is unbalanced");
    let loc = diags.first().and_then(|d| d.location.clone());
    let (line, column) = loc.map_or((0, 0), |l| (l.line, l.column));
    // Inside the string: from `s` (column 9) to the closing quote (column 14), which is
    // where an "unexpected end" error lands.
    assert!(
        line == 2 && (9..=14).contains(&column),
        "{}",
        render(&diags)
    );
}

// ---- robustness -------------------------------------------------------------------------------

/// Every prefix of a manifest using every key, and odd `--set` arguments, must give a manifest
/// or diagnostics, never a panic, and every diagnostic must have a location.
#[test]
fn no_input_panics() {
    let text = "\
[build]
out_dir = \"out\"
[cells.\"é x\"]
expr = \"cos(x) + 'y'\"
[cells.g]
tpms = 'Gyroid'
[outputs.o]
cell = \"g\"
domain = { min = [-1e308, 0, 0], max = [1e308, 0x10, 1.5] }
cell_size = [1, 2, inf]
solid = \"eccentric_shell\"
offset = -nan
thickness = 9223372036854775807
voxel = 1e-320
formats = [\"stl\", 1, [\"ply\"]]
ascii = 1979-05-27
path = \"C:x\"
";
    let sets = strings(&[
        "outputs.o.samples=99999999999999999999",
        "outputs.o.domain.min.x=1",
        "cells=1",
        "cells.g.tpms.x=1",
        "outputs.o.formats={",
        "é.=",
        "=",
        "",
        "outputs.o.cell=\"unterminated",
    ]);
    for end in (0..=text.len()).filter(|&i| text.is_char_boundary(i)) {
        for set_count in [0, sets.len()] {
            if let Err(diags) = parse(&text[..end], Path::new("m.toml"), &sets[..set_count]) {
                assert!(!diags.is_empty());
                assert!(
                    diags.iter().all(|d| d.location.is_some()),
                    "{}",
                    render(&diags)
                );
            }
        }
    }
}

/// The example in the user's reference must stay a valid manifest.
#[test]
fn reference_example_is_valid() {
    let doc = include_str!("../../docs/manifest.md");
    let example = doc
        .split("```toml\n")
        .nth(1)
        .and_then(|rest| rest.split("```").next())
        .unwrap_or_default();
    let manifest = parse_ok(example, &[]);
    assert_eq!(manifest.outputs.len(), 2);
    assert_eq!(manifest.outputs["wavy-core"].samples, [101; 3]);
    assert_eq!(manifest.outputs["block"].stem, "block");
}

mod mesh_tests;
mod symmetry_tests;
mod transform_tests;
mod voxel_tests;

mod program_tests;

mod crystal_cells {
    use super::*;

    #[test]
    fn crystal_and_ps_cells_validate_with_defaults() {
        let text = "[cells.c]\ncrystal = \"s/FAU.cif\"\nspecies = \"Si\"\n\
                    reconstruct = { max_scale = 4, include_images = true }\n\
                    [cells.p]\nps = { terms = [{ moment = 0.5, vector = [1, 1, 1] }, \
                    { moment = -1, scale = 2, vector = [0, 0, 0, 0.25] }] }\n";
        let manifest = parse(text, Path::new("m/lattice.toml"), &[]).expect("valid");
        let CellSource::Crystal(c) = &manifest.cells["c"].source else {
            panic!("not a crystal cell");
        };
        assert_eq!(c.file.path, Path::new("m/s/FAU.cif"));
        assert_eq!(c.species.as_deref(), Some("Si"));
        assert_eq!((c.tolerance, c.max_scale), (1e-9, 4));
        assert!(c.include_images && !c.optimize);
        let CellSource::Ps { terms, transform } = &manifest.cells["p"].source else {
            panic!("not a ps cell");
        };
        assert!(transform.is_none() && c.transform.is_none());
        assert_eq!(terms.len(), 2);
        assert_eq!(terms[0].vector, [1.0, 1.0, 1.0, 0.0]);
        assert_eq!((terms[1].scale, terms[1].vector[3]), (2.0, 0.25));
    }

    #[test]
    fn crystal_and_ps_errors_point_at_their_values() {
        let text = "[cells.c]\ncrystal = \"FAU.pdb\"\n\
                    [cells.d]\ncrystal = \"FAU.cif\"\nreconstruct = { max_scale = 0, tolerance = -1 }\n\
                    [cells.e]\ntpms = \"p\"\nspecies = \"Si\"\n\
                    [cells.f]\nps = { terms = [{ moment = 1, vector = [1, 0] }, { vector = [1, 0, 0] }] }\n";
        let errors = parse(text, Path::new("lattice.toml"), &[]).expect_err("invalid");
        let rendered: Vec<String> = errors
            .iter()
            .map(|d| render(std::slice::from_ref(d)))
            .collect();
        let all = rendered.join("\n");
        let expect = [
            (
                "`cells.c.crystal` is not a crystal file the readers know",
                "lattice.toml:2:11",
            ),
            (
                "`cells.d.reconstruct.max_scale` must be between 1 and 64",
                "lattice.toml:5:29",
            ),
            (
                "`cells.d.reconstruct.tolerance` must be greater than 0",
                "lattice.toml:5:44",
            ),
            (
                "`cells.e.species` applies only to crystal cells",
                "lattice.toml:8:1",
            ),
            (
                "`cells.f.ps.terms[0].vector` must have 4 values",
                "lattice.toml:10:40",
            ),
            (
                "missing key `moment` in `cells.f.ps.terms[1]`",
                "lattice.toml:10:50",
            ),
        ];
        for (message, at) in expect {
            let found = rendered
                .iter()
                .find(|r| r.contains(message))
                .unwrap_or_else(|| panic!("no `{message}` in\n{all}"));
            assert!(found.contains(at), "{message} not at {at}:\n{found}");
        }
        assert_eq!(errors.len(), expect.len(), "{all}");
    }
}

mod scaffolds_tests;

// ---- outputs writing the same file ------------------------------------------------------------

const TWO_OUTPUTS: &str = "\
[cells.g]
tpms = \"gyroid\"

[outputs.b]
cell = \"g\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
cell_size = 1
samples = 8

[outputs.c]
cell = \"g\"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
cell_size = 1
samples = 8
path = \"b\"
";

#[test]
fn two_outputs_writing_one_file_is_an_error_naming_both_and_the_file() {
    let text = render_errors(TWO_OUTPUTS, &[]);
    assert!(
        text.contains("outputs `b` and `c` both write `out/b.stl`"),
        "{text}"
    );
    assert!(
        text.contains("lattice.toml:15:8"),
        "points at c's path: {text}"
    );
}

#[test]
fn two_spellings_of_one_file_collide_and_different_formats_do_not() {
    let text = render_errors(TWO_OUTPUTS, &["outputs.c.path=./b"]);
    assert!(text.contains("both write `out/b.stl`"), "{text}");
    // `b.stl` and `b.ply` are different files, but both outputs' previews would be `b.png`.
    let text = render_errors(TWO_OUTPUTS, &["outputs.c.formats=[\"ply\"]"]);
    assert!(text.contains("both write `out/b.png`"), "{text}");
    parse_ok(
        TWO_OUTPUTS,
        &["outputs.c.formats=[\"ply\"]", "build.previews=false"],
    );
}

#[test]
fn a_set_override_cannot_make_outputs_collide() {
    let separate = TWO_OUTPUTS.replace("path = \"b\"\n", "");
    parse_ok(&separate, &[]);
    let text = render_errors(&separate, &["outputs.b.path=c"]);
    assert!(
        text.contains("outputs `b` and `c` both write `out/c.stl`"),
        "{text}"
    );
}

/// Found by `cargo xtask fuzz`: one unclosed quote made the parser's recovery report an error
/// per following line, each located by a scan of the file (18000 errors, over a second).
#[test]
fn a_broken_file_shows_its_first_ten_syntax_errors_and_counts_the_rest() {
    let text = format!(
        "[cells.u]\nexpr = \"x\nsymmetry = \"Oh\n{}",
        "symmetry = \" \"p\"\n".repeat(3000)
    );
    let rendered = render_errors(&text, &[]);
    assert_eq!(
        rendered.matches("error: invalid TOML").count(),
        10,
        "{rendered}"
    );
    let note = rendered
        .lines()
        .find(|l| l.contains("more syntax errors follow"))
        .expect("the rest are counted");
    let hidden: usize = note
        .split_whitespace()
        .find_map(|w| w.parse().ok())
        .expect("a count");
    assert!(hidden > 3000, "{note}");
    // The ten shown are the first in the file.
    assert!(rendered.contains("lattice.toml:2:"), "{rendered}");
}

#[test]
fn build_units_default_to_mm_and_must_be_known() {
    let base = "[cells.g]\ntpms = \"gyroid\"\n\n[outputs.g]\ncell = \"g\"\n\
                domain = { min = [0, 0, 0], max = [1, 1, 1] }\nsamples = 8\n";
    assert_eq!(parse_ok(base, &[]).units, "mm");
    let inch = format!("[build]\nunits = \"in\"\n\n{base}");
    assert_eq!(parse_ok(&inch, &[]).units, "in");
    let bad = format!("[build]\nunits = \"furlong\"\n\n{base}");
    let diags = parse(&bad, Path::new("lattice.toml"), &[]).expect_err("furlong is no unit");
    let text = render(&diags);
    assert!(text.contains("unknown length unit `furlong`"), "{text}");
}
