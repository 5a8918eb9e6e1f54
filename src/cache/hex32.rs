//! Lowercase hex for the 32-byte digests ([`super::Key`], [`super::ContentHash`]).
//!
//! One spelling only: object file names and record fields are compared as strings, so a digest
//! must have exactly one textual form. Uppercase is rejected rather than folded.

use serde::{Deserialize, Deserializer, Serializer};

/// The canonical text of a digest: 64 lowercase hex digits.
pub(crate) fn encode(bytes: &[u8; 32]) -> String {
    blake3::Hash::from_bytes(*bytes).to_hex().to_string()
}

/// Parses exactly 64 lowercase hex digits; anything else (including uppercase) is `None`.
pub(crate) fn decode(text: &str) -> Option<[u8; 32]> {
    let canonical = text.len() == 64
        && text
            .bytes()
            .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b));
    if !canonical {
        return None;
    }
    blake3::Hash::from_hex(text).ok().map(|h| *h.as_bytes())
}

pub(crate) fn serialize<S: Serializer>(bytes: &[u8; 32], serializer: S) -> Result<S::Ok, S::Error> {
    serializer.serialize_str(&encode(bytes))
}

pub(crate) fn deserialize<'de, D: Deserializer<'de>>(
    deserializer: D,
) -> Result<[u8; 32], D::Error> {
    let text = String::deserialize(deserializer)?;
    decode(&text).ok_or_else(|| {
        serde::de::Error::custom(format!("expected 64 lowercase hex digits, found {text:?}"))
    })
}
