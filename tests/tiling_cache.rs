//! A 3D tiling's chunked cache entry through the real binary: a damaged entry (a flipped bit
//! in a chunk, in the trailer, or a truncated file) reruns the tile stage and rewrites
//! identical files, never a wrong one; every format written from the chunked entry matches
//! the one written by a cold build.

use crate::common;

use std::path::{Path, PathBuf};

use common::{Project, ran};

const GRID: &str = r#"
[cells.p]
tpms = "p"
symmetry = "Oh"
fit = { n = 16 }

[scaffolds.block]
grid = { min = [0, 0, 0], max = [8, 6, 4], divisions = [4, 3, 2], element = "hex" }

[outputs.a]
scaffold = "block"
cell = "p"
resolution = 12
formats = ["stl", "ply", "obj", "off", "vtk"]
"#;

/// Cache entries: a 48-byte header, then the payload; the chunked one starts `LBCHUNK1`.
const HEADER: u64 = 48;

fn chunked_entry(p: &Project) -> PathBuf {
    let mut stack = vec![p.path().join(".latticebuild")];
    let mut found = Vec::new();
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).expect("dir") {
            let path = e.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if std::fs::read(&path)
                .is_ok_and(|b| b.get(48..56) == Some(b"LBCHUNK1".as_slice()))
            {
                found.push(path);
            }
        }
    }
    assert_eq!(found.len(), 1, "{found:?}");
    found.remove(0)
}

const FILES: [&str; 5] = ["a.stl", "a.ply", "a.obj", "a.off", "a.vtk"];

fn outputs(p: &Project) -> Vec<Vec<u8>> {
    FILES
        .iter()
        .map(|f| std::fs::read(p.out(f)).expect("output"))
        .collect()
}

fn remove_outputs(p: &Project) {
    for f in FILES {
        std::fs::remove_file(p.out(f)).expect("remove");
    }
}

fn flip(path: &Path, at: u64) {
    let mut bytes = std::fs::read(path).expect("read");
    bytes[at as usize] ^= 0x10;
    std::fs::write(path, bytes).expect("write");
}

/// Builds verbosely, returning the reports' stages that ran and the `-v` text.
fn build_verbose(p: &Project) -> (Vec<String>, String) {
    let out = p.run(&["build", "lattice.toml", "--report", "report.json", "-v"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(p.path().join("report.json")).expect("report"))
            .expect("json");
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    (ran(&report), text)
}

#[test]
fn damaged_chunked_entries_rerun_the_tiling_and_rewrite_identical_files() {
    let p = Project::new(GRID);
    let first = p.build(&[]);
    let before = outputs(&p);
    let entry = chunked_entry(&p);
    let len = std::fs::metadata(&entry).expect("meta").len();

    // A bit in the first chunk's triangles: seen only when the write reads it.
    flip(&entry, HEADER + 8 + (len - HEADER) / 3);
    remove_outputs(&p);
    let (stages, text) = build_verbose(&p);
    assert_eq!(stages, ["tile:a", "write:a"], "{text}");
    assert!(text.contains("corrupt"), "{text}");
    assert_eq!(outputs(&p), before);
    assert!(ran(&p.build(&[])).is_empty(), "the rebuilt entry is good");

    // A bit in the trailer (its summary): seen when the entry is opened.
    flip(&entry, len - 60);
    remove_outputs(&p);
    assert_eq!(ran(&p.build(&[])), ["tile:a", "write:a"]);
    assert_eq!(outputs(&p), before);

    // A bit in the hash the entry's header declares (a self-verifying entry: the trailer's
    // hash): seen when the entry is opened, never passed on as the mesh's hash.
    flip(&entry, 20);
    remove_outputs(&p);
    assert_eq!(ran(&p.build(&[])), ["tile:a", "write:a"]);
    assert_eq!(outputs(&p), before);

    // Truncated: seen from the header alone, so the tile node is a plain miss.
    let file = std::fs::OpenOptions::new()
        .write(true)
        .open(&entry)
        .expect("open");
    file.set_len(len / 2).expect("truncate");
    drop(file);
    remove_outputs(&p);
    assert_eq!(ran(&p.build(&[])), ["tile:a", "write:a"]);
    assert_eq!(outputs(&p), before);
    // The report is what the first build said.
    let last = p.build(&[]);
    for key in ["triangles", "vertices", "volume", "watertight", "tiling"] {
        assert_eq!(last[0][key], first[0][key], "{key}");
    }
}

#[test]
fn formats_written_from_the_cached_chunks_match_a_cold_build() {
    let cold = Project::new(GRID);
    cold.build(&[]);
    let warm = Project::new(&GRID.replace(
        "formats = [\"stl\", \"ply\", \"obj\", \"off\", \"vtk\"]",
        "formats = [\"stl\"]",
    ));
    warm.build(&[]);
    let edit = warm.build(&[
        "--set",
        "outputs.a.formats=[\"stl\", \"ply\", \"obj\", \"off\", \"vtk\"]",
    ]);
    assert_eq!(ran(&edit), ["write:a"]);
    assert_eq!(outputs(&warm), outputs(&cold));
    // And in ASCII.
    let ascii = warm.build(&["--set", "outputs.a.ascii=true"]);
    assert_eq!(ran(&ascii), ["write:a"]);
    let stl = std::fs::read(warm.out("a.stl")).expect("stl");
    assert!(stl.starts_with(b"solid latticebuild "));
}
