//! Whole-or-absent file writes: write a uniquely named temporary file in the destination's
//! directory, then `rename` it over the destination.
//!
//! `rename` within one directory is atomic on the filesystems we support, so a reader sees the
//! old file, the new file, or nothing — never a prefix. Two writers of the same destination both
//! succeed; the last rename wins, and since both wrote the same bytes (same key) either is right.

use std::collections::hash_map::RandomState;
use std::fs::{self, File, OpenOptions};
use std::hash::{BuildHasher, Hasher};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::cache::error::CacheError;
use crate::interrupt::Temporary;

/// Every temporary file starts with this. It begins with a dot, so it can never be mistaken for
/// an object (64 hex digits) or a record (escaped names never start with a dot).
pub(crate) const TEMP_PREFIX: &str = ".tmp-";

static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// `.tmp-<pid>-<counter>-<random>`: the pid separates processes (and lets `gc` recognise files
/// left by a crashed one), the counter separates threads of this process, and the random part
/// guards against a pid reused by a later process while an old temp file still lies around.
pub(crate) fn temp_name() -> String {
    let counter = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    // `RandomState` is seeded randomly per process (and perturbed per instance), which is all
    // the randomness a unique-enough suffix needs, without another dependency.
    let mut hasher = RandomState::new().build_hasher();
    hasher.write_u64(counter);
    let random = hasher.finish();
    format!(
        "{TEMP_PREFIX}{}-{counter}-{random:016x}",
        std::process::id()
    )
}

/// The pid embedded in a temp file name, if `name` is one of ours.
pub(crate) fn temp_owner_pid(name: &str) -> Option<u32> {
    let rest = name.strip_prefix(TEMP_PREFIX)?;
    rest.split('-').next()?.parse().ok()
}

/// Deletes the temporary file unless it was renamed into place, so a failed or panicking write
/// leaves nothing behind.
pub(crate) struct TempFile {
    path: PathBuf,
    persisted: bool,
    /// Dropped after `Drop::drop` has removed an unpersisted file.
    _registered: Temporary,
}

impl TempFile {
    /// A new, empty temporary file beside `destination`, opened for reading and writing.
    pub(crate) fn beside(destination: &Path) -> Result<(TempFile, File), CacheError> {
        let dir = destination.parent().unwrap_or(Path::new("."));
        let path = dir.join(temp_name());
        let temp = TempFile {
            _registered: Temporary::register(&path),
            path,
            persisted: false,
        };
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&temp.path)
            .map_err(|e| CacheError::io("create", &temp.path, e))?;
        Ok((temp, file))
    }

    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// Renames the file (closed by the caller first) over `destination`.
    pub(crate) fn persist(mut self, destination: &Path) -> Result<(), CacheError> {
        fs::rename(&self.path, destination)
            .map_err(|e| CacheError::io("rename into place", destination, e))?;
        self.persisted = true;
        Ok(())
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if !self.persisted {
            // Nothing useful can be done if this fails; `gc` removes stale temp files later.
            let _ = fs::remove_file(&self.path);
        }
    }
}

/// Writes `destination` whole or not at all. `write` fills a `BufWriter` of `buffer` bytes.
///
/// There is no fsync, on purpose: it would cost more than a whole small stage. If the machine
/// crashes, a renamed entry may be left with missing or zeroed data, but every cache entry carries
/// the blake3 of its payload (and records are parsed as JSON), so such an entry is detected on
/// the next read and rebuilt. A cache may lose work in a crash; it never returns wrong bytes.
pub(crate) fn write_atomically(
    destination: &Path,
    buffer: usize,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> Result<(), CacheError> {
    let (temp, file) = TempFile::beside(destination)?;
    let mut writer = BufWriter::with_capacity(buffer, file);
    write(&mut writer)
        .and_then(|()| writer.flush())
        .map_err(|e| CacheError::io("write", &temp.path, e))?;
    // Close before renaming: some platforms refuse to rename an open file.
    drop(writer);
    temp.persist(destination)
}
