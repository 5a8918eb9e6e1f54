//! The architecture's mechanical invariants, checked on the source text
//! (`docs/ARCHITECTURE.md` states them).

use std::path::{Path, PathBuf};

/// The modules that may reach the filesystem themselves (everything else goes through them).
const TOUCH_FILES: &[&str] = &[
    "cache/",
    "files.rs",
    "direct_file.rs",
    "interrupt.rs",
    "build.rs",
    "budget.rs",
    "commands/watch.rs",
    "commands/sdf.rs",
];

/// What reaching the filesystem looks like in our code.
const FILE_CALLS: &[&str] = &[
    "std::fs",
    "fs::",
    "File::",
    "OpenOptions",
    "read_dir(",
    "canonicalize(",
    ".exists()",
    ".is_file()",
    ".is_dir()",
    ".metadata()",
];

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("read src").flatten() {
        let path = entry.path();
        if path.is_dir() {
            sources(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// Test code may make scratch files anywhere: a module's tests live in a `tests` module
/// (a file named `*tests.rs` or under a `tests/` directory), or after `#[cfg(test)]`.
fn production_text(path: &Path, text: &str) -> Option<String> {
    let name = path.file_name()?.to_string_lossy();
    let in_tests_dir = path.components().any(|c| c.as_os_str() == "tests");
    if name.ends_with("tests.rs") || in_tests_dir {
        return None;
    }
    Some(text.split("#[cfg(test)]").next().unwrap_or("").to_string())
}

#[test]
fn only_the_listed_modules_touch_the_filesystem() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    let mut offenders = Vec::new();
    for path in &files {
        let relative = path
            .strip_prefix(&src)
            .expect("under src")
            .to_string_lossy()
            .replace('\\', "/");
        if TOUCH_FILES
            .iter()
            .any(|allowed| relative.starts_with(allowed))
        {
            continue;
        }
        let text = std::fs::read_to_string(path).expect("read source");
        let Some(code) = production_text(path, &text) else {
            continue;
        };
        for (line, content) in code.lines().enumerate() {
            let trimmed = content.trim_start();
            if trimmed.starts_with("//") {
                continue;
            }
            if let Some(call) = FILE_CALLS.iter().find(|c| content.contains(*c)) {
                offenders.push(format!("src/{relative}:{}: {call}", line + 1));
            }
        }
    }
    assert!(
        offenders.is_empty(),
        "filesystem calls outside the modules docs/ARCHITECTURE.md allows:\n{}",
        offenders.join("\n")
    );
    assert!(files.len() > 50, "found only {} sources", files.len());
}

/// The production lines of every source under `dir` that is not skipped, with their paths
/// relative to `dir`.
fn production_lines(dir: &Path) -> Vec<(String, usize, String)> {
    let mut files = Vec::new();
    sources(dir, &mut files);
    let mut lines = Vec::new();
    for path in &files {
        let relative = path
            .strip_prefix(dir)
            .expect("under the directory")
            .to_string_lossy()
            .replace('\\', "/");
        let text = std::fs::read_to_string(path).expect("read source");
        let Some(code) = production_text(path, &text) else {
            continue;
        };
        for (n, content) in code.lines().enumerate() {
            if !content.trim_start().starts_with("//") {
                lines.push((relative.clone(), n + 1, content.to_string()));
            }
        }
    }
    lines
}

/// The dependency layers: a module may use those below it, never those above.
#[test]
fn layers_point_one_way() {
    // (modules, what they must not name)
    let rules: [(&[&str], &[&str]); 4] = [
        (
            &["stages/", "graph/", "cache/", "manifest/"],
            &["crate::build", "crate::commands", "crate::cli"],
        ),
        (&["build.rs"], &["crate::commands", "crate::cli"]),
        (&["commands/"], &["crate::cli"]),
        (
            &["progress.rs", "diagnostics.rs", "report.rs"],
            &["crate::commands", "crate::cli"],
        ),
    ];
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lines = production_lines(&src);
    let mut offenders = Vec::new();
    for (modules, banned) in rules {
        for (file, n, line) in &lines {
            if !modules.iter().any(|m| file.starts_with(m)) {
                continue;
            }
            if let Some(name) = banned.iter().find(|b| line.contains(*b)) {
                offenders.push(format!("src/{file}:{n}: {name}"));
            }
        }
    }
    assert!(
        offenders.is_empty(),
        "imports against the layers docs/ARCHITECTURE.md draws:\n{}",
        offenders.join("\n")
    );
}

/// The geometry crate takes bytes and writes to any `io::Write`; it never opens a path.
#[test]
fn geometry_touches_no_file() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/geom/src");
    let lines = production_lines(&src);
    assert!(lines.len() > 10_000, "read only {} lines", lines.len());
    let offenders: Vec<String> = lines
        .iter()
        .filter_map(|(file, n, line)| {
            let call = FILE_CALLS.iter().find(|c| line.contains(*c))?;
            Some(format!("crates/geom/src/{file}:{n}: {call}"))
        })
        .collect();
    assert!(
        offenders.is_empty(),
        "filesystem calls in the geometry crate:\n{}",
        offenders.join("\n")
    );
}
