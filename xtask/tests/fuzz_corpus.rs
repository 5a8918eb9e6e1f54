//! The inputs `cargo xtask fuzz` saved (each once made a reader panic, hang or allocate past
//! the bound) now run within the limits, and the runner still catches each kind of failure
//! and blames the input that caused it.

use std::path::{Path, PathBuf};
use std::process::Command;

fn xtask() -> Command {
    Command::new(env!("CARGO_BIN_EXE_xtask"))
}

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("workspace root")
        .join("tests/fuzz_corpus")
}

#[test]
fn every_saved_input_runs_within_the_limits() {
    let out = xtask()
        .args(["fuzz", "--replay"])
        .output()
        .expect("xtask runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    // Counted here, independently of the replay: every file of every target's directory.
    let mut files = 0;
    for dir in std::fs::read_dir(corpus()).expect("tests/fuzz_corpus") {
        let dir = dir.expect("entry").path();
        files += std::fs::read_dir(&dir).expect("target directory").count();
    }
    assert!(files > 0, "the corpus is empty");
    assert_eq!(
        stdout.lines().filter(|l| l.contains(": fine: ")).count(),
        files
    );
    assert!(
        stdout.contains(&format!("{files} saved inputs replayed, 0 failed")),
        "{stdout}"
    );
}

#[test]
fn the_runner_catches_each_failure_and_blames_its_input() {
    let dir = std::env::temp_dir().join(format!("xtask-fuzz-canary-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    // Fine inputs between the failures: each failure must be pinned on its own input, and
    // the inputs after it must still run (in a new child).
    let inputs = [
        "ok", "panic", "ok", "spin", "ok", "alloc", "ok", "abort", "deep", "ok",
    ];
    let files: Vec<String> = inputs
        .iter()
        .enumerate()
        .map(|(i, word)| {
            let path = dir.join(format!("{i}-{word}"));
            std::fs::write(&path, word).expect("write");
            path.display().to_string()
        })
        .collect();
    let out = xtask()
        .args(["fuzz", "--check", "--cpu-ms", "300", "canary"])
        .args(&files)
        .output()
        .expect("xtask runs");
    let _ = std::fs::remove_dir_all(&dir);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    let verdicts: Vec<(&str, &str, &str)> = stdout
        .lines()
        .map(|l| {
            let mut parts = l.splitn(3, '\t');
            let (file, kind) = (parts.next().unwrap_or(""), parts.next().unwrap_or(""));
            (file, kind, parts.next().unwrap_or(""))
        })
        .collect();
    let files_seen: Vec<&str> = verdicts.iter().map(|v| v.0).collect();
    assert_eq!(files_seen, files, "{stdout}");
    let kinds: Vec<&str> = verdicts.iter().map(|v| v.1).collect();
    assert_eq!(
        kinds,
        [
            "fine", "panic", "fine", "hang", "fine", "memory", "fine", "crash", "crash", "fine"
        ],
        "{stdout}"
    );
    assert!(verdicts[1].2.contains("canary panic"), "{stdout}");
    assert!(verdicts[3].2.contains("SIGPROF"), "{stdout}");
    // The canary asks for 2^40 bytes; the bound (512 MiB) stops it before the system is asked.
    assert!(verdicts[5].2.contains("1099511627776 bytes"), "{stdout}");
    assert!(verdicts[7].2.contains("SIGABRT"), "{stdout}");
}
