//! [`Store`]: content by [`Key`]; [`LocalStore`]: its first backend, a directory of entry files.
//!
//! The trait is the seam for sharing results between machines later (an S3-compatible object
//! store keyed the same way): it is object-safe, has four methods, and says nothing about files.
//!
//! A local entry lives at `<dir>/objects/<first 2 hex digits>/<64 hex digits>` and is a fixed
//! 48-byte header followed by the payload:
//!
//! | bytes  | content                                   |
//! |--------|-------------------------------------------|
//! | 0..4   | magic: `LBC1`, or `LBS1` for a self-verifying entry (below) |
//! | 4..8   | format version, u32 LE ([`FORMAT_VERSION`]) |
//! | 8..16  | payload length, u64 LE                    |
//! | 16..48 | blake3 of the payload (`LBC1`), or the hash its writer declared (`LBS1`) |
//!
//! Invariants: an entry is whole or absent — it is written to a temporary file and renamed into
//! place, and `get` checks magic, length and hash, so a torn, truncated or bit-flipped entry is
//! reported as [`Lookup::Corrupt`], deleted, and never returned as a hit.
//!
//! Large payloads also go in and out a piece at a time: [`LocalStore::begin`] gives a
//! [`PendingEntry`] that hashes what is written to it and, on `commit`, fixes up the header and
//! renames the file into place (dropped uncommitted, it leaves nothing); [`LocalStore::open`]
//! checks the header and the length only and hands out an [`EntryReader`] for reads at
//! offsets. The whole-payload hash is then not checked: a reader of parts must verify what it
//! reads by hashes of its own (the chunked mesh payload keeps one per section), and report a
//! mismatch so the entry is removed and rebuilt.
//!
//! A payload that carries such hashes need not be hashed whole as well: an entry begun with
//! [`LocalStore::begin_self_verified`] is not hashed as written, and its header (`LBS1`) holds
//! the hash its writer declares on commit — the chunked mesh's hash of its trailer, which
//! holds every section's hash. Its reader must check that the declared hash is its payload's
//! (`EntryReader::self_verified`); `get` cannot, and reports such an entry as corrupt.

use std::collections::HashSet;
use std::fmt;
use std::fs::{self, File};
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use crate::cache::atomic::{TempFile, write_atomically};
use crate::cache::content_hash::ContentHash;
use crate::cache::error::CacheError;
use crate::cache::key::Key;
use crate::cache::lru::{Collected, SizeLimit};
use crate::direct_file::DirectFile;

const MAGIC: [u8; 4] = *b"LBC1";
/// The magic of a self-verifying entry (see the module docs).
const SELF_VERIFIED_MAGIC: [u8; 4] = *b"LBS1";
/// Bump when the header layout changes; older entries then read as corrupt and are rebuilt.
pub const FORMAT_VERSION: u32 = 1;
const HEADER_LEN: usize = 48;
/// Large enough that a small payload goes out in one write; a large payload bypasses the buffer
/// and is written straight from the caller's slice, so no copy of a 300 MB mesh is made.
const WRITE_BUFFER: usize = 1 << 20;

/// Stored content by key. Implementations must make entries whole or absent, and must verify
/// what they return: a corrupt entry is [`Lookup::Corrupt`], not a hit and not an error.
pub trait Store: Send + Sync {
    /// Reads and verifies the entry for `key`. A corrupt entry is removed before returning.
    fn get(&self, key: &Key) -> Result<Lookup, CacheError>;
    /// Stores `payload` under `key`, replacing any entry, and returns the payload's hash.
    /// Concurrent puts of the same key all succeed.
    fn put(&self, key: &Key, payload: &[u8]) -> Result<ContentHash, CacheError>;
    /// Stores the concatenation of `parts` (large payloads need not be joined in memory), whose
    /// hash the caller computed with [`ContentHash::of_parts`] (so it can key downstream work
    /// while this write runs elsewhere).
    fn put_parts(&self, key: &Key, parts: &[&[u8]], hash: ContentHash) -> Result<(), CacheError>;
    /// Whether an entry exists, without verifying it.
    fn contains(&self, key: &Key) -> Result<bool, CacheError>;
    /// Removes the entry; `false` if there was none.
    fn remove(&self, key: &Key) -> Result<bool, CacheError>;
}

/// The outcome of reading an entry.
pub enum Lookup {
    Hit {
        payload: Vec<u8>,
        hash: ContentHash,
    },
    Miss,
    /// The entry existed but failed verification; it has been removed. Treat as a miss (and say
    /// so under `-v`).
    Corrupt {
        reason: Corruption,
    },
}

