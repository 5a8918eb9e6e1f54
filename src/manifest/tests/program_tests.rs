//! Tests of SDF outputs in manifests: `sdf`, `bounds`, `samples`/`voxel` — invalid manifests
//! with their exact diagnostics (each at the word of the program it concerns), then valid ones.

use super::*;
use crate::manifest::{ProgramResolution, voxel_samples};
use latticebuild_geom::contour::Contouring;

pub(super) const SDF_ERR_CASES: &[ErrCase] = &[
    ErrCase {
        name: "program errors at their words, cell keys beside `sdf`, samples, bounds, quotes, escapes",
        manifest: "[outputs.a]\nsdf = \"ball intersection\"\nsamples = \"1\"\n\n[outputs.b]\nsdf = \"ball scal 2 @more.txt\"\ncell = \"g\"\nsolid = \"shell\"\n\n[outputs.c]\nsdf = 'expression \"x + * y\"'\nbounds = { min = [0, 0], max = [1, -1, 1] }\n\n[outputs.d]\nsdf = \"tpms.gyroid scale 1/0 \\\"oops\"\nvoxel = 0.1\nsamples = 3\n\n[outputs.e]\nsdf = \"ball \\u0062all union extra\"\n",
        sets: &["outputs.f.sdf=tpms.p file part.step intersection"],
    },
    ErrCase {
        name: "contour methods (unknown, misspelt, beside a cell) and sigmoid blend arguments",
        manifest: "[cells.g]\ntpms = \"gyroid\"\n\n[outputs.a]\nsdf = \"ball\"\ncontour = \"tetrahedron\"\n\n[outputs.b]\nsdf = \"ball\"\ncontour = \"dual\"\n\n[outputs.c]\ncell = \"g\"\ndomain = { min = [0, 0, 0], max = [1, 1, 1] }\nsamples = 8\ncontour = \"tetrahedra\"\n\n[outputs.d]\nsdf = \"ball box sigmoid-blend 0,0,0 0 1\"\n\n[outputs.e]\nsdf = \"ball box sigmoid-blend 1,0,0 0 -1/2\"\n",
        sets: &[],
    },
];

#[test]
fn invalid_sdf_manifests_render_exactly() {
    check_err_cases(SDF_ERR_CASES);
}

#[test]
fn an_sdf_output_is_parsed_with_its_files_and_defaults() {
    let manifest = parse_ok(
        "[outputs.fill]\n\
         sdf = \"tpms.neovius scale 0.065 file meshes/part.STL intersection file meshes/part.STL union\"\n\
         formats = [\"ply\", \"stl\"]\n",
        &[],
    );
    assert!(manifest.outputs.is_empty());
    let out = &manifest.program_outputs["fill"];
    assert_eq!(
        out.program.canonical(),
        "tpms.neovius scale 0.065 file meshes/part.STL intersection file meshes/part.STL union"
    );
    // One file, named twice; its span is the path's first word in the string.
    assert_eq!(out.files.len(), 1);
    assert_eq!(out.files[0].path, std::path::Path::new("./meshes/part.STL"));
    let text = "[outputs.fill]\nsdf = \"tpms.neovius scale 0.065 file ";
    assert_eq!(out.files[0].span.start, text.len());
    assert_eq!(out.files[0].span.len(), "meshes/part.STL".len());
    assert_eq!(out.bounds, None);
    // Cesogen's default: 60³ samples, by marching cubes.
    assert_eq!(out.resolution, ProgramResolution::Counts([60; 3]));
    assert_eq!(out.contouring, Contouring::Cubes);
    let tets = parse_ok(
        "[outputs.t]\nsdf = \"ball\"\ncontour = \"tetrahedra\"\n",
        &[],
    );
    assert_eq!(tets.program_outputs["t"].contouring, Contouring::Tetrahedra);
    assert_eq!(
        manifest.inputs,
        [std::path::PathBuf::from("./meshes/part.STL")]
    );
}

#[test]
fn samples_are_totals_counts_or_a_voxel() {
    let with = |samples: &str| {
        let text = format!(
            "[outputs.s]\nsdf = \"ball scale 2\"\nbounds = {{ min = [-2, -2, -2], max = [2, 2, 3] }}\n{samples}\n"
        );
        parse_ok(&text, &[]).program_outputs["s"].resolution
    };
    assert_eq!(
        with("samples = \"130^3\""),
        ProgramResolution::Counts([130; 3])
    );
    // A number is a total, spread as evenly as possible without exceeding it (Cesogen's `-s`).
    assert_eq!(
        with("samples = 2000"),
        ProgramResolution::Counts([13, 12, 12])
    );
    assert_eq!(
        with("samples = \"100,50,20\""),
        ProgramResolution::Counts([100, 50, 20])
    );
    assert_eq!(
        with("samples = [7, 8, 9]"),
        ProgramResolution::Counts([7, 8, 9])
    );
    // With bounds, a voxel gives counts at load: extents 4, 4, 5 over 0.5.
    assert_eq!(with("voxel = 0.5"), ProgramResolution::Counts([9, 9, 11]));
    let auto = parse_ok("[outputs.s]\nsdf = \"ball\"\nvoxel = 0.25\n", &[]);
    assert_eq!(
        auto.program_outputs["s"].resolution,
        ProgramResolution::Voxel(0.25)
    );
    assert_eq!(voxel_samples([-1.0; 3], [1.0; 3], 0.25), Ok([9; 3]));
    assert_eq!(voxel_samples([0.0; 3], [1.0; 3], 1e-9), Err(0));
}

#[test]
fn samples_past_100000_per_axis_are_too_large_in_every_form() {
    for (samples, label) in [
        ("\"100001^3\"", "100001 samples along x, more than 100000"),
        (
            "1000030000300001",
            "100001 samples along x, more than 100000",
        ),
        ("\"3,200000,3\"", "200000 samples along y, more than 100000"),
        (
            "\"3,3,4294967297\"",
            "4294967297 samples along z, more than 100000",
        ),
    ] {
        let text = format!("[outputs.s]\nsdf = \"ball\"\nsamples = {samples}\n");
        let rendered = render_errors(&text, &[]);
        let expected = format!(
            "error: `outputs.s.samples` is too large\n --> lattice.toml:3:11\n  |\n\
             3 | samples = {samples}\n  |           {} {label}\n",
            "^".repeat(samples.chars().count())
        );
        assert!(rendered.starts_with(&expected), "{rendered}");
    }
}

#[test]
fn set_replaces_the_program_and_its_samples() {
    let manifest = parse_ok(
        "[outputs.b]\nsdf = \"ball scale 2\"\nsamples = 1000\n",
        &[
            "outputs.b.sdf=cylinder orient 1,0,0 scale 1/2",
            "outputs.b.samples=40^3",
        ],
    );
    let out = &manifest.program_outputs["b"];
    assert_eq!(
        out.program.canonical(),
        "cylinder orient 1.0,0.0,0.0 scale 0.5"
    );
    assert_eq!(out.resolution, ProgramResolution::Counts([40; 3]));
    let bounds = parse_ok(
        "[outputs.b]\nsdf = \"ball\"\nbounds = { min = [-1, -2, -3], max = [1, 2, 3.5] }\n",
        &[],
    );
    assert_eq!(
        bounds.program_outputs["b"].bounds,
        Some([[-1.0, -2.0, -3.0], [1.0, 2.0, 3.5]])
    );
}
