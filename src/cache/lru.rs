//! Collection of the cache's objects: what a build used stays, the rest goes least recently
//! used first while the objects take more than the cache's size limit, so an optimizer that
//! comes back to a value finds it (`[cache] max_size`, docs/manifest.md).
//!
//! Invariants:
//! - An entry is removed whole (its one file), never truncated: entries stay whole or absent.
//! - "Used" is the entry file's modification time: a collection first sets it to now on every
//!   entry the build used (looked up or stored), and those entries are never removed, however
//!   small the limit. Nothing else writes an entry after its rename, so the time is the last
//!   build that used it.
//! - Temporary files of other processes (crashed builds: the caller holds the cache lock)
//!   go; temporaries of this process and files that are not ours stay.

use std::collections::HashSet;
use std::fs::{self, File};
use std::io;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

use crate::cache::atomic::temp_owner_pid;
use crate::cache::error::CacheError;
use crate::cache::key::Key;

/// What a collection did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Collected {
    /// Entries removed.
    pub removed: usize,
    /// Bytes of the entries left.
    pub kept_bytes: u64,
}

/// How many bytes of entries the cache may keep: at most `max_bytes` (`[cache] max_size`),
/// and at most half of the space it could have (its entries and the free disk together), so
/// the cache never takes the disk the outputs need.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SizeLimit {
    pub max_bytes: u64,
    /// Free bytes on the cache's filesystem, when known.
    pub free_disk: Option<u64>,
}

impl SizeLimit {
    /// Exactly `max_bytes`, whatever the disk.
    pub fn bytes(max_bytes: u64) -> SizeLimit {
        SizeLimit {
            max_bytes,
            free_disk: None,
        }
    }

    /// The bytes allowed when the entries take `total`.
    pub fn allowed(&self, total: u64) -> u64 {
        let disk = self
            .free_disk
            .map_or(u64::MAX, |free| total.saturating_add(free) / 2);
        self.max_bytes.min(disk)
    }
}

/// One entry of the object directory.
struct Entry {
    key: Key,
    path: PathBuf,
    bytes: u64,
    used: SystemTime,
}

/// Collects `objects/` (shards `ab/`, entries named by their key): marks `keep` as used now,
/// then removes the least recently used other entries until the rest fit in `limit`.
pub(crate) fn collect(
    objects: &Path,
    keep: &HashSet<Key>,
    limit: SizeLimit,
) -> Result<Collected, CacheError> {
    let now = SystemTime::now();
    let mut entries = Vec::new();
    let my_pid = std::process::id();
    for shard in read_dir_or_empty(objects)? {
        let Some(shard_name) = shard.file_name().to_str().map(str::to_owned) else {
            continue;
        };
        let is_shard = shard_name.len() == 2 && shard_name.bytes().all(|b| b.is_ascii_hexdigit());
        if !is_shard || !shard.path().is_dir() {
            continue;
        }
        for file in read_dir_or_empty(&shard.path())? {
            let name = file.file_name();
            let Some(name) = name.to_str() else { continue };
            let path = file.path();
            match name.parse::<Key>() {
                Ok(key) if name.starts_with(&shard_name) => {
                    // An entry that vanished or cannot be read is simply not counted.
                    let Ok(meta) = file.metadata() else { continue };
                    let used = if keep.contains(&key) {
                        touch(&path, now);
                        now
                    } else {
                        meta.modified().unwrap_or(SystemTime::UNIX_EPOCH)
                    };
                    entries.push(Entry {
                        key,
                        path,
                        bytes: meta.len(),
                        used,
                    });
                }
                Ok(_) => {}
                Err(_) => {
                    if temp_owner_pid(name).is_some_and(|pid| pid != my_pid) {
                        remove_file(&path)?;
                    }
                }
            }
        }
    }
    let mut total: u64 = entries.iter().map(|e| e.bytes).sum();
    let max_bytes = limit.allowed(total);
    let mut candidates: Vec<&Entry> = entries.iter().filter(|e| !keep.contains(&e.key)).collect();
    // Oldest first; equal times in key order, so a collection is deterministic.
    candidates.sort_by(|a, b| a.used.cmp(&b.used).then(a.key.cmp(&b.key)));
    let mut removed = 0;
    for entry in candidates {
        if total <= max_bytes {
            break;
        }
        if remove_file(&entry.path)? {
            removed += 1;
        }
        total -= entry.bytes;
    }
    Ok(Collected {
        removed,
        kept_bytes: total,
    })
}

/// Marks an entry as used at `now`. Best effort: an entry whose time cannot be set only
/// looks older than it is, and may go sooner than it should, never too late.
fn touch(path: &Path, now: SystemTime) {
    if let Ok(file) = File::open(path) {
        let _ = file.set_modified(now);
    }
}

fn remove_file(path: &Path) -> Result<bool, CacheError> {
    match fs::remove_file(path) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(false),
        Err(e) => Err(CacheError::io("remove", path, e)),
    }
}

/// The entries of `dir`, or none if it does not exist yet. Unreadable individual entries are
/// skipped rather than failing the whole walk.
fn read_dir_or_empty(dir: &Path) -> Result<Vec<fs::DirEntry>, CacheError> {
    match fs::read_dir(dir) {
        Ok(entries) => Ok(entries.filter_map(Result::ok).collect()),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(Vec::new()),
        Err(e) => Err(CacheError::io("list", dir, e)),
    }
}
