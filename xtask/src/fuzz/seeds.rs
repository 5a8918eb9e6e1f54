//! A target's seeds: the repository's own files of its formats (examples, golden tests, the
//! geometry crate's test data), small hand-made files in `tests/fuzz_seeds/<target>/` for
//! formats nothing ships, and the saved findings of `tests/fuzz_corpus/<target>/`; for `sdf`,
//! the `sdf` programs of every manifest besides.

use std::path::{Path, PathBuf};

use super::targets::{Target, extension};

/// Directories searched for files of a target's extensions.
const SEARCHED: &[&str] = &["examples", "tests", "crates/geom/tests/data"];

pub struct Seed {
    pub bytes: Vec<u8>,
}

fn files_under(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            files_under(&path, out);
        } else {
            out.push(path);
        }
    }
}

pub fn corpus_dir(root: &Path, target: &str) -> PathBuf {
    root.join("tests/fuzz_corpus").join(target)
}

pub fn seeds(root: &Path, target: &Target) -> Vec<Seed> {
    let mut paths = Vec::new();
    for dir in SEARCHED {
        let mut all = Vec::new();
        files_under(&root.join(dir), &mut all);
        // The fuzz directories are added whole below, whatever their files' names.
        all.retain(|p| {
            !p.starts_with(root.join("tests/fuzz_seeds"))
                && !p.starts_with(root.join("tests/fuzz_corpus"))
        });
        paths.extend(
            all.into_iter()
                .filter(|p| extension(p).is_some_and(|e| target.extensions.contains(&e.as_str()))),
        );
    }
    files_under(&root.join("tests/fuzz_seeds").join(target.name), &mut paths);
    files_under(&corpus_dir(root, target.name), &mut paths);
    let mut seeds: Vec<Seed> = paths
        .iter()
        .filter_map(|p| std::fs::read(p).ok().map(|bytes| Seed { bytes }))
        .collect();
    if target.name == "sdf" {
        let mut manifests = Vec::new();
        for dir in SEARCHED {
            files_under(&root.join(dir), &mut manifests);
        }
        for path in manifests {
            if extension(&path).as_deref() != Some("toml") {
                continue;
            }
            let Ok(text) = std::fs::read_to_string(&path) else {
                continue;
            };
            let Ok(value) = text.parse::<toml::Table>() else {
                continue;
            };
            let mut programs = Vec::new();
            sdf_programs(&toml::Value::Table(value), &mut programs);
            seeds.extend(programs.into_iter().map(|p| Seed {
                bytes: p.into_bytes(),
            }));
        }
    }
    seeds.sort_by(|a, b| a.bytes.cmp(&b.bytes));
    seeds.dedup_by(|a, b| a.bytes == b.bytes);
    seeds
}

/// Every string value of a key `sdf`, at any depth.
fn sdf_programs(value: &toml::Value, out: &mut Vec<String>) {
    match value {
        toml::Value::Table(t) => {
            for (key, v) in t {
                match v {
                    toml::Value::String(s) if key == "sdf" => out.push(s.clone()),
                    _ => sdf_programs(v, out),
                }
            }
        }
        toml::Value::Array(items) => {
            for v in items {
                sdf_programs(v, out);
            }
        }
        _ => {}
    }
}
