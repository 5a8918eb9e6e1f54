//! Lines and whitespace-separated tokens of text formats, with line numbers for errors.
//!
//! Works on bytes: files need not be UTF-8, only their numbers and keywords must be ASCII.
//! Lines end at `\n`; a `\r` before it is whitespace like any other.

/// Whitespace-separated tokens of a whole text, each with the line it sits on (from 1).
#[derive(Clone)]
pub(super) struct Tokens<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Tokens<'a> {
    /// Tokens of `bytes`, whose first byte is on line `first_line`.
    pub(super) fn new(bytes: &'a [u8], first_line: usize) -> Tokens<'a> {
        Tokens {
            bytes,
            pos: 0,
            line: first_line,
        }
    }

    /// The line the next token is on, or the last line when none is left.
    pub(super) fn line(&mut self) -> usize {
        self.skip_space();
        self.line
    }

    fn skip_space(&mut self) {
        while let Some(&b) = self.bytes.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
    }

    /// The next token and its line.
    pub(super) fn next_token(&mut self) -> Option<(&'a [u8], usize)> {
        self.skip_space();
        let start = self.pos;
        while self
            .bytes
            .get(self.pos)
            .is_some_and(|b| !b.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        (self.pos > start).then(|| (&self.bytes[start..self.pos], self.line))
    }

    /// Bytes not yet read.
    pub(super) fn remaining_bytes(&self) -> usize {
        self.bytes.len() - self.pos
    }

    /// Skips the rest of line `line` (for names after `solid`/`endsolid`).
    pub(super) fn skip_line(&mut self, line: usize) {
        while self.line == line && self.pos < self.bytes.len() {
            if self.bytes[self.pos] == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
    }
}

/// The lines of `bytes` with their numbers (from 1), without the line ending.
pub(super) fn lines(bytes: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    let trimmed = bytes.strip_suffix(b"\n").unwrap_or(bytes);
    let mut split = (!bytes.is_empty()).then(|| trimmed.split(|&b| b == b'\n'));
    std::iter::from_fn(move || split.as_mut()?.next())
        .enumerate()
        .map(|(i, line)| (i + 1, line))
}

/// The whitespace-separated tokens of one line.
pub(super) fn tokens(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|b| b.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
}

/// `line` up to a `#` comment.
pub(super) fn strip_comment(line: &[u8]) -> &[u8] {
    line.iter()
        .position(|&b| b == b'#')
        .map_or(line, |i| &line[..i])
}

/// A token as a float (`nan` and `inf` parse; callers check finiteness where it matters).
pub(super) fn float(token: &[u8]) -> Option<f64> {
    std::str::from_utf8(token).ok()?.parse().ok()
}

/// A token as an integer.
pub(super) fn int(token: &[u8]) -> Option<i64> {
    std::str::from_utf8(token).ok()?.parse().ok()
}

/// A token quoted for an error message, shortened to a readable length.
pub(super) fn show(token: &[u8]) -> String {
    const MAX: usize = 32;
    let text = String::from_utf8_lossy(&token[..token.len().min(MAX)]);
    let ellipsis = if token.len() > MAX { "…" } else { "" };
    format!("`{}{ellipsis}`", text.escape_debug())
}

/// The first token of the first line that is not blank or a `#` comment.
pub(super) fn first_keyword(bytes: &[u8]) -> Option<&[u8]> {
    lines(bytes)
        .take(64)
        .find_map(|(_, line)| tokens(strip_comment(line)).next())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_carry_their_lines() {
        let mut t = Tokens::new(b"a b\n\n  c\r\nd", 1);
        let got: Vec<_> = std::iter::from_fn(|| t.next_token()).collect();
        assert_eq!(
            got,
            vec![
                (&b"a"[..], 1),
                (&b"b"[..], 1),
                (&b"c"[..], 3),
                (&b"d"[..], 4)
            ]
        );
    }

    #[test]
    fn lines_are_numbered_from_one_and_lose_their_endings() {
        let got: Vec<_> = lines(b"x\ny\n").collect();
        assert_eq!(got, vec![(1, &b"x"[..]), (2, &b"y"[..])]);
        assert_eq!(lines(b"").count(), 0);
    }
}
