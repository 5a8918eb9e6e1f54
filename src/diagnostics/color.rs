//! Colour for what goes to stderr: `--color auto|always|never`, the `NO_COLOR` and
//! `CLICOLOR_FORCE` conventions, and rustc's colours laid over rendered diagnostics.
//!
//! Invariants:
//! - Colour is added, never substituted: [`style`] only inserts SGR sequences (`ESC [ … m`)
//!   between the characters of its input, so removing them gives the input back byte for
//!   byte *(tested)*. User text was made visible by the renderer before it got here, and no
//!   escape sequence is ever taken from it.
//! - The choice is made once, by the command line, before any output ([`set`]); until then,
//!   and in every test, output is plain. [`super::render`] itself never colours, so golden
//!   files and JSON hold plain text.
//!
//! Why style the rendered text rather than render in colour: the diagnostics of the manifest
//! loader and the hand-built ones of the commands (`error: no output named …`, the
//! `= help:` under a refused budget, a build report's `warning:` lines) all share rustc's
//! layout, so one function that knows the layout colours them all, and the renderer's exact
//! text (under test) stays one code path.

use std::ffi::OsString;
use std::sync::atomic::{AtomicBool, Ordering};

/// When to colour, as `--color` takes it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorChoice {
    /// Colour when stderr is a terminal, unless the environment says otherwise.
    Auto,
    Always,
    Never,
}

/// Whether to colour stderr. `--color always|never` wins over everything. Under `auto`:
/// `NO_COLOR` (any non-empty value, <https://no-color.org>) turns colour off, then
/// `CLICOLOR_FORCE` (non-empty, not `0`) turns it on even into a pipe, then `CLICOLOR=0`
/// turns it off; otherwise colour is on when stderr is a terminal that is not `TERM=dumb`.
/// `var` reads an environment variable (a parameter so tests need not change the process's).
pub fn decide(
    choice: ColorChoice,
    stderr_is_terminal: bool,
    var: impl Fn(&str) -> Option<OsString>,
) -> bool {
    let set = |name: &str| var(name).filter(|v| !v.is_empty());
    match choice {
        ColorChoice::Always => true,
        ColorChoice::Never => false,
        ColorChoice::Auto => {
            if set("NO_COLOR").is_some() {
                false
            } else if set("CLICOLOR_FORCE").is_some_and(|v| v != "0") {
                true
            } else if set("CLICOLOR").is_some_and(|v| v == "0") {
                false
            } else {
                stderr_is_terminal && set("TERM").is_none_or(|t| t != "dumb")
            }
        }
    }
}

static ON: AtomicBool = AtomicBool::new(false);

/// Colours everything [`paint`] is given from now on (`true`) or nothing (`false`).
pub fn set(on: bool) {
    ON.store(on, Ordering::Relaxed);
}

/// Whether [`paint`] colours.
pub fn enabled() -> bool {
    ON.load(Ordering::Relaxed)
}

/// `text` (rendered diagnostics, `warning:` lines) as it goes to stderr: [`style`]d when
/// colour is on, unchanged otherwise.
pub fn paint(text: &str) -> String {
    if enabled() {
        style(text)
    } else {
        text.to_string()
    }
}

const RESET: &str = "\x1b[0m";
const BOLD: &str = "\x1b[1m";
/// rustc's colours: the level bold (error bright red, warning yellow), the gutter, `-->`
/// and `=` bold bright blue, a sub-diagnostic's `note`/`help` bold.
const ERROR: &str = "\x1b[1;91m";
const WARNING: &str = "\x1b[1;33m";
const GUTTER: &str = "\x1b[1;94m";

/// `text`, made of lines laid out as [`super::render`] lays them, in rustc's colours:
/// `error`/`warning` and the carets (with their label) in the level's colour, the message
/// bold, `-->`, line numbers, `|` and `=` blue, `note`/`help` bold. A line of any other
/// shape is left as it is.
pub fn style(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + text.len() / 4);
    // The colour of the carets: that of the last `error:` or `warning:` line.
    let mut level = ERROR;
    for line in text.split_inclusive('\n') {
        let (body, end) = match line.strip_suffix('\n') {
            Some(body) => (body, "\n"),
            None => (line, ""),
        };
        style_line(&mut out, body, &mut level);
        out.push_str(end);
    }
    out
}

fn style_line(out: &mut String, line: &str, level: &mut &'static str) {
    for (word, colour) in [("error", ERROR), ("warning", WARNING)] {
        if let Some(rest) = line.strip_prefix(word)
            && rest.starts_with(':')
        {
            *level = colour;
            out.push_str(&format!("{colour}{word}{RESET}{BOLD}{rest}{RESET}"));
            return;
        }
    }
    let trimmed = line.trim_start_matches(' ');
    let pad = &line[..line.len() - trimmed.len()];
    if let Some(rest) = trimmed.strip_prefix("-->") {
        out.push_str(&format!("{pad}{GUTTER}-->{RESET}{rest}"));
    } else if trimmed == "|" {
        out.push_str(&format!("{pad}{GUTTER}|{RESET}"));
    } else if let Some(rest) = trimmed.strip_prefix("| ")
        && !pad.is_empty()
    {
        // Under a blank gutter: the carets and their label.
        let body = rest.trim_start_matches(' ');
        let indent = &rest[..rest.len() - body.len()];
        out.push_str(&format!(
            "{pad}{GUTTER}|{RESET} {indent}{level}{body}{RESET}"
        ));
    } else if let Some(rest) = trimmed.strip_prefix("= ")
        && let Some((word, after)) = ["note", "help"]
            .iter()
            .find_map(|w| Some((*w, rest.strip_prefix(w)?.strip_prefix(':')?)))
    {
        out.push_str(&format!(
            "{pad}{GUTTER}={RESET} {BOLD}{word}{RESET}:{after}"
        ));
    } else if let Some((number, rest)) = numbered(trimmed) {
        // A source line: `12 | text` (or `12 |` when the line is empty).
        out.push_str(&format!("{pad}{GUTTER}{number} |{RESET}{rest}"));
    } else {
        out.push_str(line);
    }
}

