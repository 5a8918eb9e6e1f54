//! Output files: written whole under a temporary name in the output directory, then renamed
//! into place, so a reader (or a crash) never sees half a mesh. The only writer of user-visible
//! files besides the cache.
//!
//! A written file is recognised later by its size and modification time, as cargo does for
//! its outputs: hashing a 300 MB mesh on every warm build would cost more than the build.
//! (Cache keys never involve times; this only decides whether a file must be written again.)

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::stages::{OutputSink, WrittenFile};

/// Writes output files under one directory.
pub struct OutputDir {
    pub dir: PathBuf,
}

/// A writer that counts what passes through it.
struct CountingWriter<W: Write> {
    inner: W,
    bytes: u64,
}

impl<W: Write> Write for CountingWriter<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.bytes += n as u64;
        Ok(n)
    }
    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        self.inner.write_all(buf)?;
        self.bytes += buf.len() as u64;
        Ok(())
    }
    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

/// Modification time of `path` in nanoseconds since the epoch, if the platform has one.
pub fn modified_ns(path: &Path) -> Option<u64> {
    let modified = fs::metadata(path).ok()?.modified().ok()?;
    let since = modified.duration_since(std::time::UNIX_EPOCH).ok()?;
    u64::try_from(since.as_nanos()).ok()
}

/// Writes `path` atomically from `fill`: a temporary file beside it, renamed on success and
/// removed on failure. Returns the size of what was written.
pub fn write_atomically(
    path: &Path,
    fill: &mut dyn FnMut(&mut dyn Write) -> io::Result<()>,
) -> io::Result<u64> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    fs::create_dir_all(dir)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let temp = dir.join(format!(
        ".{name}.tmp-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let result = (|| {
        let file = File::create(&temp)?;
        let mut writer = CountingWriter {
            inner: BufWriter::with_capacity(1 << 20, file),
            bytes: 0,
        };
        fill(&mut writer)?;
        writer.flush()?;
        let bytes = writer.bytes;
        drop(writer);
        fs::rename(&temp, path)?;
        Ok(bytes)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&temp);
    }
    result
}

impl OutputSink for OutputDir {
    fn write_file(
        &self,
        relative: &str,
        fill: &mut dyn FnMut(&mut dyn Write) -> io::Result<()>,
    ) -> io::Result<(u64, u64)> {
        let path = self.dir.join(relative);
        let bytes = write_atomically(&path, fill)?;
        Ok((bytes, modified_ns(&path).unwrap_or(0)))
    }

    fn holds(&self, file: &WrittenFile) -> bool {
        let path = self.dir.join(&file.path);
        fs::metadata(&path).map(|m| m.len()).ok() == Some(file.bytes)
            && modified_ns(&path) == Some(file.modified_ns)
    }
}
