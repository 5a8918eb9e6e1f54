//! A build tool under misuse: results that are empty or broken fail the build (exit 1) with a
//! message that says why, instead of writing empty files and exiting 0.

use crate::common;

use common::Project;

/// `(exit code, stderr)` of `latticebuild build lattice.toml ARGS` in `p`.
fn build(p: &Project, extra: &[&str]) -> (Option<i32>, String) {
    let mut args = vec!["build", "lattice.toml"];
    args.extend_from_slice(extra);
    let out = p.run(&args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_field_that_never_crosses_zero_fails_and_says_its_range() {
    let p = Project::new(
        "[cells.one]\nexpr = \"1 + 0.5 * cos(tau * x)\"\n\n[outputs.blank]\ncell = \"one\"\n\
         domain = { min = [0, 0, 0], max = [1, 1, 1] }\nsamples = 9\n",
    );
    let (code, stderr) = build(&p, &[]);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(stderr.contains("the output is empty"), "{stderr}");
    assert!(stderr.contains("f ≤ 0 holds at no sample"), "{stderr}");
    assert!(stderr.contains("[0.500000, 1.500000]"), "{stderr}");
    // Nothing half-made is left for the user to mistake for a result.
    assert!(!p.out("blank.stl").exists());
    assert!(!p.out("blank.report.json").exists());
}

#[test]
fn a_crystal_surface_with_no_inside_fails() {
    let p = Project::new(&format!(
        "[cells.na]\ncrystal = \"{}/crates/geom/tests/data/crystals/NaCl.cif\"\nspecies = \"Na\"\n\n\
         [outputs.na]\ncell = \"na\"\ndomain = {{ min = [0, 0, 0], max = [1, 1, 1] }}\n\
         solid = \"inside\"\nsamples = 17\n",
        env!("CARGO_MANIFEST_DIR")
    ));
    let (code, stderr) = build(&p, &[]);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(stderr.contains("the output is empty"), "{stderr}");
    assert!(!p.out("na.stl").exists());
}

// ---- interrupted builds leave no temporary files ----------------------------------------------

/// A gyroid whose text meshes take seconds to write, so a signal lands mid-write.
const SLOW_WRITE: &str = "[cells.g]\ntpms = \"gyroid\"\n\n[outputs.big]\ncell = \"g\"\n\
    domain = { min = [0, 0, 0], max = [4, 4, 4] }\nsamples = 200\n\
    formats = [\"stl\", \"ply\", \"obj\"]\nascii = true\n";

/// Our temporary files under `dir` (outputs' `.NAME.tmp-…` and the cache's `.tmp-…`).
fn temporaries(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut found = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return found;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            found.extend(temporaries(&path));
        } else if entry.file_name().to_string_lossy().contains(".tmp-") {
            found.push(path);
        }
    }
    found
}

