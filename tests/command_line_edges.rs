//! The command line at its edges, through the real binary: input that is not what it seems
//! (a manifest that is not UTF-8 or holds control characters, FIFOs and devices where files
//! are expected), output names that would create directories or replace an input, and a
//! reader that closes the pipe early. Each gets a message or a quiet exit, never a hang,
//! a panic or a file where none was asked for.

use crate::common;

use std::io::Read;
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use common::{BIN, Project};

/// A manifest with one small SDF output, built in well under a second.
const BALL: &str = "[outputs.ball]\nsdf = \"ball\"\nsamples = \"12^3\"\nformats = [\"stl\"]\n";

/// A closed tetrahedron, ASCII STL, as a mesh input.
const TETRA_STL: &str = "solid t
facet normal 0 0 -1
outer loop
vertex 0 0 0
vertex 0 1 0
vertex 1 0 0
endloop
endfacet
facet normal 0 -1 0
outer loop
vertex 0 0 0
vertex 1 0 0
vertex 0 0 1
endloop
endfacet
facet normal -1 0 0
outer loop
vertex 0 0 0
vertex 0 0 1
vertex 0 1 0
endloop
endfacet
facet normal 1 1 1
outer loop
vertex 1 0 0
vertex 0 1 0
vertex 0 0 1
endloop
endfacet
endsolid t
";

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Waits for `child`, killing it if it has not finished in 20 s: a command that blocks on a
/// FIFO fails the test instead of hanging it.
fn finish(mut child: Child) -> Output {
    let started = Instant::now();
    loop {
        match child.try_wait().expect("wait") {
            Some(_) => return child.wait_with_output().expect("output"),
            None if started.elapsed() > Duration::from_secs(20) => {
                let _ = child.kill();
                let out = child.wait_with_output().expect("output");
                panic!(
                    "still running after 20 s (blocked?); stderr: {}",
                    stderr(&out)
                );
            }
            None => std::thread::sleep(Duration::from_millis(20)),
        }
    }
}

/// Runs `latticebuild ARGS` in `dir`, with the 20 s limit of [`finish`].
fn run_limited(dir: &Path, args: &[&str]) -> Output {
    let child = Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    finish(child)
}

#[cfg(unix)]
fn make_fifo(path: &Path) {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(path.as_os_str().as_bytes()).expect("path");
    // SAFETY: a valid NUL-terminated path; mkfifo only creates the node.
    let rc = unsafe { libc::mkfifo(c.as_ptr(), 0o644) };
    assert_eq!(rc, 0, "mkfifo {}", path.display());
}

/// The names in `dir`, sorted.
fn names_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("read dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn a_manifest_that_is_not_utf8_is_an_error_at_its_first_bad_byte() {
    let project = Project::new("");
    std::fs::write(
        project.path().join("lattice.toml"),
        b"[cells.g]\ntpms = \"gyroid\"  # caf\xe9 \xff\n",
    )
    .expect("write");
    let out = project.run(&["build", "lattice.toml"]);
    assert_eq!(out.status.code(), Some(2));
    common::golden_err("not_utf8_manifest", &stderr(&out));
    // A multi-byte sequence cut short is named whole.
    std::fs::write(project.path().join("lattice.toml"), b"a = 1\n\xe2\x82").expect("write");
    let out = project.run(&["graph", "lattice.toml"]);
    assert_eq!(out.status.code(), Some(2));
    let text = stderr(&out);
    assert!(
        text.contains(" --> lattice.toml:2:1\n  |\n2 | \\xE2\\x82\n  | ^^^^^^^^ bytes 0xE2 0x82 are not UTF-8\n"),
        "{text}"
    );
}

#[test]
fn control_characters_in_a_manifest_are_never_echoed_raw() {
    let project = Project::new("[cells.g]\ntpms = \"gy\0roid\x1b[2J\"\n");
    let out = project.run(&["build", "lattice.toml"]);
    assert_eq!(out.status.code(), Some(2));
    let text = stderr(&out);
    assert!(
        text.contains("2 | tpms = \"gy␀roid␛[2J\"\n  |           ^"),
        "{text}"
    );
    assert!(
        !out.stderr.iter().any(|&b| b < 0x20 && b != b'\n'),
        "a raw control byte reached stderr: {text:?}"
    );
}

