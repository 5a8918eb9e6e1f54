//! The incremental behaviour users rely on (docs/method.md §2), checked through the real binary.

use crate::common;

use common::{Project, ran};

const MANIFEST: &str = r#"
# a comment
[cells.g]
tpms = "gyroid"

[cells.p]
tpms = "p"

[outputs.a]
cell = "g"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 41
formats = ["stl"]

[outputs.b]
cell = "p"
domain = { min = [0, 0, 0], max = [2, 1, 1] }
solid = "shell"
thickness = 0.5
samples = [61, 31, 31]
formats = ["ply"]
"#;

#[test]
fn second_build_runs_nothing() {
    let p = Project::new(MANIFEST);
    let first = p.build(&[]);
    assert_eq!(
        ran(&first),
        [
            "cell:g",
            "cell:p",
            "contour:a",
            "contour:b",
            "write:a",
            "write:b"
        ]
    );
    let second = p.build(&[]);
    assert!(ran(&second).is_empty(), "ran {:?}", ran(&second));
}

#[test]
fn comments_and_table_order_do_not_rebuild() {
    let p = Project::new(MANIFEST);
    p.build(&[]);
    // Move output `b` before the cells and change comments and spacing.
    let (head, b) = MANIFEST.split_at(MANIFEST.find("[outputs.b]").expect("b"));
    p.write(
        "lattice.toml",
        &format!(
            "# another comment\n{b}\n\n{}\n# end",
            head.replace("# a comment", "")
        ),
    );
    assert!(ran(&p.build(&[])).is_empty());
}

#[test]
fn changing_formats_reruns_only_writing() {
    let p = Project::new(MANIFEST);
    p.build(&[]);
    let reports = p.build(&["--set", "outputs.a.formats=[\"stl\", \"obj\"]"]);
    assert_eq!(ran(&reports), ["write:a"]);
    assert!(p.out("a.obj").is_file());
}

#[test]
fn changing_an_offset_reruns_its_contour_and_write_only() {
    let p = Project::new(MANIFEST);
    p.build(&[]);
    let reports = p.build(&["--set", "outputs.a.offset=0.2"]);
    assert_eq!(ran(&reports), ["contour:a", "write:a"]);
}

#[test]
fn an_equivalent_cell_name_stops_the_rebuild_at_the_cell() {
    let p = Project::new(MANIFEST);
    p.build(&[]);
    // `schwarz-p` is an alias of `p`: the cell reruns, produces the same formula, and the
    // contour keyed on that formula stays cached.
    let reports = p.build(&["--set", "cells.p.tpms=schwarz-p"]);
    assert!(
        ran(&reports).is_empty() || ran(&reports) == ["cell:p"],
        "ran {:?}",
        ran(&reports)
    );
}

#[test]
fn deleted_output_files_are_rewritten() {
    let p = Project::new(MANIFEST);
    p.build(&[]);
    let before = std::fs::read(p.out("a.stl")).expect("a.stl");
    std::fs::remove_file(p.out("a.stl")).expect("remove");
    assert_eq!(ran(&p.build(&[])), ["write:a"]);
    assert_eq!(std::fs::read(p.out("a.stl")).expect("a.stl"), before);
}

fn outputs(p: &Project) -> Vec<Vec<u8>> {
    ["a.stl", "b.ply"]
        .iter()
        .map(|f| std::fs::read(p.out(f)).expect("output"))
        .collect()
}

#[test]
fn one_and_many_threads_and_cold_and_warm_builds_give_identical_files() {
    let p = Project::new(MANIFEST);
    p.build(&["-j", "1"]);
    let single = outputs(&p);
    let clean = p.run(&["clean", "lattice.toml"]);
    assert!(clean.status.success());
    for f in ["a.stl", "b.ply"] {
        std::fs::remove_file(p.out(f)).expect("remove");
    }
    let cold = p.build(&["-j", "2"]);
    assert_eq!(ran(&cold).len(), 6, "clean emptied the cache");
    assert_eq!(outputs(&p), single);
    // Warm: change the formats of b and back, so b is rewritten from the cached mesh.
    p.build(&["--set", "outputs.b.formats=[\"stl\"]"]);
    std::fs::remove_file(p.out("b.ply")).expect("remove");
    p.build(&[]);
    assert_eq!(outputs(&p), single);
}

