//! STL, binary or ASCII, told apart by content.
//!
//! Binary: an 80-byte header (which may begin with `solid`), a little-endian `u32` facet count
//! `n`, then `n` records of 50 bytes (normal, three vertices as `f32`, a `u16` attribute). A
//! file whose size is not exactly `84 + 50 n` is rejected: it is truncated or not binary STL.
//!
//! ASCII: `solid name`, then `facet normal nx ny nz`, `outer loop`, `vertex x y z` lines,
//! `endloop`, `endfacet`, and finally `endsolid name`. A missing `endsolid` means the file was
//! cut short, even when it ends between two facets. Several `solid` blocks may follow each
//! other. Normals are read but ignored (the winding decides); a loop of more than three
//! vertices is fan-triangulated.

use super::text::{self, Tokens};
use super::{Format, Location, MeshReadError, TriangleSoup};

const HEADER: usize = 84;
const RECORD: usize = 50;
/// How much of the file must be plain text for a `solid` file to count as ASCII.
const SNIFF: usize = 1024;

pub(super) fn read(bytes: &[u8]) -> Result<TriangleSoup, MeshReadError> {
    if !is_binary(bytes) && is_ascii(bytes) {
        ascii(bytes)
    } else {
        binary(bytes)
    }
}

/// Declared facet count and the size it implies.
fn declared(bytes: &[u8]) -> Option<(u64, u64)> {
    let count = u32::from_le_bytes(bytes.get(80..84)?.try_into().ok()?);
    Some((
        u64::from(count),
        HEADER as u64 + RECORD as u64 * u64::from(count),
    ))
}

/// Exactly the size a binary STL of its declared count must have.
pub(super) fn is_binary(bytes: &[u8]) -> bool {
    declared(bytes).is_some_and(|(_, needed)| needed == bytes.len() as u64)
}

/// Begins with `solid` and, as far as we look, holds only text.
pub(super) fn is_ascii(bytes: &[u8]) -> bool {
    let start = bytes.iter().position(|b| !b.is_ascii_whitespace());
    let Some(start) = start else { return false };
    bytes[start..].starts_with(b"solid")
        && bytes[..bytes.len().min(SNIFF)]
            .iter()
            .all(|&b| b.is_ascii_graphic() || b.is_ascii_whitespace())
}

fn binary(bytes: &[u8]) -> Result<TriangleSoup, MeshReadError> {
    let Some((declared, needed)) = declared(bytes) else {
        return Err(MeshReadError::Truncated {
            format: Format::Stl,
            at: Location::Byte(bytes.len()),
            expected: "the 84-byte binary STL header with its facet count".into(),
        });
    };
    if needed != bytes.len() as u64 {
        return Err(MeshReadError::StlSize {
            declared,
            needed,
            actual: bytes.len() as u64,
        });
    }
    let n = declared as usize;
    let mut soup = TriangleSoup {
        positions: Vec::with_capacity(3 * n),
        triangles: Vec::with_capacity(n),
    };
    for (facet, record) in bytes[HEADER..].chunks_exact(RECORD).enumerate() {
        let base = HEADER + facet * RECORD;
        // Skip the stored normal (12 bytes); the three corners follow.
        for corner in 0..3 {
            let mut p = [0.0; 3];
            for (axis, c) in p.iter_mut().enumerate() {
                let at = 12 + 12 * corner + 4 * axis;
                let raw: [u8; 4] = record[at..at + 4].try_into().unwrap_or_default();
                *c = f64::from(f32::from_le_bytes(raw));
                if !c.is_finite() {
                    return Err(MeshReadError::NonFinite {
                        format: Format::Stl,
                        at: Location::Byte(base + at),
                        vertex: 3 * facet + corner,
                        value: *c,
                    });
                }
            }
            soup.positions.push(p);
        }
        let first = (3 * facet) as u32;
        soup.triangles.push([first, first + 1, first + 2]);
    }
    Ok(soup)
}