#[cfg(unix)]
#[test]
fn a_manifest_that_is_a_device_or_fifo_is_refused_before_anything_is_made() {
    let project = Project::new("");
    std::fs::remove_file(project.path().join("lattice.toml")).expect("rm");
    // `build /dev/null` made `/dev/.latticebuild/`: here a link to it, so the test makes
    // nothing outside its directory whatever the code does.
    std::os::unix::fs::symlink("/dev/null", project.path().join("lattice.toml")).expect("ln");
    let out = run_limited(project.path(), &["build", "lattice.toml"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert_eq!(
        stderr(&out),
        "error: could not read `lattice.toml`
  |
  = note: it is a character device, not a regular file

error: could not load `lattice.toml` due to 1 previous error
"
    );
    make_fifo(&project.path().join("pipe.toml"));
    let out = run_limited(project.path(), &["graph", "pipe.toml"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("= note: it is a FIFO (named pipe), not a regular file"),
        "{}",
        stderr(&out)
    );
    assert_eq!(names_in(project.path()), ["lattice.toml", "pipe.toml"]);
}

#[cfg(unix)]
#[test]
fn sdf_crystal_and_points_refuse_fifos_instead_of_waiting_on_them() {
    let project = Project::new("[cells.p]\ntpms = \"p\"\nsymmetry = \"Oh\"\nfit = { n = 8 }\n");
    make_fifo(&project.path().join("points.txt"));
    let out = run_limited(
        project.path(),
        &["cell", "lattice.toml", "p", "--points", "points.txt"],
    );
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert_eq!(
        stderr(&out),
        "error: cannot read `points.txt`: it is a FIFO (named pipe), not a regular file\n"
    );
    make_fifo(&project.path().join("part.stl"));
    make_fifo(&project.path().join("words.txt"));
    make_fifo(&project.path().join("x.cif"));
    let out = run_limited(project.path(), &["sdf", "file", "part.stl", "-q"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out)
            .contains("cannot read `part.stl`: it is a FIFO (named pipe), not a regular file"),
        "{}",
        stderr(&out)
    );
    let out = run_limited(project.path(), &["sdf", "ball", "@words.txt"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out)
            .contains("cannot read `words.txt`: it is a FIFO (named pipe), not a regular file"),
        "{}",
        stderr(&out)
    );
    // A device, through a link in the project (read only, but never `/dev/zero`: a reader
    // that did not refuse it would fill the memory).
    std::os::unix::fs::symlink("/dev/null", project.path().join("null.stl")).expect("ln");
    let out = run_limited(project.path(), &["sdf", "file", "null.stl"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out)
            .contains("cannot read `null.stl`: it is a character device, not a regular file"),
        "{}",
        stderr(&out)
    );
    let out = run_limited(project.path(), &["crystal", "x.cif"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("cannot read `x.cif`: it is a FIFO (named pipe), not a regular file"),
        "{}",
        stderr(&out)
    );
    assert!(!project.path().join("out.ply").exists());
}

#[test]
fn report_into_a_missing_directory_is_refused_before_the_build_and_creates_nothing() {
    let project = Project::new(BALL);
    let out = project.run(&["build", "lattice.toml", "--report", "no/such/r.json"]);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        stderr(&out),
        "error: cannot write the report to `no/such/r.json`: the directory `no/such` does not \
         exist\n  = help: create it first: `--report` does not create directories\n"
    );
    // Nothing built and nothing created: not `no/`, not the cache, not `out/`.
    assert_eq!(names_in(project.path()), ["lattice.toml"]);
    // A file where the directory should be is no directory either.
    project.write("plain", "");
    let out = project.run(&["build", "lattice.toml", "--report", "plain/r.json"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("`plain` is not a directory"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn report_never_replaces_the_manifest_or_a_file_it_reads() {
    let manifest = "[outputs.cut]\nsdf = \"ball scale 2 file part.stl intersection\"\n\
                    samples = \"12^3\"\nformats = [\"stl\"]\n";
    let project = Project::new(manifest);
    project.write("part.stl", TETRA_STL);
    std::fs::create_dir(project.path().join("sub")).expect("mkdir");
    for (report, what) in [
        ("lattice.toml", "it is the manifest"),
        ("sub/../lattice.toml", "it is the manifest"),
        ("part.stl", "it is `./part.stl`, a file the manifest reads"),
    ] {
        let out = project.run(&["build", "lattice.toml", "--report", report]);
        assert_eq!(out.status.code(), Some(2), "{report}");
        assert_eq!(
            stderr(&out),
            format!(
                "error: cannot write the report to `{report}`: {what}\n  = help: name another \
                 file for the report, like `report.json`\n"
            )
        );
    }
    assert_eq!(
        std::fs::read_to_string(project.path().join("lattice.toml")).expect("manifest"),
        manifest
    );
    assert_eq!(
        std::fs::read_to_string(project.path().join("part.stl")).expect("mesh"),
        TETRA_STL
    );
    // A name the report may have: written whole, nothing else left beside it.
    let out = project.run(&["build", "lattice.toml", "--report", "sub/r.json", "-q"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let reports: serde_json::Value =
        serde_json::from_slice(&std::fs::read(project.path().join("sub/r.json")).expect("r"))
            .expect("json");
    assert_eq!(reports[0]["name"], "cut", "{reports}");
    assert_eq!(names_in(&project.path().join("sub")), ["r.json"]);
}

#[cfg(unix)]
#[test]
fn report_onto_a_device_or_fifo_is_refused() {
    let project = Project::new(BALL);
    // A link to `/dev/null` in the project: `--report /dev/null` itself once renamed the
    // report over the device's name; through a link the test can harm nothing outside.
    std::os::unix::fs::symlink("/dev/null", project.path().join("null")).expect("ln");
    make_fifo(&project.path().join("pipe"));
    for (report, kind) in [
        ("null", "a character device"),
        ("pipe", "a FIFO (named pipe)"),
    ] {
        let out = run_limited(
            project.path(),
            &["build", "lattice.toml", "--report", report],
        );
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        assert_eq!(
            stderr(&out),
            format!(
                "error: cannot write the report to `{report}`: it is {kind}\n  = help: name a \
                 regular file, or give `--report -` to print the report\n"
            )
        );
    }
    assert_eq!(names_in(project.path()), ["lattice.toml", "null", "pipe"]);
}

#[cfg(unix)]
#[test]
fn sdf_output_into_a_missing_directory_or_onto_a_fifo_is_refused() {
    let project = Project::new("");
    let out = project.run(&["sdf", "ball", "-o", "no/such/ball.stl"]);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        stderr(&out),
        "error: cannot write `no/such/ball.stl`: the directory `no/such` does not exist\n"
    );
    assert_eq!(names_in(project.path()), ["lattice.toml"]);
    // Nor over a FIFO, whose reader would never see it.
    make_fifo(&project.path().join("pipe.stl"));
    let out = run_limited(project.path(), &["sdf", "ball", "-o", "pipe.stl"]);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        stderr(&out),
        "error: cannot write `pipe.stl`: it is a FIFO (named pipe)\n"
    );
}

#[test]
fn sdf_samples_past_the_axis_limit_say_so() {
    let project = Project::new("");
    for (samples, message) in [
        (
            "100001^3",
            "`100001^3` gives 100001 samples along x; an axis has at most 100000",
        ),
        (
            "200000,3,3",
            "`200000,3,3` gives 200000 samples along x; an axis has at most 100000",
        ),
        (
            "3,4294967297,3",
            "`3,4294967297,3` gives 4294967297 samples along y; an axis has at most 100000",
        ),
    ] {
        let out = run_limited(project.path(), &["sdf", "ball", "-s", samples]);
        assert_eq!(out.status.code(), Some(2), "{samples}: {}", stderr(&out));
        assert_eq!(stderr(&out), format!("error: word 2 `-s`: {message}\n"));
    }
    assert!(!project.path().join("out.ply").exists());
}

/// Runs `latticebuild ARGS` in `dir` with its stdout (or stderr) a pipe whose reading end is
/// closed before it starts, as `| head` leaves it once it has its line (closed before, so
/// that no write can slip into the pipe's buffer first), and returns the exit code, the
/// signal that ended it, and what it wrote to the other stream.
#[cfg(unix)]
fn with_closed_pipe(dir: &Path, args: &[&str], close_stderr: bool) -> (i32, Option<i32>, String) {
    use std::os::fd::{FromRawFd, OwnedFd};
    use std::os::unix::process::ExitStatusExt;
    let mut fds = [0; 2];
    // SAFETY: `fds` has room for the two descriptors pipe2 writes.
    assert_eq!(unsafe { libc::pipe2(fds.as_mut_ptr(), libc::O_CLOEXEC) }, 0);
    // SAFETY: both descriptors were just opened and are owned by nothing else.
    let (read, write) = unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) };
    drop(read);
    let mut command = Command::new(BIN);
    command.args(args).current_dir(dir).stdin(Stdio::null());
    if close_stderr {
        command.stdout(Stdio::piped()).stderr(Stdio::from(write));
    } else {
        command.stdout(Stdio::from(write)).stderr(Stdio::piped());
    }
    let mut child = command.spawn().expect("spawn");
    drop(command);
    let mut other: Box<dyn Read + Send> = match (child.stdout.take(), child.stderr.take()) {
        (Some(out), _) => Box::new(out),
        (_, Some(err)) => Box::new(err),
        _ => panic!("no pipe to read"),
    };
    let reader = std::thread::spawn(move || {
        let mut text = String::new();
        let _ = other.read_to_string(&mut text);
        text
    });
    let out = finish(child);
    let text = reader.join().expect("reader");
    (out.status.code().unwrap_or(-1), out.status.signal(), text)
}

#[cfg(unix)]
#[test]
fn every_command_ends_quietly_when_its_reader_goes_away() {
    let manifest = "[cells.p]\ntpms = \"p\"\nsymmetry = \"Oh\"\nfit = { n = 8 }\n\n\
                    [outputs.ball]\nsdf = \"ball\"\nsamples = \"12^3\"\nformats = [\"stl\"]\n";
    let project = Project::new(manifest);
    let nacl = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/crates/geom/tests/data/crystals/NaCl.cif"
    );
    let commands: [&[&str]; 5] = [
        &["cell", "lattice.toml", "p", "--json"],
        &["cell", "lattice.toml", "p"],
        &["graph", "lattice.toml"],
        &["build", "lattice.toml", "--report", "-", "-q"],
        &["crystal", nacl],
    ];
    for args in commands {
        let (code, signal, err) = with_closed_pipe(project.path(), args, false);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert_ne!(code, 101, "{args:?}: {err}");
        // Ended by the closed pipe, as `cat` would be: no message, no backtrace.
        assert_eq!(signal, Some(libc::SIGPIPE), "{args:?}: exit {code}, {err}");
        assert_eq!(err, "", "{args:?}");
    }
    // `sdf` writes only its summary, to stderr: the mesh is written first and whole.
    let (code, signal, _) = with_closed_pipe(
        project.path(),
        &["sdf", "ball", "-s", "8^3", "-o", "b.stl"],
        true,
    );
    assert_ne!(code, 101);
    assert_eq!(signal, Some(libc::SIGPIPE));
    let stl = std::fs::read(project.path().join("b.stl")).expect("b.stl");
    let triangles = u32::from_le_bytes(stl[80..84].try_into().expect("count"));
    assert_eq!(stl.len(), 84 + 50 * triangles as usize);
    assert!(triangles > 0);
}
