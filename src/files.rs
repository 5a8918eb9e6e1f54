//! Output files: written whole under a temporary name in the output directory, then renamed
//! into place, so a reader (or a crash) never sees half a mesh. The only writer of user-visible
//! files besides the cache.

use std::fs::{self, File};
use std::io::{self, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::stages::{OutputSink, WrittenFile};

/// Writes output files under one directory.
pub struct OutputDir {
    pub dir: PathBuf,
}

/// A writer that hashes and counts what passes through it.
struct HashingWriter<W: Write> {
    inner: W,
    hasher: blake3::Hasher,
    bytes: u64,
}

impl<W: Write> Write for HashingWriter<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hasher.update(&buf[..n]);
        self.bytes += n as u64;
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

/// Writes `path` atomically from `fill`: a temporary file beside it, renamed on success and
/// removed on failure. Returns the size and blake3 (hex) of what was written.
pub fn write_atomically(
    path: &Path,
    fill: &mut dyn FnMut(&mut dyn Write) -> io::Result<()>,
) -> io::Result<(u64, String)> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    fs::create_dir_all(dir)?;
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let temp = dir.join(format!(
        ".{name}.tmp-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let result = (|| {
        let file = File::create(&temp)?;
        let mut writer = HashingWriter {
            inner: BufWriter::with_capacity(1 << 20, file),
            hasher: blake3::Hasher::new(),
            bytes: 0,
        };
        fill(&mut writer)?;
        writer.flush()?;
        let (bytes, hash) = (writer.bytes, writer.hasher.finalize().to_hex().to_string());
        drop(writer);
        fs::rename(&temp, path)?;
        Ok((bytes, hash))
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
    ) -> io::Result<(u64, String)> {
        write_atomically(&self.dir.join(relative), fill)
    }

    fn holds(&self, file: &WrittenFile) -> bool {
        let path = self.dir.join(&file.path);
        // Size first: a cheap answer for the common case of a file deleted or rewritten.
        if fs::metadata(&path).map(|m| m.len()) != Ok(file.bytes) {
            return false;
        }
        let Ok(mut f) = File::open(&path) else { return false };
        let mut hasher = blake3::Hasher::new();
        let mut buf = vec![0u8; 1 << 20];
        loop {
            match f.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => {
                    hasher.update(&buf[..n]);
                }
                Err(_) => return false,
            }
        }
        hasher.finalize().to_hex().as_str() == file.blake3
    }
}
