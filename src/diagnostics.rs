//! User-facing diagnostics: a message, where it happened, and what would fix it.
//!
//! Invariants:
//! - A [`Diagnostic`] carries everything needed to show it: its location (file name, line,
//!   column, the text of the line) is computed when it is created, so [`render`] needs no
//!   source text and no file system.
//! - Rendering is plain text, deterministic and free of colour, in the style of rustc and cargo:
//!   messages are lower case, name things in backticks and end without a period. On a
//!   terminal, [`color`] lays rustc's colours over the rendered text.
//! - Nothing a file contains reaches the terminal raw: control characters (NUL, escape, a
//!   lone carriage return…) are shown as their Unicode pictures (`␀`, `␛`, `␍`), as rustc
//!   shows them, and invisible formatting characters (bidirectional overrides, zero-width
//!   spaces, C1 controls) as `\u{…}`; tabs as four spaces. Carets stay under what they mark.
//! - A diagnostic's size does not grow with its line: a line longer than [`SHOWN_CHARS`]
//!   characters is kept and shown as a window around the span, cut ends marked `…`. (A
//!   mangled 60 kB one-line manifest has thousands of TOML errors; each with the whole line
//!   took gigabytes to render.)
//!
//! The renderer is hand-rolled rather than taken from `annotate-snippets`: we only ever show one
//! line with one underline, and owning the ~80 lines keeps the exact text stable (it is under
//! test) whatever a dependency's next release decides about spacing or colour.

use std::fmt::Write as _;

pub mod color;

/// One problem found in user input.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    /// What is wrong, e.g. ``unknown key `sampels` in output `g` ``.
    pub message: String,
    /// Where it is wrong; `None` for problems that have no place in a file (an unreadable file).
    pub location: Option<Location>,
    /// A short text printed after the underline, e.g. `unknown key`.
    pub label: Option<String>,
    /// What would fix it, e.g. ``did you mean `samples`?``.
    pub help: Option<String>,
    /// Further facts worth knowing, each printed as `= note: …`.
    pub notes: Vec<String>,
    /// The file that was being processed (the manifest), named in the closing summary line of
    /// [`render`]. Distinct from `location.file`, which may be `--set` for an override.
    pub origin: Option<String>,
}

/// Longest line shown whole, in characters.
pub const SHOWN_CHARS: usize = 120;
/// Characters of a longer line shown before the span.
const CONTEXT_BEFORE: usize = 40;

/// A place in a source text, resolved to what a reader needs to see it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// The file's display name, as the user gave it (or `--set` for a command-line override).
    pub file: String,
    /// 1-based line number.
    pub line: usize,
    /// 1-based column, counted in characters (not bytes).
    pub column: usize,
    /// The text of the line, without its line break; of a line longer than [`SHOWN_CHARS`],
    /// that many characters around the span, with `…` for each end cut off.
    pub source_line: String,
    /// The column of the line that the first character of `source_line` stands for: 1, or
    /// for a line cut at its start, the column of the last character left out (its `…`).
    pub first_column: usize,
    /// How many characters to underline, starting at `column` (at least 1; a window's
    /// underline stops at its end).
    pub underline: usize,
}

impl Diagnostic {
    /// A diagnostic with only a message.
    pub fn error(message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            message: message.into(),
            location: None,
            label: None,
            help: None,
            notes: Vec::new(),
            origin: None,
        }
    }

    pub fn with_location(mut self, location: Location) -> Diagnostic {
        self.location = Some(location);
        self
    }

    pub fn with_label(mut self, label: impl Into<String>) -> Diagnostic {
        self.label = Some(label.into());
        self
    }

    pub fn with_help(mut self, help: impl Into<String>) -> Diagnostic {
        self.help = Some(help.into());
        self
    }

    pub fn with_note(mut self, note: impl Into<String>) -> Diagnostic {
        self.notes.push(note.into());
        self
    }

    pub fn with_origin(mut self, origin: impl Into<String>) -> Diagnostic {
        self.origin = Some(origin.into());
        self
    }
}

