//! `latticebuild watch`: builds, rebuilds after a save, survives a broken manifest, and exits
//! cleanly on Ctrl-C (SIGINT).

mod common;

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
