//! A reading position in a file's bytes: whitespace-separated tokens for text, fixed-size
//! numbers for binary, and errors that say where.
//!
//! Invariants: no method panics or reads past the end; every failure is a [`ScaffoldError`]
//! at the offending token (text: its line; binary: its byte offset) saying what was expected.

use super::{Location, ScaffoldError};

/// Turns byte offsets into the locations the errors show.
#[derive(Clone, Copy)]
pub(super) struct Locator<'a> {
    pub bytes: &'a [u8],
    pub name: &'a str,
    /// Report byte offsets (binary data) rather than lines.
    pub binary: bool,
}

impl<'a> Locator<'a> {
    pub fn at(&self, pos: usize) -> Location {
        if self.binary {
            Location::Byte(pos as u64)
        } else {
            let end = pos.min(self.bytes.len());
            Location::Line(self.bytes[..end].iter().filter(|&&b| b == b'\n').count() as u64 + 1)
        }
    }

    pub fn error(&self, pos: usize, message: impl Into<String>) -> ScaffoldError {
        ScaffoldError::new(self.name, self.at(pos), message)
    }

    pub fn file_error(&self, message: impl Into<String>) -> ScaffoldError {
        ScaffoldError::new(self.name, Location::File, message)
    }
}

pub(super) struct Cursor<'a> {
    pub loc: Locator<'a>,
    pub pos: usize,
    pub big_endian: bool,
}

/// Shows a token in a message: at most 40 characters, lossy UTF-8.
pub(super) fn show(token: &[u8]) -> String {
    let text = String::from_utf8_lossy(&token[..token.len().min(40)]).into_owned();
    if token.len() > 40 {
        format!("{text}…")
    } else {
        text
    }
}

