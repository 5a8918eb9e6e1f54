//! [`DirectFile`]: a big file written front to back by a thread of its own, around the page
//! cache where the system allows it.
//!
//! Why: a tiling writes gigabytes (a 100k-tet scaffold gives a 2.2 GB STL and a 0.8 GB cache
//! entry). Through the page cache, the kernel copies every byte into pages it must first find,
//! and on a VM whose memory has not been touched yet that copy alone costs about 2.8 s of CPU
//! per GB (measured: `dd` of 1 GiB, 2.95 s of system time), more than the tiling. Written with
//! `O_DIRECT` in 4 MiB blocks, the same gigabyte costs 0.1 s of CPU and goes to the device at
//! 1.3–1.8 GB/s while the producer goes on making the next block. No crate does this for a
//! `Write`: the blocks must be aligned in memory, on disk and in length, and the unaligned tail
//! and later patches (an STL's facet count, a cache entry's header) must go another way.
//!
//! Invariants:
//! - The file holds exactly the bytes written, at the offsets they were written at, as a plain
//!   `File` would: only how they get there differs.
//! - Only whole blocks of [`BLOCK`] bytes, at offsets that are multiples of [`BLOCK`], from
//!   memory aligned to [`ALIGN`], go through the `O_DIRECT` descriptor. A file that never fills
//!   one block never uses it (nor the thread), so small files cost what they did.
//! - Streaming ends at the first seek to anywhere but the current position, at `flush`, or at
//!   [`DirectFile::into_file`]: every block is then written, the tail goes through the ordinary
//!   descriptor, and later writes go straight to it.
//! - An error of the writer thread is returned by the next write, seek or flush, never lost;
//!   after a block failed to go out, every later call fails (the file would have a gap).
//!   Where the file system refuses `O_DIRECT` (at open or at the first write), the blocks are
//!   written through the ordinary descriptor instead, still off the producing thread.
//!   [`DirectFile::blocks`] counts which way each block went.

use std::fs::File;
use std::io::{self, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TryRecvError, sync_channel};
use std::thread::JoinHandle;

/// Bytes per block handed to the writer thread: large enough that the device runs at full
/// speed (1.8 GB/s here at 4 MiB, 1.3 at 1 MiB), small enough that three cost nothing.
pub const BLOCK: usize = 4 << 20;
/// Memory and offset alignment `O_DIRECT` needs; 4096 covers every logical block size in use.
pub const ALIGN: usize = 4096;
/// Blocks queued for the writer thread besides the one it writes and the one being filled.
const BLOCKS_QUEUED: usize = 1;

/// How the whole blocks of a [`DirectFile`] went to disk so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BlockStats {
    /// Written through the `O_DIRECT` descriptor.
    pub direct: u64,
    /// Written through the ordinary descriptor: `O_DIRECT` refused (or not on this system).
    pub plain: u64,
}

/// The writer thread's counts behind [`BlockStats`].
#[derive(Debug, Default)]
struct BlockCounts {
    direct: AtomicU64,
    plain: AtomicU64,
}

/// How the writer thread gets its direct descriptor: as the system allows, or (in tests)
/// refused at open or at the first write, to run the fallback on a file system that would
/// take `O_DIRECT`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Direct {
    Try,
    #[cfg(test)]
    RefusedAtOpen,
    #[cfg(test)]
    RefusedAtWrite,
}

/// A file being written front to back (see the module doc).
pub struct DirectFile {
    /// The ordinary descriptor: the tail, patches, and everything once streaming has ended.
    file: File,
    /// The block being filled, while streaming.
    block: Option<AlignedBlock>,
    /// Started when the first block fills.
    writer: Option<BlockWriter>,
    /// Bytes handed to the writer thread: the offset of `block`.
    handed: u64,
    /// Where the direct descriptor is opened from.
    path: PathBuf,
    /// Set when a block could not be handed off: the file has a gap, so every later call fails.
    broken: bool,
    /// Which way the blocks went, counted by the writer thread.
    counts: Arc<BlockCounts>,
    direct: Direct,
}

impl DirectFile {
    /// Writes `file` (opened for writing, empty) at `path`, which a second, direct descriptor
    /// opens if a block ever fills.
    pub fn new(file: File, path: &Path) -> DirectFile {
        DirectFile {
            file,
            block: Some(AlignedBlock::new()),
            writer: None,
            handed: 0,
            path: path.to_path_buf(),
            broken: false,
            counts: Arc::default(),
            direct: Direct::Try,
        }
    }