impl fmt::Debug for Lookup {
    // Hand-written so that a failing test prints a payload's size, not 300 MB of numbers.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Lookup::Hit { payload, hash } => f
                .debug_struct("Hit")
                .field("payload_len", &payload.len())
                .field("hash", hash)
                .finish(),
            Lookup::Miss => f.write_str("Miss"),
            Lookup::Corrupt { reason } => {
                f.debug_struct("Corrupt").field("reason", reason).finish()
            }
        }
    }
}

/// Why an entry failed verification.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Corruption {
    #[error("not a latticebuild cache entry (bad magic)")]
    BadMagic,
    #[error("entry format version {found} is not {FORMAT_VERSION}")]
    UnknownFormat { found: u32 },
    #[error("entry is truncated: {found} bytes on disk, {expected} expected")]
    Truncated { expected: u64, found: u64 },
    #[error("entry has trailing data: {found} bytes on disk, {expected} expected")]
    TrailingData { expected: u64, found: u64 },
    #[error("entry payload of {len} bytes does not fit in memory on this machine")]
    TooLarge { len: u64 },
    #[error("entry payload does not match its hash")]
    HashMismatch,
    #[error("a self-verifying entry cannot be read whole")]
    SelfVerified,
}

/// A store in a local directory. Holds no open files, so it is cheap, `Send` and `Sync`.
#[derive(Clone, Debug)]
pub struct LocalStore {
    objects: PathBuf,
}

struct Header {
    payload_len: u64,
    hash: ContentHash,
    /// `LBS1`: `hash` was declared by the writer, not computed over the payload.
    self_verified: bool,
}

enum ReadFailure {
    Corrupt(Corruption),
    Io(&'static str, io::Error),
}

impl From<Corruption> for ReadFailure {
    fn from(c: Corruption) -> ReadFailure {
        ReadFailure::Corrupt(c)
    }
}

impl LocalStore {
    /// A store whose entries live under `<dir>/objects/`. Directories are created on first `put`.
    pub fn new(dir: &Path) -> LocalStore {
        LocalStore {
            objects: dir.join("objects"),
        }
    }

    /// Where the entry for `key` lives (whether or not it exists).
    pub fn entry_path(&self, key: &Key) -> PathBuf {
        let hex = key.to_string();
        self.objects.join(&hex[..2]).join(hex)
    }

    /// The payload hash recorded in the entry's header, reading only the header. The payload is
    /// not verified — this is for displays such as `latticebuild graph`, where reading 300 MB to
    /// show a hash would be absurd. `None` if the entry is absent or its header is unusable.
    pub fn peek_hash(&self, key: &Key) -> Option<ContentHash> {
        let mut file = File::open(self.entry_path(key)).ok()?;
        let file_len = file.metadata().ok()?.len();
        read_header(&mut file, file_len).ok().map(|h| h.hash)
    }

    /// Marks every object in `keep` as used now, and removes the least recently used others
    /// until what is left fits in `limit` (0 bytes: every other one), with temporary files left
    /// by other (crashed) processes; see [`super::lru`]. Files it does not recognise are left
    /// alone. Must only run while holding the cache lock (as [`super::Cache`] does), or
    /// another process's in-flight temporary files could be removed.
    pub fn gc(&self, keep: &HashSet<Key>, limit: SizeLimit) -> Result<Collected, CacheError> {
        super::lru::collect(&self.objects, keep, limit)
    }
}

impl LocalStore {
    /// Starts writing the entry for `key` a piece at a time (see [`PendingEntry`]).
    pub fn begin(&self, key: &Key) -> Result<PendingEntry, CacheError> {
        let destination = self.entry_path(key);
        if let Some(dir) = destination.parent() {
            fs::create_dir_all(dir).map_err(|e| CacheError::io("create directory", dir, e))?;
        }
        let (temp, file) = TempFile::beside(&destination)?;
        let mut writer = DirectFile::new(file, temp.path());
        // Zeros until `commit` knows the length and hash: a crash before then leaves a temp
        // file (removed by `gc`), and even a renamed zero header reads as bad magic.
        writer
            .write_all(&[0u8; HEADER_LEN])
            .map_err(|e| CacheError::io("write", temp.path(), e))?;
        Ok(PendingEntry {
            temp,
            writer,
            hasher: Some(blake3::Hasher::new()),
            len: 0,
            destination,
        })
    }

