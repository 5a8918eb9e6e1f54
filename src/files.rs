//! Output files: written whole under a temporary name in the output directory, then renamed
//! into place, so a reader (or a crash) never sees half a mesh. The only writer of user-visible
//! files besides the cache.
//!
//! A written file is recognised later by its size and modification time, as cargo does for
//! its outputs: hashing a 300 MB mesh on every warm build would cost more than the build.
//! (Cache keys never involve times; this only decides whether a file must be written again.)
//!
//! Also the checks on the files the command line names: an input is read only if it is a
//! regular file ([`read_input`]); a file the user names for output (`--report FILE`, `sdf -o
//! FILE`) goes into an existing directory, never over a device ([`output_problem`]), and a
//! report never over the manifest or its inputs ([`check_report_path`]).

use std::collections::{BTreeMap, BTreeSet};
use std::ffi::OsStr;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::direct_file::DirectFile;
use crate::interrupt::Temporary;
use crate::stages::{OutputSink, PendingFile, WrittenFile};

/// Writes output files under one directory. A file it replaces is replaced by a rename, which
/// frees the old file's data in-process (a reader holding the old file keeps its bytes).
pub struct OutputDir {
    pub dir: PathBuf,
}

impl OutputDir {
    pub fn new(dir: PathBuf) -> OutputDir {
        OutputDir { dir }
    }
}

/// What a file that is not a regular file is, for messages (symlinks already followed).
fn not_regular(meta: &fs::Metadata) -> Option<&'static str> {
    let kind = meta.file_type();
    if kind.is_file() {
        return None;
    }
    if kind.is_dir() {
        return Some("a directory");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return Some("a FIFO (named pipe)");
        }
        if kind.is_char_device() {
            return Some("a character device");
        }
        if kind.is_block_device() {
            return Some("a block device");
        }
        if kind.is_socket() {
            return Some("a socket");
        }
    }
    Some("not a regular file")
}

fn not_regular_error(kind: &str) -> io::Error {
    let text = if kind.starts_with("not ") {
        format!("it is {kind}")
    } else {
        format!("it is {kind}, not a regular file")
    };
    io::Error::new(io::ErrorKind::InvalidInput, text)
}

/// Why `path` cannot be read as an input, if it cannot: it does not exist (the OS's words) or
/// is not a regular file. Inputs are checked before a build; their bytes are read by it.
pub fn input_problem(path: &Path) -> Option<String> {
    match fs::metadata(path) {
        Ok(meta) => not_regular(&meta).map(|kind| not_regular_error(kind).to_string()),
        Err(e) => Some(e.to_string()),
    }
}

/// The bytes of the regular file at `path`. Anything else is refused: a FIFO would block the
/// read until another process wrote to it (forever, if none does), a device like `/dev/zero`
/// never ends, and `/dev/null` would read as an empty manifest. The type is checked before
/// opening (so a device is never opened) and again on the opened file, which is opened
/// non-blocking on Unix, so a FIFO put in its place in between is refused, not waited on.
pub fn read_input(path: &Path) -> io::Result<Vec<u8>> {
    if let Some(kind) = not_regular(&fs::metadata(path)?) {
        return Err(not_regular_error(kind));
    }
    let mut options = OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let mut file = options.open(path)?;
    let meta = file.metadata()?;
    if let Some(kind) = not_regular(&meta) {
        return Err(not_regular_error(kind));
    }
    let mut bytes = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0));
    file.read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// The regular file at `path`, opened for streaming, and its length: [`read_input`]'s checks
/// for a file too big to read whole (a tiling's STL for display).
pub fn open_regular(path: &Path) -> io::Result<(io::BufReader<File>, u64)> {
    if let Some(kind) = not_regular(&fs::metadata(path)?) {
        return Err(not_regular_error(kind));
    }
    let mut options = OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path)?;
    let meta = file.metadata()?;
    if let Some(kind) = not_regular(&meta) {
        return Err(not_regular_error(kind));
    }
    Ok((io::BufReader::with_capacity(1 << 20, file), meta.len()))
}