/// `12 | text` as (`12`, ` text`); `12 |` as (`12`, ``).
fn numbered(line: &str) -> Option<(&str, &str)> {
    let digits = line.len() - line.trim_start_matches(|c: char| c.is_ascii_digit()).len();
    if digits == 0 {
        return None;
    }
    let (number, rest) = line.split_at(digits);
    let rest = rest.strip_prefix(" |")?;
    (rest.is_empty() || rest.starts_with(' ')).then_some((number, rest))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnostics::{Diagnostic, Location, render};

    /// Removes every `ESC [ … m` sequence.
    fn strip(text: &str) -> String {
        let mut out = String::new();
        let mut rest = text;
        while let Some(at) = rest.find("\x1b[") {
            out.push_str(&rest[..at]);
            let after = &rest[at + 2..];
            let end = after.find('m').expect("an SGR sequence ends in `m`");
            assert!(
                after[..end].chars().all(|c| c.is_ascii_digit() || c == ';'),
                "not an SGR sequence: {:?}",
                &after[..=end]
            );
            rest = &after[end + 1..];
        }
        out.push_str(rest);
        out
    }

    fn sample() -> String {
        let text = "[outputs.g]\ncell = \"a\"\n\n\n\n\n\n\n\n\n\nsampels = 64\n";
        let span = text.find("sampels").unwrap();
        render(&[Diagnostic::error("unknown key `sampels` in output `g`")
            .with_location(Location::of_span("lattice.toml", text, span..span + 7))
            .with_label("unknown key")
            .with_note("a note")
            .with_help("did you mean `samples`?")
            .with_origin("lattice.toml")])
    }

    #[test]
    fn styles_each_part_as_rustc_does() {
        let styled = style(&sample());
        let expected = [
            "\x1b[1;91merror\x1b[0m\x1b[1m: unknown key `sampels` in output `g`\x1b[0m",
            "  \x1b[1;94m-->\x1b[0m lattice.toml:12:1",
            "   \x1b[1;94m|\x1b[0m",
            "\x1b[1;94m12 |\x1b[0m sampels = 64",
            "   \x1b[1;94m|\x1b[0m \x1b[1;91m^^^^^^^ unknown key\x1b[0m",
            "   \x1b[1;94m|\x1b[0m",
            "   \x1b[1;94m=\x1b[0m \x1b[1mnote\x1b[0m: a note",
            "   \x1b[1;94m=\x1b[0m \x1b[1mhelp\x1b[0m: did you mean `samples`?",
            "",
            "\x1b[1;91merror\x1b[0m\x1b[1m: could not load `lattice.toml` due to 1 previous error\x1b[0m",
        ];
        assert_eq!(styled.lines().collect::<Vec<_>>(), expected);
        let warning = style("warning: g: thin walls\n   | ^ here\n");
        assert!(
            warning.starts_with("\x1b[1;33mwarning\x1b[0m\x1b[1m:"),
            "{warning:?}"
        );
        assert!(warning.contains("\x1b[1;33m^ here\x1b[0m"), "{warning:?}");
    }

    #[test]
    fn styling_only_adds_sgr_sequences() {
        // User text with pictures of control characters, a line that only looks like a
        // gutter, lines of no known shape, and no final newline.
        let plain = format!(
            "{}error: `a␛[31mb` 12 | x\nerror:\n  = help:x\n12|3\n 7 |\n| a\nnote: x\n   |   ^^ ␀",
            sample()
        );
        let styled = style(&plain);
        assert_eq!(strip(&styled), plain);
        assert!(!plain.contains('\x1b') && styled.contains('\x1b'));
        // Lines of no known shape are not touched.
        assert!(styled.contains("\n12|3\n") && styled.contains("\n| a\nnote: x\n"));
    }

    #[test]
    fn the_choice_follows_the_flag_then_the_environment_then_the_terminal() {
        let env = |pairs: &'static [(&'static str, &'static str)]| {
            move |name: &str| {
                pairs
                    .iter()
                    .find(|(k, _)| *k == name)
                    .map(|(_, v)| OsString::from(v))
            }
        };
        use ColorChoice::*;
        assert!(decide(Always, false, env(&[("NO_COLOR", "1")])));
        assert!(!decide(Never, true, env(&[("CLICOLOR_FORCE", "1")])));
        assert!(decide(Auto, true, env(&[])));
        assert!(!decide(Auto, false, env(&[])));
        assert!(!decide(Auto, true, env(&[("NO_COLOR", "1")])));
        // An empty NO_COLOR does not count.
        assert!(decide(Auto, true, env(&[("NO_COLOR", "")])));
        assert!(decide(Auto, false, env(&[("CLICOLOR_FORCE", "1")])));
        assert!(!decide(Auto, false, env(&[("CLICOLOR_FORCE", "0")])));
        assert!(!decide(
            Auto,
            false,
            env(&[("CLICOLOR_FORCE", "1"), ("NO_COLOR", "1")])
        ));
        assert!(!decide(Auto, true, env(&[("CLICOLOR", "0")])));
        assert!(!decide(Auto, true, env(&[("TERM", "dumb")])));
    }
}
