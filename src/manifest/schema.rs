//! The manifest schema (v1): walks the raw spanned TOML tree and builds a [`Manifest`].
//!
//! Invariants:
//! - Validation reports every error, not the first: a bad value is reported and its output or
//!   cell skipped, and the walk goes on. A [`Manifest`] is built only when nothing was reported.
//! - Each error cites the most specific span: the value for a bad value, the key for an unknown
//!   key or a bad name, the table header for a missing key.
//! - No IO and no geometry: the only facts used beyond the tree are the TPMS library's names,
//!   the format names, the expression parser, and the closure of symmetry groups (for
//!   generators, and for comparing the groups of combined cells; see `symmetry.rs`).
//! - Every key the manifest accepts is listed once, in `keys.rs`: unknown-key detection,
//!   suggestions and `--set` typing ([`expects_string`]) all read those lists.

use std::collections::{BTreeMap, BTreeSet};
use std::ops::Range;
use std::path::{Path, PathBuf};

use latticebuild_geom::field::Solid;
use latticebuild_geom::mesh_io::{Encoding, Format};
use latticebuild_geom::{spelling, tpms};
use toml::Spanned;
use toml::de::{DeString, DeTable, DeValue};

use super::expression;
use super::model::{Cell, MAX_SAMPLES_PER_AXIS, Manifest, Name, Output, Sizing, voxel_samples};
use super::source::Report;
use crate::diagnostics::Diagnostic;
use crate::stages::measure::ReportLevel;

mod cache;
mod crystals;
mod islands;
#[cfg(test)]
mod json_schema;
mod keys;
mod meshes;
mod optimize;
pub(crate) mod output_files;
mod previews;
mod program;
mod scaffolds;
mod sizing;
mod symmetry;
mod voxels;

pub(crate) use keys::expects_string;
use keys::{BUILD_KEYS, DOMAIN_KEYS, OUTPUT_KEYS, TOP_KEYS};

type Key<'i> = Spanned<DeString<'i>>;

/// What [`Checker::written_files`] reads: the files an output writes, in the model's terms.
struct WrittenFiles {
    formats: Vec<Format>,
    encoding: Encoding,
    stem: String,
}
type Value<'i> = Spanned<DeValue<'i>>;

/// `[build]`'s out_dir, units, report level, and previews (on, size).
type BuildSection = (
    Option<String>,
    Option<String>,
    Option<ReportLevel>,
    Option<(bool, [u32; 2])>,
);

/// The length units `[build] units` accepts: what the model's numbers mean (reports echo it).
pub(crate) const UNITS: [&str; 5] = ["mm", "cm", "m", "um", "in"];
pub(crate) const SOLIDS: [&str; 4] = ["inside", "outside", "shell", "eccentric_shell"];
const AXES: [&str; 3] = ["x", "y", "z"];

/// The largest number of samples allowed along one axis (a guard against typos such as
/// `voxel = 1e-9`, which would otherwise ask for an absurd grid).
pub(crate) const MAX_SAMPLES: i64 = MAX_SAMPLES_PER_AXIS as i64;