    /// Starts writing a self-verifying entry for `key` (see the module docs): nothing is
    /// hashed as it is written, and [`PendingEntry::commit_declared`] records the hash.
    pub fn begin_self_verified(&self, key: &Key) -> Result<PendingEntry, CacheError> {
        let mut pending = self.begin(key)?;
        pending.hasher = None;
        Ok(pending)
    }

    /// Opens the entry for `key` for reads at offsets, after checking its header and length
    /// (not its hash). An entry whose header is bad is removed and reported as corrupt.
    pub fn open(&self, key: &Key) -> Result<Opened, CacheError> {
        let path = self.entry_path(key);
        let mut file = match File::open(&path) {
            Ok(file) => file,
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Opened::Miss),
            Err(e) => return Err(CacheError::io("open", &path, e)),
        };
        let file_len = file
            .metadata()
            .map_err(|e| CacheError::io("read metadata of", &path, e))?
            .len();
        match read_header(&mut file, file_len) {
            Ok(header) => Ok(Opened::Entry(EntryReader {
                file,
                len: header.payload_len,
                hash: header.hash,
                self_verified: header.self_verified,
            })),
            Err(ReadFailure::Corrupt(reason)) => {
                drop(file);
                // As in `get`: failing to remove only means it is reported again.
                let _ = fs::remove_file(&path);
                Ok(Opened::Corrupt(reason))
            }
            Err(ReadFailure::Io(action, e)) => Err(CacheError::io(action, &path, e)),
        }
    }
}

/// An entry being written. Bytes written to it are the payload, hashed as they pass (unless it
/// is self-verifying); `commit` writes the header and renames the file into place. Dropping it
/// uncommitted (an error, a failed stage) removes the temporary file, so the entry stays whole
/// or absent.
pub struct PendingEntry {
    temp: TempFile,
    writer: DirectFile,
    /// `None` for a self-verifying entry.
    hasher: Option<blake3::Hasher>,
    len: u64,
    destination: PathBuf,
}

impl Write for PendingEntry {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.writer.write(buf)?;
        if let Some(hasher) = &mut self.hasher {
            hasher.update(&buf[..n]);
        }
        self.len += n as u64;
        Ok(n)
    }

    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        self.writer.write_all(buf)?;
        if let Some(hasher) = &mut self.hasher {
            hasher.update(buf);
        }
        self.len += buf.len() as u64;
        Ok(())
    }

    fn flush(&mut self) -> io::Result<()> {
        self.writer.flush()
    }
}

impl PendingEntry {
    /// Payload bytes written so far.
    pub fn len(&self) -> u64 {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Fixes up the header and renames the entry into place; returns the payload's hash, the
    /// same [`ContentHash::of`] the whole payload would have. A self-verifying entry cannot
    /// be committed this way (it has no hash of its payload): use `commit_declared`.
    pub fn commit(mut self) -> Result<ContentHash, CacheError> {
        match self.hasher.take() {
            Some(hasher) => {
                let hash = ContentHash::from_bytes(*hasher.finalize().as_bytes());
                self.seal(MAGIC, hash)
            }
            None => Err(CacheError::io(
                "commit",
                self.temp.path(),
                io::Error::other("a self-verifying entry needs its declared hash"),
            )),
        }
    }

    /// Commits a self-verifying entry under the hash its writer declares for the payload.
    /// Returns that hash.
    pub fn commit_declared(mut self, hash: ContentHash) -> Result<ContentHash, CacheError> {
        match self.hasher.take() {
            None => self.seal(SELF_VERIFIED_MAGIC, hash),
            Some(_) => Err(CacheError::io(
                "commit",
                self.temp.path(),
                io::Error::other("an entry hashed as written cannot take a declared hash"),
            )),
        }
    }

    fn seal(self, magic: [u8; 4], hash: ContentHash) -> Result<ContentHash, CacheError> {
        let PendingEntry {
            temp,
            writer,
            len,
            destination,
            ..
        } = self;
        let mut header = [0u8; HEADER_LEN];
        header[0..4].copy_from_slice(&magic);
        header[4..8].copy_from_slice(&FORMAT_VERSION.to_le_bytes());
        header[8..16].copy_from_slice(&len.to_le_bytes());
        header[16..48].copy_from_slice(hash.as_bytes());
        let fix_up = |writer: DirectFile| -> io::Result<()> {
            let mut file = writer.into_file()?;
            file.seek(SeekFrom::Start(0))?;
            file.write_all(&header)
        };
        fix_up(writer).map_err(|e| CacheError::io("write", temp.path(), e))?;
        // The file was closed by `fix_up`: some platforms refuse to rename an open file.
        temp.persist(&destination)?;
        Ok(hash)
    }
}

/// The outcome of [`LocalStore::open`].
pub enum Opened {
    Miss,
    /// The header was bad; the entry has been removed.
    Corrupt(Corruption),
    Entry(EntryReader),
}

/// An entry opened for reads at offsets into its payload. Reads never move a shared cursor,
/// so one reader serves several threads at once.
#[derive(Debug)]
pub struct EntryReader {
    file: File,
    len: u64,
    hash: ContentHash,
    self_verified: bool,
}

impl EntryReader {
    /// The payload's length.
    pub fn len(&self) -> u64 {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The payload hash the header records (not verified: see the module docs).
    pub fn hash(&self) -> ContentHash {
        self.hash
    }

    /// Whether the entry is self-verifying: [`EntryReader::hash`] is what its writer declared,
    /// which its reader must check against the payload.
    pub fn self_verified(&self) -> bool {
        self.self_verified
    }

    /// Fills `buf` from the payload at `offset`. Reading past the payload is `UnexpectedEof`.
    pub fn read_at(&self, offset: u64, buf: &mut [u8]) -> io::Result<()> {
        let end = offset.checked_add(buf.len() as u64);
        if end.is_none_or(|end| end > self.len) {
            return Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                format!(
                    "{} bytes at {offset} are past the payload's {}",
                    buf.len(),
                    self.len
                ),
            ));
        }
        read_exact_at(&self.file, buf, HEADER_LEN as u64 + offset)
    }
}

