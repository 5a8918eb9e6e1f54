//! The files each output writes under `out_dir`, and the check that no two outputs write the
//! same one. Without it, `path = "b"` on output `c` beside an output `b` makes both report
//! `out/b.stl` while the file holds whichever was written last, a different one each build.
//!
//! Invariants: paths are compared after normalisation (`./a`, `a//b` and `a\b` name what
//! `a`, `a/b` and `a/b` name), so two spellings of one file collide; an output's SVG drawing
//! counts when the output is planar (a 2D cell's region, not thickened); `--set` values are
//! checked like the file's, since overrides are applied before validation.

use std::collections::BTreeMap;
use std::ops::Range;

use toml::de::{DeTable, DeValue};

use latticebuild_geom::mesh_io::Format;

use crate::diagnostics::Diagnostic;
use crate::manifest::model::{Cell, GroupSpec, Manifest};
use crate::manifest::source::Report;

/// `stem` with `.` and empty components dropped and `\` read as `/`: one spelling per file.
fn normalise(stem: &str) -> String {
    stem.split(['/', '\\'])
        .filter(|part| !part.is_empty() && *part != ".")
        .collect::<Vec<_>>()
        .join("/")
}

/// Whether `cell` draws planar regions (a D3 or D4 group), which also get an SVG.
fn is_planar(cells: &BTreeMap<String, Cell>, cell: &str) -> bool {
    let Some(symmetric) = cells.get(cell).and_then(|c| c.symmetric.as_ref()) else {
        return false;
    };
    match &symmetric.group {
        GroupSpec::Named(name) => matches!(name.as_str(), "D3" | "D4"),
        GroupSpec::Generators { dimension, .. } => *dimension == 2,
    }
}

/// Every output's files (formats, a region's drawing, the preview), relative to `out_dir` and
/// normalised, in order of output kind and name.
pub(crate) fn files_by_output(manifest: &Manifest) -> Vec<(&str, Vec<String>)> {
    let files = |stem: &str, formats: &[Format], planar: bool| -> Vec<String> {
        let stem = normalise(stem);
        // `formats = []` writes no file at all: no region drawing, no preview.
        let writes = !formats.is_empty();
        let svg = (planar && writes).then_some("svg");
        let png = (manifest.previews && writes).then_some("png");
        let extensions = formats.iter().map(|f| f.name()).chain(svg).chain(png);
        extensions.map(|ext| format!("{stem}.{ext}")).collect()
    };
    let plain = manifest.outputs.iter().map(|(name, o)| {
        let planar = o.planar_domain || (o.over_element && is_planar(&manifest.cells, &o.cell));
        (name.as_str(), files(&o.stem, &o.formats, planar))
    });
    let sdf = (manifest.program_outputs.iter())
        .map(|(name, o)| (name.as_str(), files(&o.stem, &o.formats, false)));
    let tiled = manifest.tiled_outputs.iter().map(|(name, o)| {
        let planar = o.thicken.is_none() && is_planar(&manifest.cells, &o.cell);
        (name.as_str(), files(&o.stem, &o.formats, planar))
    });
    plain.chain(sdf).chain(tiled).collect()
}

/// Where to point at output `name`: its `path` value if it has one, else its name.
fn span_of(outputs: Option<&DeTable<'_>>, name: &str) -> Range<usize> {
    let Some((key, value)) = outputs
        .into_iter()
        .flatten()
        .find(|(key, _)| key.get_ref().as_ref() == name)
    else {
        return 0..0;
    };
    let path = match value.get_ref() {
        DeValue::Table(table) => table.iter().find(|(k, _)| k.get_ref().as_ref() == "path"),
        _ => None,
    };
    match path {
        Some((_, path)) => path.span(),
        None => key.span(),
    }
}

/// Reports every file that two outputs would both write, at the later output's `path`.
pub(crate) fn check_collisions(
    manifest: &Manifest,
    outputs: Option<&DeTable<'_>>,
    report: &mut Report<'_, '_>,
) {
    let mut writer_of: BTreeMap<String, &str> = BTreeMap::new();
    for (name, files) in files_by_output(manifest) {
        for file in files {
            match writer_of.get(&file) {
                None => {
                    writer_of.insert(file, name);
                }
                Some(&first) => {
                    let out_dir = manifest.out_dir.display();
                    let diag = Diagnostic::error(format!(
                        "outputs `{first}` and `{name}` both write `{out_dir}/{file}`"
                    ))
                    .with_label("this output's file is already written by another output")
                    .with_help(format!(
                        "give `outputs.{name}` (or `outputs.{first}`) a `path` of its own"
                    ));
                    report.at(&span_of(outputs, name), diag);
                }
            }
        }
    }
}

/// Every file the manifest's outputs write, under `out_dir`: each format, a planar region's
/// drawing, and the output's report.
pub fn output_paths(manifest: &Manifest) -> Vec<std::path::PathBuf> {
    let mut paths = Vec::new();
    for (name, files) in files_by_output(manifest) {
        paths.extend(files.iter().map(|file| manifest.out_dir.join(file)));
        paths.push(manifest.out_dir.join(format!("{name}.report.json")));
    }
    paths
}