/// Starts a build of `p` and returns it once a temporary output file exists.
fn build_until_writing(p: &Project) -> std::process::Child {
    let mut child = std::process::Command::new(common::BIN)
        .args(["build", "lattice.toml", "-q"])
        .current_dir(p.path())
        .spawn()
        .expect("spawn build");
    let start = std::time::Instant::now();
    while temporaries(&p.path().join("out")).is_empty() {
        assert!(
            child.try_wait().expect("poll").is_none(),
            "the build ended before writing"
        );
        assert!(start.elapsed().as_secs() < 60, "no temporary file appeared");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child
}

/// Waits for `child`, which must end within `seconds`.
fn ends_within(child: &mut std::process::Child, seconds: f64) -> std::process::ExitStatus {
    let start = std::time::Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("poll") {
            return status;
        }
        assert!(
            start.elapsed().as_secs_f64() < seconds,
            "the build did not stop within {seconds} s"
        );
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

#[cfg(unix)]
fn send(child: &std::process::Child, signal: &str) {
    let sent = std::process::Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(sent.success());
}

#[cfg(unix)]
#[test]
fn ctrl_c_and_sigterm_stop_a_build_at_once_and_remove_its_temporaries() {
    use std::os::unix::process::ExitStatusExt;
    let p = Project::new(SLOW_WRITE);
    for (flag, number) in [("-INT", 2), ("-TERM", 15)] {
        let mut child = build_until_writing(&p);
        send(&child, flag);
        let status = ends_within(&mut child, 2.0);
        assert_eq!(status.signal(), Some(number), "killed by the signal it got");
        assert_eq!(temporaries(p.path()), Vec::<std::path::PathBuf>::new());
    }
}

#[cfg(unix)]
#[test]
fn a_build_killed_hard_leaves_temporaries_that_the_next_build_and_clean_remove() {
    let p = Project::new(SLOW_WRITE);
    for next in ["build", "clean"] {
        let mut child = build_until_writing(&p);
        send(&child, "-KILL");
        ends_within(&mut child, 5.0);
        let left = temporaries(&p.path().join("out"));
        assert!(!left.is_empty(), "SIGKILL cannot be handled");
        // A quick build (a small grid) sweeps as it starts.
        let args: &[&str] = match next {
            "build" => &[
                "build",
                "lattice.toml",
                "-q",
                "--set",
                "outputs.big.samples=8",
            ],
            _ => &["clean", "lattice.toml"],
        };
        let out = p.run(args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        for path in left {
            assert!(!path.exists(), "`{next}` left {}", path.display());
        }
    }
}

#[cfg(unix)]
#[test]
fn a_live_builds_temporaries_are_not_swept() {
    let p = Project::new(SLOW_WRITE);
    // A temporary of one of the outputs, as another running build of it would have: this
    // test's own pid. (A name of a file no output writes is never swept at all.)
    std::fs::create_dir_all(p.path().join("out")).expect("mkdir");
    let busy = p.out(&format!(".big.stl.tmp-{}-0", std::process::id()));
    std::fs::write(&busy, b"being written").expect("write");
    let out = p.run(&[
        "build",
        "lattice.toml",
        "-q",
        "--set",
        "outputs.big.samples=8",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(busy.exists());
}

// ---- requests the machine cannot hold are refused before anything runs -----------------------

const GYROID: &str = "[cells.g]\ntpms = \"gyroid\"\n\n[outputs.g]\ncell = \"g\"\n\
    domain = { min = [0, 0, 0], max = [10, 10, 10] }\ncell_size = 5\nsamples = 40\n";

#[test]
fn samples_beyond_the_machine_are_refused_up_front_naming_the_key_and_sizes() {
    let p = Project::new(GYROID);
    for samples in ["100000", "35000"] {
        let started = std::time::Instant::now();
        let set = format!("outputs.g.samples={samples}");
        let (code, stderr) = build(&p, &["--set", &set]);
        assert_eq!(code, Some(2), "{stderr}");
        assert!(
            started.elapsed().as_secs() < 10,
            "refused only after working"
        );
        assert!(stderr.contains("output `g` would need about"), "{stderr}");
        assert!(
            stderr.contains("of memory (`outputs.g.samples`"),
            "{stderr}"
        );
        assert!(stderr.contains("is available"), "{stderr}");
        assert!(stderr.contains("--allow-large"), "{stderr}");
        assert!(!stderr.contains("panicked") && !stderr.contains("memory allocation"));
    }
    assert!(!p.path().join("out").exists(), "nothing is written");
}

#[test]
fn a_tiling_that_would_fill_the_disk_is_refused() {
    let p = Project::new(
        "[cells.p]\ntpms = \"p\"\nsymmetry = \"Oh\"\n\n[scaffolds.big]\n\
         grid = { min = [0, 0, 0], max = [215, 215, 216], divisions = [215, 215, 216], \
         element = \"hex\" }\n\n[outputs.t]\nscaffold = \"big\"\ncell = \"p\"\nresolution = 12\n",
    );
    let (code, stderr) = build(&p, &[]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("TB (files and cache; `t`"), "{stderr}");
    assert!(stderr.contains("`outputs.t.resolution`"), "{stderr}");
    assert!(stderr.contains("free"), "{stderr}");
}

#[test]
fn the_report_carries_the_estimate_and_it_bounds_the_real_mesh() {
    let p = Project::new(GYROID);
    let reports = p.build(&[]);
    let report = &reports[0];
    let triangles = report["triangles"].as_f64().expect("triangles");
    let estimated = report["estimate"]["triangles"].as_f64().expect("estimate");
    assert!(
        (triangles..6.0 * triangles).contains(&estimated),
        "{estimated} against {triangles}"
    );
    assert!(report["estimate"]["memory_bytes"].as_u64().is_some());
    assert!(report["estimate"]["disk_bytes"].as_u64().is_some());
}

#[test]
fn absurd_job_counts_are_capped() {
    let p = Project::new(GYROID);
    let started = std::time::Instant::now();
    let (code, stderr) = build(&p, &["-j", "100000", "-q"]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        stderr.contains("warning: `--jobs 100000` is more than"),
        "{stderr}"
    );
    assert!(started.elapsed().as_secs() < 20);
}

#[test]
fn the_sdf_command_refuses_a_grid_beyond_the_machine() {
    let p = Project::new("");
    let out = p.run(&["sdf", "-s", "99999,99999,3", "ball", "-o", "big.stl"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("of memory (`-s`"), "{stderr}");
    assert!(stderr.contains("--allow-large"), "{stderr}");
    assert!(!stderr.contains("memory allocation"), "{stderr}");
    assert!(!p.path().join("big.stl").exists());
}
