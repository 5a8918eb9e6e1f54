//! `--set dotted.key=value` and `--unset dotted.key`: command-line edits applied to the raw
//! tree before validation (every `--unset` first, then every `--set`, each in command-line
//! order, so `--unset outputs.g.voxel --set outputs.g.samples=64` switches how a grid is
//! sized).
//!
//! Invariants:
//! - An override is an edit of the raw TOML tree, so an overridden value is validated exactly
//!   like one written in the file; the only difference is its span, which points into the
//!   `--set` argument (see [`super::source`]), so errors about it show the argument.
//! - The value's type follows the schema: where the schema expects a string the raw text is the
//!   string (quotes optional), elsewhere the text is a TOML value. Text that is not a TOML value
//!   and does not look like an attempt at one (`samples=big`) becomes a string, so the validator
//!   reports it as a type error naming the key instead of a TOML syntax error.
//! - `--unset` removes a key that is in the tree (written in the file or added by nothing
//!   else); a key that is not there is an error at the argument, with the keys that are (or
//!   the closest one), so a typo never passes silently.

use std::borrow::Cow;
use std::ops::Range;

use toml::Spanned;
use toml::de::{DeTable, DeValue};

use super::schema;
use super::source::Report;
use crate::diagnostics::Diagnostic;

/// One parsed `--set` argument; spans are addresses in [`super::source::Sources`].
pub(crate) struct Override<'a> {
    /// The dotted key's segments, each with its span.
    pub(crate) path: Vec<(&'a str, Range<usize>)>,
    /// The text after `=`, trimmed.
    pub(crate) value: &'a str,
    pub(crate) value_span: Range<usize>,
}

/// Parses every `--set` argument, reporting each malformed one.
pub(crate) fn parse_all<'a>(report: &mut Report<'_, 'a>) -> Vec<Override<'a>> {
    let sources = report.sources();
    (0..sources.override_count())
        .filter_map(|index| sources.override_arg(index))
        .filter_map(|(base, arg)| parse_one(base, arg, report))
        .collect()
}

fn parse_one<'a>(base: usize, arg: &'a str, report: &mut Report<'_, 'a>) -> Option<Override<'a>> {
    let Some(eq) = arg.find('=') else {
        let message = if arg.trim().is_empty() {
            "empty `--set` argument".to_string()
        } else {
            format!("invalid `--set` argument `{arg}`")
        };
        report.at(
            &(base..base + arg.len()),
            Diagnostic::error(message)
                .with_label("expected `dotted.key=value`")
                .with_help("for example `--set outputs.g.offset=0.12`"),
        );
        return None;
    };
    let key = &arg[..eq];
    if key.trim().is_empty() {
        report.at(
            &(base..base + eq + 1),
            Diagnostic::error(format!("invalid `--set` argument `{arg}`"))
                .with_label("expected a key before `=`")
                .with_help("for example `--set outputs.g.offset=0.12`"),
        );
        return None;
    }
    let mut path = Vec::new();
    let mut offset = 0;
    for segment in key.split('.') {
        let trimmed = segment.trim();
        let start = offset + (segment.len() - segment.trim_start().len());
        if trimmed.is_empty() {
            let lead = key.len() - key.trim_start().len();
            let trail = key.trim_end().len();
            report.at(
                &(base + lead..base + trail),
                Diagnostic::error(format!("invalid key `{}` in `--set`", key.trim()))
                    .with_label("empty segment in dotted key")
                    .with_help("write keys like `outputs.g.offset`"),
            );
            return None;
        }
        path.push((trimmed, base + start..base + start + trimmed.len()));
        offset += segment.len() + 1;
    }
    let raw_value = &arg[eq + 1..];
    let value = raw_value.trim();
    let value_start = eq + 1 + (raw_value.len() - raw_value.trim_start().len());
    Some(Override {
        path,
        value,
        value_span: base + value_start..base + value_start + value.len(),
    })
}

/// One parsed `--unset` argument: the dotted key's segments, each with its span.
pub(crate) struct Unset<'a> {
    pub(crate) path: Vec<(&'a str, Range<usize>)>,
}

/// Parses every `--unset` argument, reporting each malformed one.
pub(crate) fn parse_unsets<'a>(report: &mut Report<'_, 'a>) -> Vec<Unset<'a>> {
    let sources = report.sources();
    let mut unsets = Vec::new();
    for (base, arg) in (0..sources.unset_count()).filter_map(|i| sources.unset_arg(i)) {
        let mut path = Vec::new();
        let mut offset = 0;
        for segment in arg.split('.') {
            let trimmed = segment.trim();
            let start = base + offset + (segment.len() - segment.trim_start().len());
            path.push((trimmed, start..start + trimmed.len()));
            offset += segment.len() + 1;
        }
        if path.iter().any(|(name, _)| name.is_empty()) || arg.contains('=') {
            let label = if arg.contains('=') {
                "`--unset` takes a key, not `key=value`"
            } else {
                "expected a dotted key"
            };
            report.at(
                &(base..base + arg.len()),
                Diagnostic::error(format!("invalid `--unset` argument `{arg}`"))
                    .with_label(label)
                    .with_help("for example `--unset outputs.g.voxel`"),
            );
            continue;
        }
        unsets.push(Unset { path });
    }
    unsets
}