impl Location {
    /// The location of the byte range `span` in `text`, shown as file `file`. Spans past the
    /// end of the text or inside a character are clamped, so any span gives a location.
    pub fn of_span(file: &str, text: &str, span: std::ops::Range<usize>) -> Location {
        let start = floor_char_boundary(text, span.start.min(text.len()));
        let end = floor_char_boundary(text, span.end.clamp(start, text.len()));
        let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
        let line_end = text[start..].find('\n').map_or(text.len(), |i| start + i);
        let source_line = text[line_start..line_end].trim_end_matches('\r');
        let line = text[..start].matches('\n').count() + 1;
        let column = text[line_start..start].chars().count() + 1;
        // A span running onto later lines is underlined to the end of its first line only.
        let underline_end = end.min(line_start + source_line.len()).max(start);
        let underline = text[start..underline_end].chars().count().max(1);
        if source_line.chars().nth(SHOWN_CHARS).is_none() {
            return Location {
                file: file.to_string(),
                line,
                column,
                source_line: source_line.to_string(),
                first_column: 1,
                underline,
            };
        }
        // A window of SHOWN_CHARS characters, from CONTEXT_BEFORE characters before the span
        // (byte `at` of the line), moved back to stay full near the line's end. Found by
        // walking characters from the span, so its cost does not grow with the line.
        let at = (start - line_start).min(source_line.len());
        let back = |b: usize| source_line[..b].chars().next_back().map(char::len_utf8);
        let mut begin = at;
        for _ in 0..CONTEXT_BEFORE {
            match back(begin) {
                Some(n) => begin -= n,
                None => break,
            }
        }
        let mut end = begin;
        let mut count = 0;
        for c in source_line[begin..].chars().take(SHOWN_CHARS) {
            end += c.len_utf8();
            count += 1;
        }
        while count < SHOWN_CHARS {
            let Some(n) = back(begin) else { break };
            begin -= n;
            count += 1;
        }
        // 0-based character index of the window's first character in the line.
        let begin_index = column - 1 - text[line_start + begin..start].chars().count();
        let mut shown = String::with_capacity(end - begin + 6);
        if begin > 0 {
            shown.push('…');
        }
        shown.push_str(&source_line[begin..end]);
        if end < source_line.len() {
            shown.push('…');
        }
        let after = source_line[at..end].chars().count();
        Location {
            file: file.to_string(),
            line,
            column,
            source_line: shown,
            first_column: begin_index.max(1),
            underline: underline.min(after).max(1),
        }
    }
}

fn floor_char_boundary(text: &str, mut index: usize) -> usize {
    while !text.is_char_boundary(index) {
        index -= 1;
    }
    index
}

/// Renders diagnostics as plain text, each followed by a blank line, then a closing line
/// counting them (``error: could not load `lattice.toml` due to 2 previous errors``).
/// An empty slice renders as an empty string.
pub fn render(diags: &[Diagnostic]) -> String {
    let mut out = String::new();
    for diag in diags {
        render_one(&mut out, diag);
        out.push('\n');
    }
    if !diags.is_empty() {
        let count = match diags.len() {
            1 => "1 previous error".to_string(),
            n => format!("{n} previous errors"),
        };
        match diags.iter().find_map(|d| d.origin.as_deref()) {
            Some(origin) => {
                let _ = writeln!(out, "error: could not load `{origin}` due to {count}");
            }
            None => {
                let _ = writeln!(out, "error: aborting due to {count}");
            }
        }
    }
    out
}

