//! [`Param`]: one typed parameter value of a stage, with its canonical encoding and a readable
//! rendering.
//!
//! The canonical encoding is what enters a [`super::Key`]; the rendering only goes into
//! [`super::KeyDescription`] for humans. Every value is encoded as a one-byte type tag followed
//! by a fixed-width or length-prefixed body, so no two different values share an encoding:
//!
//! | variant  | tag  | body                                                    |
//! |----------|------|---------------------------------------------------------|
//! | `U64`    | 0x01 | 8 bytes little-endian                                   |
//! | `I64`    | 0x02 | 8 bytes little-endian two's complement                  |
//! | `F64`    | 0x03 | `f64::to_bits`, 8 bytes little-endian (0.0 ≠ −0.0; a NaN is its bits) |
//! | `Bool`   | 0x04 | 1 byte, 0 or 1                                          |
//! | `Str`    | 0x05 | u64 LE byte length, then the UTF-8 bytes                |
//! | `Bytes`  | 0x06 | u64 LE length, then the bytes                           |
//! | `List`   | 0x07 | u64 LE element count, then each element's encoding      |
//!
//! Changing any row changes every key; bump [`super::key`]'s context string if you ever must.

use std::fmt::Write as _;

/// A parameter value. There is deliberately no map variant: a map would bring an iteration order
/// with it. Pass a sorted `List` of pairs, or — better — give each entry its own parameter name.
#[derive(Clone, Debug, PartialEq)]
pub enum Param {
    U64(u64),
    I64(i64),
    F64(f64),
    Bool(bool),
    Str(String),
    Bytes(Vec<u8>),
    List(Vec<Param>),
}

const TAG_U64: u8 = 0x01;
const TAG_I64: u8 = 0x02;
const TAG_F64: u8 = 0x03;
const TAG_BOOL: u8 = 0x04;
const TAG_STR: u8 = 0x05;
const TAG_BYTES: u8 = 0x06;
const TAG_LIST: u8 = 0x07;

/// Renderings longer than this are cut, with "…": a description is for reading, and its hash
/// field still identifies the exact value.
const MAX_RENDERED_CHARS: usize = 160;

/// Short byte strings are shown in hex; longer ones only by length.
const MAX_HEX_BYTES: usize = 16;

impl Param {
    /// Appends the canonical encoding (see the module table) to `out`.
    pub(crate) fn encode(&self, out: &mut Vec<u8>) {
        match self {
            Param::U64(v) => {
                out.push(TAG_U64);
                out.extend_from_slice(&v.to_le_bytes());
            }
            Param::I64(v) => {
                out.push(TAG_I64);
                out.extend_from_slice(&v.to_le_bytes());
            }
            Param::F64(v) => {
                out.push(TAG_F64);
                out.extend_from_slice(&v.to_bits().to_le_bytes());
            }
            Param::Bool(v) => {
                out.push(TAG_BOOL);
                out.push(u8::from(*v));
            }
            Param::Str(s) => {
                out.push(TAG_STR);
                encode_len_prefixed(s.as_bytes(), out);
            }
            Param::Bytes(b) => {
                out.push(TAG_BYTES);
                encode_len_prefixed(b, out);
            }
            Param::List(items) => {
                out.push(TAG_LIST);
                encode_len(items.len(), out);
                for item in items {
                    item.encode(out);
                }
            }
        }
    }

    /// A human-readable rendering, at most [`MAX_RENDERED_CHARS`] characters. Two different values
    /// may render alike (`U64(1)` and `I64(1)`, two NaNs with the same payload class); the
    /// description's per-parameter hash tells them apart.
    pub(crate) fn render(&self) -> String {
        let mut out = String::new();
        self.render_into(&mut out);
        if out.chars().count() > MAX_RENDERED_CHARS {
            let cut: String = out.chars().take(MAX_RENDERED_CHARS - 1).collect();
            return cut + "…";
        }
        out
    }