/// A value's type with its article, for "found …" labels.
pub(crate) fn describe(value: &DeValue<'_>) -> &'static str {
    match value {
        DeValue::String(_) => "a string",
        DeValue::Integer(_) => "an integer",
        DeValue::Float(_) => "a float",
        DeValue::Boolean(_) => "a boolean",
        DeValue::Datetime(_) => "a date-time",
        DeValue::Array(_) => "an array",
        DeValue::Table(_) => "a table",
    }
}

/// Validates the tree. `None` when anything was reported (including before this call).
pub(crate) fn validate(
    root: &DeTable<'_>,
    manifest_path: &Path,
    report: &mut Report<'_, '_>,
) -> Option<Manifest> {
    let dir = match manifest_path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut checker = Checker {
        report,
        root: dir.clone(),
    };
    let mut out_dir = Some("out".to_string());
    let mut units = Some("mm".to_string());
    let mut report_level = Some(ReportLevel::default());
    let mut cache_max_size = Some(cache::DEFAULT_MAX_SIZE);
    let mut previews = Some((true, crate::stages::preview::DEFAULT_SIZE));
    let mut cells_table = None;
    let mut scaffolds_table = None;
    let mut outputs_table = None;
    for (key, value) in root {
        match key.get_ref().as_ref() {
            "build" => (out_dir, units, report_level, previews) = checker.build(value),
            "cache" => cache_max_size = checker.cache(value),
            "cells" => {
                cells_table = checker.table("cells", value, "define cells as `[cells.NAME]` tables")
            }
            "scaffolds" => {
                scaffolds_table = checker.table(
                    "scaffolds",
                    value,
                    "define scaffolds as `[scaffolds.NAME]` tables",
                )
            }
            "outputs" => {
                outputs_table = checker.table(
                    "outputs",
                    value,
                    "define outputs as `[outputs.NAME]` tables",
                )
            }
            name => {
                let message = format!("unknown top-level key `{name}`");
                // Top-level keys are all optional, so there is no missing key to hold back.
                let _ = checker.unknown_key(key, &TOP_KEYS, &message);
            }
        }
    }

    // References are checked against every defined cell name, valid or not, so that a cell
    // with a bad value does not also make each output using it report a dangling reference.
    let cell_names: BTreeSet<&str> = cells_table
        .iter()
        .flat_map(|t| t.keys())
        .map(|k| k.get_ref().as_ref())
        .collect();
    let mut drafts = Vec::new();
    for (key, value) in cells_table.into_iter().flatten() {
        drafts.extend(checker.cell(key, value, &cell_names));
    }
    let cells = checker.resolve(drafts);
    let scaffold_names: BTreeSet<&str> = scaffolds_table
        .iter()
        .flat_map(|t| t.keys())
        .map(|k| k.get_ref().as_ref())
        .collect();
    let mut scaffolds = BTreeMap::new();
    for (key, value) in scaffolds_table.into_iter().flatten() {
        if let Some(scaffold) = checker.scaffold(key, value) {
            scaffolds.insert(scaffold.name.text.clone(), scaffold);
        }
    }
    let tiling = scaffolds::TilingContext {
        scaffold_names: &scaffold_names,
        scaffolds: &scaffolds,
        cell_names: &cell_names,
        cells: &cells,
    };
    let mut outputs = BTreeMap::new();
    let mut program_outputs = BTreeMap::new();
    let mut tiled_outputs = BTreeMap::new();
    for (key, value) in outputs_table.into_iter().flatten() {
        if scaffolds::is_tiled_output(value) && !program::is_sdf_output(value) {
            if let Some(output) = checker.tiled_output(key, value, &tiling) {
                tiled_outputs.insert(output.name.text.clone(), output);
            }
        } else if program::is_sdf_output(value) {
            if let Some(output) = checker.sdf_output(key, value) {
                program_outputs.insert(output.name.text.clone(), output);
            }
        } else if let Some(output) = checker.output(key, value, &cell_names, &cells) {
            outputs.insert(output.name.text.clone(), output);
        }
    }

    if !checker.report.is_empty() {
        return None;
    }
    // `out`, not `./out`, for a manifest in the current directory: paths in reports read better.
    let out_dir = match manifest_path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent.join(out_dir?),
        _ => PathBuf::from(out_dir?),
    };
    let mut inputs =
        program::with_program_files(meshes::input_files(&cells, &outputs), &program_outputs);
    inputs.extend(scaffolds::scaffold_files(&scaffolds));
    inputs.sort();
    inputs.dedup();
    let manifest = Manifest {
        path: manifest_path.to_path_buf(),
        out_dir,
        units: units?,
        report: report_level?,
        previews: previews?.0,
        preview_size: previews?.1,
        root: dir,
        inputs,
        cells,
        outputs,
        program_outputs,
        scaffolds,
        tiled_outputs,
        parameters: super::parameters::of_outputs(root),
        cell_tables: super::parameters::of_tables(root, "cells"),
        scaffold_tables: super::parameters::of_tables(root, "scaffolds"),
        cache_max_size: cache_max_size?,
    };
    output_files::check_collisions(&manifest, outputs_table, checker.report);
    Some(manifest)
}

/// The fields of one table that the schema knows, by their schema name.
struct Fields<'t, 'i> {
    known: BTreeMap<&'static str, (&'t Key<'i>, &'t Value<'i>)>,
    /// Schema names that an unknown key was reported as a likely misspelling of. A missing
    /// key is not reported again when its misspelling already was: one error, one fix.
    misspelled: BTreeSet<&'static str>,
}

impl<'t, 'i> Fields<'t, 'i> {
    fn get(&self, name: &str) -> Option<&(&'t Key<'i>, &'t Value<'i>)> {
        self.known.get(name)
    }

    fn contains_key(&self, name: &str) -> bool {
        self.known.contains_key(name)
    }

    fn misspelled(&self, name: &str) -> bool {
        self.misspelled.contains(name)
    }
}

struct Checker<'r, 's, 'a> {
    report: &'r mut Report<'s, 'a>,
    /// The manifest's directory: relative file names resolve against it.
    root: PathBuf,
}

