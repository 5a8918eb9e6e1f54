//! The schema of SDF outputs: `sdf = "…"`, a program in the Cesogen stack language
//! (`latticebuild_geom::stack_lang`), with `bounds`, `samples` or `voxel`, `contour`, and the
//! write keys.
//!
//! A child of `schema.rs` (it extends its `Checker`). Invariants:
//! - An output has `cell` or `sdf`, never both; the keys of cell outputs (`domain`, `solid`,
//!   `within`, …) are errors beside `sdf`, and `bounds` is one beside `cell`, each naming
//!   what to write instead.
//! - The program is parsed and checked here, with the geometry crate's parser: its errors are
//!   its exact messages, shown at the word of the string they concern (the whole string when
//!   the TOML spelling of the string differs from its value, e.g. with escapes).
//! - `file PATH` words are resolved against the manifest's directory, their extension checked
//!   at the path's word; whether the file exists is checked by `check_input_files` on load.
//! - No IO and no geometry: the bounds of the program are found when it is contoured.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::PathBuf;

use latticebuild_geom::contour::Contouring;
use latticebuild_geom::spelling;
use latticebuild_geom::stack_lang::{self as lang, Op, Origin, Program, ProgramError, Word};
use toml::de::DeValue;

use super::super::expression;
use super::super::model::{InputFile, ProgramOutput, ProgramResolution, voxel_samples};
use super::keys::{DOMAIN_KEYS, OUTPUT_KEYS};
use super::meshes::PROGRAM_MESH_FILES;
use super::{Checker, Fields, Key, Value};

/// Keys of cell outputs, each with why it does not apply to an SDF output and what to do.
const CELL_OUTPUT_KEYS: [(&str, &str, &str); 9] = [
    (
        "cell",
        "the output's solid is its `sdf` program",
        "give either `cell` or `sdf`",
    ),
    (
        "domain",
        "the box of an `sdf` output is `bounds`",
        "write `bounds = { min = [x, y, z], max = [x, y, z] }`, or leave it out for the \
         program's own bounds",
    ),
    ("over", "an `sdf` program is not a cell", "remove `over`"),
    (
        "cell_size",
        "an `sdf` program is not a repeated cell",
        "scale the solid in the program, e.g. `tpms.gyroid scale 2`",
    ),
    (
        "solid",
        "the program is the solid",
        "use `complement`, `offset R` or `shell T` in the program",
    ),
    (
        "offset",
        "the program is the solid",
        "add `offset R` to the program",
    ),
    (
        "thickness",
        "the program is the solid",
        "add `shell T` to the program",
    ),
    (
        "within",
        "an `sdf` program fills a part by intersection",
        "end the program with `file part.stl intersection`",
    ),
    (
        "skin",
        "an `sdf` program has no part to put a skin on",
        "union the program with a shell of the part: `… file part.stl shell T union`",
    ),
];

/// The values of `contour`.
const CONTOURINGS: [&str; 2] = ["cubes", "tetrahedra"];

/// Whether an output table holds an `sdf` program (and is checked by [`Checker::sdf_output`]).
pub(super) fn is_sdf_output(value: &Value<'_>) -> bool {
    matches!(value.get_ref(), DeValue::Table(t) if t.keys().any(|k| k.get_ref() == "sdf"))
}

/// `inputs` with the mesh files of every program, sorted, once each.
pub(super) fn with_program_files(
    mut inputs: Vec<PathBuf>,
    outputs: &BTreeMap<String, ProgramOutput>,
) -> Vec<PathBuf> {
    inputs.extend(
        outputs
            .values()
            .flat_map(|o| o.files.iter().map(|f| f.path.clone())),
    );
    inputs.sort();
    inputs.dedup();
    inputs
}

