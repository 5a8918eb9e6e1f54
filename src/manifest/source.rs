//! Where manifest values come from, and the collector of the diagnostics that cite them.
//!
//! A value is either written in the manifest file or given on the command line with `--set`
//! (and a key removed with `--unset`). Both kinds live in one tree, so spans must say which
//! text they index. They do it with one address space: bytes `0..=text.len()` are the
//! manifest, and each `--set` argument, then each `--unset` argument, gets the range after the
//! previous one (with a one-byte gap, so an empty argument still has an address of its own).
//! [`Sources::locate`] turns any span back into a file (`--set`, `--unset`), line and column.

use std::ops::Range;
use std::str::Utf8Error;

use crate::diagnostics::{Diagnostic, Location};

/// The diagnostic for a manifest that is not UTF-8: where its first invalid byte is (line,
/// and column in characters, as for any other error), with that line shown and the bytes
/// that do not decode written as `\xHH`.
pub(crate) fn not_utf8(name: &str, bytes: &[u8], err: Utf8Error) -> Diagnostic {
    let at = err.valid_up_to();
    let bad_len = err.error_len().unwrap_or(bytes.len() - at);
    let line_start = bytes[..at]
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    let line_end = bytes[at..]
        .iter()
        .position(|&b| b == b'\n')
        .map_or(bytes.len(), |i| at + i);
    // Up to `at` the bytes are valid UTF-8 (that is what `valid_up_to` means).
    let before = String::from_utf8_lossy(&bytes[line_start..at]);
    let mut source_line = before.to_string();
    for chunk in bytes[at..line_end].utf8_chunks() {
        source_line.push_str(chunk.valid());
        for b in chunk.invalid() {
            source_line.push_str(&format!("\\x{b:02X}"));
        }
    }
    let source_line = source_line.trim_end_matches('\r').to_string();
    let shown: Vec<String> = bytes[at..at + bad_len]
        .iter()
        .map(|b| format!("0x{b:02X}"))
        .collect();
    let label = match shown.len() {
        1 => format!("byte {} is not UTF-8", shown[0]),
        _ => format!("bytes {} are not UTF-8", shown.join(" ")),
    };
    let location = Location {
        file: name.to_string(),
        line: bytes[..at].iter().filter(|&&b| b == b'\n').count() + 1,
        column: before.chars().count() + 1,
        source_line,
        // One diagnostic per file, so the whole line is shown however long.
        first_column: 1,
        // Each byte is shown as four characters, `\xHH`.
        underline: 4 * bad_len,
    };
    Diagnostic::error(format!("`{name}` is not UTF-8 text"))
        .with_location(location)
        .with_label(label)
        .with_help("a manifest is TOML, which is UTF-8; save the file as UTF-8")
        .with_origin(name)
}

/// The file name shown for values that came from a `--set` argument.
pub(crate) const OVERRIDE_FILE: &str = "--set";
/// The file name shown for a `--unset` argument.
pub(crate) const UNSET_FILE: &str = "--unset";

/// The texts spans index: the manifest and each `--set` argument.
pub(crate) struct Sources<'a> {
    /// The manifest's display name, as given by the caller.
    pub(crate) name: String,
    pub(crate) text: &'a str,
    /// Each `--set` argument with the address of its first byte, then each `--unset`.
    overrides: Vec<(usize, &'a str)>,
    /// How many of `overrides` are `--set` arguments.
    sets: usize,
}

impl<'a> Sources<'a> {
    #[cfg(test)]
    pub(crate) fn new(name: String, text: &'a str, overrides: &'a [String]) -> Sources<'a> {
        Sources::edited(name, text, overrides, &[])
    }

    /// The manifest with `--set` arguments `sets` and `--unset` arguments `unsets`.
    pub(crate) fn edited(
        name: String,
        text: &'a str,
        sets: &'a [String],
        unsets: &'a [String],
    ) -> Sources<'a> {
        let mut base = text.len() + 1;
        let overrides = sets
            .iter()
            .chain(unsets)
            .map(|arg| {
                let entry = (base, arg.as_str());
                base += arg.len() + 1;
                entry
            })
            .collect();
        Sources {
            name,
            text,
            overrides,
            sets: sets.len(),
        }
    }

    /// The address of byte 0 of `--set` argument `index` and its text.
    pub(crate) fn override_arg(&self, index: usize) -> Option<(usize, &'a str)> {
        self.overrides[..self.sets].get(index).copied()
    }

    pub(crate) fn override_count(&self) -> usize {
        self.sets
    }

    /// The address of byte 0 of `--unset` argument `index` and its text.
    pub(crate) fn unset_arg(&self, index: usize) -> Option<(usize, &'a str)> {
        self.overrides[self.sets..].get(index).copied()
    }

    pub(crate) fn unset_count(&self) -> usize {
        self.overrides.len() - self.sets
    }

    /// Whether `span` is in the manifest file (rather than in a `--set` argument).
    pub(crate) fn in_manifest(&self, span: &Range<usize>) -> bool {
        span.start <= self.text.len()
    }

    /// The text holding a span, the file name to show for it, and the span within that text.
    fn resolve(&self, span: &Range<usize>) -> (&str, &'a str, Range<usize>) {
        if self.in_manifest(span) {
            return (self.name.as_str(), self.text, span.clone());
        }
        // The last override starting at or before the span holds it.
        let (index, (base, arg)) = self
            .overrides
            .iter()
            .enumerate()
            .rev()
            .find(|(_, (base, _))| *base <= span.start)
            .map_or((0, (0, "")), |(i, entry)| (i, *entry));
        (
            if index < self.sets {
                OVERRIDE_FILE
            } else {
                UNSET_FILE
            },
            arg,
            span.start - base..span.end.saturating_sub(base),
        )
    }

    /// The file, line and column of a span, with its line of text.
    pub(crate) fn locate(&self, span: &Range<usize>) -> Location {
        let (file, text, local) = self.resolve(span);
        Location::of_span(file, text, local)
    }

    /// The raw source text of a span, if it lies within one text.
    pub(crate) fn slice(&self, span: &Range<usize>) -> Option<&'a str> {
        let (_, text, local) = self.resolve(span);
        text.get(local)
    }
}

/// Diagnostics found so far, each kept with the address it cites so they can be shown in
/// source order (manifest first, then each `--set` in command-line order) whatever order the
/// validator happened to visit things in.
pub(crate) struct Report<'s, 'a> {
    sources: &'s Sources<'a>,
    found: Vec<(usize, Diagnostic)>,
}

impl<'s, 'a> Report<'s, 'a> {
    pub(crate) fn new(sources: &'s Sources<'a>) -> Report<'s, 'a> {
        Report {
            sources,
            found: Vec::new(),
        }
    }

    pub(crate) fn sources(&self) -> &'s Sources<'a> {
        self.sources
    }

    /// Records `diag` as found at `span`, filling in its location and origin.
    pub(crate) fn at(&mut self, span: &Range<usize>, diag: Diagnostic) {
        let diag = diag
            .with_location(self.sources.locate(span))
            .with_origin(self.sources.name.clone());
        self.found.push((span.start, diag));
    }

    pub(crate) fn len(&self) -> usize {
        self.found.len()
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.found.is_empty()
    }

    /// The diagnostics in source order; a stable sort keeps discovery order for equal starts.
    pub(crate) fn finish(mut self) -> Vec<Diagnostic> {
        self.found.sort_by_key(|(start, _)| *start);
        self.found.into_iter().map(|(_, d)| d).collect()
    }
}
