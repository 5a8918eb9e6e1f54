//! `@file` includes: a word `@NAME` is replaced by the words of the file NAME (paper §4.2),
//! recursively, where names inside an included file are relative to that file.
//!
//! This module knows no paths: an [`IncludeResolver`] given by the caller turns a name (and
//! the file it appears in) into an identity and a text. The command line resolves against the
//! filesystem; a manifest could resolve against its own directory and hash what it reads.
//!
//! Invariants:
//! - Expansion always ends: a file that includes itself, directly or through others, is an
//!   error naming the chain; nesting is limited to [`MAX_DEPTH`] and the expanded program to
//!   [`MAX_WORDS`] words (a file included twice by each of a chain of files doubles per level).
//! - Every word keeps its origin: top-level words their position, included words their file
//!   and position in it.

use std::sync::Arc;

use super::error::ProgramError;
use super::words::{Origin, Word, split_words};

/// Deepest nesting of includes.
pub const MAX_DEPTH: usize = 64;
/// Most words a program may have after expansion.
pub const MAX_WORDS: usize = 1 << 20;

/// An included file: an identity that is the same whichever way the file was named (the
/// command line uses the canonical path), and its text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Included {
    pub id: String,
    pub text: String,
}

/// Finds included files for [`expand`].
pub trait IncludeResolver {
    /// Reads the file named `name` (the word without its `@`), included from the file `from`
    /// (its id) or from the top-level words (`None`). Errors are shown after the word.
    fn read(&self, name: &str, from: Option<&str>) -> Result<Included, String>;
}

/// The words of `args` with every `@file` replaced by the words of its file, recursively.
pub fn expand<S: AsRef<str>>(
    args: &[S],
    resolver: &dyn IncludeResolver,
) -> Result<Vec<Word>, ProgramError> {
    let mut out = Vec::new();
    let mut chain = Vec::new();
    for (i, arg) in args.iter().enumerate() {
        let word = Word::arg(i + 1, arg.as_ref());
        expand_word(word, None, resolver, &mut chain, &mut out)?;
    }
    Ok(out)
}

fn expand_word(
    word: Word,
    from: Option<&str>,
    resolver: &dyn IncludeResolver,
    chain: &mut Vec<String>,
    out: &mut Vec<Word>,
) -> Result<(), ProgramError> {
    let Some(name) = word.text.strip_prefix('@') else {
        if out.len() >= MAX_WORDS {
            return Err(ProgramError::TooManyWords { limit: MAX_WORDS });
        }
        out.push(word);
        return Ok(());
    };
    if chain.len() >= MAX_DEPTH {
        return Err(ProgramError::IncludeTooDeep {
            at: word.at(),
            limit: MAX_DEPTH,
        });
    }
    let included = resolver
        .read(name, from)
        .map_err(|message| ProgramError::IncludeRead {
            at: word.at(),
            message,
        })?;
    if let Some(first) = chain.iter().position(|id| *id == included.id) {
        let mut cycle = chain[first..].to_vec();
        cycle.push(included.id);
        return Err(ProgramError::IncludeCycle {
            at: word.at(),
            chain: cycle,
        });
    }
    let file: Arc<str> = included.id.as_str().into();
    let words = split_words(&included.text).map_err(|byte| ProgramError::UnclosedQuote {
        file: Some(file.clone()),
        byte,
    })?;
    chain.push(included.id.clone());
    for (i, text) in words.into_iter().enumerate() {
        let inner = Word {
            text,
            origin: Origin::File {
                file: file.clone(),
                index: i + 1,
            },
        };
        expand_word(inner, Some(&included.id), resolver, chain, out)?;
    }
    chain.pop();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// Files in memory; names are ids, and a name is looked up relative to nothing.
    struct Files(HashMap<&'static str, &'static str>);

    impl IncludeResolver for Files {
        fn read(&self, name: &str, _from: Option<&str>) -> Result<Included, String> {
            self.0
                .get(name)
                .map(|text| Included {
                    id: name.to_string(),
                    text: text.to_string(),
                })
                .ok_or_else(|| format!("no file `{name}`"))
        }
    }

    fn texts(words: &[Word]) -> Vec<&str> {
        words.iter().map(|w| w.text.as_str()).collect()
    }

    #[test]
    fn includes_expand_recursively_with_origins() {
        let files = Files(HashMap::from([
            ("a", "ball @b\nunion"),
            ("b", "cylinder scale 1/2"),
        ]));
        let words = expand(&["-s", "40^3", "@a", "complement"], &files).unwrap();
        assert_eq!(
            texts(&words),
            [
                "-s",
                "40^3",
                "ball",
                "cylinder",
                "scale",
                "1/2",
                "union",
                "complement"
            ]
        );
        assert_eq!(words[3].origin.to_string(), "word 1 of `b`");
        assert_eq!(words[6].origin.to_string(), "word 3 of `a`");
        assert_eq!(words[7].origin, Origin::Arg(4));
    }

    #[test]
    fn the_same_file_twice_is_fine_but_a_cycle_is_an_error() {
        let files = Files(HashMap::from([("b", "ball"), ("two", "@b @b union")]));
        assert_eq!(
            texts(&expand(&["@two"], &files).unwrap()),
            ["ball", "ball", "union"]
        );

        let files = Files(HashMap::from([("a", "ball @b"), ("b", "@a union")]));
        let err = expand(&["@a"], &files).unwrap_err();
        assert_eq!(
            err.to_string(),
            "word 1 of `b` `@a`: the file includes itself: a → b → a"
        );
        let files = Files(HashMap::from([("self", "ball @self")]));
        assert!(matches!(
            expand(&["@self"], &files),
            Err(ProgramError::IncludeCycle { .. })
        ));
    }

    #[test]
    fn missing_files_and_quotes_are_reported() {
        let files = Files(HashMap::from([("q", "expression \"x + y")]));
        assert_eq!(
            expand(&["ball", "@nope"], &files).unwrap_err().to_string(),
            "word 2 `@nope`: cannot include it: no file `nope`"
        );
        assert_eq!(
            expand(&["@q"], &files).unwrap_err().to_string(),
            "`q` has an unclosed quote at byte 11"
        );
    }
}
