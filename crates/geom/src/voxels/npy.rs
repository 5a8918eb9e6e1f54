//! The NumPy `.npy` container: a magic, a version, and a header that is a Python dict literal
//! (`{'descr': '<f4', 'fortran_order': False, 'shape': (64, 64, 64), }`) padded with spaces,
//! followed by the array's bytes.
//!
//! We parse the header ourselves: it is a tiny subset of Python literals (strings, booleans,
//! tuples of integers), and the crates that read `.npy` bring an n-dimensional array type we
//! would convert out of at once. Invariants: no input panics; the keys may come in any order
//! and with either quote; anything else in the dict is an error naming it.

use super::{VoxelError, VoxelType};

const MAGIC: &[u8] = b"\x93NUMPY";

/// What the header says about the array, and where its bytes begin.
#[derive(Debug, PartialEq)]
pub(super) struct NpyHeader {
    pub dtype: VoxelType,
    pub big_endian: bool,
    pub fortran_order: bool,
    pub shape: Vec<u64>,
    pub data_start: usize,
}

fn malformed(what: impl Into<String>) -> VoxelError {
    VoxelError::NpyHeader(what.into())
}

/// Reads the header of an `.npy` file.
pub(super) fn header(bytes: &[u8]) -> Result<NpyHeader, VoxelError> {
    if !bytes.starts_with(MAGIC) {
        return Err(VoxelError::NotNpy);
    }
    let (major, minor) = match bytes.get(6..8) {
        Some(&[a, b]) => (a, b),
        _ => return Err(malformed("the file ends inside the version")),
    };
    let (len_size, encoding_utf8) = match major {
        1 => (2, false),
        2 => (4, false),
        3 => (4, true),
        _ => return Err(malformed(format!("unknown format version {major}.{minor}"))),
    };
    let len_bytes = bytes
        .get(8..8 + len_size)
        .ok_or_else(|| malformed("the file ends inside the header length"))?;
    let mut len = 0usize;
    for (i, b) in len_bytes.iter().enumerate() {
        len |= usize::from(*b) << (8 * i);
    }
    let start = 8 + len_size;
    let text = bytes.get(start..start.saturating_add(len)).ok_or_else(|| {
        malformed(format!(
            "it declares {len} bytes of header, but the file ends after {}",
            bytes.len().saturating_sub(start)
        ))
    })?;
    let text = std::str::from_utf8(text)
        .ok()
        .filter(|t| encoding_utf8 || t.is_ascii())
        .ok_or_else(|| malformed("the header is not text"))?;
    let dict = Parser { text, pos: 0 }.dict()?;
    let (mut descr, mut fortran, mut shape) = (None, None, None);
    for (key, value) in dict {
        match (key.as_str(), value) {
            ("descr", Literal::Str(s)) => descr = Some(s),
            ("fortran_order", Literal::Bool(b)) => fortran = Some(b),
            ("shape", Literal::Tuple(t)) => shape = Some(t),
            ("descr" | "fortran_order" | "shape", other) => {
                return Err(malformed(format!("`{key}` has the wrong type: {other:?}")));
            }
            _ => return Err(malformed(format!("unknown key `{key}`"))),
        }
    }
    let descr = descr.ok_or_else(|| malformed("no `descr`"))?;
    let (dtype, big_endian) = dtype_of(&descr)?;
    Ok(NpyHeader {
        dtype,
        big_endian,
        fortran_order: fortran.ok_or_else(|| malformed("no `fortran_order`"))?,
        shape: shape.ok_or_else(|| malformed("no `shape`"))?,
        data_start: start + len,
    })
}

/// A NumPy type string (`<f4`, `|u1`, `>i2`…) as a voxel type and its byte order.
fn dtype_of(descr: &str) -> Result<(VoxelType, bool), VoxelError> {
    let unsupported = || VoxelError::NpyType(descr.to_string());
    let (order, code) = match descr.as_bytes().first() {
        Some(b'<' | b'>' | b'|' | b'=') => descr.split_at(1),
        _ => ("=", descr),
    };
    let dtype = match code {
        "u1" | "b1" => VoxelType::U8,
        "u2" => VoxelType::U16,
        "i2" => VoxelType::I16,
        "f4" => VoxelType::F32,
        "f8" => VoxelType::F64,
        _ => return Err(unsupported()),
    };
    // `=` is the writer's native order; every platform NumPy writes `.npy` on names it
    // explicitly, so `=` only appears by hand and is read as little-endian.
    Ok((dtype, order == ">"))
}

#[derive(Debug)]
enum Literal {
    Str(String),
    Bool(bool),
    Tuple(Vec<u64>),
}

struct Parser<'a> {
    text: &'a str,
    pos: usize,
}