impl Checker<'_, '_, '_> {
    // ---- sections ------------------------------------------------------------------------

    /// `[build]`: the output directory, the length units, the report level and the previews
    /// (`None` each where invalid).
    fn build(&mut self, value: &Value<'_>) -> BuildSection {
        let Some(table) = self.table("build", value, "write it as a `[build]` table") else {
            return (None, None, None, None);
        };
        let fields = self.fields(table, &BUILD_KEYS, "in `[build]`");
        let units = match fields.get("units") {
            None => Some("mm".to_string()),
            Some((_, value)) => self.units(value),
        };
        let report = match fields.get("report") {
            None => Some(ReportLevel::default()),
            Some((_, value)) => self.report_level(value),
        };
        let previews = self.previews(&fields);
        (
            self.out_dir(fields.get("out_dir").map(|(_, v)| *v)),
            units,
            report,
            previews,
        )
    }

    /// `build.report`: one of [`ReportLevel::NAMES`].
    fn report_level(&mut self, value: &Value<'_>) -> Option<ReportLevel> {
        let name = self.string("build.report", value)?;
        if let Some(level) = ReportLevel::parse(name) {
            return Some(level);
        }
        self.error(
            value.span(),
            &format!("unknown report level `{name}` in `build.report`"),
            "unknown level",
            Some(
                "use `\"full\"` (wall thickness and pore size too) or `\"basic\"` (topology only)",
            ),
        );
        None
    }

    /// `build.units`: one of [`UNITS`].
    fn units(&mut self, value: &Value<'_>) -> Option<String> {
        let units = self.string("build.units", value)?;
        if UNITS.contains(&units) {
            return Some(units.to_string());
        }
        let help = format!(
            "use one of {}",
            UNITS.map(|u| format!("`\"{u}\"`")).join(", ")
        );
        self.error(
            value.span(),
            &format!("unknown length unit `{units}` in `build.units`"),
            "unknown unit",
            Some(&help),
        );
        None
    }

    fn out_dir(&mut self, value: Option<&Value<'_>>) -> Option<String> {
        let Some(value) = value else {
            return Some("out".to_string());
        };
        let dir = self.string("build.out_dir", value)?;
        if dir.is_empty() {
            self.error(
                value.span(),
                "`build.out_dir` is empty",
                "expected a directory",
                Some("omit `out_dir` to write into `out` next to the manifest"),
            );
            return None;
        }
        Some(dir.to_string())
    }

    fn output(
        &mut self,
        key: &Key<'_>,
        value: &Value<'_>,
        cells: &BTreeSet<&str>,
        valid_cells: &BTreeMap<String, Cell>,
    ) -> Option<Output> {
        let before = self.report.len();
        let name = key.get_ref().as_ref();
        self.check_name("output", key);
        let help = format!("define it as an `[outputs.{name}]` table");
        let table = self.table(&format!("outputs.{name}"), value, &help)?;
        let within = format!("in output `{name}`");
        let fields = self.fields(table, &OUTPUT_KEYS, &within);
        let header = value.span();
        let path = |k: &str| format!("outputs.{name}.{k}");
        self.sdf_only_keys(name, &fields);

        let cell = match fields.get("cell") {
            None => {
                let help = "add `cell = \"NAME\"` naming one of the `[cells.NAME]` tables, \
                            or `sdf = \"…\"` with an SDF program";
                self.missing(&fields, &header, "cell", &within, "missing `cell`", help);
                None
            }
            Some((_, v)) => self.cell_reference(&path("cell"), v, cells),
        };
        // `over = "element"`: the domain is the reference element's box, and one cell fills it.
        let over = fields
            .get("over")
            .map(|(_, v)| (*v, self.over(&path("over"), v)));
        let domain = match over {
            None => self.domain(name, &header, &within, &fields),
            // An invalid `over` may have meant the element: a missing `domain` is not reported.
            Some((_, None)) => fields
                .get("domain")
                .and_then(|_| self.domain(name, &header, &within, &fields)),
            Some((over, Some(_))) => {
                for (k, why) in [
                    ("domain", "the element is the reference cell"),
                    ("cell_size", "the element is one cell of size 1"),
                ] {
                    if let Some((key, _)) = fields.get(k) {
                        self.error(
                            key.span(),
                            &format!("`{}` does not apply with `over = \"element\"`", path(k)),
                            why,
                            Some(&format!("remove `{k}`, or remove `over` to fill a box")),
                        );
                    }
                }
                let cell = cell.as_deref();
                cell.and_then(|cell| self.element_box(name, over, cell, valid_cells))
                    .map(|(min, max)| Domain {
                        min,
                        max,
                        planar: false,
                    })
            }
        };
        let planar = domain.as_ref().is_some_and(|d| d.planar);
        if planar && let (Some(cell), Some((_, value))) = (cell.as_deref(), fields.get("domain")) {
            self.check_planar_cell(name, value, cell, valid_cells);
        }
        let over_element = over.is_some_and(|(_, element)| element == Some(true));
        let cell_size = match fields.get("cell_size") {
            _ if over_element => Some([1.0; 3]),
            None => Some([1.0; 3]),
            Some((_, v)) if planar && is_pair(v) => {
                self.pair(&path("cell_size"), v, 1.0, |s, k, v, expected| {
                    s.positive_number(k, v, expected)
                })
            }
            Some((_, v)) => self.scalar_or_vec3(
                &path("cell_size"),
                v,
                ("a number", "a number or an array of 3 numbers"),
                Self::positive_number,
            ),
        };
        let (solid, sizing) = match self.sized_solid(name, &fields, sizing::GradedFrom::Block) {
            Some(sized) => (sized.as_ref().map(|s| s.0), sized.map(|s| s.1)),
            None => (
                self.solid(name, &header, &within, &fields),
                Some(Sizing::Field),
            ),
        };
        let samples = self.samples(name, &header, &within, &fields, domain.as_ref(), planar);
        let written = self.written_files(name, &fields);
        let (within, skin) = self.within(name, &fields, over_element, planar);
        let islands = self.islands(name, &fields, planar);

        if self.report.len() > before {
            return None;
        }
        let domain = domain?;
        let (mut cell_size, mut samples) = (cell_size?, samples?);
        if domain.planar {
            // z has no extent in the plane: fixed values keep cache keys independent of it.
            cell_size[2] = 1.0;
            samples[2] = 2;
        }
        let written = written?;
        Some(Output {
            name: self.name(key),
            cell: cell?,
            over_element,
            planar_domain: domain.planar,
            domain_min: domain.min,
            domain_max: domain.max,
            cell_size,
            solid: solid?,
            sizing: sizing?,
            samples,
            formats: written.formats,
            encoding: written.encoding,
            stem: written.stem,
            within: within?,
            skin: skin?,
            islands: islands?,
        })
    }

    // ---- cell sources ----------------------------------------------------------------------

    fn tpms_name(&mut self, cell: &str, value: &Value<'_>) -> Option<String> {
        let key = format!("cells.{cell}.tpms");
        let text = self.string(&key, value)?;
        if let Some(surface) = tpms::lookup(text) {
            return Some(surface.name.to_string());
        }
        let help = match tpms::suggest(text) {
            Some(name) => format!("did you mean `{name}`?"),
            None => "the surface names are listed under \"TPMS library\" in docs/manifest.md"
                .to_string(),
        };
        self.error(
            value.span(),
            &format!("unknown TPMS surface `{text}` in `{key}`"),
            "not in the TPMS library",
            Some(&help),
        );
        None
    }

    fn expression(&mut self, cell: &str, value: &Value<'_>) -> Option<String> {
        let key = format!("cells.{cell}.expr");
        let text = self.string(&key, value)?;
        match expression::check_expression(text) {
            Ok(()) => Some(text.to_string()),
            Err(err) => {
                let sources = self.report.sources();
                let (span, diag) = expression::error_at(sources, &key, &value.span(), text, err);
                self.report.at(&span, diag);
                None
            }
        }
    }

    // ---- output keys -----------------------------------------------------------------------

    fn cell_reference(
        &mut self,
        key: &str,
        value: &Value<'_>,
        cells: &BTreeSet<&str>,
    ) -> Option<String> {
        let name = self.string(key, value)?;
        if cells.contains(name) {
            return Some(name.to_string());
        }
        let help = match spelling::closest(name, cells.iter().copied()) {
            Some(close) => format!("did you mean `{close}`?"),
            None => format!("define the cell in a `[cells.{name}]` table"),
        };
        self.error(
            value.span(),
            &format!("unknown cell `{name}` in `{key}`"),
            "no cell with this name",
            Some(&help),
        );
        None
    }

    fn domain(
        &mut self,
        output: &str,
        header: &Range<usize>,
        within: &str,
        output_fields: &Fields<'_, '_>,
    ) -> Option<Domain> {
        let example = "{ min = [0, 0, 0], max = [1, 1, 1] }";
        let Some((_, value)) = output_fields.get("domain") else {
            let help = format!("add `domain = {example}` (the box to fill, in model units)");
            self.missing(
                output_fields,
                header,
                "domain",
                within,
                "missing `domain`",
                &help,
            );
            return None;
        };
        let key = format!("outputs.{output}.domain");
        let table = self.table(&key, value, &format!("write it as `domain = {example}`"))?;
        let fields = self.fields(table, &DOMAIN_KEYS, &format!("in `{key}`"));
        let mut corner = |corner: &str| {
            let Some((_, v)) = fields.get(corner) else {
                let help = format!("add `{corner} = [x, y, z]`");
                let label = format!("missing `{corner}`");
                let within = format!("in `{key}`");
                self.missing(&fields, &value.span(), corner, &within, &label, &help);
                return None;
            };
            self.point_numbers(&format!("{key}.{corner}"), v)
        };
        let min = corner("min");
        let max = corner("max");
        let ((min, min_values), (max, max_values)) = (min?, max?);
        if min_values.len() != max_values.len() {
            let (min_len, max_len) = (min_values.len(), max_values.len());
            self.error(
                value.span(),
                &format!("`{key}.min` and `{key}.max` differ in length"),
                &format!("`min` has {min_len} values, `max` has {max_len}"),
                Some("give both corners as [x, y] for a planar domain, or both as [x, y, z]"),
            );
            return None;
        }
        let planar = min_values.len() == 2;
        let mut ok = true;
        for axis in 0..min_values.len() {
            // Both are finite here (non-finite numbers were rejected), so `>=` is `!(<)`.
            if min[axis] >= max[axis] {
                ok = false;
                let shown = self.raw(min_values[axis]);
                self.error(
                    max_values[axis].span(),
                    &format!("`{key}.max` must be greater than `min` on every axis"),
                    &format!("not greater than min {} `{shown}`", AXES[axis]),
                    None,
                );
            }
        }
        ok.then_some(Domain { min, max, planar })
    }

    fn solid(
        &mut self,
        output: &str,
        header: &Range<usize>,
        within: &str,
        fields: &Fields<'_, '_>,
    ) -> Option<Solid> {
        let path = |k: &str| format!("outputs.{output}.{k}");
        let kind = match fields.get("solid") {
            None => Some("inside"),
            Some((_, v)) => self.solid_kind(&path("solid"), v),
        };
        let offset_field = fields.get("offset").map(|(_, v)| *v);
        let thickness_field = fields.get("thickness").map(|(_, v)| *v);
        let defaulted = if fields.contains_key("solid") {
            ""
        } else {
            " (the default)"
        };
        let Some(kind) = kind else {
            // The solid is unknown, but its parameters can still be checked on their own.
            if let Some(v) = offset_field {
                self.finite_number(&path("offset"), v);
            }
            if let Some(v) = thickness_field {
                self.positive_number(&path("thickness"), v, "a number");
            }
            return None;
        };
        let shell = kind == "shell" || kind == "eccentric_shell";
        if !shell && let Some(v) = thickness_field {
            self.error(
                v.span(),
                &format!("`{}` applies only to shells", path("thickness")),
                &format!("`solid` is `{kind}`{defaulted}"),
                Some("remove `thickness`, or set `solid = \"shell\"` or `\"eccentric_shell\"`"),
            );
        }
        if kind == "shell"
            && let Some(v) = offset_field
        {
            self.error(
                v.span(),
                &format!("`{}` does not apply to `solid = \"shell\"`", path("offset")),
                "a shell is centred on the surface",
                Some("use `solid = \"eccentric_shell\"` for a shell around an offset level set"),
            );
        }
        let offset = match offset_field {
            Some(v) if kind != "shell" => self.finite_number(&path("offset"), v),
            _ => Some(0.0),
        };
        let thickness = match thickness_field {
            Some(v) if shell => self.positive_number(&path("thickness"), v, "a number"),
            Some(_) => None,
            None if shell => {
                let label = format!("`solid = \"{kind}\"` needs a `thickness`");
                let help = "add `thickness = 0.2` (the shell's width in field values)";
                self.missing(fields, header, "thickness", within, &label, help);
                None
            }
            None => Some(0.0),
        };
        let (offset, thickness) = (offset?, thickness?);
        Some(match kind {
            "inside" => Solid::Inside { offset },
            "outside" => Solid::Outside { offset },
            "shell" => Solid::Shell { thickness },
            _ => Solid::EccentricShell { offset, thickness },
        })
    }

    fn solid_kind(&mut self, key: &str, value: &Value<'_>) -> Option<&'static str> {
        let text = self.string(key, value)?;
        if let Some(kind) = SOLIDS.iter().find(|s| **s == text) {
            return Some(kind);
        }
        let help = match spelling::closest(text, SOLIDS) {
            Some(close) => format!("did you mean `{close}`?"),
            None => format!("expected one of {}", list(&SOLIDS)),
        };
        self.error(
            value.span(),
            &format!("unknown solid `{text}` in `{key}`"),
            "not a kind of solid",
            Some(&help),
        );
        None
    }

    fn samples(
        &mut self,
        output: &str,
        header: &Range<usize>,
        within: &str,
        fields: &Fields<'_, '_>,
        domain: Option<&Domain>,
        planar: bool,
    ) -> Option<[usize; 3]> {
        let path = |k: &str| format!("outputs.{output}.{k}");
        match (fields.get("samples"), fields.get("voxel")) {
            (None, None) if fields.misspelled("samples") || fields.misspelled("voxel") => None,
            (None, None) => {
                let help = "add `samples = 64` (grid points per axis) \
                            or `voxel = 0.05` (grid spacing in model units)";
                self.error(
                    header.clone(),
                    &format!("missing key `samples` or `voxel` {within}"),
                    "missing `samples` or `voxel`",
                    Some(help),
                );
                None
            }
            (Some((_, samples)), Some((_, voxel))) => {
                self.samples_and_voxel(samples, voxel, within, "grid points per axis");
                None
            }
            (Some((_, v)), None) if planar && is_pair(v) => {
                self.pair(&path("samples"), v, 2, Self::sample_count)
            }
            (Some((_, v)), None) => {
                let counts = self.scalar_or_vec3(
                    &path("samples"),
                    v,
                    ("an integer", "an integer or an array of 3 integers"),
                    Self::sample_count,
                )?;
                Some(counts)
            }
            (None, Some((_, v))) => {
                let key = path("voxel");
                let voxel = self.positive_number(&key, v, "a number")?;
                let (min, max) = domain.map(|d| (d.min, d.max))?;
                match voxel_samples(min, max, voxel) {
                    Ok(counts) => Some(counts),
                    Err(axis) => {
                        self.voxel_too_small(&key, v, axis);
                        None
                    }
                }
            }
        }
    }

    fn voxel_too_small(&mut self, key: &str, value: &Value<'_>, axis: usize) {
        self.error(
            value.span(),
            &format!("`{key}` is too small for the domain"),
            &format!("gives more than {MAX_SAMPLES} samples along {}", AXES[axis]),
            Some("samples per axis are ceil(extent / voxel) + 1"),
        );
    }

    /// `formats`, `ascii` and `path`: which files an output writes, and where.
    fn written_files(&mut self, output: &str, fields: &Fields<'_, '_>) -> Option<WrittenFiles> {
        let path = |k: &str| format!("outputs.{output}.{k}");
        let formats = self.formats(&path("formats"), fields.get("formats"));
        let encoding = match fields.get("ascii") {
            None => Some(Encoding::Binary),
            Some((_, v)) => self.boolean(&path("ascii"), v).map(|ascii| {
                if ascii {
                    Encoding::Ascii
                } else {
                    Encoding::Binary
                }
            }),
        };
        let stem = match fields.get("path") {
            None => Some(output.to_string()),
            Some((_, v)) => self.stem(&path("path"), v),
        };
        Some(WrittenFiles {
            formats: formats?,
            encoding: encoding?,
            stem: stem?,
        })
    }

    fn formats(
        &mut self,
        key: &str,
        field: Option<&(&Key<'_>, &Value<'_>)>,
    ) -> Option<Vec<Format>> {
        let Some((_, value)) = field else {
            return Some(vec![Format::Stl]);
        };
        let items = match value.get_ref() {
            DeValue::Array(items) => items,
            DeValue::String(text) => {
                let help = format!("write a list: `formats = [\"{text}\"]`");
                self.wrong_type(key, value, "an array of format names", Some(&help));
                return None;
            }
            _ => {
                self.wrong_type(key, value, "an array of format names", None);
                return None;
            }
        };
        // An empty list is allowed: the output is built and reported, and no file written
        // (an optimizer's loop reads the report only).
        let names = Format::ALL.map(Format::name);
        let mut formats = Some(Vec::new());
        for item in items.iter() {
            let format = self.string(key, item).and_then(|text| {
                let format = Format::from_name(text);
                if format.is_none() {
                    let help = match spelling::closest(text, names) {
                        Some(close) => format!("did you mean `{close}`?"),
                        None => format!("expected one of {}", list(&names)),
                    };
                    self.error(
                        item.span(),
                        &format!("unknown format `{text}` in `{key}`"),
                        "not a supported format",
                        Some(&help),
                    );
                }
                format
            });
            formats = formats.zip(format).map(|(mut all, f)| {
                all.push(f);
                all
            });
        }
        formats.map(|mut all| {
            all.sort_unstable();
            all.dedup();
            all
        })
    }

    fn stem(&mut self, key: &str, value: &Value<'_>) -> Option<String> {
        let text = self.string(key, value)?;
        let parts: Vec<&str> = text.split(['/', '\\']).collect();
        let problem = if text.is_empty() {
            Some(("`{key}` is empty", "expected a file name stem"))
        } else if Path::new(text).is_absolute()
            || text.starts_with(['/', '\\'])
            || text.get(1..2) == Some(":")
        {
            Some(("`{key}` must be relative to `out_dir`", "absolute path"))
        } else if parts.contains(&"..") {
            Some(("`{key}` must stay inside `out_dir`", "`..` is not allowed"))
        } else if matches!(parts.last(), Some(&"" | &".")) {
            Some((
                "`{key}` must end in a file name",
                "expected a file name stem",
            ))
        } else {
            None
        };
        if let Some((message, label)) = problem {
            let help =
                "give a path relative to `out_dir` without the extension, like `parts/gyroid`";
            self.error(
                value.span(),
                &message.replace("{key}", key),
                label,
                Some(help),
            );
            return None;
        }
        Some(text.to_string())
    }

    // ---- typed values ----------------------------------------------------------------------

    fn table<'t, 'i>(
        &mut self,
        key: &str,
        value: &'t Value<'i>,
        help: &str,
    ) -> Option<&'t DeTable<'i>> {
        match value.get_ref() {
            DeValue::Table(table) => Some(table),
            _ => {
                self.wrong_type(key, value, "a table", Some(help));
                None
            }
        }
    }

    fn string<'t>(&mut self, key: &str, value: &'t Value<'_>) -> Option<&'t str> {
        match value.get_ref() {
            DeValue::String(text) => Some(text.as_ref()),
            _ => {
                self.wrong_type(key, value, "a string", None);
                None
            }
        }
    }

    fn boolean(&mut self, key: &str, value: &Value<'_>) -> Option<bool> {
        match value.get_ref() {
            DeValue::Boolean(b) => Some(*b),
            _ => {
                self.wrong_type(key, value, "`true` or `false`", None);
                None
            }
        }
    }

    /// A finite number; integers are accepted where numbers are expected.
    fn number(&mut self, key: &str, value: &Value<'_>, expected: &str) -> Option<f64> {
        let number = match value.get_ref() {
            DeValue::Integer(int) => i64::from_str_radix(int.as_str(), int.radix())
                .map(|n| n as f64)
                .or_else(|_| int.as_str().parse::<f64>())
                .ok(),
            DeValue::Float(float) => float.as_str().parse::<f64>().ok(),
            _ => {
                self.wrong_type(key, value, expected, None);
                return None;
            }
        };
        match number {
            Some(n) if n.is_finite() => Some(n),
            _ => {
                let shown = self.raw(value);
                self.error(
                    value.span(),
                    &format!("`{key}` must be a finite number"),
                    &format!("found `{shown}`"),
                    None,
                );
                None
            }
        }
    }

    fn finite_number(&mut self, key: &str, value: &Value<'_>) -> Option<f64> {
        self.number(key, value, "a number")
    }

    fn positive_number(&mut self, key: &str, value: &Value<'_>, expected: &str) -> Option<f64> {
        let n = self.number(key, value, expected)?;
        if n > 0.0 {
            return Some(n);
        }
        let shown = self.raw(value);
        self.error(
            value.span(),
            &format!("`{key}` must be greater than 0"),
            &format!("found `{shown}`"),
            None,
        );
        None
    }

    fn sample_count(&mut self, key: &str, value: &Value<'_>, expected: &str) -> Option<usize> {
        let int = match value.get_ref() {
            DeValue::Integer(int) => int,
            _ => {
                self.wrong_type(key, value, expected, None);
                return None;
            }
        };
        let shown = self.raw(value);
        let count = i64::from_str_radix(int.as_str(), int.radix()).ok();
        let message = match count {
            Some(n) if n < 2 => format!("`{key}` must be at least 2 per axis"),
            Some(n) if n > MAX_SAMPLES => format!("`{key}` must be at most {MAX_SAMPLES} per axis"),
            Some(n) => return usize::try_from(n).ok(),
            None => format!("`{key}` is out of range"),
        };
        self.error(value.span(), &message, &format!("found `{shown}`"), None);
        None
    }

    /// An array of 2 (x, y) for a planar domain, completed with `z`.
    fn pair<T: Copy>(
        &mut self,
        key: &str,
        value: &Value<'_>,
        z: T,
        mut item: impl FnMut(&mut Self, &str, &Value<'_>, &str) -> Option<T>,
    ) -> Option<[T; 3]> {
        let DeValue::Array(items) = value.get_ref() else {
            return None;
        };
        let [x, y] = [&items[0], &items[1]].map(|v| item(self, key, v, "a number"));
        Some([x?, y?, z])
    }

    /// A scalar (used on every axis) or an array of exactly 3. `expected` is the description
    /// of one element and of the whole value, for type errors.
    fn scalar_or_vec3<T: Copy>(
        &mut self,
        key: &str,
        value: &Value<'_>,
        (element, whole): (&str, &str),
        mut item: impl FnMut(&mut Self, &str, &Value<'_>, &str) -> Option<T>,
    ) -> Option<[T; 3]> {
        let DeValue::Array(items) = value.get_ref() else {
            return item(self, key, value, whole).map(|v| [v; 3]);
        };
        if items.len() != 3 {
            self.wrong_length(key, value, items.len());
            return None;
        }
        let [x, y, z] = [&items[0], &items[1], &items[2]].map(|v| item(self, key, v, element));
        Some([x?, y?, z?])
    }

    /// A point of 2 (planar, z = 0) or 3 numbers, with each element's value for citing it.
    fn point_numbers<'t, 'i>(
        &mut self,
        key: &str,
        value: &'t Value<'i>,
    ) -> Option<([f64; 3], Vec<&'t Value<'i>>)> {
        let DeValue::Array(items) = value.get_ref() else {
            self.wrong_type(
                key,
                value,
                "an array of 3 numbers (or 2, in the plane)",
                None,
            );
            return None;
        };
        if items.len() != 2 && items.len() != 3 {
            self.error(
                value.span(),
                &format!("`{key}` must have 3 values (x, y, z), or 2 (x, y) in the plane"),
                &format!("found {}", items.len()),
                None,
            );
            return None;
        }
        let values: Vec<&Value<'i>> = items.iter().collect();
        let mut point = [0.0; 3];
        let mut ok = true;
        for (axis, v) in values.iter().enumerate() {
            match self.finite_number(key, v) {
                Some(x) => point[axis] = x,
                None => ok = false,
            }
        }
        ok.then_some((point, values))
    }

    // ---- names and keys --------------------------------------------------------------------

    /// Splits a table into the fields the schema knows, reporting every other key.
    fn fields<'t, 'i>(
        &mut self,
        table: &'t DeTable<'i>,
        allowed: &[&'static str],
        within: &str,
    ) -> Fields<'t, 'i> {
        let mut fields = Fields {
            known: BTreeMap::new(),
            misspelled: BTreeSet::new(),
        };
        for (key, value) in table {
            match allowed.iter().find(|name| **name == key.get_ref().as_ref()) {
                Some(name) => {
                    fields.known.insert(*name, (key, value));
                }
                None => {
                    let message = format!("unknown key `{}` {within}", key.get_ref());
                    if let Some(close) = self.unknown_key(key, allowed, &message) {
                        fields.misspelled.insert(close);
                    }
                }
            }
        }
        fields
    }

    /// Reports an unknown key; returns the allowed name it is likely a misspelling of.
    fn unknown_key(
        &mut self,
        key: &Key<'_>,
        allowed: &[&'static str],
        message: &str,
    ) -> Option<&'static str> {
        let name = key.get_ref().as_ref();
        let close = spelling::closest(name, allowed.iter().copied());
        let help = match close {
            Some(close) => format!("did you mean `{close}`?"),
            None => format!("expected one of {}", list(allowed)),
        };
        self.error(key.span(), message, "unknown key", Some(&help));
        close
    }

    fn check_name(&mut self, kind: &str, key: &Key<'_>) {
        let name = key.get_ref().as_ref();
        let valid = !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        if !valid {
            self.error(
                key.span(),
                &format!("invalid {kind} name `{name}`"),
                "names may contain only letters, digits, `_` and `-`",
                None,
            );
        }
    }

    fn name(&self, key: &Key<'_>) -> Name {
        let span = key.span();
        Name {
            text: key.get_ref().to_string(),
            span: self.report.sources().in_manifest(&span).then_some(span),
        }
    }

    // ---- reporting -------------------------------------------------------------------------

    fn error(&mut self, span: Range<usize>, message: &str, label: &str, help: Option<&str>) {
        let mut diag = Diagnostic::error(message).with_label(label);
        if let Some(help) = help {
            diag = diag.with_help(help);
        }
        self.report.at(&span, diag);
    }

    /// Reports `samples` and `voxel` given together, at the one written later (the one that
    /// conflicts with the other); `counts` says what `samples` counts there.
    fn samples_and_voxel(
        &mut self,
        samples: &Spanned<DeValue<'_>>,
        voxel: &Spanned<DeValue<'_>>,
        within: &str,
        counts: &str,
    ) {
        let (later, earlier) = if voxel.span().start > samples.span().start {
            (voxel, "samples")
        } else {
            (samples, "voxel")
        };
        self.error(
            later.span(),
            &format!("both `samples` and `voxel` given {within}"),
            &format!("`{earlier}` is already given"),
            Some(&format!(
                "give either `samples` ({counts}) or `voxel` (grid spacing)"
            )),
        );
    }

    /// Reports a missing required key, unless a misspelling of it was already reported.
    fn missing(
        &mut self,
        fields: &Fields<'_, '_>,
        at: &Range<usize>,
        key: &str,
        within: &str,
        label: &str,
        help: &str,
    ) {
        if fields.misspelled(key) {
            return;
        }
        let message = format!("missing key `{key}` {within}");
        self.error(at.clone(), &message, label, Some(help));
    }

    fn wrong_type(&mut self, key: &str, value: &Value<'_>, expected: &str, help: Option<&str>) {
        let found = describe(value.get_ref());
        let label = format!("expected {expected}, found {found}");
        self.error(
            value.span(),
            &format!("wrong type for `{key}`"),
            &label,
            help,
        );
    }

    fn wrong_length(&mut self, key: &str, value: &Value<'_>, len: usize) {
        self.error(
            value.span(),
            &format!("`{key}` must have 3 values (x, y, z)"),
            &format!("found {len}"),
            None,
        );
    }

    /// The source text of a value, for quoting it in a label.
    fn raw(&self, value: &Value<'_>) -> String {
        self.report
            .sources()
            .slice(&value.span())
            .unwrap_or_default()
            .to_string()
    }
}

/// An output's box: `planar` when its corners were given as `[x, y]` (then z is 0).
struct Domain {
    min: [f64; 3],
    max: [f64; 3],
    planar: bool,
}

/// Whether a value is an array of exactly two items.
fn is_pair(value: &Value<'_>) -> bool {
    matches!(value.get_ref(), DeValue::Array(items) if items.len() == 2)
}

/// Names as a list for help texts: `a`, `b`, `c`.
fn list(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ")
}