#[cfg(unix)]
fn read_exact_at(file: &File, buf: &mut [u8], at: u64) -> io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(file, buf, at)
}

#[cfg(windows)]
fn read_exact_at(file: &File, mut buf: &mut [u8], mut at: u64) -> io::Result<()> {
    use std::os::windows::fs::FileExt;
    while !buf.is_empty() {
        match file.seek_read(buf, at)? {
            0 => return Err(io::ErrorKind::UnexpectedEof.into()),
            n => {
                buf = &mut buf[n..];
                at += n as u64;
            }
        }
    }
    Ok(())
}

impl Store for LocalStore {
    fn get(&self, key: &Key) -> Result<Lookup, CacheError> {
        let path = self.entry_path(key);
        let mut file = match File::open(&path) {
            Ok(file) => file,
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Lookup::Miss),
            Err(e) => return Err(CacheError::io("open", &path, e)),
        };
        let file_len = file
            .metadata()
            .map_err(|e| CacheError::io("read metadata of", &path, e))?
            .len();
        match read_entry(&mut file, file_len) {
            Ok((payload, hash)) => Ok(Lookup::Hit { payload, hash }),
            Err(ReadFailure::Corrupt(reason)) => {
                drop(file);
                // If this fails the entry stays corrupt and is reported again next time, or is
                // replaced by the rebuild's `put`; either way no wrong bytes are served. A
                // concurrent `put` may have just renamed a good entry here, which we then
                // delete: that costs one rebuild, never correctness.
                let _ = fs::remove_file(&path);
                Ok(Lookup::Corrupt { reason })
            }
            Err(ReadFailure::Io(action, e)) => Err(CacheError::io(action, &path, e)),
        }
    }

    fn put(&self, key: &Key, payload: &[u8]) -> Result<ContentHash, CacheError> {
        let hash = ContentHash::of(payload);
        self.put_parts(key, &[payload], hash)?;
        Ok(hash)
    }

    fn put_parts(&self, key: &Key, parts: &[&[u8]], hash: ContentHash) -> Result<(), CacheError> {
        debug_assert!(
            hash == ContentHash::of_parts(parts),
            "put_parts with a wrong hash"
        );
        let payload_len: usize = parts.iter().map(|p| p.len()).sum();
        let path = self.entry_path(key);
        if let Some(dir) = path.parent() {
            fs::create_dir_all(dir).map_err(|e| CacheError::io("create directory", dir, e))?;
        }
        let mut header = [0u8; HEADER_LEN];
        header[0..4].copy_from_slice(&MAGIC);
        header[4..8].copy_from_slice(&FORMAT_VERSION.to_le_bytes());
        header[8..16].copy_from_slice(&(payload_len as u64).to_le_bytes());
        header[16..48].copy_from_slice(hash.as_bytes());
        let buffer = WRITE_BUFFER.min(HEADER_LEN + payload_len);
        write_atomically(&path, buffer, |w| {
            w.write_all(&header)?;
            parts.iter().try_for_each(|part| w.write_all(part))
        })?;
        Ok(())
    }

    fn contains(&self, key: &Key) -> Result<bool, CacheError> {
        let path = self.entry_path(key);
        match fs::metadata(&path) {
            Ok(meta) => Ok(meta.is_file()),
            Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(false),
            Err(e) => Err(CacheError::io("read metadata of", &path, e)),
        }
    }

    fn remove(&self, key: &Key) -> Result<bool, CacheError> {
        remove_file(&self.entry_path(key))
    }
}

