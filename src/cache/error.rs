//! [`CacheError`]: what went wrong, and which path it happened at.

use std::io;
use std::path::{Path, PathBuf};

/// A failure of the cache's own filesystem work. Corrupt entries are *not* errors — they are
/// reported as [`super::Lookup::Corrupt`] and rebuilt — so an error here means the cache could
/// not do its job at all (permissions, a full disk, a path that is not a directory…).
#[derive(Debug, thiserror::Error)]
pub enum CacheError {
    #[error("cannot {action} `{}`: {source}", path.display())]
    Io {
        /// What the cache was doing, as a verb phrase: "create directory", "rename into".
        action: &'static str,
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    #[error("manifest path `{}` does not name a file", path.display())]
    NotAManifestFile { path: PathBuf },
    #[error("cannot encode the build record `{}`: {source}", path.display())]
    Record {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
}

impl CacheError {
    pub(crate) fn io(action: &'static str, path: &Path, source: io::Error) -> CacheError {
        CacheError::Io {
            action,
            path: path.to_path_buf(),
            source,
        }
    }
}
