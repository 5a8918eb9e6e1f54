//! Cache keys: what a stage's result depends on, hashed from a canonical encoding.
//!
//! A [`Key`] names a stage result in the store. It is the blake3 (in derive-key mode, with
//! [`KEY_CONTEXT`] as the context string) of the canonical encoding of exactly these things:
//!
//! | part                 | encoded as                                       | why it is in the key |
//! |----------------------|--------------------------------------------------|----------------------|
//! | stage kind           | u64 LE length + UTF-8                            | `fit` and `contour` with equal parameters are different results |
//! | stage version        | u32 LE                                           | bumped when an algorithm changes, so old results are not reused |
//! | parameters           | u64 LE count, then per parameter sorted by name: name (length + UTF-8) and the typed value (see [`Param`]) | every value that changes the output; sorted so that the order a stage or the manifest lists them in never matters |
//! | inputs               | u64 LE count, then per input sorted by name: name and the 32-byte [`ContentHash`] of its bytes | upstream *outputs* by content: identical upstream bytes ⇒ identical key (early cutoff), and an external file enters by content only |
//!
//! What never enters a key: file paths, mtimes, thread or shard counts, the machine, hash-map
//! iteration order, or `{:?}` renderings of floats. A key computed on a laptop with 2 threads and
//! on a cluster node with 64 is the same, which is what lets results be shared later. Floats
//! enter by bit pattern: `0.0` and `-0.0` are different keys, and a NaN is its bits.
//!
//! Alongside the key, [`KeyBuilder::build`] returns a [`KeyDescription`] — the same facts in
//! readable, serializable form — that the cache records per node, so that [`explain`] can say
//! *why* a key changed (`latticebuild build -v`).

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::cache::content_hash::{ContentHash, InvalidHex};
use crate::cache::hex32;
use crate::cache::param::Param;

/// The derive-key context of every key. Changing the encoding in any way (this module's table or
/// [`Param`]'s) must change this string, so that no old entry is ever read under a new meaning.
/// The stability test in `key_tests.rs` pins one literal key to catch accidental changes.
pub const KEY_CONTEXT: &str = "latticebuild 2026-01 stage cache key, encoding v1";

/// The identity of a stage result: 32 bytes, shown as 64 lowercase hex digits.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Key(#[serde(with = "hex32")] [u8; 32]);

impl Key {
    pub const fn from_bytes(bytes: [u8; 32]) -> Key {
        Key(bytes)
    }

    pub const fn as_bytes(&self) -> &[u8; 32] {
        &self.0
    }
}

impl fmt::Display for Key {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&hex32::encode(&self.0))
    }
}

impl fmt::Debug for Key {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Key({self})")
    }
}

impl FromStr for Key {
    type Err = InvalidHex;

    fn from_str(text: &str) -> Result<Key, InvalidHex> {
        hex32::decode(text).map(Key).ok_or(InvalidHex)
    }
}

/// A stage gave two parameters (or two inputs) the same name. That is a bug in the stage, not a
/// user error; it is an error rather than a panic so the CLI can report it with the manifest name.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum KeyError {
    #[error("stage `{kind}` was given the parameter `{name}` twice")]
    DuplicateParameter { kind: String, name: String },
    #[error("stage `{kind}` was given the input `{name}` twice")]
    DuplicateInput { kind: String, name: String },
}

/// Collects everything a stage result depends on; [`KeyBuilder::build`] produces its [`Key`].
///
/// ```
/// use latticebuild::cache::{ContentHash, KeyBuilder};
/// let cell = ContentHash::of(b"fitted cell bytes");
/// let (key, description) = KeyBuilder::new("contour", 1)
///     .param("offset", 0.1)
///     .param("resolution", 64u32)
///     .input("cell", cell)
///     .build()
///     .unwrap();
/// assert_eq!(key.to_string().len(), 64);
/// assert_eq!(description.params[0].value, "0.1");
/// ```
#[derive(Clone, Debug)]
pub struct KeyBuilder {
    kind: String,
    version: u32,
    params: Vec<(String, Param)>,
    inputs: Vec<(String, ContentHash)>,
}

impl KeyBuilder {
    /// `version` is the stage's algorithm version: bump it whenever the stage would produce
    /// different bytes from the same parameters and inputs.
    pub fn new(kind: &str, version: u32) -> KeyBuilder {
        KeyBuilder {
            kind: kind.to_owned(),
            version,
            params: Vec::new(),
            inputs: Vec::new(),
        }
    }

    /// Adds a named parameter. The order of calls does not matter.
    pub fn param(mut self, name: &str, value: impl Into<Param>) -> KeyBuilder {
        self.params.push((name.to_owned(), value.into()));
        self
    }

    /// Adds a named input by the content hash of its bytes (an upstream stage's output, or an
    /// external file's content). The order of calls does not matter.
    pub fn input(mut self, name: &str, hash: ContentHash) -> KeyBuilder {
        self.inputs.push((name.to_owned(), hash));
        self
    }

