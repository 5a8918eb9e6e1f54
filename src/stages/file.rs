//! The `file` node: an input file's bytes brought into the graph. Every file a manifest names
//! as an input (a mesh, a crystal, a scaffold, a mesh an SDF program reads) is one.
//!
//! Invariants:
//! - A `file` node's hash is the blake3 hash of the file's bytes, so every stage reading it is
//!   keyed on the content, never on the path or the time: renaming or touching an input
//!   rebuilds nothing.
//! - The builder reads the file (`build.rs`); no stage opens a path. Its bytes are never
//!   cached: the file itself is their store.

/// Part of every key downstream of a `file` node, like any stage's version.
pub const VERSION: u32 = 1;

/// `file`: the bytes of an input file named in the manifest.
#[derive(Clone, Debug, PartialEq)]
pub struct FileStage {
    /// As written in the manifest, for messages.
    pub given: String,
    /// Resolved against the manifest's directory.
    pub path: std::path::PathBuf,
}
