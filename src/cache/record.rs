//! [`Record`]: what a node last built — its key, the description of that key, and the hash of its
//! output — stored as one JSON file per node, so the next build can explain a miss and `gc` knows
//! which entries are live.

use serde::{Deserialize, Serialize};

use crate::cache::content_hash::ContentHash;
use crate::cache::key::{Key, KeyDescription};

/// The last successful build of one node.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Record {
    pub node: String,
    pub key: Key,
    pub description: KeyDescription,
    pub output: ContentHash,
}

/// Escaped names longer than this are shortened and suffixed with a hash of the full name, to
/// stay well inside the common 255-byte file name limit (leaving room for ".json").
const MAX_ESCAPED_LEN: usize = 160;
/// How much of a long escaped name is kept, for the reader's benefit, before the hash.
const LONG_PREFIX_LEN: usize = 80;

/// A file name for `node`'s record that is safe on every common filesystem and distinct for
/// distinct node names, even on case-insensitive filesystems.
///
/// Lowercase ASCII letters, digits, `_`, `-` and non-leading `.` are kept; every other byte of
/// the UTF-8 (including uppercase letters, whose case a filesystem may fold, and `%` itself) is
/// written as `%XX`. That escaping is reversible, hence collision-free. A name whose escaping is
/// too long becomes `<prefix>~<blake3 of the node name>`; `~` is always escaped otherwise, so the
/// two forms never meet. The empty name becomes a lone `%`, which no escaping produces. No result
/// starts with a dot, so none is hidden or can be a temporary file.
pub(crate) fn file_name(node: &str) -> String {
    if node.is_empty() {
        return "%.json".to_owned();
    }
    let mut escaped = String::with_capacity(node.len());
    for (i, byte) in node.bytes().enumerate() {
        let keep = byte.is_ascii_lowercase()
            || byte.is_ascii_digit()
            || byte == b'_'
            || byte == b'-'
            || (byte == b'.' && i > 0);
        if keep {
            escaped.push(char::from(byte));
        } else {
            escaped.push_str(&format!("%{byte:02X}"));
        }
    }
    if escaped.len() > MAX_ESCAPED_LEN {
        // The escaped string is pure ASCII, so any byte index is a char boundary.
        escaped.truncate(LONG_PREFIX_LEN);
        escaped.push('~');
        escaped.push_str(&blake3::hash(node.as_bytes()).to_hex());
    }
    escaped.push_str(".json");
    escaped
}