struct Ascii<'a> {
    tokens: Tokens<'a>,
    soup: TriangleSoup,
}

impl<'a> Ascii<'a> {
    fn next(&mut self, expected: &str) -> Result<(&'a [u8], usize), MeshReadError> {
        let line = self.tokens.line();
        self.tokens
            .next_token()
            .ok_or_else(|| MeshReadError::Truncated {
                format: Format::Stl,
                at: Location::Line(line),
                expected: expected.to_string(),
            })
    }

    fn keyword(&mut self, word: &str) -> Result<usize, MeshReadError> {
        let expected = format!("`{word}`");
        let (token, line) = self.next(&expected)?;
        if token == word.as_bytes() {
            Ok(line)
        } else {
            Err(unexpected(line, expected, token))
        }
    }

    fn number(&mut self, what: &str) -> Result<(f64, usize), MeshReadError> {
        let (token, line) = self.next(what)?;
        text::float(token)
            .map(|v| (v, line))
            .ok_or_else(|| unexpected(line, what.to_string(), token))
    }

    fn facet(&mut self) -> Result<(), MeshReadError> {
        let (token, line) = self.next("`normal` or `outer`")?;
        match token {
            b"normal" => {
                for _ in 0..3 {
                    self.number("a normal component")?;
                }
                self.keyword("outer")?;
            }
            b"outer" => {}
            _ => return Err(unexpected(line, "`normal` or `outer`".into(), token)),
        }
        self.keyword("loop")?;
        let first = self.soup.positions.len();
        loop {
            let (token, line) = self.next("`vertex` or `endloop`")?;
            match token {
                b"vertex" => {
                    let mut p = [0.0; 3];
                    for c in &mut p {
                        let (v, line) = self.number("a vertex coordinate")?;
                        if !v.is_finite() {
                            return Err(MeshReadError::NonFinite {
                                format: Format::Stl,
                                at: Location::Line(line),
                                vertex: self.soup.positions.len(),
                                value: v,
                            });
                        }
                        *c = v;
                    }
                    self.soup.positions.push(p);
                }
                b"endloop" if self.soup.positions.len() - first >= 3 => break,
                b"endloop" => {
                    return Err(unexpected(
                        line,
                        "at least three `vertex` lines".into(),
                        token,
                    ));
                }
                _ => return Err(unexpected(line, "`vertex` or `endloop`".into(), token)),
            }
        }
        let last = self.soup.positions.len() as u32 - 1;
        let first = first as u32;
        for i in first + 1..last {
            self.soup.triangles.push([first, i, i + 1]);
        }
        self.keyword("endfacet")?;
        Ok(())
    }
}

fn unexpected(line: usize, expected: String, found: &[u8]) -> MeshReadError {
    MeshReadError::Unexpected {
        format: Format::Stl,
        at: Location::Line(line),
        expected,
        found: text::show(found),
    }
}

fn ascii(bytes: &[u8]) -> Result<TriangleSoup, MeshReadError> {
    let mut r = Ascii {
        tokens: Tokens::new(bytes, 1),
        soup: TriangleSoup::default(),
    };
    // One or more `solid … endsolid` blocks.
    loop {
        let line = r.keyword("solid")?;
        r.tokens.skip_line(line); // the solid's name
        loop {
            let (token, line) = r.next("`facet` or `endsolid`")?;
            match token {
                b"facet" => r.facet()?,
                b"endsolid" => {
                    r.tokens.skip_line(line);
                    break;
                }
                _ => return Err(unexpected(line, "`facet` or `endsolid`".into(), token)),
            }
        }
        // Another block may follow; anything else after `endsolid` is an error.
        match r.tokens.clone().next_token() {
            None => return Ok(r.soup),
            Some((b"solid", _)) => {}
            Some((token, line)) => {
                return Err(unexpected(
                    line,
                    "`solid` or the end of the file".into(),
                    token,
                ));
            }
        }
    }
}
