//! Everything that can be wrong with an SDF program, each naming the word at fault.
//!
//! Invariant: every error that concerns a word starts with that word's position and text
//! (``word 3 `scale`: …``), says what was wrong and, where we can tell, what was expected or
//! meant. Messages are lower case with names in backticks and no trailing period.

use std::sync::Arc;

use super::words::At;

/// A problem with an SDF program.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ProgramError {
    #[error(
        "the program is empty: start it with a solid such as `ball`, `tpms.gyroid` or `expression \"…\"`"
    )]
    Empty,

    #[error("{at}: unknown word{help}")]
    UnknownWord { at: At, help: String },

    #[error("{at}: no TPMS named `{name}` in the library{help}")]
    UnknownTpms { at: At, name: String, help: String },

    #[error("{at}: `{word}` needs {expected}, found the end of the program")]
    MissingArgument {
        at: At,
        word: &'static str,
        expected: &'static str,
    },

    #[error("{at}: `{word}` needs {expected}: {problem}")]
    BadArgument {
        at: At,
        word: &'static str,
        expected: &'static str,
        problem: String,
    },

    #[error("{at}: bad expression at byte {byte}: {message}{help}")]
    BadExpression {
        at: At,
        byte: usize,
        message: String,
        help: String,
    },

    #[error("{at}: {word} needs {}, found {}", solids(*.needs), count(*.found))]
    Underflow {
        at: At,
        word: &'static str,
        needs: usize,
        found: usize,
    },

    #[error(
        "{at}: the solid made here is never used: the program ends with {count} solids on the \
         stack; join them with `union`, `intersection` or `difference`"
    )]
    Leftover { at: At, count: usize },

    #[error("{at}: `file` cannot be used: {message}")]
    File { at: At, message: String },

    #[error("{at}: `@file` includes must be expanded before the program is parsed")]
    UnexpandedInclude { at: At },

    #[error("{at}: cannot include it: {message}")]
    IncludeRead { at: At, message: String },

    #[error("{at}: the file includes itself: {}", .chain.join(" → "))]
    IncludeCycle { at: At, chain: Vec<String> },

    #[error("{at}: includes nest more than {limit} deep")]
    IncludeTooDeep { at: At, limit: usize },

    #[error("the program has more than {limit} words after expanding `@file` includes")]
    TooManyWords { limit: usize },

    #[error("{} has an unclosed quote at byte {byte}", source_name(.file))]
    UnclosedQuote { file: Option<Arc<str>>, byte: usize },
}

impl ProgramError {
    /// The word at fault, when the error concerns one.
    pub fn at(&self) -> Option<&At> {
        match self {
            ProgramError::UnknownWord { at, .. }
            | ProgramError::UnknownTpms { at, .. }
            | ProgramError::MissingArgument { at, .. }
            | ProgramError::BadArgument { at, .. }
            | ProgramError::BadExpression { at, .. }
            | ProgramError::Underflow { at, .. }
            | ProgramError::Leftover { at, .. }
            | ProgramError::File { at, .. }
            | ProgramError::UnexpandedInclude { at }
            | ProgramError::IncludeRead { at, .. }
            | ProgramError::IncludeCycle { at, .. }
            | ProgramError::IncludeTooDeep { at, .. } => Some(at),
            ProgramError::Empty
            | ProgramError::TooManyWords { .. }
            | ProgramError::UnclosedQuote { .. } => None,
        }
    }
}

fn solids(n: usize) -> &'static str {
    if n == 1 { "a solid" } else { "two solids" }
}

fn count(n: usize) -> &'static str {
    match n {
        0 => "none",
        1 => "one",
        _ => "more",
    }
}

fn source_name(file: &Option<Arc<str>>) -> String {
    match file {
        Some(f) => format!("`{f}`"),
        None => "the program".to_string(),
    }
}