    /// How the whole blocks handed to the writer thread went to disk: all of them once
    /// streaming has ended (after `flush` or a seek elsewhere), those written so far before.
    pub fn blocks(&self) -> BlockStats {
        BlockStats {
            direct: self.counts.direct.load(Ordering::Relaxed),
            plain: self.counts.plain.load(Ordering::Relaxed),
        }
    }

    /// Ends streaming and hands back the ordinary descriptor, positioned at the end.
    pub fn into_file(mut self) -> io::Result<File> {
        self.end_streaming()?;
        self.file.try_clone()
    }

    fn check(&self) -> io::Result<()> {
        match self.broken {
            true => Err(io::Error::other("an earlier write to this file failed")),
            false => Ok(()),
        }
    }

    /// Whether blocks are still being streamed.
    fn streaming(&self) -> bool {
        self.block.is_some()
    }

    fn position(&self) -> u64 {
        self.handed + self.block.as_ref().map_or(0, |b| b.len as u64)
    }

    /// Hands the full block to the writer thread and takes an empty one.
    fn hand_off(&mut self) -> io::Result<()> {
        let handed = self.try_hand_off();
        self.broken |= handed.is_err();
        handed
    }

    fn try_hand_off(&mut self) -> io::Result<()> {
        if self.writer.is_none() {
            let counts = Arc::clone(&self.counts);
            self.writer = Some(BlockWriter::start(
                &self.file,
                &self.path,
                self.direct,
                counts,
            )?);
        }
        let (Some(writer), Some(full)) = (self.writer.as_mut(), self.block.take()) else {
            return Ok(());
        };
        let at = self.handed;
        self.handed += full.len as u64;
        writer.send(at, full)?;
        let mut empty = writer.empty_block()?;
        empty.len = 0;
        self.block = Some(empty);
        Ok(())
    }

    /// Writes every block, then the tail through the ordinary descriptor, and leaves that
    /// descriptor at the end of the file.
    fn end_streaming(&mut self) -> io::Result<()> {
        self.check()?;
        let Some(tail) = self.block.take() else {
            return Ok(());
        };
        if let Some(writer) = self.writer.take() {
            writer.finish()?;
        }
        write_all_at(&self.file, tail.bytes(), self.handed)?;
        self.handed += tail.len as u64;
        self.file.seek(SeekFrom::Start(self.handed))?;
        Ok(())
    }
}

impl Write for DirectFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.check()?;
        let Some(block) = self.block.as_mut() else {
            return self.file.write(buf);
        };
        let n = block.fill(buf);
        if block.len == BLOCK {
            self.hand_off()?;
        }
        Ok(n)
    }

    fn write_all(&mut self, mut buf: &[u8]) -> io::Result<()> {
        while !buf.is_empty() {
            match self.write(buf)? {
                0 => return Err(io::ErrorKind::WriteZero.into()),
                n => buf = &buf[n..],
            }
        }
        Ok(())
    }

    /// Ends streaming: after a flush every byte is in the file.
    fn flush(&mut self) -> io::Result<()> {
        self.end_streaming()?;
        self.file.flush()
    }
}

impl Seek for DirectFile {
    fn seek(&mut self, to: SeekFrom) -> io::Result<u64> {
        self.check()?;
        if self.streaming() {
            let here = self.position();
            if matches!(to, SeekFrom::Current(0)) || to == SeekFrom::Start(here) {
                return Ok(here);
            }
            self.end_streaming()?;
        }
        self.file.seek(to)
    }
}

impl Drop for DirectFile {
    fn drop(&mut self) {
        // Joined so that no write lands after the owner removes or renames the file.
        if let Some(writer) = self.writer.take() {
            let _ = writer.finish();
        }
    }
}

/// [`BLOCK`] bytes of memory aligned to [`ALIGN`], of which the first `len` are data.
struct AlignedBlock {
    memory: Vec<u8>,
    start: usize,
    len: usize,
}

