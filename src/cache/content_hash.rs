//! [`ContentHash`]: the blake3 of some bytes — a stage's output or an external file.

use std::fmt;
use std::fs::File;
use std::io::BufReader;
use std::path::Path;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::cache::error::CacheError;
use crate::cache::hex32;

/// Payloads at least this large are hashed with `update_rayon`. Below it the cost of splitting
/// the work across threads outweighs the gain (blake3's own advice is "≥ 128 KiB"; we pick a
/// little more because the cores are shared with the stages themselves). The choice never
/// changes the hash: blake3's tree mode gives the same digest however the input is split.
const RAYON_THRESHOLD: usize = 1 << 20;

/// The blake3 digest of a byte string: an upstream stage's *output* bytes, or an external file's
/// content. Downstream keys are built from these rather than from upstream keys, so a rebuilt
/// stage that produces identical bytes stops the rebuild there (early cutoff).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(transparent)]
pub struct ContentHash(#[serde(with = "hex32")] [u8; 32]);

impl ContentHash {
    /// Hashes `bytes`, in parallel when they are large.
    pub fn of(bytes: &[u8]) -> ContentHash {
        ContentHash::of_parts(&[bytes])
    }

    /// Hashes `bytes` on the calling thread only. For threads outside the rayon pool that
    /// rayon workers wait on (the builder's chunk writer): asking the pool for help there
    /// deadlocks once every worker is blocked sending it chunks.
    pub fn of_serial(bytes: &[u8]) -> ContentHash {
        ContentHash(*blake3::hash(bytes).as_bytes())
    }

    /// Hashes the concatenation of `parts` without concatenating them.
    pub fn of_parts(parts: &[&[u8]]) -> ContentHash {
        let mut hasher = blake3::Hasher::new();
        for bytes in parts {
            if bytes.len() >= RAYON_THRESHOLD {
                hasher.update_rayon(bytes);
            } else {
                hasher.update(bytes);
            }
        }
        ContentHash(*hasher.finalize().as_bytes())
    }

    /// Hashes the content of an external file referenced by the manifest. Only the content is
    /// hashed — the path and mtime never enter a key, so moving or `touch`ing a file rebuilds
    /// nothing.
    pub fn of_file(path: &Path) -> Result<ContentHash, CacheError> {
        let io_err = |source| CacheError::io("read", path, source);
        let file = File::open(path).map_err(io_err)?;
        let mut hasher = blake3::Hasher::new();
        hasher
            .update_reader(BufReader::with_capacity(1 << 16, file))
            .map_err(io_err)?;
        Ok(ContentHash(*hasher.finalize().as_bytes()))
    }

    pub const fn from_bytes(bytes: [u8; 32]) -> ContentHash {
        ContentHash(bytes)
    }

    pub const fn as_bytes(&self) -> &[u8; 32] {
        &self.0
    }
}

impl fmt::Display for ContentHash {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&hex32::encode(&self.0))
    }
}

impl fmt::Debug for ContentHash {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "ContentHash({self})")
    }
}

impl FromStr for ContentHash {
    type Err = InvalidHex;

    fn from_str(text: &str) -> Result<ContentHash, InvalidHex> {
        hex32::decode(text).map(ContentHash).ok_or(InvalidHex)
    }
}

/// A digest's text was not exactly 64 lowercase hex digits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("expected 64 lowercase hex digits")]
pub struct InvalidHex;