fn render_one(out: &mut String, diag: &Diagnostic) {
    let _ = writeln!(out, "error: {}", visible(&diag.message));
    // The gutter is as wide as the line number, as in rustc; one column when there is no line.
    let width = diag
        .location
        .as_ref()
        .map_or(1, |l| l.line.to_string().len());
    let pad = " ".repeat(width);
    if let Some(loc) = &diag.location {
        let file = visible(&loc.file);
        let _ = writeln!(out, "{pad}--> {file}:{}:{}", loc.line, loc.column);
        let _ = writeln!(out, "{pad} |");
        // Built then trimmed, so an empty source line leaves no trailing space.
        let line = format!("{} | {}", loc.line, visible(&loc.source_line));
        let _ = writeln!(out, "{}", line.trim_end());
        // Tabs and escapes are wider than the characters they show, so the caret offset and
        // the underline count the shown text.
        let before: String = loc
            .source_line
            .chars()
            .take(loc.column.saturating_sub(loc.first_column))
            .collect();
        let marked: String = loc
            .source_line
            .chars()
            .skip(loc.column.saturating_sub(loc.first_column))
            .take(loc.underline)
            .collect();
        let indent = " ".repeat(visible(&before).chars().count());
        let width = visible(&marked).chars().count();
        let carets = "^".repeat(width.max(loc.underline).max(1));
        match &diag.label {
            Some(label) => {
                let _ = writeln!(out, "{pad} | {indent}{carets} {}", visible(label));
            }
            None => {
                let _ = writeln!(out, "{pad} | {indent}{carets}");
            }
        }
    } else if let Some(label) = &diag.label {
        // Without a line to underline, the label is still worth showing.
        let _ = writeln!(out, "{pad} = note: {}", visible(label));
    }
    if diag.help.is_some() || !diag.notes.is_empty() {
        let _ = writeln!(out, "{pad} |");
        for note in &diag.notes {
            let _ = writeln!(out, "{pad} = note: {}", visible(note));
        }
        if let Some(help) = &diag.help {
            let _ = writeln!(out, "{pad} = help: {}", visible(help));
        }
    }
}