impl<'a> Cursor<'a> {
    pub fn new(bytes: &'a [u8], name: &'a str) -> Cursor<'a> {
        Cursor {
            loc: Locator {
                bytes,
                name,
                binary: false,
            },
            pos: 0,
            big_endian: false,
        }
    }

    pub fn bytes(&self) -> &'a [u8] {
        self.loc.bytes
    }

    pub fn remaining(&self) -> usize {
        self.loc.bytes.len().saturating_sub(self.pos)
    }

    pub fn error(&self, pos: usize, message: impl Into<String>) -> ScaffoldError {
        self.loc.error(pos, message)
    }

    pub fn eof(&self, what: &str) -> ScaffoldError {
        self.loc.error(
            self.loc.bytes.len(),
            format!("unexpected end of file: expected {what}"),
        )
    }

    /// The position of the next item: in text after any whitespace, in binary data as is.
    pub fn mark(&mut self) -> usize {
        if !self.loc.binary {
            self.skip_whitespace();
        }
        self.pos
    }

    pub fn skip_whitespace(&mut self) {
        let b = self.loc.bytes;
        while self.pos < b.len() && b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    /// The next whitespace-separated token, or `None` at the end.
    pub fn next_token(&mut self) -> Option<(usize, &'a [u8])> {
        self.skip_whitespace();
        let b = self.loc.bytes;
        let start = self.pos;
        while self.pos < b.len() && !b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        (self.pos > start).then(|| (start, &b[start..self.pos]))
    }

    pub fn token(&mut self, what: &str) -> Result<(usize, &'a [u8]), ScaffoldError> {
        self.next_token().ok_or_else(|| self.eof(what))
    }

    pub fn expect(&mut self, word: &str) -> Result<(), ScaffoldError> {
        let (at, token) = self.token(&format!("`{word}`"))?;
        if token != word.as_bytes() {
            return Err(self.error(at, format!("expected `{word}`, found `{}`", show(token))));
        }
        Ok(())
    }

    fn parse<T: std::str::FromStr>(&mut self, what: &str) -> Result<(usize, T), ScaffoldError> {
        let (at, token) = self.token(what)?;
        std::str::from_utf8(token)
            .ok()
            .and_then(|t| t.parse::<T>().ok())
            .map(|v| (at, v))
            .ok_or_else(|| self.error(at, format!("expected {what}, found `{}`", show(token))))
    }

    pub fn uint(&mut self, what: &str) -> Result<u64, ScaffoldError> {
        self.parse::<u64>(what).map(|(_, v)| v)
    }

    pub fn int(&mut self, what: &str) -> Result<i64, ScaffoldError> {
        self.parse::<i64>(what).map(|(_, v)| v)
    }

    /// A finite number (NaN and infinities are errors).
    pub fn float(&mut self, what: &str) -> Result<f64, ScaffoldError> {
        let (at, v) = self.parse::<f64>(what)?;
        finite(v, what).map_err(|m| self.error(at, m))
    }

    /// A count: a non-negative integer; `min_bytes` per item must fit in what is left.
    pub fn count(&mut self, what: &str, min_bytes: usize) -> Result<usize, ScaffoldError> {
        let (at, v) = self.parse::<u64>(what)?;
        self.check_count(at, v, what, min_bytes)
    }

    pub fn check_count(
        &self,
        at: usize,
        v: u64,
        what: &str,
        min_bytes: usize,
    ) -> Result<usize, ScaffoldError> {
        let left = self.remaining() as u64;
        if v.saturating_mul(min_bytes as u64) > left {
            return Err(self.error(
                at,
                format!(
                    "{what} is {v}, but only {left} bytes follow (truncated file or bad count)"
                ),
            ));
        }
        Ok(v as usize)
    }

    /// A double-quoted string token (may contain spaces); a bare token is accepted too.
    pub fn quoted(&mut self, what: &str) -> Result<String, ScaffoldError> {
        self.skip_whitespace();
        let b = self.loc.bytes;
        if self.pos < b.len() && b[self.pos] == b'"' {
            let start = self.pos + 1;
            match b[start..].iter().position(|&c| c == b'"') {
                Some(len) => {
                    self.pos = start + len + 1;
                    Ok(String::from_utf8_lossy(&b[start..start + len]).into_owned())
                }
                None => Err(self.error(self.pos, format!("unterminated string: expected {what}"))),
            }
        } else {
            let (_, t) = self.token(what)?;
            Ok(String::from_utf8_lossy(t).into_owned())
        }
    }

    /// Moves past the end of the current line.
    pub fn skip_line(&mut self) {
        let b = self.loc.bytes;
        while self.pos < b.len() && b[self.pos] != b'\n' {
            self.pos += 1;
        }
        if self.pos < b.len() {
            self.pos += 1;
        }
    }

    pub fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], ScaffoldError> {
        if self.remaining() < n {
            return Err(self.error(
                self.pos,
                format!(
                    "unexpected end of file: expected {what} ({n} bytes, {} left)",
                    self.remaining()
                ),
            ));
        }
        let s = &self.loc.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], ScaffoldError> {
        let s = self.take(N, what)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        if self.big_endian {
            a.reverse();
        }
        Ok(a)
    }

    pub fn i32(&mut self, what: &str) -> Result<i32, ScaffoldError> {
        self.array::<4>(what).map(i32::from_le_bytes)
    }

    pub fn u64(&mut self, what: &str) -> Result<u64, ScaffoldError> {
        self.array::<8>(what).map(u64::from_le_bytes)
    }

    /// A finite binary double.
    pub fn f64(&mut self, what: &str) -> Result<f64, ScaffoldError> {
        let at = self.pos;
        let v = self.array::<8>(what).map(f64::from_le_bytes)?;
        finite(v, what).map_err(|m| self.error(at, m))
    }

    /// A binary 4-byte int that must be ≥ 0.
    pub fn index32(&mut self, what: &str) -> Result<u64, ScaffoldError> {
        let at = self.pos;
        let v = self.i32(what)?;
        u64::try_from(v).map_err(|_| self.error(at, format!("expected {what}, found {v}")))
    }
}

pub(super) fn finite(v: f64, what: &str) -> Result<f64, String> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("expected {what}, found {v} (not a finite number)"))
    }
}
