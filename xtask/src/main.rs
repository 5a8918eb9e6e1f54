//! Chores: `cargo xtask golden [--bless]`, `cargo xtask bench [--sizes 200,400,800]
//! [--no-peers] [--field separable|dense]`, `cargo xtask bench geom [NAME…]` (see
//! `bench_geom.rs`), `cargo xtask bench-mesh [triangles] [samples]`,
//! `cargo xtask bench-tile [--resolution N] [--formats stl,ply] [--keep]`,
//! `cargo xtask gallery` (the README's previews, see `gallery.rs`),
//! `cargo xtask codegen [--check]`, `cargo xtask fuzz [--minutes M] [TARGET…]` (see
//! `fuzz/mod.rs`; `--list`, `--replay`), `cargo xtask man [DIR]` (see `man.rs`),
//! `cargo xtask vendor-web` (see `vendor_web.rs`).
//!
//! Invariant: every generated file has a test that fails when it is stale
//! (`tests/codegen.rs`), so generated text cannot drift from its source.

mod bench_geom;
mod bench_mesh;
mod bench_tile;
mod fuzz;
mod gallery;
mod man;
mod vendor_web;

/// Counts live heap bytes so that the fuzz runner can bound them (see `fuzz/bound.rs`).
#[global_allocator]
static ALLOCATOR: fuzz::Bounded = fuzz::Bounded;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("golden") => golden(args.iter().any(|a| a == "--bless")),
        Some("bench") if args.get(1).is_some_and(|a| a == "geom") => bench_geom::run(&args[2..]),
        Some("bench") => bench(&args[1..]),
        Some("bench-mesh") => bench_mesh::run(&args[1..]),
        Some("bench-tile") => bench_tile::run(&args[1..]),
        Some("gallery") => gallery::run(),
        Some("codegen") => codegen(args.iter().any(|a| a == "--check")),
        Some("fuzz") => fuzz::run(&args[1..]),
        Some("man") => man::run(&args[1..]),
        Some("vendor-web") => vendor_web::run(),
        // Hidden: the child process of `fuzz`, one per target, fed inputs on stdin.
        Some("fuzz-runner") => match args.get(1) {
            Some(target) => fuzz::serve(target),
            None => Err("fuzz-runner needs a target".to_string()),
        },
        _ => Err(
            "usage: cargo xtask golden [--bless] | bench [--sizes 200,400,800] [--no-peers] \
                  [--field separable|dense] | bench geom [expr|mesh-io|periodic|scaffold|symmetric|validate|constrain|measure]… | bench-mesh [triangles] [samples] | bench-tile \
                  [--resolution N] [--formats stl,ply] [--keep] | gallery | codegen [--check] | fuzz \
                  [--minutes M] [--seed N] [TARGET…] | fuzz --list | fuzz --replay | man [DIR] | vendor-web"
                .to_string(),
        ),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("workspace root")
        .to_path_buf()
}

/// Material kept outside the repository (peer benchmark scripts, large scaffolds):
/// `$LATTICEBUILD_SHARED`, by default `../shared` beside the checkout.
fn shared_dir() -> PathBuf {
    std::env::var_os("LATTICEBUILD_SHARED").map_or_else(|| root().join("../shared"), PathBuf::from)
}

fn run(cmd: &mut Command) -> Result<(), String> {
    let status = cmd
        .status()
        .map_err(|e| format!("cannot run {cmd:?}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{cmd:?} failed: {status}"))
    }
}

/// Builds the release binary and returns its path.
fn release_binary() -> Result<PathBuf, String> {
    run(Command::new(env!("CARGO")).current_dir(root()).args([
        "build",
        "--release",
        "--quiet",
        "--bin",
        "latticebuild",
    ]))?;
    let target =
        std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root().join("target"), PathBuf::from);
    Ok(target.join("release/latticebuild"))
}

/// The tests that compare with files under `tests/golden/` (and bless them): the golden cases,
/// the manifest diagnostics of `src/manifest/tests` (`tests/golden/err/*.txt`), and the
/// integration tests that check a rendered diagnostic with `common::golden_err`.
const GOLDEN_TESTS: &[&str] = &[
    "golden::",
    "render_exactly",
    "manifest_json_schema_is_generated",
    "command_line_edges::a_manifest_that_is_not_utf8",
];

/// Runs the golden tests; with `--bless`, rewrites their expected files first.
fn golden(bless: bool) -> Result<(), String> {
    let mut cmd = Command::new(env!("CARGO"));
    cmd.current_dir(root())
        .args([
            "test",
            "--package",
            "latticebuild",
            "--lib",
            "--test",
            "integration",
            "--",
        ])
        .args(GOLDEN_TESTS);
    if bless {
        cmd.env("LATTICEBUILD_BLESS", "1");
    }
    run(&mut cmd)
}