/// `text` as it may be shown on a terminal: a tab as four spaces, a control character as its
/// picture (U+2400 + code, `␡` for DEL; one character wide, so columns keep their place), and
/// a character that would be invisible or reorder the line (C1 controls, bidirectional
/// controls, zero-width characters, the byte-order mark) as `\u{…}`.
fn visible(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '\t' => out.push_str("    "),
            '\0'..='\x1f' => out.push(char::from_u32(0x2400 + c as u32).unwrap_or('\u{fffd}')),
            '\x7f' => out.push('\u{2421}'),
            '\u{80}'..='\u{9f}'
            | '\u{200b}'..='\u{200f}'
            | '\u{2028}'..='\u{202e}'
            | '\u{2060}'..='\u{2069}'
            | '\u{feff}' => {
                let _ = write!(out, "\\u{{{:x}}}", c as u32);
            }
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_like_rustc() {
        let text = "[outputs.g]\ncell = \"a\"\n\n\n\n\n\n\n\n\n\nsampels = 64\n";
        let span = text.find("sampels").unwrap_or(0);
        let diag = Diagnostic::error("unknown key `sampels` in output `g`")
            .with_location(Location::of_span("lattice.toml", text, span..span + 7))
            .with_label("unknown key")
            .with_help("did you mean `samples`?")
            .with_origin("lattice.toml");
        let expected = "\
error: unknown key `sampels` in output `g`
  --> lattice.toml:12:1
   |
12 | sampels = 64
   | ^^^^^^^ unknown key
   |
   = help: did you mean `samples`?

error: could not load `lattice.toml` due to 1 previous error
";
        assert_eq!(render(&[diag]), expected);
    }

    #[test]
    fn columns_count_characters_and_tabs_keep_carets_aligned() {
        let text = "a = \"é\"\tx\n";
        let span = text.find('x').unwrap_or(0);
        let loc = Location::of_span("f", text, span..span + 1);
        assert_eq!((loc.line, loc.column, loc.underline), (1, 9, 1));
        let out = render(&[Diagnostic::error("m").with_location(loc)]);
        assert!(
            out.contains("1 | a = \"é\"    x\n  |            ^\n"),
            "{out}"
        );
        assert!(out.ends_with("error: aborting due to 1 previous error\n"));
    }

    /// Found by `cargo xtask fuzz` (tests/fuzz_corpus/manifest): thousands of TOML errors on
    /// one 60 kB line, each diagnostic holding and rendering the whole line, took 2 GB.
    #[test]
    fn long_lines_are_shown_as_a_window_around_the_span() {
        let line: String = (0..1000)
            .map(|i| char::from(b'a' + (i % 26) as u8))
            .collect();
        let text = format!("x = 1\n{line}\n");
        let at = |col: usize| 6 + col - 1;
        // In the middle: 40 characters before the span, `…` at both ends.
        let loc = Location::of_span("f", &text, at(501)..at(505));
        assert_eq!((loc.line, loc.column, loc.underline), (2, 501, 4));
        assert_eq!(loc.source_line.chars().count(), SHOWN_CHARS + 2);
        assert_eq!(loc.first_column, 460);
        assert_eq!(loc.source_line, format!("…{}…", &line[460..580]));
        let out = render(&[Diagnostic::error("m").with_location(loc)]);
        let lines: Vec<&str> = out.lines().collect();
        // The carets stand under the span's characters (columns 501..=504).
        let caret = lines[4].chars().position(|c| c == '^').expect("carets");
        let row: String = lines[3].chars().skip(caret).take(4).collect();
        assert_eq!(row, line[500..504]);
        assert_eq!(lines[4].chars().skip(caret).collect::<String>(), "^^^^");
        // At the start: no leading `…`; at the end: a full window, no trailing `…`.
        let loc = Location::of_span("f", &text, at(3)..at(4));
        assert_eq!(loc.first_column, 1);
        assert_eq!(loc.source_line, format!("{}…", &line[..120]));
        let loc = Location::of_span("f", &text, at(1000)..at(2000));
        assert_eq!(loc.source_line, format!("…{}", &line[880..]));
        assert_eq!((loc.first_column, loc.underline), (880, 1));
        // Characters, not bytes.
        let wide = format!("{}x{}", "é".repeat(300), "é".repeat(300));
        let loc = Location::of_span("f", &wide, 600..601);
        assert_eq!((loc.column, loc.first_column), (301, 260));
        assert_eq!(
            loc.source_line,
            format!("…{}x{}…", "é".repeat(40), "é".repeat(79))
        );
        // The rendered size no longer depends on the line's length.
        let diags: Vec<Diagnostic> = (0..1000)
            .map(|c| {
                Diagnostic::error("m").with_location(Location::of_span(
                    "f",
                    &text,
                    at(c + 1)..at(c + 2),
                ))
            })
            .collect();
        assert!(render(&diags).len() < 1000 * 400);
    }

    #[test]
    fn control_characters_are_shown_as_pictures_and_carets_stay_aligned() {
        // A NUL, an escape sequence that would recolour the terminal, a carriage return.
        let text = "a = \"x\0y\"\nb = \"\x1b[31mred\r!\"\n";
        let span = text.find('\0').unwrap_or(0);
        let nul = Diagnostic::error("invalid basic string")
            .with_location(Location::of_span("f.toml", text, span..span + 1))
            .with_label("here");
        let span = text.find('!').unwrap_or(0);
        let after =
            Diagnostic::error("m").with_location(Location::of_span("f.toml", text, span..span + 1));
        let out = render(&[nul, after]);
        assert!(
            out.contains(&format!("1 | a = \"x␀y\"\n  | {}^ here\n", " ".repeat(6))),
            "{out}"
        );
        assert!(
            out.contains(&format!(
                "2 | b = \"␛[31mred␍!\"\n  | {}^\n",
                " ".repeat(14)
            )),
            "{out}"
        );
        assert!(!out.chars().any(|c| c.is_control() && c != '\n'), "{out:?}");
    }

    #[test]
    fn invisible_characters_are_escaped_in_lines_and_messages() {
        // A right-to-left override would display the rest of the line reversed.
        let text = "k = \"\u{202e}abc\" # \u{200b}x";
        let span = text.find('x').unwrap_or(0);
        let diag = Diagnostic::error("unknown key `a\u{0}b`")
            .with_location(Location::of_span("f", text, span..span + 1))
            .with_label("label\u{7}")
            .with_help("help\u{1b}");
        let out = render(&[diag]);
        assert!(out.starts_with("error: unknown key `a␀b`\n"), "{out}");
        assert!(
            out.contains(&format!(
                "1 | k = \"\\u{{202e}}abc\" # \\u{{200b}}x\n  | {}^ label␇\n",
                " ".repeat(28)
            )),
            "{out}"
        );
        assert!(out.contains("= help: help␛\n"), "{out}");
        assert!(
            !out.contains('\u{202e}') && !out.contains('\u{200b}'),
            "{out:?}"
        );
    }

    #[test]
    fn clamps_spans_and_stops_underlines_at_the_line_end() {
        let text = "ab\ncd";
        let loc = Location::of_span("f", text, 1..100);
        assert_eq!((loc.line, loc.column, loc.underline), (1, 2, 1));
        let loc = Location::of_span("f", text, 500..600);
        assert_eq!((loc.line, loc.column, loc.underline), (2, 3, 1));
        assert_eq!(render(&[]), "");
    }
}