/// Reads and checks the header, including that the file is exactly as long as it says.
fn read_header(file: &mut File, file_len: u64) -> Result<Header, ReadFailure> {
    if file_len < HEADER_LEN as u64 {
        return Err(Corruption::Truncated {
            expected: HEADER_LEN as u64,
            found: file_len,
        }
        .into());
    }
    let mut header = [0u8; HEADER_LEN];
    file.read_exact(&mut header).map_err(|e| match e.kind() {
        // The file shrank after we looked at its length: it is not a whole entry.
        io::ErrorKind::UnexpectedEof => Corruption::Truncated {
            expected: HEADER_LEN as u64,
            found: file_len,
        }
        .into(),
        _ => ReadFailure::Io("read", e),
    })?;
    let self_verified = match field(&header, 0) {
        MAGIC => false,
        SELF_VERIFIED_MAGIC => true,
        _ => return Err(Corruption::BadMagic.into()),
    };
    let version = u32::from_le_bytes(field(&header, 4));
    if version != FORMAT_VERSION {
        return Err(Corruption::UnknownFormat { found: version }.into());
    }
    let payload_len = u64::from_le_bytes(field(&header, 8));
    let hash = ContentHash::from_bytes(field(&header, 16));
    // A garbage length can overflow; such a file is certainly not as long as it claims.
    let expected = payload_len.saturating_add(HEADER_LEN as u64);
    if file_len < expected {
        return Err(Corruption::Truncated {
            expected,
            found: file_len,
        }
        .into());
    }
    if file_len > expected {
        return Err(Corruption::TrailingData {
            expected,
            found: file_len,
        }
        .into());
    }
    Ok(Header {
        payload_len,
        hash,
        self_verified,
    })
}

/// `N` bytes of the header starting at `at`; the offsets are the constants of the layout table.
fn field<const N: usize>(header: &[u8; HEADER_LEN], at: usize) -> [u8; N] {
    let mut out = [0; N];
    out.copy_from_slice(&header[at..at + N]);
    out
}

/// Reads the whole entry and verifies it. The allocation is sized from the header only after the
/// header's length has been checked against the real file length, so a corrupt header cannot
/// make us allocate more than the file holds.
fn read_entry(file: &mut File, file_len: u64) -> Result<(Vec<u8>, ContentHash), ReadFailure> {
    let header = read_header(file, file_len)?;
    if header.self_verified {
        return Err(Corruption::SelfVerified.into());
    }
    let len = usize::try_from(header.payload_len).map_err(|_| Corruption::TooLarge {
        len: header.payload_len,
    })?;
    let mut payload = Vec::new();
    payload
        .try_reserve_exact(len)
        .map_err(|_| Corruption::TooLarge {
            len: header.payload_len,
        })?;
    // `take` bounds the read in case the file grows underneath us; it is then caught below.
    file.take(header.payload_len)
        .read_to_end(&mut payload)
        .map_err(|e| ReadFailure::Io("read", e))?;
    if payload.len() != len {
        return Err(Corruption::Truncated {
            expected: header.payload_len + HEADER_LEN as u64,
            found: (payload.len() + HEADER_LEN) as u64,
        }
        .into());
    }
    let actual = ContentHash::of(&payload);
    if actual != header.hash {
        return Err(Corruption::HashMismatch.into());
    }
    Ok((payload, actual))
}

/// `Ok(false)` if already gone: another thread or process removing the same file is fine.
fn remove_file(path: &Path) -> Result<bool, CacheError> {
    match fs::remove_file(path) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(false),
        Err(e) => Err(CacheError::io("remove", path, e)),
    }
}