/// [`read_input`] as UTF-8 text.
pub fn read_input_text(path: &Path) -> io::Result<String> {
    String::from_utf8(read_input(path)?)
        .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e.utf8_error()))
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

/// The length of the file at `path`, if it can be looked at.
pub fn file_len(path: &Path) -> Option<u64> {
    fs::metadata(path).ok().map(|m| m.len())
}

/// Modification time of `path` in nanoseconds since the epoch, if the platform has one.
pub fn modified_ns(path: &Path) -> Option<u64> {
    let modified = fs::metadata(path).ok()?.modified().ok()?;
    let since = modified.duration_since(std::time::UNIX_EPOCH).ok()?;
    u64::try_from(since.as_nanos()).ok()
}

/// Between an output's name and the writer's pid in a temporary name:
/// `.NAME.EXT.tmp-PID-COUNTER`.
const TEMP_INFIX: &str = ".tmp-";

/// The file a temporary output name stands for and the pid that made it, if `name` is one:
/// `.NAME.EXT.tmp-PID-COUNTER` gives `NAME.EXT` and `PID`.
fn temporary_of(name: &str) -> Option<(&str, u32)> {
    let rest = name.strip_prefix('.')?;
    let (target, tail) = rest.rsplit_once(TEMP_INFIX)?;
    let (pid, counter) = tail.split_once('-')?;
    counter.parse::<u64>().ok()?;
    Some((target, pid.parse().ok()?)).filter(|(target, _)| !target.is_empty())
}

/// Whether process `pid` is running (on this machine). Where that cannot be told, it is
/// assumed to be, so a file that might still be written is never removed.
fn process_alive(pid: u32) -> bool {
    #[cfg(unix)]
    {
        let Ok(pid) = libc::pid_t::try_from(pid) else {
            return true;
        };
        // SAFETY: signal 0 performs only the existence and permission check.
        let rc = unsafe { libc::kill(pid, 0) };
        rc == 0 || io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
    }
    #[cfg(not(unix))]
    {
        let _ = pid;
        true
    }
}

/// Removes the temporary files of `files` (the files a manifest writes) left by processes
/// that are gone (a build killed with `kill -9`, or a crash): an interrupted build removes its
/// own, but nothing can run after SIGKILL. Only a name this tool gives a temporary file of one
/// of `files` is removed, `.NAME.EXT.tmp-PID-N` beside `NAME.EXT`: any other file, even one
/// that looks temporary, is not ours to remove. Returns the files removed. Another live
/// build's files are kept, even one of another manifest sharing the directory.
pub fn sweep_stale_temporaries(files: &[PathBuf]) -> Vec<PathBuf> {
    let mut by_dir: BTreeMap<&Path, BTreeSet<&OsStr>> = BTreeMap::new();
    for file in files {
        if let Some(name) = file.file_name() {
            by_dir.entry(directory_of(file)).or_default().insert(name);
        }
    }
    let mut removed = Vec::new();
    for (dir, names) in by_dir {
        let Ok(entries) = fs::read_dir(dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let name = entry.file_name();
            let Some((target, pid)) = name.to_str().and_then(temporary_of) else {
                continue;
            };
            let is_file = entry.file_type().is_ok_and(|t| t.is_file());
            if names.contains(OsStr::new(target))
                && is_file
                && pid != std::process::id()
                && !process_alive(pid)
            {
                let path = entry.path();
                if fs::remove_file(&path).is_ok() {
                    removed.push(path);
                }
            }
        }
    }
    removed
}