/// The generated TPMS table of `docs/manifest.md`.
pub fn tpms_table() -> String {
    let mut s =
        String::from("| name | paper | formula (x, y, z in cells; τ = 2π) |\n|---|---|---|\n");
    for surface in &latticebuild_geom::tpms::LIBRARY {
        let formula = surface
            .formula
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        s.push_str(&format!(
            "| `{}` | {} | `{}` |\n",
            surface.name, surface.title, formula
        ));
    }
    s.push_str("\nAliases: ");
    let aliases: Vec<String> = latticebuild_geom::tpms::ALIASES
        .iter()
        .map(|(alias, name)| format!("`{alias}` → `{name}`"))
        .collect();
    s.push_str(&aliases.join(", "));
    s.push('\n');
    s
}

const TABLE_START: &str = "<!-- tpms-table -->";
const TABLE_END: &str = "<!-- /tpms-table -->";

/// `docs/manifest.md` with the TPMS table between the markers regenerated.
fn with_table(doc: &str) -> Result<String, String> {
    let start = doc
        .find(TABLE_START)
        .ok_or("docs/manifest.md has no <!-- tpms-table --> marker")?;
    let after = start + TABLE_START.len();
    let end = doc[after..]
        .find(TABLE_END)
        .map_or(after, |e| after + e + TABLE_END.len());
    Ok(format!(
        "{}{TABLE_START}\n{}{TABLE_END}{}",
        &doc[..start],
        tpms_table(),
        &doc[end..]
    ))
}

fn codegen(check: bool) -> Result<(), String> {
    let path = root().join("docs/manifest.md");
    let doc = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let new = with_table(&doc)?;
    if check {
        return if new == doc {
            Ok(())
        } else {
            Err("docs/manifest.md is stale: run `cargo xtask codegen`".into())
        };
    }
    std::fs::write(&path, new).map_err(|e| format!("{}: {e}", path.display()))
}

struct Timing {
    seconds: f64,
    peak_kib: u64,
}

