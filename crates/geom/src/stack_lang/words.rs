//! Words: the tokens of an SDF program, where each one came from, and splitting program text
//! into words.
//!
//! A program is a list of words, exactly as a shell hands them to a command: `ball`, `scale`,
//! `1/2`, `0,-2,0`, `x*x + y*y - 1`. Program text (a manifest string, an included file) is split
//! at whitespace, and a run in double or single quotes is part of one word without its quotes,
//! as in a shell, so `expression "x + y"` is two words.
//!
//! Invariants:
//! - Every word keeps its [`Origin`], so an error found later can name the word by position.
//! - Splitting never fails except on an unclosed quote, reported by the byte offset of the
//!   opening quote.

use std::fmt;
use std::ops::Range;
use std::sync::Arc;

/// Where a word came from.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Origin {
    /// The `n`th (1-based) word of the program as given: a command-line argument, or a word of
    /// a program string.
    Arg(usize),
    /// The `index`th (1-based) word of an included file, named as the include resolver named it.
    File { file: Arc<str>, index: usize },
}

impl fmt::Display for Origin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Origin::Arg(n) => write!(f, "word {n}"),
            Origin::File { file, index } => write!(f, "word {index} of `{file}`"),
        }
    }
}

/// One word of a program.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Word {
    pub text: String,
    pub origin: Origin,
}

impl Word {
    /// The `n`th (1-based) word of a program given directly.
    pub fn arg(n: usize, text: impl Into<String>) -> Word {
        Word {
            text: text.into(),
            origin: Origin::Arg(n),
        }
    }

    /// Words numbered 1, 2, … from a list of strings (command-line arguments).
    pub fn args<S: AsRef<str>>(texts: &[S]) -> Vec<Word> {
        texts
            .iter()
            .enumerate()
            .map(|(i, t)| Word::arg(i + 1, t.as_ref()))
            .collect()
    }

    /// Where the word is and what it says, for error messages.
    pub fn at(&self) -> At {
        At {
            origin: self.origin.clone(),
            text: self.text.clone(),
        }
    }
}

/// A word's position and text, as errors show it: ``word 3 `scale` ``.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct At {
    pub origin: Origin,
    pub text: String,
}

impl fmt::Display for At {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} `{}`", self.origin, self.text)
    }
}

/// Splits program text into words at whitespace; quoted runs (`"…"` or `'…'`) belong to one
/// word and lose their quotes. On an unclosed quote, returns the byte offset of the quote.
pub fn split_words(text: &str) -> Result<Vec<String>, usize> {
    Ok(split_words_spanned(text)?
        .into_iter()
        .map(|(word, _)| word)
        .collect())
}

/// [`split_words`], with the byte range each word spans in `text` (quotes included), so that
/// a caller can point at a word of a program string.
pub fn split_words_spanned(text: &str) -> Result<Vec<(String, Range<usize>)>, usize> {
    let mut words = Vec::new();
    let mut current = String::new();
    let mut start = None;
    let mut chars = text.char_indices();
    while let Some((at, c)) = chars.next() {
        match c {
            '"' | '\'' => {
                start.get_or_insert(at);
                let mut closed = false;
                for (_, d) in chars.by_ref() {
                    if d == c {
                        closed = true;
                        break;
                    }
                    current.push(d);
                }
                if !closed {
                    return Err(at);
                }
            }
            c if c.is_whitespace() => {
                if let Some(from) = start.take() {
                    words.push((std::mem::take(&mut current), from..at));
                }
            }
            c => {
                start.get_or_insert(at);
                current.push(c);
            }
        }
    }
    if let Some(from) = start {
        words.push((current, from..text.len()));
    }
    Ok(words)
}

/// `text` as one word of program text: quoted when it is empty or holds whitespace or quotes,
/// so that [`split_words`] gives it back unchanged.
pub fn quote(text: &str) -> String {
    let plain = !text.is_empty()
        && !text
            .chars()
            .any(|c| c.is_whitespace() || c == '"' || c == '\'');
    if plain {
        text.to_string()
    } else if text.contains('"') {
        format!("'{text}'")
    } else {
        format!("\"{text}\"")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_like_a_shell() {
        assert_eq!(
            split_words("  ball scale 2\n\tmove 0,-2,0 ").unwrap(),
            ["ball", "scale", "2", "move", "0,-2,0"]
        );
        assert_eq!(
            split_words("expression \"x + y - 1\" offset '1 / 2'").unwrap(),
            ["expression", "x + y - 1", "offset", "1 / 2"]
        );
        assert_eq!(split_words("a\"b c\"d").unwrap(), ["ab cd"]);
        assert_eq!(split_words("\"\"").unwrap(), [""]);
        assert_eq!(split_words("ball \"oops").unwrap_err(), 5);
        assert!(split_words("   ").unwrap().is_empty());
    }

    #[test]
    fn spans_cover_each_word_with_its_quotes() {
        let text = "ball  'x + y'\tscale 1/2";
        let words = split_words_spanned(text).unwrap();
        let spans: Vec<&str> = words.iter().map(|(_, r)| &text[r.clone()]).collect();
        assert_eq!(spans, ["ball", "'x + y'", "scale", "1/2"]);
        assert_eq!(words[1].0, "x + y");
        assert_eq!(
            split_words_spanned("a\"b c\"d").unwrap(),
            [("ab cd".to_string(), 0..7)]
        );
    }

    #[test]
    fn quoting_round_trips() {
        for text in ["ball", "x + y", "a\"b", "", "it's here"] {
            if text.contains('"') && text.contains('\'') {
                continue;
            }
            assert_eq!(split_words(&quote(text)).unwrap(), [text]);
        }
    }
}