/// A fresh temporary name beside `path`, registered for removal should the process be
/// interrupted while the returned entry lives.
fn temporary_beside(path: &Path) -> (PathBuf, Temporary) {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let temp = directory_of(path).join(format!(
        ".{name}{TEMP_INFIX}{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let registered = Temporary::register(&temp);
    (temp, registered)
}

/// Creates the directory of `path` (the output directory, which the build owns).
fn create_directory_of(path: &Path) -> io::Result<()> {
    fs::create_dir_all(directory_of(path))
}

/// Writes `path` atomically from `fill`: a temporary file beside it (its directory created),
/// renamed on success and removed on failure. Returns the size of what was written.
pub fn write_atomically(
    path: &Path,
    fill: &mut dyn FnMut(&mut dyn Write) -> io::Result<()>,
) -> io::Result<u64> {
    create_directory_of(path)?;
    write_replacing(path, fill)
}

/// Writes a file the user named on the command line (`--report FILE`, `sdf -o FILE`)
/// atomically, like [`write_atomically`], but never creates its directory nor replaces what
/// is not a regular file: see [`output_problem`].
pub fn write_user_file(
    path: &Path,
    fill: &mut dyn FnMut(&mut dyn Write) -> io::Result<()>,
) -> io::Result<u64> {
    if let Some(problem) = output_problem(path) {
        return Err(io::Error::new(io::ErrorKind::InvalidInput, problem));
    }
    write_replacing(path, fill)
}

/// The directory of a file named on the command line, when it is not an existing directory
/// (as a message). Such a directory is not created, as a compiler's `-o` creates none: a typo
/// must not leave directories behind (`--report /tmpp/r.json` once made `/tmpp`).
pub fn missing_directory(path: &Path) -> Option<String> {
    let dir = directory_of(path);
    match fs::metadata(dir) {
        Ok(meta) if meta.is_dir() => None,
        Ok(_) => Some(format!("`{}` is not a directory", dir.display())),
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            Some(format!("the directory `{}` does not exist", dir.display()))
        }
        Err(e) => Some(format!("cannot use the directory `{}`: {e}", dir.display())),
    }
}

/// The directory `path` is in (`.` for a bare name).
fn directory_of(path: &Path) -> &Path {
    path.parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// Whether two existing paths are the same file, links followed: the same device and inode
/// on Unix, the same canonical path elsewhere.
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (fs::metadata(a), fs::metadata(b)) {
            (Ok(a), Ok(b)) => (a.dev(), a.ino()) == (b.dev(), b.ino()),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        match (fs::canonicalize(a), fs::canonicalize(b)) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        }
    }
}

/// Why a file named on the command line cannot be written, if it cannot: its directory is
/// missing ([`missing_directory`]), or the name exists as something other than a regular
/// file. The file is renamed into place, so over `/dev/stdout` it would replace the device's
/// name, and over a FIFO its reader would never see it.
pub fn output_problem(path: &Path) -> Option<String> {
    if let Some(problem) = missing_directory(path) {
        return Some(problem);
    }
    let meta = fs::metadata(path).ok()?;
    not_regular(&meta).map(|kind| format!("it is {kind}"))
}

/// Checks `--report FILE` (`-` is stdout) before anything is built, so that a bad name fails
/// at once rather than after the build, as a usage error (exit 2) with the rendered text:
/// FILE must be writable ([`output_problem`]: its directory exists, it is not a device), and
/// it must not be the manifest or a file the manifest reads, which the report would replace.
pub fn check_report_path(
    report: Option<&str>,
    manifest: &crate::manifest::Manifest,
) -> Result<(), String> {
    let file = match report {
        None | Some("-") => return Ok(()),
        Some(file) => file,
    };
    let refuse = |why: String, help: &str| {
        Err(format!(
            "error: cannot write the report to `{file}`: {why}\n  = help: {help}\n"
        ))
    };
    let path = Path::new(file);
    if file.is_empty() || path.file_name().is_none() {
        return refuse(
            "that is not a file name".into(),
            "name a file, like `--report report.json`, or `-` for stdout",
        );
    }
    if let Some(problem) = output_problem(path) {
        let help = if missing_directory(path).is_some() {
            "create it first: `--report` does not create directories"
        } else {
            "name a regular file, or give `--report -` to print the report"
        };
        return refuse(problem, help);
    }
    let another = "name another file for the report, like `report.json`";
    if same_file(path, &manifest.path) {
        return refuse("it is the manifest".into(), another);
    }
    if let Some(input) = manifest.inputs.iter().find(|i| same_file(path, i)) {
        return refuse(
            format!("it is `{}`, a file the manifest reads", input.display()),
            another,
        );
    }
    Ok(())
}