/// Removes the key of `unset` from the tree, or reports that it is not there.
pub(crate) fn remove<'a>(root: &mut DeTable<'a>, unset: &Unset<'a>, report: &mut Report<'_, 'a>) {
    let names: Vec<&str> = unset.path.iter().map(|(name, _)| *name).collect();
    let Some(((last, last_span), parents)) = unset.path.split_last() else {
        return;
    };
    let mut table = root;
    for (depth, (segment, span)) in parents.iter().enumerate() {
        let parent = names[..=depth].join(".");
        if !table.contains_key(*segment) {
            not_there(table, segment, span, &parent, &names, report);
            return;
        }
        match table.get_mut(*segment).map(Spanned::get_mut) {
            Some(DeValue::Table(inner)) => table = inner,
            Some(other) => {
                let what = schema::describe(other);
                report.at(
                    span,
                    Diagnostic::error(format!("cannot unset `{}`", names.join(".")))
                        .with_label(format!("`{parent}` is {what}, not a table")),
                );
                return;
            }
            None => return,
        }
    }
    if table.remove(*last).is_none() {
        not_there(table, last, last_span, &names.join("."), &names, report);
    }
}

/// The error for a `--unset` key (or a table on its way) that the manifest does not have.
fn not_there(
    table: &DeTable<'_>,
    missing: &str,
    span: &Range<usize>,
    path: &str,
    names: &[&str],
    report: &mut Report<'_, '_>,
) {
    let present: Vec<&str> = table.keys().map(|k| k.get_ref().as_ref()).collect();
    let help = match latticebuild_geom::spelling::closest(missing, present.iter().copied()) {
        Some(close) => format!("did you mean `{close}`?"),
        None if present.is_empty() => "the table is empty".to_string(),
        None => format!(
            "the keys there are {}",
            present
                .iter()
                .map(|k| format!("`{k}`"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    report.at(
        span,
        Diagnostic::error(format!("cannot unset `{}`", names.join(".")))
            .with_label(format!("`{path}` is not in the manifest"))
            .with_help(help),
    );
}

/// Applies one override to the tree, creating tables on the way as needed.
pub(crate) fn apply<'a>(root: &mut DeTable<'a>, ov: &Override<'a>, report: &mut Report<'_, 'a>) {
    let names: Vec<&str> = ov.path.iter().map(|(name, _)| *name).collect();
    let Some(value) = make_value(ov, &names, report) else {
        return;
    };
    let Some(((last, last_span), parents)) = ov.path.split_last() else {
        return;
    };
    let mut table = root;
    for (depth, (segment, span)) in parents.iter().enumerate() {
        let slot = table
            .entry(Spanned::new(span.clone(), Cow::Borrowed(*segment)))
            .or_insert_with(|| Spanned::new(span.clone(), DeValue::Table(DeTable::new())));
        match slot.get_mut() {
            DeValue::Table(inner) => table = inner,
            other => {
                let parent = names[..=depth].join(".");
                report.at(
                    span,
                    Diagnostic::error(format!("cannot set `{}`", names.join("."))).with_label(
                        format!("`{parent}` is {}, not a table", schema::describe(other)),
                    ),
                );
                return;
            }
        }
    }
    // Replacing keeps the key's original span (a key written in the file stays pointed at
    // there) while the value's span now points into the `--set` argument.
    table.insert(Spanned::new(last_span.clone(), Cow::Borrowed(*last)), value);
}

fn make_value<'a>(
    ov: &Override<'a>,
    names: &[&str],
    report: &mut Report<'_, 'a>,
) -> Option<Spanned<DeValue<'a>>> {
    let raw_string = || {
        Some(Spanned::new(
            ov.value_span.clone(),
            DeValue::String(Cow::Borrowed(ov.value)),
        ))
    };
    let quoted = ov.value.starts_with(['"', '\'']);
    if schema::expects_string(names) && !quoted {
        return raw_string();
    }
    match DeValue::parse(ov.value) {
        Ok(value) => Some(shift(value, ov.value_span.start)),
        Err(_) if !ov.value.starts_with(['"', '\'', '[', '{']) => raw_string(),
        Err(err) => {
            let span = err.span().map_or(ov.value_span.clone(), |s| {
                let start = ov.value_span.start;
                start + s.start..start + s.end
            });
            report.at(
                &span,
                Diagnostic::error(format!(
                    "invalid TOML value for `{}` in `--set`",
                    names.join(".")
                ))
                .with_label(err.message().to_string()),
            );
            None
        }
    }
}

/// Moves every span in a value parsed from an override's text by `by` bytes, into the
/// override's address range.
fn shift(value: Spanned<DeValue<'_>>, by: usize) -> Spanned<DeValue<'_>> {
    let moved = |span: Range<usize>| span.start + by..span.end + by;
    let span = moved(value.span());
    let inner = match value.into_inner() {
        DeValue::Array(items) => DeValue::Array(items.into_iter().map(|v| shift(v, by)).collect()),
        DeValue::Table(table) => DeValue::Table(
            table
                .into_iter()
                .map(|(k, v)| (Spanned::new(moved(k.span()), k.into_inner()), shift(v, by)))
                .collect(),
        ),
        other => other,
    };
    Spanned::new(span, inner)
}