impl AlignedBlock {
    fn new() -> AlignedBlock {
        let memory = vec![0u8; BLOCK + ALIGN];
        // Never fails for bytes in practice; if it did, the direct write refuses the block
        // (EINVAL) and it goes through the ordinary descriptor.
        let start = memory.as_ptr().align_offset(ALIGN).min(ALIGN);
        AlignedBlock {
            memory,
            start,
            len: 0,
        }
    }

    /// Copies as much of `buf` as fits; how much.
    fn fill(&mut self, buf: &[u8]) -> usize {
        let n = buf.len().min(BLOCK - self.len);
        let at = self.start + self.len;
        self.memory[at..at + n].copy_from_slice(&buf[..n]);
        self.len += n;
        n
    }

    fn bytes(&self) -> &[u8] {
        &self.memory[self.start..self.start + self.len]
    }
}

/// The writer thread: blocks in at their offsets, emptied blocks (or the first error) out.
struct BlockWriter {
    full: SyncSender<(u64, AlignedBlock)>,
    emptied: Receiver<io::Result<AlignedBlock>>,
    thread: JoinHandle<()>,
    /// Blocks made so far; more are made until the queue is full, then emptied ones reused.
    made: usize,
}

impl BlockWriter {
    fn start(
        file: &File,
        path: &Path,
        mode: Direct,
        counts: Arc<BlockCounts>,
    ) -> io::Result<BlockWriter> {
        let plain = file.try_clone()?;
        let direct = match mode {
            Direct::Try => open_direct(path),
            #[cfg(test)]
            Direct::RefusedAtOpen => None,
            // A descriptor that refuses every write, as a file system can after the open.
            #[cfg(test)]
            Direct::RefusedAtWrite => File::open(path).ok(),
        };
        let (full, blocks) = sync_channel::<(u64, AlignedBlock)>(BLOCKS_QUEUED);
        let (done, emptied) = sync_channel(BLOCKS_QUEUED + 2);
        let thread = std::thread::Builder::new()
            .name("direct-file".into())
            .spawn(move || write_blocks(direct, plain, blocks, done, &counts))?;
        Ok(BlockWriter {
            full,
            emptied,
            thread,
            made: 1,
        })
    }

    fn send(&mut self, at: u64, block: AlignedBlock) -> io::Result<()> {
        if self.full.send((at, block)).is_err() {
            // The thread stopped: it reported why with the block it stopped on.
            return Err(self.error_or_gone());
        }
        Ok(())
    }

    /// An emptied block, or a new one while fewer than the queue holds exist.
    fn empty_block(&mut self) -> io::Result<AlignedBlock> {
        match self.emptied.try_recv() {
            Ok(emptied) => return emptied,
            Err(TryRecvError::Disconnected) => return Err(gone()),
            Err(TryRecvError::Empty) => {}
        }
        if self.made < BLOCKS_QUEUED + 2 {
            self.made += 1;
            return Ok(AlignedBlock::new());
        }
        self.emptied.recv().map_err(|_| gone())?
    }

    fn error_or_gone(&mut self) -> io::Error {
        while let Ok(result) = self.emptied.recv() {
            if let Err(e) = result {
                return e;
            }
        }
        gone()
    }

    /// Waits for every block handed over; the first error, if any.
    fn finish(self) -> io::Result<()> {
        let BlockWriter {
            full,
            emptied,
            thread,
            ..
        } = self;
        drop(full);
        let mut first_error = None;
        for result in emptied.iter() {
            if let Err(e) = result {
                first_error.get_or_insert(e);
            }
        }
        if thread.join().is_err() {
            first_error
                .get_or_insert_with(|| io::Error::other("the file's writer thread panicked"));
        }
        first_error.map_or(Ok(()), Err)
    }
}

fn gone() -> io::Error {
    io::Error::other("the file's writer thread stopped")
}

fn write_blocks(
    mut direct: Option<File>,
    plain: File,
    blocks: Receiver<(u64, AlignedBlock)>,
    done: SyncSender<io::Result<AlignedBlock>>,
    counts: &BlockCounts,
) {
    for (at, block) in blocks {
        let mut written = match &direct {
            Some(d) => write_all_at(d, block.bytes(), at),
            None => write_all_at(&plain, block.bytes(), at),
        };
        let mut way = match direct {
            Some(_) => &counts.direct,
            None => &counts.plain,
        };
        if written.is_err() && direct.is_some() {
            // Refused (a file system that takes the flag but not the write): write this and
            // every later block the ordinary way. Rewriting bytes a partial direct write
            // already put there is harmless.
            direct = None;
            written = write_all_at(&plain, block.bytes(), at);
            way = &counts.plain;
        }
        let failed = written.is_err();
        if !failed {
            way.fetch_add(1, Ordering::Relaxed);
        }
        if done.send(written.map(|()| block)).is_err() || failed {
            return;
        }
    }
}