/// Runs `cmd` under `/usr/bin/time -v` and reads wall time and peak RSS.
fn timed(cmd: &mut Command) -> Result<Timing, String> {
    let log = std::env::temp_dir().join(format!("xtask-time-{}.txt", std::process::id()));
    let program = cmd.get_program().to_owned();
    let mut timed = Command::new("/usr/bin/time");
    timed
        .arg("-v")
        .arg("-o")
        .arg(&log)
        .arg(program)
        .args(cmd.get_args());
    if let Some(dir) = cmd.get_current_dir() {
        timed.current_dir(dir);
    }
    for (k, v) in cmd.get_envs() {
        match v {
            Some(v) => timed.env(k, v),
            None => timed.env_remove(k),
        };
    }
    let out = timed
        .output()
        .map_err(|e| format!("cannot run /usr/bin/time: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "{:?} failed: {}\n{}",
            cmd.get_program(),
            out.status,
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let text = std::fs::read_to_string(&log).map_err(|e| e.to_string())?;
    let field = |name: &str| {
        text.lines().find_map(|l| {
            l.trim()
                .strip_prefix(name)
                .map(str::trim)
                .map(str::to_string)
        })
    };
    let wall = field("Elapsed (wall clock) time (h:mm:ss or m:ss):").ok_or("no wall time")?;
    let seconds = wall
        .split(':')
        .try_fold(0.0, |acc, part| part.parse::<f64>().map(|v| acc * 60.0 + v))
        .map_err(|e| e.to_string())?;
    let peak_kib = field("Maximum resident set size (kbytes):")
        .and_then(|v| v.parse().ok())
        .ok_or("no peak RSS")?;
    Ok(Timing { seconds, peak_kib })
}

fn bench(args: &[String]) -> Result<(), String> {
    let mut sizes = vec![200usize, 400, 800];
    let mut peers = true;
    let mut field = "separable".to_string();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--sizes" => {
                let v = it.next().ok_or("--sizes needs a list")?;
                sizes = v
                    .split(',')
                    .map(|s| s.parse().map_err(|_| format!("bad size `{s}`")))
                    .collect::<Result<_, _>>()?;
            }
            "--no-peers" => peers = false,
            "--field" => field = it.next().ok_or("--field needs a value")?.clone(),
            other => return Err(format!("unknown bench argument `{other}`")),
        }
    }
    let peer_dir = shared_dir().join("bench/peers");
    if peers && !peer_dir.join("run.sh").is_file() {
        println!(
            "peers skipped: {} not found (the peer scripts live outside the repository; set \
             LATTICEBUILD_SHARED to the folder holding bench/peers)",
            peer_dir.join("run.sh").display()
        );
        peers = false;
    }
    let bin = release_binary()?;
    let scratch = std::env::temp_dir().join(format!("latticebuild-bench-{}", std::process::id()));
    std::fs::create_dir_all(&scratch).map_err(|e| e.to_string())?;
    println!(
        "gyroid, domain [-1,1]^3, cell_size 1, solid inside, binary PLY; cold builds (cache cleaned);\n\
         `seconds` with report = \"basic\" (what the peers do), `full` the same cold build with the\n\
         full report (wall thickness and pore size measured); `preview s` what previews add to\n\
         `seconds`: the fastest of three cold builds with them less the fastest of three without"
    );
    println!(
        "{:>5} {:>10} {:>10} {:>12} {:>10} {:>10} {:>10} | peers ({field} field): seconds, peak MiB, ratio to latticebuild",
        "N", "seconds", "peak MiB", "triangles", "full s", "full MiB", "preview s"
    );
    for &n in &sizes {
        let manifest = scratch.join(format!("gyroid{n}.toml"));
        std::fs::write(
            &manifest,
            format!(
                "[build]\nreport = \"basic\"\n\n[cells.g]\ntpms = \"gyroid\"\n\n[outputs.g{n}]\ncell = \"g\"\ndomain = {{ min = [-1, -1, -1], max = [1, 1, 1] }}\ncell_size = 1\nsolid = \"inside\"\nsamples = {n}\nformats = [\"ply\"]\n"
            ),
        )
        .map_err(|e| e.to_string())?;
        let clean = || {
            run(Command::new(&bin)
                .arg("clean")
                .arg(&manifest)
                .stderr(std::process::Stdio::null()))
        };
        // Cold builds with and without previews, alternating; the fastest of each.
        let (mut ours, mut without) = (None::<Timing>, f64::INFINITY);
        for _ in 0..3 {
            clean()?;
            let with = timed(Command::new(&bin).arg("build").arg(&manifest).arg("-q"))?;
            if ours.as_ref().is_none_or(|o| with.seconds < o.seconds) {
                ours = Some(with);
            }
            clean()?;
            let bare = timed(
                Command::new(&bin)
                    .arg("build")
                    .arg(&manifest)
                    .args(["-q", "--no-previews"]),
            )?;
            without = without.min(bare.seconds);
        }
        let ours = ours.ok_or("no build timed")?;
        let preview = ours.seconds - without;
        // The report of the last build (without previews: the same mesh).
        let report = std::fs::read_to_string(scratch.join(format!("out/g{n}.report.json")))
            .unwrap_or_default();
        let triangles = report
            .lines()
            .find_map(|l| {
                l.trim()
                    .strip_prefix("\"triangles\":")
                    .map(|v| v.trim().trim_end_matches(',').to_string())
            })
            .unwrap_or_default();
        clean()?;
        let full = timed(
            Command::new(&bin)
                .arg("build")
                .arg(&manifest)
                .arg("-q")
                .args(["--set", "build.report=full"]),
        )?;
        let mut line = format!(
            "{n:>5} {:>10.3} {:>10.0} {:>12} {:>10.3} {:>10.0} {:>10} |",
            ours.seconds,
            ours.peak_kib as f64 / 1024.0,
            triangles,
            full.seconds,
            full.peak_kib as f64 / 1024.0,
            format!("{preview:+.3} ({:.1}%)", 100.0 * preview / ours.seconds),
        );
        if peers {
            for peer in ["vtk_flyingedges", "pymcubes", "skimage"] {
                let result = timed(
                    Command::new("bash")
                        .arg(peer_dir.join("run.sh"))
                        .arg(n.to_string())
                        .arg(peer)
                        .env("FIELD", &field)
                        .env("PEER_VENV", root().join("target/peers-venv"))
                        .env("OUT", &scratch),
                );
                match result {
                    Ok(t) => line.push_str(&format!(
                        " {peer} {:.3} s {:.0} MiB ({:.1}x)",
                        t.seconds,
                        t.peak_kib as f64 / 1024.0,
                        t.seconds / ours.seconds
                    )),
                    Err(e) => line.push_str(&format!(
                        " {peer} failed ({})",
                        e.lines().next().unwrap_or("")
                    )),
                }
            }
        }
        println!("{line}");
    }
    let _ = std::fs::remove_dir_all(&scratch);
    Ok(())
}
