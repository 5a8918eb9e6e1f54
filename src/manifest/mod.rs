//! The manifest: TOML text in, a validated [`Manifest`] out, or every error found.
//!
//! Two levels, as in cargo's schema or just's unresolved recipes:
//! 1. the raw level is toml's spanned tree ([`toml::de::DeTable`]), edited by `--set`
//!    overrides (`overrides.rs`) and never interpreted on its own;
//! 2. the validated level is [`Manifest`], built by `schema.rs`, in which every default is
//!    filled in, every reference resolved and every value in range.
//!
//! Invariants:
//! - Validation reports every error, not the first, in source order (the manifest first, then
//!   each `--set` argument in command-line order). TOML syntax errors stop the process before
//!   validation, since a recovered tree would only add errors that are not really there.
//! - Every diagnostic cites a place (file, line, column, the line's text), computed when it is
//!   made; overridden values are shown in their `--set` argument.
//! - [`load`] reads the one manifest file (a regular file of UTF-8 text) and checks that the
//!   files it names are regular files; nothing else here does IO, and nothing does geometry.
//! - No input makes this module panic.

use std::path::Path;

use toml::de::DeTable;

use crate::diagnostics::Diagnostic;

mod expression;
pub mod model;
mod overrides;
mod parameters;
mod resolved;
mod schema;
mod source;
#[cfg(test)]
mod tests;

pub use model::*;
pub use resolved::flatten;
pub use schema::output_files::output_paths;

use source::{Report, Sources};

/// Reads and validates the manifest at `path`, with `--set` overrides applied. The manifest
/// must be a regular file (`/dev/null` or a FIFO is refused before anything is made next to
/// it) of UTF-8 text (the first byte that is not is shown at its line and column).
pub fn load(path: &Path, overrides: &[String]) -> Result<Manifest, Vec<Diagnostic>> {
    load_edited(path, overrides, &[])
}

/// [`load`] with `--unset` keys removed too (before the `--set` overrides apply).
pub fn load_edited(
    path: &Path,
    overrides: &[String],
    unsets: &[String],
) -> Result<Manifest, Vec<Diagnostic>> {
    match crate::files::read_input(path) {
        Ok(bytes) => {
            let name = path.display().to_string();
            let text = String::from_utf8(bytes)
                .map_err(|e| vec![source::not_utf8(&name, e.as_bytes(), e.utf8_error())])?;
            let manifest = parse_edited(&text, path, overrides, unsets)?;
            check_input_files(&manifest, &text, path, overrides, unsets)?;
            Ok(manifest)
        }
        Err(err) => {
            let name = path.display().to_string();
            Err(vec![
                Diagnostic::error(format!("could not read `{name}`"))
                    .with_note(err.to_string())
                    .with_origin(name),
            ])
        }
    }
}

/// Every mesh or crystal file the manifest names must be a regular file: one error per missing file,
/// pointing at where it is named. (Its contents are read, and checked, by the build.)
fn check_input_files(
    manifest: &Manifest,
    text: &str,
    path: &Path,
    overrides: &[String],
    unsets: &[String],
) -> Result<(), Vec<Diagnostic>> {
    let sources = Sources::edited(path.display().to_string(), text, overrides, unsets);
    let mut report = Report::new(&sources);
    let named = manifest
        .cells
        .iter()
        .filter_map(|(name, c)| match &c.source {
            CellSource::Mesh(m) => Some((format!("cells.{name}.mesh"), &m.file, "mesh")),
            CellSource::Voxels(v) => Some((format!("cells.{name}.voxels"), &v.file, "voxel image")),
            CellSource::Points(f) => Some((format!("cells.{name}.points"), f, "point cloud")),
            CellSource::Crystal(c) => Some((format!("cells.{name}.crystal"), &c.file, "crystal")),
            _ => None,
        })
        .chain(manifest.outputs.iter().filter_map(|(name, o)| {
            o.within
                .as_ref()
                .map(|f| (format!("outputs.{name}.within"), f, "mesh"))
        }))
        .chain(manifest.program_outputs.iter().flat_map(|(name, o)| {
            o.files
                .iter()
                .map(move |f| (format!("outputs.{name}.sdf"), f, "mesh"))
        }))
        .chain(
            manifest
                .scaffolds
                .iter()
                .filter_map(|(name, s)| match &s.source {
                    ScaffoldSource::Mesh(f) => {
                        Some((format!("scaffolds.{name}.mesh"), f, "scaffold"))
                    }
                    ScaffoldSource::Grid(_) => None,
                }),
        );
    for (key, file, kind) in named {
        let Some(problem) = crate::files::input_problem(&file.path) else {
            continue;
        };
        let diag = Diagnostic::error(format!(
            "cannot read the {kind} `{}` of `{key}`",
            file.given
        ))
        .with_label(problem)
        .with_help(format!(
            "file names are relative to the manifest's directory; this one is `{}`",
            file.path.display()
        ));
        report.at(&file.span, diag);
    }
    if report.is_empty() {
        Ok(())
    } else {
        Err(report.finish())
    }
}

/// Validates manifest `text`, with `--set` overrides applied. `path` is shown in diagnostics
/// as given, and locates the manifest's directory (`root`) and its `out_dir`; it is not read.
/// How many TOML syntax errors a failed parse shows.
const SHOWN_SYNTAX_ERRORS: usize = 10;

pub fn parse(text: &str, path: &Path, overrides: &[String]) -> Result<Manifest, Vec<Diagnostic>> {
    parse_edited(text, path, overrides, &[])
}

/// [`parse`] with `--unset` keys removed too (before the `--set` overrides apply).
pub fn parse_edited(
    text: &str,
    path: &Path,
    overrides: &[String],
    unsets: &[String],
) -> Result<Manifest, Vec<Diagnostic>> {
    let sources = Sources::edited(path.display().to_string(), text, overrides, unsets);
    let mut report = Report::new(&sources);
    let overrides = overrides::parse_all(&mut report);
    let unsets = overrides::parse_unsets(&mut report);

    let (tree, syntax_errors) = DeTable::parse_recoverable(text);
    if !syntax_errors.is_empty() {
        // The parser's recovery can report an error per line of a broken file (18000 for one
        // unclosed quote); the first few are the useful ones, and locating each costs a scan.
        let mut errors: Vec<_> = syntax_errors
            .iter()
            .map(|e| (e.span().unwrap_or(0..0), e.message()))
            .collect();
        errors.sort_by_key(|(span, _)| span.start);
        let hidden = errors.len().saturating_sub(SHOWN_SYNTAX_ERRORS);
        errors.truncate(SHOWN_SYNTAX_ERRORS);
        let last = errors.len() - 1;
        for (i, (span, message)) in errors.into_iter().enumerate() {
            let mut diag =
                Diagnostic::error("invalid TOML").with_label(message.replace('\n', ", "));
            if i == last && hidden > 0 {
                diag = diag.with_note(format!(
                    "{hidden} more syntax errors follow; fix these first, later ones often \
                     come from them"
                ));
            }
            report.at(&span, diag);
        }
        return Err(report.finish());
    }

    let mut tree = tree.into_inner();
    for unset in &unsets {
        overrides::remove(&mut tree, unset, &mut report);
    }
    for ov in &overrides {
        overrides::apply(&mut tree, ov, &mut report);
    }
    match schema::validate(&tree, path, &mut report) {
        Some(manifest) if report.is_empty() => Ok(manifest),
        _ => Err(report.finish()),
    }
}