#[test]
fn truncated_cache_entries_are_rebuilt() {
    let p = Project::new(MANIFEST);
    p.build(&[]);
    let before = outputs(&p);
    let objects = p.path().join(".latticebuild");
    let mut entries = Vec::new();
    let mut stack = vec![objects];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).expect("dir") {
            let path = e.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if path
                .parent()
                .and_then(|d| d.parent())
                .is_some_and(|d| d.ends_with("objects"))
            {
                entries.push(path);
            }
        }
    }
    assert!(!entries.is_empty());
    for entry in &entries {
        let len = std::fs::metadata(entry).expect("meta").len();
        let f = std::fs::OpenOptions::new()
            .write(true)
            .open(entry)
            .expect("open");
        f.set_len(len / 2).expect("truncate");
    }
    // Every output file must be rewritten identically even though every entry is broken.
    for f in ["a.stl", "b.ply"] {
        std::fs::remove_file(p.out(f)).expect("remove");
    }
    p.build(&[]);
    assert_eq!(outputs(&p), before);
    assert!(
        ran(&p.build(&[])).is_empty(),
        "the rebuilt entries are good again"
    );
}

#[test]
fn graph_marks_cached_and_stale_nodes() {
    let p = Project::new(MANIFEST);
    let before = String::from_utf8(p.run(&["graph", "lattice.toml"]).stdout).expect("utf8");
    assert!(before.lines().all(|l| l.contains("stale")), "{before}");
    p.build(&[]);
    let after = String::from_utf8(p.run(&["graph", "lattice.toml"]).stdout).expect("utf8");
    // Two cells, two contours, two writes and two previews.
    assert_eq!(
        after.lines().filter(|l| l.contains("cached")).count(),
        8,
        "{after}"
    );
    let changed = p.run(&["graph", "lattice.toml", "--set", "outputs.a.samples=33"]);
    let text = String::from_utf8(changed.stdout).expect("utf8");
    let contour = text
        .lines()
        .find(|l| l.starts_with("contour:a"))
        .expect("contour:a line");
    assert!(
        contour.contains("stale") && contour.contains("samples"),
        "{contour}"
    );
}

#[test]
fn concurrent_builds_on_one_cache_both_succeed_with_identical_files() {
    let p = Project::new(MANIFEST);
    let spawn = || {
        std::process::Command::new(common::BIN)
            .args(["build", "lattice.toml", "-q"])
            .current_dir(p.path())
            .spawn()
            .expect("spawn build")
    };
    let (mut a, mut b) = (spawn(), spawn());
    assert!(a.wait().expect("wait a").success());
    assert!(b.wait().expect("wait b").success());
    let first = outputs(&p);
    // Whatever interleaving happened, the cache is sound: a rebuild runs nothing and the
    // files equal a fresh build's.
    assert!(ran(&p.build(&[])).is_empty());
    let fresh = Project::new(MANIFEST);
    fresh.build(&[]);
    assert_eq!(outputs(&fresh), first);
}

#[cfg(unix)]
#[test]
fn a_build_removes_only_the_temporary_files_of_its_own_outputs() {
    let p = Project::new(MANIFEST);
    std::fs::create_dir_all(p.out("")).expect("mkdir");
    // A process that is gone, as a build killed with SIGKILL is.
    let mut child = std::process::Command::new("true").spawn().expect("spawn");
    child.wait().expect("wait");
    let dead = child.id();
    let ours = [
        format!(".a.stl.tmp-{dead}-0"),
        format!(".b.ply.tmp-{dead}-3"),
        format!(".a.report.json.tmp-{dead}-1"),
    ];
    // Names like ours, of files no output of this manifest writes: not ours to remove.
    let others = [
        format!(".notes.txt.tmp-{dead}-0"),
        format!(".a.ply.tmp-{dead}-0"),
        format!(".tmp-{dead}-0-00ff"),
        "part.stl".to_string(),
    ];
    for name in ours.iter().chain(&others) {
        std::fs::write(p.out(name), b"old").expect("write");
    }
    p.build(&[]);
    for name in &ours {
        assert!(!p.out(name).exists(), "`{name}` was left");
    }
    for name in &others {
        assert!(p.out(name).exists(), "`{name}` was removed");
    }
}
