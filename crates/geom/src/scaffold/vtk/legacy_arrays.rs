//! Reading past the arrays of a legacy `.vtk` file that are not kept: values of any type
//! (numbers, VTK's packed bits, length-prefixed or line-per-value strings) and the `METADATA`
//! block VTK 9 writes after an array.
//!
//! Invariants: nothing here interprets a value (a NaN in an unused array is fine); every count
//! must fit in the bytes that follow before anything is read; no panic on any input.

use super::scalar_type;
use crate::scaffold::ScaffoldError;
use crate::scaffold::cursor::{Cursor, show};
use crate::scalar::Scalar;

/// An array's data type: a number, VTK's packed bits, or strings.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum ArrayType {
    Number(Scalar),
    Bit,
    Text,
}

/// Reads past `count` values of type `ty` (header at `at`) without interpreting them.
pub(super) fn skip_values(
    cur: &mut Cursor<'_>,
    binary: bool,
    ty: ArrayType,
    count: usize,
    at: usize,
) -> Result<(), ScaffoldError> {
    let what = "the number of values";
    match (ty, binary) {
        (ArrayType::Number(s), true) => {
            let n = cur.check_count(at, count as u64, what, s.size())?;
            cur.take(n * s.size(), "the array's values")?;
        }
        (ArrayType::Bit, true) => {
            cur.take(count.div_ceil(8), "the array's bits")?;
        }
        (ArrayType::Number(_) | ArrayType::Bit, false) => {
            let n = cur.check_count(at, count as u64, what, 2)?;
            for _ in 0..n {
                cur.token("a value")?;
            }
        }
        (ArrayType::Text, true) => {
            let n = cur.check_count(at, count as u64, what, 1)?;
            for _ in 0..n {
                let len = string_length(cur)?;
                cur.take(len, "a string")?;
            }
        }
        (ArrayType::Text, false) => {
            // One (escaped) string per line, empty strings as empty lines.
            let n = cur.check_count(at, count as u64, what, 1)?;
            cur.skip_line();
            for _ in 0..n {
                if cur.remaining() == 0 {
                    return Err(cur.eof("a string"));
                }
                cur.skip_line();
            }
        }
    }
    Ok(())
}

/// A binary string's length: VTK writes it big-endian in 1, 2, 4 or 8 bytes, the top two bits
/// of the first byte saying which (11, 10, 01, 00).
fn string_length(cur: &mut Cursor<'_>) -> Result<usize, ScaffoldError> {
    let at = cur.pos;
    let first = cur.take(1, "a string's length")?[0];
    let (extra, bits) = match first >> 6 {
        3 => (0, 6),
        2 => (1, 14),
        1 => (3, 30),
        _ => (7, 64),
    };
    let mut v = u64::from(first & 0x3f);
    for &b in cur.take(extra, "a string's length")? {
        v = v << 8 | u64::from(b);
    }
    if bits < 64 {
        v &= (1u64 << bits) - 1;
    }
    usize::try_from(v).map_err(|_| cur.error(at, format!("string length {v} too large")))
}

/// Reads past a `METADATA` block if one is next (VTK 9 writes one after an array with
/// component names or information keys): lines up to an empty one, where COMPONENT_NAMES is
/// followed by one line per component (a name may be empty).
pub(super) fn skip_metadata(cur: &mut Cursor<'_>, components: usize) {
    let save = cur.pos;
    match cur.next_token() {
        Some((_, t)) if t.eq_ignore_ascii_case(b"METADATA") => cur.skip_line(),
        _ => {
            cur.pos = save;
            return;
        }
    }
    let bytes = cur.bytes();
    while cur.remaining() > 0 {
        let start = cur.pos;
        cur.skip_line();
        let line = &bytes[start..cur.pos];
        let text = line.trim_ascii();
        if text.is_empty() {
            break;
        }
        if text.len() >= 15 && text[..15].eq_ignore_ascii_case(b"COMPONENT_NAMES") {
            for _ in 0..components {
                if cur.remaining() == 0 {
                    break;
                }
                cur.skip_line();
            }
        }
    }
}

/// A data type name of an array: a number type, `bit`, or `string`.
pub(super) fn array_type(cur: &mut Cursor<'_>, what: &str) -> Result<ArrayType, ScaffoldError> {
    let (at, ty) = cur.token(what)?;
    if ty.eq_ignore_ascii_case(b"bit") {
        return Ok(ArrayType::Bit);
    }
    if ty.eq_ignore_ascii_case(b"string") || ty.eq_ignore_ascii_case(b"utf8_string") {
        return Ok(ArrayType::Text);
    }
    scalar_type(ty)
        .map(ArrayType::Number)
        .ok_or_else(|| cur.error(at, format!("unknown VTK data type `{}`", show(ty))))
}
