//! The content-addressed stage cache under `.latticebuild/`.
//!
//! A manifest `dir/lattice.toml` has its cache in `dir/.latticebuild/lattice.toml/`:
//!
//! ```text
//! .latticebuild/
//!   CACHEDIR.TAG, .gitignore          so backups and git skip the cache
//!   lattice.toml/
//!     lock                            held exclusively by the one build using this cache
//!     objects/ab/ab12…ef              entries: header + payload (see `store.rs`)
//!     records/contour%3Aoutputs.g.json  per node: last key, its description, output hash
//! ```
//!
//! Entries of every key a node was built with stay (an optimizer that comes back to a value
//! finds it) until the objects outgrow the size limit: [`Cache::gc`] then removes the least
//! recently used that this build did not use (`lru.rs`).
//!
//! How a stage uses it: build a [`Key`] with [`KeyBuilder`] from the stage kind and version, its
//! parameters and the [`ContentHash`]es of its inputs; [`Cache::get`] it; on a miss run the stage,
//! [`Cache::put`] the output, and [`Cache::record`] the node. Under `-v`, [`explain`] the
//! difference between [`Cache::previous`] and the new description.
//!
//! Invariants:
//! - Entries are whole or absent. They are written to a temporary file and renamed into place;
//!   every `get` verifies length and blake3, and a corrupt entry is reported, removed and rebuilt.
//! - Keys never include absolute paths, mtimes or thread counts (the table in [`key`] lists
//!   what they do include; input files enter by the hash of their bytes, and the one path is
//!   the write stage's output path relative to `out_dir`): the same work has the same key on
//!   every machine, which keeps a shared remote [`Store`] possible.
//! - One build per cache at a time: [`Cache`] holds an exclusive lock on `lock` for its lifetime.
//!   Within that build, any number of threads may `get`/`put` concurrently.
//! - Stages never reach the cache's files: they are pure functions of bytes, and the builder
//!   moves those bytes in and out of here.
//! - A corrupt or foreign cache directory is never a panic: at worst a miss or a [`CacheError`].

mod atomic;
mod content_hash;
mod error;
mod hex32;
pub mod key;
mod lru;
pub mod param;
mod record;
pub mod store;

#[cfg(test)]
mod cache_tests;
#[cfg(test)]
mod key_tests;
#[cfg(test)]
mod store_tests;

use std::collections::HashSet;
use std::ffi::OsStr;
use std::fs::{self, File, OpenOptions, TryLockError};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

pub use content_hash::{ContentHash, InvalidHex};
pub use error::CacheError;
pub use key::{
    InputDescription, KEY_CONTEXT, Key, KeyBuilder, KeyDescription, KeyError, ParamDescription,
    explain,
};
pub use lru::{Collected, SizeLimit};
pub use param::Param;
pub use record::Record;
pub use store::{
    Corruption, EntryReader, FORMAT_VERSION, LocalStore, Lookup, Opened, PendingEntry, Store,
};

use crate::cache::atomic::write_atomically;

/// The cache of one manifest, locked for this build. `Send + Sync`: share it by reference
/// between the threads executing the graph.
#[derive(Debug)]
pub struct Cache {
    dir: PathBuf,
    store: LocalStore,
    records: PathBuf,
    /// Held (exclusively locked) for the Cache's lifetime; the OS releases the lock when the file
    /// is closed on drop, including when the process dies.
    _lock: File,
}

const LOCK_FILE: &str = "lock";
const CACHEDIR_TAG: &str = "Signature: 8a477f597d28d172789f06886806bc55\n\
# This file is a cache directory tag created by latticebuild.\n\
# For information about cache directory tags see https://bford.info/cachedir/\n";

impl Cache {
    /// Opens (creating as needed) the cache of the manifest at `manifest_path`, waiting silently
    /// if another build holds it.
    pub fn open(manifest_path: &Path) -> Result<Cache, CacheError> {
        Cache::open_with(manifest_path, || {})
    }