/// Writes `path` whole under a temporary name beside it, then renames it into place; the
/// temporary file is removed on failure. Returns the size of what was written.
fn write_replacing(
    path: &Path,
    fill: &mut dyn FnMut(&mut dyn Write) -> io::Result<()>,
) -> io::Result<u64> {
    let (temp, _registered) = temporary_beside(path);
    let result = (|| {
        let file = File::create(&temp)?;
        let mut writer = CountingWriter {
            inner: DirectFile::new(file, &temp),
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
        create_directory_of(&path)?;
        let bytes = write_replacing(&path, fill)?;
        Ok((bytes, modified_ns(&path).unwrap_or(0)))
    }

    fn begin_file(&self, relative: &str) -> io::Result<Box<dyn PendingFile>> {
        let path = self.dir.join(relative);
        create_directory_of(&path)?;
        let (temp, registered) = temporary_beside(&path);
        let file = File::create(&temp)?;
        Ok(Box::new(PendingOutput {
            writer: Some(DirectFile::new(file, &temp)),
            temp,
            _registered: registered,
            path,
        }))
    }

    fn holds(&self, file: &WrittenFile) -> bool {
        let path = self.dir.join(&file.path);
        fs::metadata(&path).map(|m| m.len()).ok() == Some(file.bytes)
            && modified_ns(&path) == Some(file.modified_ns)
    }
}

/// A file being written under its temporary name: renamed into place by `commit`, removed
/// when dropped before (a failed or unused early write leaves nothing behind).
struct PendingOutput {
    /// `None` once committed.
    writer: Option<DirectFile>,
    temp: PathBuf,
    /// Dropped after `Drop::drop` has removed an uncommitted file.
    _registered: Temporary,
    path: PathBuf,
}

impl PendingOutput {
    fn writer(&mut self) -> io::Result<&mut DirectFile> {
        self.writer
            .as_mut()
            .ok_or_else(|| io::Error::other("the file was already committed"))
    }
}

impl Write for PendingOutput {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.writer()?.write(buf)
    }
    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        self.writer()?.write_all(buf)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.writer()?.flush()
    }
}

impl Seek for PendingOutput {
    fn seek(&mut self, to: SeekFrom) -> io::Result<u64> {
        self.writer()?.seek(to)
    }
}

impl PendingFile for PendingOutput {
    fn commit(mut self: Box<Self>) -> io::Result<(u64, u64)> {
        let writer = self
            .writer
            .take()
            .ok_or_else(|| io::Error::other("the file was already committed"))?;
        let placed = (|| {
            let file = writer.into_file()?;
            let bytes = file.metadata()?.len();
            drop(file);
            fs::rename(&self.temp, &self.path)?;
            Ok(bytes)
        })();
        match placed {
            Ok(bytes) => Ok((bytes, modified_ns(&self.path).unwrap_or(0))),
            Err(e) => {
                let _ = fs::remove_file(&self.temp);
                Err(e)
            }
        }
    }
}

impl Drop for PendingOutput {
    fn drop(&mut self) {
        if self.writer.take().is_some() {
            let _ = fs::remove_file(&self.temp);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names_in(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(dir)
            .expect("read dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn a_replaced_file_leaves_no_second_name_and_a_holder_keeps_its_bytes() {
        let dir = tempfile::tempdir().expect("temp dir");
        let sink = OutputDir::new(dir.path().to_path_buf());
        let old = vec![7u8; 3 * crate::direct_file::BLOCK];
        sink.write_file("part.stl", &mut |w| w.write_all(&old))
            .expect("first write");
        // Another name for the old file, as a reader holding it would: it must keep its bytes.
        fs::hard_link(dir.path().join("part.stl"), dir.path().join("held")).expect("link");
        let mut early = sink.begin_file("part.stl").expect("begin");
        early.write_all(b"new mesh").expect("write");
        early.commit().expect("commit");
        sink.write_file("part.ply", &mut |w| w.write_all(b"ply"))
            .expect("a file with nothing to replace");
        drop(sink);
        assert_eq!(
            fs::read(dir.path().join("part.stl")).expect("read"),
            b"new mesh"
        );
        assert!(fs::read(dir.path().join("held")).expect("read held") == old);
        assert_eq!(names_in(dir.path()), ["held", "part.ply", "part.stl"]);
    }
}