#[cfg(unix)]
fn write_all_at(file: &File, buf: &[u8], at: u64) -> io::Result<()> {
    std::os::unix::fs::FileExt::write_all_at(file, buf, at)
}

#[cfg(windows)]
fn write_all_at(file: &File, mut buf: &[u8], mut at: u64) -> io::Result<()> {
    while !buf.is_empty() {
        let n = std::os::windows::fs::FileExt::seek_write(file, buf, at)?;
        if n == 0 {
            return Err(io::ErrorKind::WriteZero.into());
        }
        buf = &buf[n..];
        at += n as u64;
    }
    Ok(())
}

#[cfg(target_os = "linux")]
fn open_direct(path: &Path) -> Option<File> {
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new()
        .write(true)
        .custom_flags(libc::O_DIRECT)
        .open(path)
        .ok()
}

#[cfg(not(target_os = "linux"))]
fn open_direct(_path: &Path) -> Option<File> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bytes that differ at every offset, so a block in the wrong place shows.
    fn pattern(len: usize) -> Vec<u8> {
        (0..len as u64)
            .map(|i| (i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 56) as u8)
            .collect()
    }

    fn direct_file(dir: &tempfile::TempDir, name: &str) -> (DirectFile, std::path::PathBuf) {
        let path = dir.path().join(name);
        let file = File::create(&path).expect("create");
        (DirectFile::new(file, &path), path)
    }

    #[test]
    fn the_file_holds_what_was_written_whatever_the_pieces() {
        let dir = tempfile::tempdir().expect("temp dir");
        let data = pattern(3 * BLOCK + 12_345);
        for (k, piece) in [1usize, 4095, 65_536, BLOCK - 1, BLOCK, 5 * BLOCK]
            .into_iter()
            .enumerate()
        {
            let (mut out, path) = direct_file(&dir, &format!("f{k}"));
            for part in data.chunks(piece) {
                out.write_all(part).expect("write");
            }
            assert_eq!(out.stream_position().expect("position"), data.len() as u64);
            let file = out.into_file().expect("finish");
            assert_eq!(file.metadata().expect("metadata").len(), data.len() as u64);
            drop(file);
            assert!(
                std::fs::read(&path).expect("read") == data,
                "pieces of {piece}"
            );
        }
    }

    #[test]
    fn small_files_and_exact_blocks_come_out_whole() {
        let dir = tempfile::tempdir().expect("temp dir");
        for len in [0, 1, ALIGN, BLOCK - 1, BLOCK, 2 * BLOCK] {
            let data = pattern(len);
            let (mut out, path) = direct_file(&dir, &format!("len{len}"));
            out.write_all(&data).expect("write");
            out.flush().expect("flush");
            drop(out);
            assert!(std::fs::read(&path).expect("read") == data, "{len} bytes");
        }
    }

    #[test]
    fn a_patch_after_seeking_back_lands_in_place_and_writing_goes_on_at_the_end() {
        let dir = tempfile::tempdir().expect("temp dir");
        let mut data = pattern(2 * BLOCK + 999);
        let (mut out, path) = direct_file(&dir, "patched");
        out.write_all(&data).expect("write");
        let end = out.stream_position().expect("position");
        out.seek(SeekFrom::Start(80)).expect("seek back");
        out.write_all(b"PATCH").expect("patch");
        out.seek(SeekFrom::Start(end)).expect("seek to the end");
        out.write_all(b"tail").expect("write after the patch");
        out.flush().expect("flush");
        drop(out);
        data[80..85].copy_from_slice(b"PATCH");
        data.extend_from_slice(b"tail");
        assert!(std::fs::read(&path).expect("read") == data);
    }

    /// Whether the file system holding `dir` takes an `O_DIRECT` write of one aligned block,
    /// tried here with the system calls themselves, not through `DirectFile`.
    #[cfg(target_os = "linux")]
    fn takes_o_direct(dir: &Path) -> bool {
        let path = dir.join("probe");
        File::create(&path).expect("create the probe");
        let Some(file) = open_direct(&path) else {
            return false;
        };
        let block = {
            let mut block = AlignedBlock::new();
            block.fill(&[7u8; ALIGN]);
            block
        };
        let taken = write_all_at(&file, block.bytes(), 0).is_ok();
        let _ = std::fs::remove_file(&path);
        taken
    }

    #[cfg(not(target_os = "linux"))]
    fn takes_o_direct(_dir: &Path) -> bool {
        false
    }

    /// Writes five blocks and a tail to `name` in `dir` (with `direct` as the descriptor's
    /// way), checks the bytes read back, and returns how the blocks went.
    fn write_blocks_in(dir: &Path, name: &str, direct: Direct) -> BlockStats {
        let data = pattern(5 * BLOCK + 4321);
        let path = dir.join(name);
        let mut out = DirectFile::new(File::create(&path).expect("create"), &path);
        out.direct = direct;
        for part in data.chunks(1 << 20) {
            out.write_all(part).expect("write");
        }
        out.flush().expect("flush");
        let blocks = out.blocks();
        drop(out);
        assert!(
            std::fs::read(&path).expect("read") == data,
            "`{name}` in {}: the bytes read back differ from those written",
            dir.display()
        );
        blocks
    }

    #[test]
    fn whole_blocks_go_through_o_direct_where_the_file_system_takes_it() {
        // The system's temporary directory (tmpfs on many machines: it refused `O_DIRECT`
        // before Linux 6.6), the test binary's directory (the target directory) and the
        // crate's: a checkout on an ordinary disk takes `O_DIRECT` in the last two.
        let mut candidates = vec![std::env::temp_dir()];
        if let Some(dir) = std::env::current_exe()
            .ok()
            .and_then(|e| e.parent().map(Into::into))
        {
            candidates.push(dir);
        }
        candidates.push(PathBuf::from(env!("CARGO_MANIFEST_DIR")));
        let mut seen = Vec::new();
        for candidate in candidates {
            let dir = tempfile::Builder::new()
                .prefix(".direct-file-test")
                .tempdir_in(&candidate)
                .expect("temp dir");
            let takes = takes_o_direct(dir.path());
            let blocks = write_blocks_in(dir.path(), "five-blocks", Direct::Try);
            let expected = match takes {
                true => BlockStats {
                    direct: 5,
                    plain: 0,
                },
                false => BlockStats {
                    direct: 0,
                    plain: 5,
                },
            };
            assert_eq!(
                blocks,
                expected,
                "in {} (O_DIRECT {})",
                candidate.display(),
                if takes { "taken" } else { "refused" }
            );
            seen.push((candidate, takes));
        }
        eprintln!("O_DIRECT taken (true) or refused (false) by the file system of: {seen:?}");
        let direct: Vec<_> = seen.iter().filter(|(_, takes)| *takes).collect();
        assert!(
            cfg!(not(target_os = "linux")) || !direct.is_empty(),
            "no directory tried here takes O_DIRECT, so the direct path was not tested: {seen:?}"
        );
    }

    #[test]
    fn blocks_refused_at_open_or_at_the_first_write_go_the_ordinary_way() {
        let dir = tempfile::tempdir().expect("temp dir");
        for (name, direct) in [
            ("refused-at-open", Direct::RefusedAtOpen),
            ("refused-at-write", Direct::RefusedAtWrite),
        ] {
            let blocks = write_blocks_in(dir.path(), name, direct);
            assert_eq!(
                blocks,
                BlockStats {
                    direct: 0,
                    plain: 5
                },
                "{name}"
            );
        }
    }

    #[test]
    fn writes_after_a_flush_follow_the_flushed_bytes() {
        let dir = tempfile::tempdir().expect("temp dir");
        let data = pattern(BLOCK + BLOCK / 2);
        let (mut out, path) = direct_file(&dir, "flushed");
        let (head, rest) = data.split_at(BLOCK + 7);
        out.write_all(head).expect("write");
        out.flush().expect("flush");
        out.write_all(rest).expect("write after flush");
        drop(out.into_file().expect("finish"));
        assert!(std::fs::read(&path).expect("read") == data);
    }
}