    fn render_into(&self, out: &mut String) {
        // Rendering can be asked of a list of a million floats; stop early once the result is
        // going to be cut anyway, so a description stays cheap to build.
        if out.len() > 4 * MAX_RENDERED_CHARS {
            return;
        }
        // `write!` into a String cannot fail; the results are ignored for that reason.
        match self {
            Param::U64(v) => {
                let _ = write!(out, "{v}");
            }
            Param::I64(v) => {
                let _ = write!(out, "{v}");
            }
            Param::F64(v) => render_f64(*v, out),
            Param::Bool(v) => {
                let _ = write!(out, "{v}");
            }
            Param::Str(s) => {
                let _ = write!(out, "{s:?}");
            }
            Param::Bytes(b) if b.len() <= MAX_HEX_BYTES => {
                out.push_str("0x");
                for byte in b {
                    let _ = write!(out, "{byte:02x}");
                }
            }
            Param::Bytes(b) => {
                let _ = write!(out, "<{} bytes>", b.len());
            }
            Param::List(items) => {
                out.push('[');
                for (i, item) in items.iter().enumerate() {
                    if i > 0 {
                        out.push_str(", ");
                    }
                    item.render_into(out);
                    if out.len() > 4 * MAX_RENDERED_CHARS {
                        break;
                    }
                }
                out.push(']');
            }
        }
    }
}

/// Floats are shown by their shortest round-tripping decimal (`0.1`, `-0.0`, `1e300`), so what
/// is printed is what was hashed. NaNs other than the canonical quiet NaN show their bits, since
/// their bits are what the key sees.
fn render_f64(v: f64, out: &mut String) {
    const CANONICAL_NAN: u64 = 0x7ff8_0000_0000_0000;
    if v.is_nan() && v.to_bits() != CANONICAL_NAN {
        let _ = write!(out, "NaN(0x{:016x})", v.to_bits());
    } else {
        let _ = write!(out, "{v:?}");
    }
}

fn encode_len(len: usize, out: &mut Vec<u8>) {
    // usize → u64 is lossless on every supported target; the width is fixed so that a key is
    // the same on 32- and 64-bit machines.
    out.extend_from_slice(&(len as u64).to_le_bytes());
}

fn encode_len_prefixed(bytes: &[u8], out: &mut Vec<u8>) {
    encode_len(bytes.len(), out);
    out.extend_from_slice(bytes);
}

impl From<u64> for Param {
    fn from(v: u64) -> Param {
        Param::U64(v)
    }
}

impl From<u32> for Param {
    fn from(v: u32) -> Param {
        Param::U64(u64::from(v))
    }
}

/// `usize` counts (resolutions, divisions) are widened to `U64`, so a key never depends on the
/// machine's pointer width.
impl From<usize> for Param {
    fn from(v: usize) -> Param {
        Param::U64(v as u64)
    }
}

impl From<i64> for Param {
    fn from(v: i64) -> Param {
        Param::I64(v)
    }
}

impl From<i32> for Param {
    fn from(v: i32) -> Param {
        Param::I64(i64::from(v))
    }
}

impl From<f64> for Param {
    fn from(v: f64) -> Param {
        Param::F64(v)
    }
}

impl From<bool> for Param {
    fn from(v: bool) -> Param {
        Param::Bool(v)
    }
}

impl From<&str> for Param {
    fn from(v: &str) -> Param {
        Param::Str(v.to_owned())
    }
}

impl From<String> for Param {
    fn from(v: String) -> Param {
        Param::Str(v)
    }
}

impl From<&[u8]> for Param {
    fn from(v: &[u8]) -> Param {
        Param::Bytes(v.to_vec())
    }
}

impl From<Vec<u8>> for Param {
    fn from(v: Vec<u8>) -> Param {
        Param::Bytes(v)
    }
}

impl From<Vec<Param>> for Param {
    fn from(v: Vec<Param>) -> Param {
        Param::List(v)
    }
}

/// Fixed-size arrays (`[f64; 3]` bounds, `[u32; 3]` divisions) become lists.
impl<T: Into<Param>, const N: usize> From<[T; N]> for Param {
    fn from(v: [T; N]) -> Param {
        Param::List(v.into_iter().map(Into::into).collect())
    }
}
