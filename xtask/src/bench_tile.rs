//! `cargo xtask bench-tile [--resolution N] [--formats stl,ply] [--keep]`: tiling end to end,
//! through the release binary, as a user runs it: a Td-fitted Schwarz P tiled into the Gmsh
//! brackets of `data/scaffolds` (9,627 and 98,228 tet4) in the shared folder outside the
//! repository (`$LATTICEBUILD_SHARED`, default `shared` beside the checkout; a bracket not found
//! there is skipped with a message). Each timed build reruns the
//! tile and write stages (a new offset; the fitted cell stays cached), so it measures reading
//! the scaffold, tiling, checking the mesh, streaming the cache entry and writing the files.
//!
//! Printed per scaffold, for a build writing new files and for one replacing them: the stage
//! times from the build's report, the whole command's wall time, triangles per second of both,
//! the child's peak resident memory (its `VmHWM`, polled from `/proc` while it runs, so Linux
//! only) and the bytes written. Threads: all cores.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const SCAFFOLDS: [(&str, &str); 2] = [
    ("bracket_10k", "bracket_tet4.msh"),
    ("bracket_100k", "bracket_tet4_100k_msh41bin.msh"),
];

struct Options {
    resolution: usize,
    formats: Vec<String>,
    keep: bool,
}

fn options(args: &[String]) -> Result<Options, String> {
    let mut o = Options {
        resolution: 12,
        formats: vec!["stl".into()],
        keep: false,
    };
    let mut args = args.iter();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--resolution" => {
                o.resolution = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .ok_or("--resolution takes a number")?;
            }
            "--formats" => {
                let list = args.next().ok_or("--formats takes a list, as stl,ply")?;
                o.formats = list.split(',').map(|f| f.trim().to_string()).collect();
            }
            "--keep" => o.keep = true,
            other => return Err(format!("unknown bench-tile argument `{other}`")),
        }
    }
    Ok(o)
}

fn manifest(o: &Options, scaffolds: &[(&str, &str)]) -> String {
    let formats: Vec<String> = o.formats.iter().map(|f| format!("\"{f}\"")).collect();
    // The tiling and its files only: the full report's wall-thickness measurement is timed by
    // `cargo xtask bench` (it would be most of the 10k bracket's write, and skips the 100k).
    let mut text = String::from(
        "[build]\nreport = \"basic\"\n\n[cells.p_td]\ntpms = \"p\"\nsymmetry = \"Td\"\nfit = { n = 32 }\n",
    );
    for (name, file) in scaffolds {
        text += &format!("\n[scaffolds.{name}]\nmesh = \"{file}\"\n");
        text += &format!(
            "\n[outputs.{name}]\nscaffold = \"{name}\"\ncell = \"p_td\"\noffset = 0.2\n\
             resolution = {}\nformats = [{}]\n",
            o.resolution,
            formats.join(", ")
        );
    }
    text
}