    /// Like [`Cache::open`], but if another build (another process, or another `Cache` in this
    /// one) holds the lock, calls `on_wait` once before blocking — so the CLI can print "waiting
    /// for another build of lattice.toml…". `on_wait` is not called when the lock is free.
    pub fn open_with(manifest_path: &Path, on_wait: impl FnOnce()) -> Result<Cache, CacheError> {
        let not_a_file = || CacheError::NotAManifestFile {
            path: manifest_path.to_path_buf(),
        };
        let file_name = manifest_path.file_name().ok_or_else(not_a_file)?;
        // A bare `lattice.toml` has an empty parent, which means the current directory.
        let manifest_dir = match manifest_path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let root = manifest_dir.join(".latticebuild");
        let dir = root.join(file_name);
        fs::create_dir_all(&dir).map_err(|e| CacheError::io("create directory", &dir, e))?;
        mark_as_cache(&root);

        let lock_path = dir.join(LOCK_FILE);
        let lock = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&lock_path)
            .map_err(|e| CacheError::io("open", &lock_path, e))?;
        match lock.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                on_wait();
                lock.lock()
                    .map_err(|e| CacheError::io("lock", &lock_path, e))?;
            }
            Err(TryLockError::Error(e)) => return Err(CacheError::io("lock", &lock_path, e)),
        }

        Ok(Cache {
            store: LocalStore::new(&dir),
            records: dir.join("records"),
            dir,
            _lock: lock,
        })
    }

    /// This manifest's cache directory, `<manifest dir>/.latticebuild/<manifest file name>/`.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The entry store, for callers that want the backend-neutral [`Store`] interface.
    pub fn store(&self) -> &LocalStore {
        &self.store
    }

    /// Reads and verifies the entry for `key`. `Corrupt` entries have been removed: rebuild.
    pub fn get(&self, key: &Key) -> Result<Lookup, CacheError> {
        self.store.get(key)
    }

    /// Stores a stage's output under `key`; returns its hash, which downstream keys use.
    pub fn put(&self, key: &Key, payload: &[u8]) -> Result<ContentHash, CacheError> {
        self.store.put(key, payload)
    }

    /// Stores the concatenation of `parts` under `key`, without joining them in memory; `hash`
    /// must be [`ContentHash::of_parts`] of them, computed by the caller beforehand.
    pub fn put_parts(
        &self,
        key: &Key,
        parts: &[&[u8]],
        hash: ContentHash,
    ) -> Result<(), CacheError> {
        self.store.put_parts(key, parts, hash)
    }

    /// Starts writing `key`'s entry a piece at a time; see [`PendingEntry`].
    pub fn begin(&self, key: &Key) -> Result<PendingEntry, CacheError> {
        self.store.begin(key)
    }

    /// Starts writing a self-verifying entry for `key` (see [`LocalStore::begin_self_verified`]).
    pub fn begin_self_verified(&self, key: &Key) -> Result<PendingEntry, CacheError> {
        self.store.begin_self_verified(key)
    }

    /// Opens `key`'s entry for reads at offsets, its header checked but not its hash; see
    /// [`EntryReader`].
    pub fn open_entry(&self, key: &Key) -> Result<Opened, CacheError> {
        self.store.open(key)
    }

    /// Removes `key`'s entry (one found corrupt by a reader of parts); `false` if absent.
    pub fn remove(&self, key: &Key) -> Result<bool, CacheError> {
        self.store.remove(key)
    }

    /// Whether an entry for `key` exists (not verified).
    pub fn contains(&self, key: &Key) -> Result<bool, CacheError> {
        self.store.contains(key)
    }

    /// The output hash of `key`'s entry from its header alone, without reading or verifying the
    /// payload (for `latticebuild graph`). `None` if absent or the header is unusable.
    pub fn peek_hash(&self, key: &Key) -> Option<ContentHash> {
        self.store.peek_hash(key)
    }

    /// Records that `node` was built as `key` (described by `description`) with output `output`.
    /// Call it only after the output is stored, so a record never points at a failed build.
    pub fn record(
        &self,
        node: &str,
        key: &Key,
        description: &KeyDescription,
        output: &ContentHash,
    ) -> Result<(), CacheError> {
        let record = Record {
            node: node.to_owned(),
            key: *key,
            description: description.clone(),
            output: *output,
        };
        let path = self.records.join(record::file_name(node));
        let json = serde_json::to_vec_pretty(&record).map_err(|source| CacheError::Record {
            path: path.clone(),
            source,
        })?;
        fs::create_dir_all(&self.records)
            .map_err(|e| CacheError::io("create directory", &self.records, e))?;
        write_atomically(&path, json.len() + 1, |w| {
            w.write_all(&json)?;
            w.write_all(b"\n")
        })
    }

    /// The last record of `node`, if there is a readable one. A missing, unreadable or foreign
    /// record is `None`: records only explain misses and guide `gc`, so losing one costs nothing
    /// but an explanation.
    pub fn previous(&self, node: &str) -> Option<Record> {
        let path = self.records.join(record::file_name(node));
        let record = read_record(&path)?;
        // Guards against a file that was copied or renamed by hand.
        (record.node == node).then_some(record)
    }

    /// Every readable record, sorted by node name. Their keys are what [`Cache::gc`] should keep
    /// after a build.
    pub fn records(&self) -> Result<Vec<Record>, CacheError> {
        let entries = match fs::read_dir(&self.records) {
            Ok(entries) => entries,
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Vec::new()),
            Err(e) => return Err(CacheError::io("list", &self.records, e)),
        };
        let mut records: Vec<Record> = entries
            .filter_map(Result::ok)
            .map(|entry| entry.path())
            .filter(|path| path.extension() == Some(OsStr::new("json")))
            .filter_map(|path| read_record(&path))
            .collect();
        records.sort_by(|a, b| a.node.cmp(&b.node));
        Ok(records)
    }

    /// Removes every entry and record of this manifest (everything in the directory except the
    /// lock, which this Cache holds: deleting it would let another build lock a fresh file of the
    /// same name while we still think we own the cache).
    pub fn clean(&mut self) -> Result<(), CacheError> {
        let entries = match fs::read_dir(&self.dir) {
            Ok(entries) => entries,
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(()),
            Err(e) => return Err(CacheError::io("list", &self.dir, e)),
        };
        for entry in entries {
            let entry = entry.map_err(|e| CacheError::io("list", &self.dir, e))?;
            if entry.file_name() == LOCK_FILE {
                continue;
            }
            let path = entry.path();
            // `file_type` does not follow symlinks, so a symlink is removed, never its target.
            let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
            let result = if is_dir {
                fs::remove_dir_all(&path)
            } else {
                fs::remove_file(&path)
            };
            match result {
                Ok(()) => {}
                Err(e) if e.kind() == io::ErrorKind::NotFound => {}
                Err(e) => return Err(CacheError::io("remove", &path, e)),
            }
        }
        Ok(())
    }

    /// Marks the entries of `keep` (what this build used) as used now and keeps them; removes
    /// the least recently used others until the objects fit in `limit` (0 bytes removes every
    /// other one), so that a long optimisation loop does not fill the disk. Temporary files
    /// left by crashed builds go too.
    ///
    /// Records are kept even when their entry goes: a record only explains the next miss, and
    /// "parameter `offset` changed" is still true after the old mesh is gone.
    pub fn gc(&self, keep: &HashSet<Key>, limit: SizeLimit) -> Result<Collected, CacheError> {
        let collected = self.store.gc(keep, limit)?;
        let my_pid = std::process::id();
        if let Ok(entries) = fs::read_dir(&self.records) {
            for entry in entries.filter_map(Result::ok) {
                let name = entry.file_name();
                let stale_temp = name
                    .to_str()
                    .and_then(atomic::temp_owner_pid)
                    .is_some_and(|pid| pid != my_pid);
                if stale_temp {
                    // Another process's temp file can only be left over from a crash: we hold
                    // the lock. Failing to remove it is harmless, so it is not an error.
                    let _ = fs::remove_file(entry.path());
                }
            }
        }
        Ok(collected)
    }
}

fn read_record(path: &Path) -> Option<Record> {
    let bytes = fs::read(path).ok()?;
    serde_json::from_slice(&bytes).ok()
}

/// Writes `CACHEDIR.TAG` and a `.gitignore` of `*` into `.latticebuild/` if absent, so backup
/// tools and git leave the cache alone. Best effort: neither is needed for correctness, so a
/// failure (read-only parent, a race with another build) is ignored.
fn mark_as_cache(root: &Path) {
    for (name, content) in [("CACHEDIR.TAG", CACHEDIR_TAG), (".gitignore", "*\n")] {
        let path = root.join(name);
        if path.exists() {
            continue;
        }
        let _ = write_atomically(&path, content.len(), |w| w.write_all(content.as_bytes()));
    }
}