impl Parser<'_> {
    fn skip_space(&mut self) {
        let rest = &self.text[self.pos..];
        self.pos += rest.len() - rest.trim_start().len();
    }

    fn peek(&mut self) -> Option<char> {
        self.skip_space();
        self.text[self.pos..].chars().next()
    }

    fn expect(&mut self, c: char) -> Result<(), VoxelError> {
        match self.peek() {
            Some(found) if found == c => {
                self.pos += c.len_utf8();
                Ok(())
            }
            found => Err(malformed(format!(
                "expected `{c}` at byte {}, found {}",
                self.pos,
                found.map_or("the end".to_string(), |f| format!("`{f}`"))
            ))),
        }
    }

    fn dict(&mut self) -> Result<Vec<(String, Literal)>, VoxelError> {
        self.expect('{')?;
        let mut entries = Vec::new();
        loop {
            if self.peek() == Some('}') {
                self.pos += 1;
                return Ok(entries);
            }
            let key = self.string()?;
            self.expect(':')?;
            let value = self.literal()?;
            entries.push((key, value));
            if self.peek() == Some(',') {
                self.pos += 1;
            } else {
                self.expect('}')?;
                return Ok(entries);
            }
        }
    }

    fn string(&mut self) -> Result<String, VoxelError> {
        let quote = match self.peek() {
            Some(q @ ('\'' | '"')) => q,
            _ => return Err(malformed(format!("expected a string at byte {}", self.pos))),
        };
        let body = &self.text[self.pos + 1..];
        let end = body
            .find(quote)
            .ok_or_else(|| malformed("a string is not closed"))?;
        self.pos += end + 2;
        Ok(body[..end].to_string())
    }

    fn literal(&mut self) -> Result<Literal, VoxelError> {
        match self.peek() {
            Some('\'' | '"') => Ok(Literal::Str(self.string()?)),
            Some('(') => self.tuple(),
            _ => {
                let rest = &self.text[self.pos..];
                for (word, value) in [("True", true), ("False", false)] {
                    if rest.starts_with(word) {
                        self.pos += word.len();
                        return Ok(Literal::Bool(value));
                    }
                }
                Err(malformed(format!(
                    "expected a string, a boolean or a tuple at byte {}",
                    self.pos
                )))
            }
        }
    }

    fn tuple(&mut self) -> Result<Literal, VoxelError> {
        self.expect('(')?;
        let mut items = Vec::new();
        loop {
            if self.peek() == Some(')') {
                self.pos += 1;
                return Ok(Literal::Tuple(items));
            }
            let rest = &self.text[self.pos..];
            let digits = rest.len() - rest.trim_start_matches(|c: char| c.is_ascii_digit()).len();
            let value = rest[..digits]
                .parse::<u64>()
                .map_err(|_| malformed(format!("expected a size at byte {}", self.pos)))?;
            self.pos += digits;
            // Python writes `3L` for a long in old files.
            if self.text[self.pos..].starts_with('L') {
                self.pos += 1;
            }
            items.push(value);
            if self.peek() == Some(',') {
                self.pos += 1;
            } else {
                self.expect(')')?;
                return Ok(Literal::Tuple(items));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(dict: &str) -> Vec<u8> {
        let mut out = MAGIC.to_vec();
        out.extend([1, 0]);
        out.extend((dict.len() as u16).to_le_bytes());
        out.extend(dict.as_bytes());
        out
    }

    #[test]
    fn reads_numpys_own_header_in_any_key_order() {
        let h = header(&file(
            "{'descr': '<f4', 'fortran_order': False, 'shape': (4, 5, 6), }   \n",
        ))
        .expect("header");
        assert_eq!(h.dtype, VoxelType::F32);
        assert!(!h.big_endian && !h.fortran_order);
        assert_eq!(h.shape, vec![4, 5, 6]);
        let h = header(&file(
            "{\"shape\": (2,), \"fortran_order\": True, \"descr\": \">u2\"}",
        ))
        .expect("header");
        assert_eq!(
            (h.dtype, h.big_endian, h.fortran_order),
            (VoxelType::U16, true, true)
        );
        assert_eq!(h.shape, vec![2]);
    }

    #[test]
    fn malformed_headers_say_what_is_wrong() {
        let err = |d: &str| header(&file(d)).expect_err(d).to_string();
        assert!(
            err("{'descr': '<c16', 'fortran_order': False, 'shape': (2, 2, 2)}").contains("`<c16`")
        );
        assert!(err("{'descr': '<f4', 'shape': (2, 2, 2)}").contains("no `fortran_order`"));
        assert!(err("{'descr': '<f4', 'fortran_order': Maybe}").contains("a boolean"));
        assert!(err("{'descr': '<f4' 'shape': (2,)}").contains("expected `}`"));
        assert_eq!(header(b"PK\x03\x04"), Err(VoxelError::NotNpy));
        let mut cut = file("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2, 2)}");
        cut.truncate(20);
        assert!(
            header(&cut)
                .expect_err("cut")
                .to_string()
                .contains("declares")
        );
    }
}
