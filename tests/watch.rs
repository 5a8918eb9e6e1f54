//! `latticebuild watch`: builds, rebuilds after a save, survives a broken manifest, and exits
//! cleanly on Ctrl-C (SIGINT).

use crate::common;

use std::io::Read;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::Project;

const MANIFEST: &str = r#"
[cells.g]
tpms = "gyroid"

[outputs.g]
cell = "g"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 24
"#;

/// Waits until `check` holds, polling; panics with `what` after 30 s.
fn wait_for(what: &str, mut check: impl FnMut() -> bool) {
    let start = Instant::now();
    while !check() {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "timed out waiting for {what}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn report_offset_volume(p: &Project) -> Option<f64> {
    let text = std::fs::read_to_string(p.out("g.report.json")).ok()?;
    let json: serde_json::Value = serde_json::from_str(&text).ok()?;
    json["volume"].as_f64()
}

#[test]
fn watch_rebuilds_on_save_survives_errors_and_stops_on_ctrl_c() {
    let p = Project::new(MANIFEST);
    let mut child = Command::new(common::BIN)
        .args(["watch", "lattice.toml"])
        .current_dir(p.path())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn watch");

    wait_for("the first build", || report_offset_volume(&p).is_some());
    let first = report_offset_volume(&p).expect("volume");

    // A save that changes the solid: the report must change.
    p.write(
        "lattice.toml",
        &MANIFEST.replace("samples = 24", "samples = 24\noffset = 0.5"),
    );
    wait_for("the rebuild after a save", || {
        report_offset_volume(&p).is_some_and(|v| v > first + 1e-3)
    });

    // A broken manifest: watch keeps running, and the next good save builds again.
    p.write("lattice.toml", "[outputs.g\n");
    std::thread::sleep(Duration::from_millis(800));
    assert!(
        child.try_wait().expect("poll").is_none(),
        "watch exited on a broken manifest"
    );
    p.write(
        "lattice.toml",
        &MANIFEST.replace("samples = 24", "samples = 24\noffset = -0.5"),
    );
    wait_for("the rebuild after fixing the manifest", || {
        report_offset_volume(&p).is_some_and(|v| v < first - 1e-3)
    });

    let interrupted = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("send SIGINT");
    assert!(interrupted.success());
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("poll") {
            break status;
        }
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "watch did not stop on Ctrl-C"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .expect("stderr")
        .read_to_string(&mut stderr)
        .expect("read stderr");
    assert!(status.success(), "watch exited with {status}\n{stderr}");
    assert!(
        stderr.contains("error: invalid TOML"),
        "the broken manifest was reported:\n{stderr}"
    );
}

/// A running `watch` whose stderr is collected by a thread, for counting its builds.
struct Watcher {
    child: std::process::Child,
    stderr: std::sync::Arc<std::sync::Mutex<String>>,
}

impl Watcher {
    fn start(p: &Project) -> Watcher {
        let mut child = Command::new(common::BIN)
            .args(["watch", "lattice.toml"])
            .current_dir(p.path())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn watch");
        let stderr = std::sync::Arc::new(std::sync::Mutex::new(String::new()));
        let mut pipe = child.stderr.take().expect("stderr");
        let sink = std::sync::Arc::clone(&stderr);
        std::thread::spawn(move || {
            let mut buffer = [0u8; 4096];
            while let Ok(n) = pipe.read(&mut buffer) {
                if n == 0 {
                    break;
                }
                let text = String::from_utf8_lossy(&buffer[..n]).into_owned();
                sink.lock().expect("lock").push_str(&text);
            }
        });
        Watcher { child, stderr }
    }

    /// Builds finished so far (each ends with the "watching" line).
    fn builds(&self) -> usize {
        self.stderr
            .lock()
            .expect("lock")
            .matches("for changes (Ctrl-C to stop)")
            .count()
    }

    fn text(&self) -> String {
        self.stderr.lock().expect("lock").clone()
    }

    fn stop(mut self) -> std::process::ExitStatus {
        let sent = Command::new("kill")
            .args(["-INT", &self.child.id().to_string()])
            .status()
            .expect("kill");
        assert!(sent.success());
        let start = Instant::now();
        loop {
            if let Some(status) = self.child.try_wait().expect("poll") {
                return status;
            }
            assert!(
                start.elapsed() < Duration::from_secs(5),
                "watch did not stop"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

/// CPU time (user + system, in clock ticks) that process `pid` has used, from /proc.
fn cpu_ticks(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    Some(fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?)
}

#[test]
fn an_idle_watch_rebuilds_nothing_and_one_edit_rebuilds_once() {
    let p = Project::new(MANIFEST);
    let w = Watcher::start(&p);
    wait_for("the first build", || w.builds() == 1);
    let ticks = cpu_ticks(w.child.id());
    std::thread::sleep(Duration::from_secs(5));
    assert_eq!(w.builds(), 1, "rebuilt while idle:\n{}", w.text());
    if let (Some(before), Some(after)) = (ticks, cpu_ticks(w.child.id())) {
        // ~0 CPU: well under a tenth of a second in 5 s (ticks are 1/100 s).
        assert!(
            after - before < 10,
            "idle watch used {} ticks",
            after - before
        );
    }

    // A touch and a save of the same bytes change no content: no build.
    let manifest = p.path().join("lattice.toml");
    std::fs::File::options()
        .write(true)
        .open(&manifest)
        .expect("open")
        .set_modified(std::time::SystemTime::now())
        .expect("touch");
    p.write("lattice.toml", MANIFEST);
    std::thread::sleep(Duration::from_secs(2));
    assert_eq!(w.builds(), 1, "rebuilt without a change:\n{}", w.text());

    // One edit: exactly one rebuild, then idle again.
    p.write(
        "lattice.toml",
        &MANIFEST.replace("samples = 24", "samples = 20"),
    );
    wait_for("the rebuild", || w.builds() == 2);
    std::thread::sleep(Duration::from_secs(2));
    assert_eq!(w.builds(), 2, "more than one rebuild:\n{}", w.text());
    assert!(w.stop().success());
}

#[test]
fn a_failing_build_is_not_retried_until_something_changes() {
    // Parses, but its stage fails at run time (an empty solid).
    let failing = MANIFEST.replace("tpms = \"gyroid\"", "expr = \"2\"");
    let p = Project::new(&failing);
    let w = Watcher::start(&p);
    wait_for("the first build", || w.builds() == 1);
    assert!(w.text().contains("the output is empty"), "{}", w.text());
    std::thread::sleep(Duration::from_secs(3));
    assert_eq!(w.builds(), 1, "the failing stage reran:\n{}", w.text());
    // And a separate build does not wait for a lock held by the watch.
    let out = p.run(&["build", "lattice.toml", "-q"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("waiting for another build"), "{stderr}");
    assert!(w.stop().success());
}

#[test]
fn ctrl_c_during_a_watch_build_stops_it_at_once() {
    // Text meshes that take seconds to write.
    let slow = MANIFEST.replace(
        "samples = 24",
        "samples = 200\nformats = [\"stl\", \"ply\", \"obj\"]\nascii = true",
    );
    let p = Project::new(&slow);
    let w = Watcher::start(&p);
    let out = p.path().join("out");
    wait_for("the build to start writing", || {
        std::fs::read_dir(&out).is_ok_and(|entries| {
            entries
                .flatten()
                .any(|e| e.file_name().to_string_lossy().contains(".tmp-"))
        })
    });
    let status = w.stop();
    assert!(!status.success(), "the build was cut off, not finished");
    let left: Vec<_> = std::fs::read_dir(&out)
        .expect("out")
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp-"))
        .collect();
    assert!(left.is_empty(), "temporaries left: {left:?}");
}