    /// Hashes the canonical encoding (see the module table) into a [`Key`], and describes it.
    pub fn build(mut self) -> Result<(Key, KeyDescription), KeyError> {
        // Sorting by name (byte order of the UTF-8) is what makes insertion order irrelevant.
        // Names are unique, so the sort needs no tie-break to be deterministic.
        self.params.sort_by(|a, b| a.0.cmp(&b.0));
        self.inputs.sort_by(|a, b| a.0.cmp(&b.0));
        if let Some(pair) = self.params.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(KeyError::DuplicateParameter {
                kind: self.kind,
                name: pair[0].0.clone(),
            });
        }
        if let Some(pair) = self.inputs.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(KeyError::DuplicateInput {
                kind: self.kind,
                name: pair[0].0.clone(),
            });
        }

        let mut hasher = blake3::Hasher::new_derive_key(KEY_CONTEXT);
        let mut scratch = Vec::new();
        hash_str(&mut hasher, &self.kind);
        hasher.update(&self.version.to_le_bytes());

        hasher.update(&(self.params.len() as u64).to_le_bytes());
        let mut params = Vec::with_capacity(self.params.len());
        for (name, value) in &self.params {
            scratch.clear();
            value.encode(&mut scratch);
            hash_str(&mut hasher, name);
            hasher.update(&scratch);
            params.push(ParamDescription {
                name: name.clone(),
                value: value.render(),
                hash: ContentHash::of(&scratch),
            });
        }

        hasher.update(&(self.inputs.len() as u64).to_le_bytes());
        let mut inputs = Vec::with_capacity(self.inputs.len());
        for (name, hash) in &self.inputs {
            hash_str(&mut hasher, name);
            hasher.update(hash.as_bytes());
            inputs.push(InputDescription {
                name: name.clone(),
                hash: *hash,
            });
        }

        let key = Key(*hasher.finalize().as_bytes());
        let description = KeyDescription {
            kind: self.kind,
            version: self.version,
            params,
            inputs,
        };
        Ok((key, description))
    }
}

fn hash_str(hasher: &mut blake3::Hasher, s: &str) {
    hasher.update(&(s.len() as u64).to_le_bytes());
    hasher.update(s.as_bytes());
}

/// Everything that went into a [`Key`], readable: recorded per node so that a later build can
/// [`explain`] a miss. Parameters and inputs are sorted by name.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct KeyDescription {
    pub kind: String,
    pub version: u32,
    pub params: Vec<ParamDescription>,
    pub inputs: Vec<InputDescription>,
}

#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ParamDescription {
    pub name: String,
    /// For reading only (may be shortened with "…"); never compared to decide a change.
    pub value: String,
    /// blake3 of the value's canonical encoding: this, not `value`, says whether it changed.
    pub hash: ContentHash,
}

#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct InputDescription {
    pub name: String,
    pub hash: ContentHash,
}

/// Why a key changed from `prev` to `now`, one line per difference, in a fixed order: kind,
/// version, parameters by name, inputs by name. Empty when the descriptions agree.
///
/// Lines look like `parameter `offset` changed: 0.1 → 0.2`, `input `cell` changed`,
/// `stage version changed: 1 → 2`, `parameter `formats` added: ["stl"]`.
pub fn explain(prev: &KeyDescription, now: &KeyDescription) -> Vec<String> {
    let mut lines = Vec::new();
    if prev.kind != now.kind {
        lines.push(format!("stage kind changed: {} → {}", prev.kind, now.kind));
    }
    if prev.version != now.version {
        lines.push(format!(
            "stage version changed: {} → {}",
            prev.version, now.version
        ));
    }

    // Descriptions read back from disk may come from an older build or be hand-edited, so do
    // not rely on their order: index both sides by name.
    let before: BTreeMap<&str, &ParamDescription> =
        prev.params.iter().map(|p| (p.name.as_str(), p)).collect();
    let after: BTreeMap<&str, &ParamDescription> =
        now.params.iter().map(|p| (p.name.as_str(), p)).collect();
    for name in union_of_keys(&before, &after) {
        match (before.get(name), after.get(name)) {
            (Some(old), Some(new)) if old.hash != new.hash => {
                let note = if old.value == new.value {
                    " (same text, different type or bits)"
                } else {
                    ""
                };
                lines.push(format!(
                    "parameter `{name}` changed: {} → {}{note}",
                    old.value, new.value
                ));
            }
            (Some(old), None) => {
                lines.push(format!("parameter `{name}` removed (was {})", old.value));
            }
            (None, Some(new)) => {
                lines.push(format!("parameter `{name}` added: {}", new.value));
            }
            _ => {}
        }
    }

    let before: BTreeMap<&str, ContentHash> = prev
        .inputs
        .iter()
        .map(|i| (i.name.as_str(), i.hash))
        .collect();
    let after: BTreeMap<&str, ContentHash> = now
        .inputs
        .iter()
        .map(|i| (i.name.as_str(), i.hash))
        .collect();
    for name in union_of_keys(&before, &after) {
        match (before.get(name), after.get(name)) {
            (Some(old), Some(new)) if old != new => {
                lines.push(format!("input `{name}` changed"));
            }
            (Some(_), None) => lines.push(format!("input `{name}` removed")),
            (None, Some(_)) => lines.push(format!("input `{name}` added")),
            _ => {}
        }
    }
    lines
}

fn union_of_keys<'a, V>(a: &BTreeMap<&'a str, V>, b: &BTreeMap<&'a str, V>) -> Vec<&'a str> {
    let mut names: Vec<&str> = a.keys().chain(b.keys()).copied().collect();
    names.sort_unstable();
    names.dedup();
    names
}