impl Checker<'_, '_, '_> {
    /// An output with `sdf = "…"`; `None` when anything was reported.
    pub(super) fn sdf_output(&mut self, key: &Key<'_>, value: &Value<'_>) -> Option<ProgramOutput> {
        let before = self.report.len();
        let name = key.get_ref().as_ref();
        self.check_name("output", key);
        let help = format!("define it as an `[outputs.{name}]` table");
        let table = self.table(&format!("outputs.{name}"), value, &help)?;
        let within = format!("in output `{name}`");
        let fields = self.fields(table, &OUTPUT_KEYS, &within);
        let path = |k: &str| format!("outputs.{name}.{k}");

        for (k, why, help) in CELL_OUTPUT_KEYS {
            if let Some((key, _)) = fields.get(k) {
                let message = format!("`{}` does not apply to an `sdf` output", path(k));
                self.error(key.span(), &message, why, Some(help));
            }
        }
        let program = fields
            .get("sdf")
            .and_then(|(_, v)| self.sdf_program(&path("sdf"), v));
        let bounds = match fields.get("bounds") {
            None => Some(None),
            Some((_, v)) => self.sdf_bounds(&path("bounds"), v).map(Some),
        };
        let resolution = self.sdf_resolution(name, &within, &fields, bounds.flatten());
        let contouring = match fields.get("contour") {
            None => Some(Contouring::Cubes),
            Some((_, v)) => self.contouring(&path("contour"), v),
        };
        let written = self.written_files(name, &fields);
        let islands = self.islands(name, &fields, false);
        if self.report.len() > before {
            return None;
        }
        let (program, files) = program?;
        let written = written?;
        Some(ProgramOutput {
            name: self.name(key),
            program,
            files,
            bounds: bounds?,
            resolution: resolution?,
            contouring: contouring?,
            formats: written.formats,
            encoding: written.encoding,
            stem: written.stem,
            islands: islands?,
        })
    }

    /// `contour = "cubes"` or `"tetrahedra"`.
    fn contouring(&mut self, key: &str, value: &Value<'_>) -> Option<Contouring> {
        let text = self.string(key, value)?;
        if let Some(method) = Contouring::from_name(text) {
            return Some(method);
        }
        let help = match spelling::closest(text, CONTOURINGS) {
            Some(close) => format!("did you mean `\"{close}\"`?"),
            None => "`\"cubes\"` (the default) is marching cubes; `\"tetrahedra\"` marching \
                     tetrahedra"
                .to_string(),
        };
        self.error(
            value.span(),
            &format!("unknown value `{text}` for `{key}`"),
            "expected \"cubes\" or \"tetrahedra\"",
            Some(&help),
        );
        None
    }

    /// `bounds` and `contour` of a cell output: errors, since cells fill a `domain` and are
    /// contoured by marching cubes only.
    pub(super) fn sdf_only_keys(&mut self, output: &str, fields: &Fields<'_, '_>) {
        if let Some((key, _)) = fields.get("contour") {
            self.error(
                key.span(),
                &format!("`outputs.{output}.contour` applies only to `sdf` outputs"),
                "cell outputs are contoured by marching cubes only",
                Some(
                    "remove `contour`, or write the solid as an `sdf` program (`sdf = \
                     \"tpms.gyroid offset 0.3\"`) to contour it with tetrahedra",
                ),
            );
        }
        if let Some((key, _)) = fields.get("bounds") {
            self.error(
                key.span(),
                &format!("`outputs.{output}.bounds` applies only to `sdf` outputs"),
                "a cell output fills its `domain`",
                Some("write the box as `domain = { min = [x, y, z], max = [x, y, z] }`"),
            );
        }
    }

    /// The program of `sdf = "…"` and the mesh files it reads.
    fn sdf_program(&mut self, key: &str, value: &Value<'_>) -> Option<(Program, Vec<InputFile>)> {
        let text = self.string(key, value)?;
        let sources = self.report.sources();
        // Where the string's characters start in the source, when it spells them unchanged.
        let start = expression::content_start(sources, &value.span(), text);
        let at = |range: Range<usize>| match start {
            Some(s) => s + range.start..s + range.end,
            None => value.span(),
        };
        // The character at byte `b` of the string (or its end).
        let char_at = |b: usize| {
            let len = text
                .get(b..)
                .and_then(|r| r.chars().next())
                .map_or(0, char::len_utf8);
            b..b + len
        };
        let words = match lang::split_words_spanned(text) {
            Ok(words) => words,
            Err(byte) => {
                let err = ProgramError::UnclosedQuote { file: None, byte };
                self.program_error(key, at(char_at(byte)), &err.to_string(), None);
                return None;
            }
        };
        let program_words: Vec<Word> = words
            .iter()
            .enumerate()
            .map(|(i, (w, _))| Word::arg(i + 1, w.as_str()))
            .collect();
        let word_span = |index: usize| words.get(index).map(|(_, r)| r.clone());
        let program = match Program::parse(&program_words) {
            Ok(program) => program,
            Err(err) => {
                let word = match err.at().map(|a| &a.origin) {
                    Some(Origin::Arg(n)) => words.get(n - 1),
                    _ => None,
                };
                let span = match (word, &err) {
                    (Some((w, range)), ProgramError::BadExpression { byte, .. }) => {
                        match formula_start(text, range, w) {
                            Some(start) => at(char_at(start + (*byte).min(w.len()))),
                            None => at(range.clone()),
                        }
                    }
                    (Some((_, range)), _) => at(range.clone()),
                    (None, _) => at(0..text.len()),
                };
                let help = match err {
                    ProgramError::UnexpandedInclude { .. } => Some(
                        "`@file` includes are read by `latticebuild sdf` only; write the words \
                         into the string",
                    ),
                    _ => None,
                };
                self.program_error(key, span, &err.to_string(), help);
                return None;
            }
        };
        let mut files: Vec<InputFile> = Vec::new();
        let mut ok = true;
        for node in program.tree().nodes() {
            let (Op::File(given), Origin::Arg(n)) = (&node.op, &node.at.origin) else {
                continue;
            };
            // The path is the word after `file`.
            let span = at(word_span(*n).unwrap_or(0..text.len()));
            let what = format!("`file {given}` in `{key}`");
            let Some(file) = self.input_file(&what, given, span, &PROGRAM_MESH_FILES) else {
                ok = false;
                continue;
            };
            if files.iter().all(|f| f.given != *given) {
                files.push(file);
            }
        }
        ok.then_some((program, files))
    }

    fn program_error(&mut self, key: &str, span: Range<usize>, label: &str, help: Option<&str>) {
        self.error(
            span,
            &format!("invalid SDF program in `{key}`"),
            label,
            help,
        );
    }

    /// `bounds = { min = [x, y, z], max = [x, y, z] }`, `min < max` on every axis.
    fn sdf_bounds(&mut self, key: &str, value: &Value<'_>) -> Option<[[f64; 3]; 2]> {
        let example = "{ min = [-1, -1, -1], max = [1, 1, 1] }";
        let table = self.table(key, value, &format!("write it as `bounds = {example}`"))?;
        let fields = self.fields(table, &DOMAIN_KEYS, &format!("in `{key}`"));
        let mut corner = |corner: &str| -> Option<([f64; 3], Span)> {
            let Some((_, v)) = fields.get(corner) else {
                let (label, help) = (
                    format!("missing `{corner}`"),
                    format!("add `{corner} = [x, y, z]`"),
                );
                let within = format!("in `{key}`");
                self.missing(&fields, &value.span(), corner, &within, &label, &help);
                return None;
            };
            let corner_key = format!("{key}.{corner}");
            let (point, values) = self.point_numbers(&corner_key, v)?;
            if values.len() != 3 {
                self.wrong_length(&corner_key, v, values.len());
                return None;
            }
            Some((point, values.iter().map(|v| v.span()).collect()))
        };
        let (min, max) = (corner("min"), corner("max"));
        let ((min, _), (max, max_spans)) = (min?, max?);
        let mut ok = true;
        for axis in 0..3 {
            if min[axis] >= max[axis] {
                ok = false;
                self.error(
                    max_spans[axis].clone(),
                    &format!("`{key}.max` must be greater than `min` on every axis"),
                    &format!("not greater than min {} = {}", super::AXES[axis], min[axis]),
                    None,
                );
            }
        }
        ok.then_some([min, max])
    }

    /// `samples` (a total like `"130^3"` or `2197000`, or `[nx, ny, nz]`) or `voxel`; 60³
    /// samples when neither is given, as Cesogen.
    fn sdf_resolution(
        &mut self,
        output: &str,
        within: &str,
        fields: &Fields<'_, '_>,
        bounds: Option<[[f64; 3]; 2]>,
    ) -> Option<ProgramResolution> {
        let path = |k: &str| format!("outputs.{output}.{k}");
        match (fields.get("samples"), fields.get("voxel")) {
            (None, None) => Some(ProgramResolution::Counts(lang::DEFAULT_SAMPLES)),
            (Some((_, samples)), Some((_, voxel))) => {
                self.samples_and_voxel(samples, voxel, within, "how many grid points");
                None
            }
            (Some((_, v)), None) => {
                let key = path("samples");
                let total = match v.get_ref() {
                    DeValue::String(text) => text.to_string(),
                    // A number is a total, spread over the axes as Cesogen spreads `-s N`.
                    DeValue::Integer(_) => self.raw(v).replace('_', ""),
                    DeValue::Array(_) => {
                        let counts = self.scalar_or_vec3(
                            &key,
                            v,
                            ("an integer", "an array of 3 integers"),
                            Self::sample_count,
                        )?;
                        return Some(ProgramResolution::Counts(counts));
                    }
                    _ => {
                        let help = "write a total like `samples = \"130^3\"` or counts per axis \
                                    like `samples = [100, 50, 50]`";
                        self.wrong_type(&key, v, "a string, an integer or an array", Some(help));
                        return None;
                    }
                };
                match lang::parse_samples(&total) {
                    Ok(counts) => Some(ProgramResolution::Counts(counts)),
                    Err(lang::OptionError::TooManySamples { count, axis, .. }) => {
                        self.error(
                            v.span(),
                            &format!("`{key}` is too large"),
                            &format!(
                                "{count} samples along {}, more than {MAX_PER_AXIS}",
                                ["x", "y", "z"][axis]
                            ),
                            None,
                        );
                        None
                    }
                    Err(err) => {
                        let help = "write a total like `\"130^3\"` (spread evenly over the \
                                    axes) or counts per axis like `[100, 50, 50]`";
                        self.error(
                            v.span(),
                            &format!("invalid `{key}`"),
                            &err.to_string(),
                            Some(help),
                        );
                        None
                    }
                }
            }
            (None, Some((_, v))) => {
                let key = path("voxel");
                let voxel = self.positive_number(&key, v, "a number")?;
                let Some([min, max]) = bounds else {
                    return Some(ProgramResolution::Voxel(voxel));
                };
                match voxel_samples(min, max, voxel) {
                    Ok(counts) => Some(ProgramResolution::Counts(counts)),
                    Err(axis) => {
                        self.voxel_too_small(&key, v, axis);
                        None
                    }
                }
            }
        }
    }
}

type Span = Vec<Range<usize>>;

/// Where the characters of word `w` start in `text`, when its span spells them as is or in
/// one pair of quotes; then an expression's error can point at its character.
fn formula_start(text: &str, range: &Range<usize>, w: &str) -> Option<usize> {
    let raw = text.get(range.clone())?;
    if raw == w {
        return Some(range.start);
    }
    let quoted = ['"', '\''].iter().any(|&q| {
        raw.len() >= 2
            && raw.starts_with(q)
            && raw.ends_with(q)
            && raw.get(1..raw.len() - 1) == Some(w)
    });
    quoted.then_some(range.start + 1)
}

const MAX_PER_AXIS: usize = super::super::model::MAX_SAMPLES_PER_AXIS;
// `-s` text is checked by the geometry crate against its own limit: the two must agree.
const _: () = assert!(MAX_PER_AXIS == lang::MAX_SAMPLES_PER_AXIS);