/// Runs `latticebuild ARGS` in `dir`: its stdout, wall seconds and peak RSS in KiB.
fn timed(bin: &Path, dir: &Path, args: &[&str]) -> Result<(String, f64, Option<u64>), String> {
    let started = Instant::now();
    let mut child = Command::new(bin)
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot run {}: {e}", bin.display()))?;
    let status_file = PathBuf::from(format!("/proc/{}/status", child.id()));
    let mut peak = None;
    // stdout is small (one report), so it cannot fill the pipe while we poll.
    while child.try_wait().map_err(|e| e.to_string())?.is_none() {
        if let Ok(status) = std::fs::read_to_string(&status_file)
            && let Some(kib) = status
                .lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        {
            peak = Some(kib);
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().map_err(|e| e.to_string())?;
    let seconds = started.elapsed().as_secs_f64();
    if !out.status.success() {
        return Err(format!("latticebuild {args:?} failed: {}", out.status));
    }
    Ok((
        String::from_utf8_lossy(&out.stdout).into_owned(),
        seconds,
        peak,
    ))
}

fn stage_seconds(report: &serde_json::Value, prefix: &str) -> f64 {
    report["stages"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|s| s["stage"].as_str().is_some_and(|n| n.starts_with(prefix)))
        .filter_map(|s| s["seconds"].as_f64())
        .sum()
}

pub fn run(args: &[String]) -> Result<(), String> {
    let o = options(args)?;
    let data = super::shared_dir().join("data/scaffolds");
    let (found, missing): (Vec<_>, Vec<_>) = SCAFFOLDS
        .iter()
        .copied()
        .partition(|s| data.join(s.1).is_file());
    for (name, file) in missing {
        println!(
            "{name} skipped: {} not found (the brackets live outside the repository; set \
             LATTICEBUILD_SHARED to the folder holding data/scaffolds)",
            data.join(file).display()
        );
    }
    if found.is_empty() {
        return Ok(());
    }
    let bin = super::release_binary()?;
    let dir = std::env::temp_dir().join(format!("latticebuild-bench-tile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    for (_, file) in &found {
        std::fs::copy(data.join(file), dir.join(file))
            .map_err(|e| format!("cannot copy {}: {e}", data.join(file).display()))?;
    }
    std::fs::write(dir.join("lattice.toml"), manifest(&o, &found)).map_err(|e| e.to_string())?;
    // Fits the cell (and reads the small scaffold) once, untimed.
    timed(&bin, &dir, &["build", "lattice.toml", found[0].0, "-q"])?;
    // So that each scaffold's first timed build writes new files, and its second replaces them.
    let _ = std::fs::remove_dir_all(dir.join("out"));
    println!(
        "tiling end to end, resolution {}, formats {}, {} cores (all threads)",
        o.resolution,
        o.formats.join(","),
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    println!(
        "{:<13} {:<8} {:>8} {:>11} {:>7} {:>7} {:>7} {:>9} {:>9} {:>9} {:>10}",
        "scaffold",
        "files",
        "elements",
        "triangles",
        "tile s",
        "write s",
        "total s",
        "tile M/s",
        "total M/s",
        "peak MiB",
        "written MB"
    );
    // `new`: no file of that name yet; `replace`: the previous build's files are replaced,
    // which on a `discard` mount waits for the old file to be freed (about 0.2 s a GB).
    let runs = found
        .iter()
        .flat_map(|(name, _)| [(*name, "new"), (*name, "replace")]);
    for (k, (name, files)) in runs.enumerate() {
        let offset = format!("outputs.{name}.offset={}", 0.2 + 1e-6 * (k + 1) as f64);
        let (stdout, seconds, peak) = timed(
            &bin,
            &dir,
            &[
                "build",
                "lattice.toml",
                name,
                "-q",
                "--set",
                &offset,
                "--report",
                "-",
            ],
        )?;
        let reports: serde_json::Value =
            serde_json::from_str(&stdout).map_err(|e| format!("report: {e}"))?;
        let r = &reports[0];
        let reran = r["stages"].as_array().into_iter().flatten().any(|s| {
            s["stage"].as_str().is_some_and(|n| n.starts_with("tile:")) && s["cached"] == false
        });
        if !reran {
            return Err(format!("the tile stage of `{name}` did not rerun: {r}"));
        }
        let triangles = r["triangles"].as_f64().unwrap_or(0.0);
        let tile = stage_seconds(r, "tile:");
        let write = stage_seconds(r, "write:");
        let written: u64 = r["files"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|f| f.as_str())
            .filter_map(|f| std::fs::metadata(dir.join(f)).ok())
            .map(|m| m.len())
            .sum();
        println!(
            "{:<13} {:<8} {:>8} {:>11} {:>7.2} {:>7.2} {:>7.2} {:>9.2} {:>9.2} {:>9} {:>10.0}",
            name,
            files,
            r["tiling"]["elements"].as_u64().unwrap_or(0),
            triangles,
            tile,
            write,
            seconds,
            triangles / tile.max(1e-9) / 1e6,
            triangles / seconds / 1e6,
            peak.map_or("n/a".into(), |kib| format!("{:.0}", kib as f64 / 1024.0)),
            written as f64 / 1e6
        );
    }
    if o.keep {
        println!("kept {}", dir.display());
    } else {
        std::fs::remove_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    Ok(())
}
