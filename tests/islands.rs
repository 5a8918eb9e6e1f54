//! Removing loose pieces (`keep = "largest"`, `min_island_volume`) through the real binary.
//! The expected numbers are measured here, independently of the tool's own piece code: the
//! unfiltered output is written as ASCII PLY, split into connected surfaces by a union-find of
//! this file, and each surface's signed volume summed; the filtered output must be exactly
//! the pieces that pass.

use crate::common;

use common::{Project, number, ran};

/// Schwarz P's `f ≥ offset` in each hexahedron of a 3 × 2 × 2 grid is a ball about the
/// element's centre (P is 3 there and at most 1 on the faces); a graded offset makes the 12
/// balls of 12 sizes. A hollow ball with a small ball in its cavity, as a plain output.
const MANIFEST: &str = r#"
[cells.p_oh]
tpms = "p"
symmetry = "Oh"

[cells.hollow]
expr = "min(abs(sqrt(x*x + y*y + z*z) - 0.3) - 0.05, sqrt(x*x + y*y + z*z) - 0.12)"

[scaffolds.cubes]
grid = { min = [0, 0, 0], max = [3, 2, 2], divisions = [3, 2, 2], element = "hex" }

[outputs.balls]
scaffold = "cubes"
cell = "p_oh"
solid = "outside"
offset = "2.4 - 0.2 * x - 0.05 * y - 0.02 * z"
resolution = 12
formats = ["ply"]
ascii = true

[outputs.hollow_balls]
scaffold = "cubes"
cell = "p_oh"
solid = "eccentric_shell"
offset = "2.4 - 0.2 * x - 0.05 * y - 0.02 * z"
thickness = 0.3
resolution = 12
formats = ["ply"]
ascii = true

[outputs.hollow]
cell = "hollow"
domain = { min = [-0.5, -0.5, -0.5], max = [0.5, 0.5, 0.5] }
samples = 41
formats = ["ply"]
ascii = true
"#;

/// The vertices and triangles of an ASCII PLY file of ours.
fn read_ply(path: &std::path::Path) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let text = std::fs::read_to_string(path).expect("ply");
    let (header, body) = text.split_once("end_header\n").expect("header");
    let count = |element: &str| -> usize {
        header
            .lines()
            .find_map(|l| l.strip_prefix(&format!("element {element} ")))
            .and_then(|n| n.trim().parse().ok())
            .expect("count")
    };
    let (nv, nf) = (count("vertex"), count("face"));
    let mut lines = body.lines();
    let vertices = (0..nv)
        .map(|_| {
            // Written as the shortest text of each `f32`: read back as the same `f32`.
            let v: Vec<f64> = lines
                .next()
                .expect("vertex")
                .split_whitespace()
                .map(|x| f64::from(x.parse::<f32>().expect("number")))
                .collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    let faces = (0..nf)
        .map(|_| {
            let f: Vec<usize> = lines
                .next()
                .expect("face")
                .split_whitespace()
                .map(|x| x.parse().expect("index"))
                .collect();
            assert_eq!(f[0], 3);
            [f[1], f[2], f[3]]
        })
        .collect();
    (vertices, faces)
}

/// The signed volume of each connected surface (through shared vertices), in first-triangle
/// order.
fn surface_volumes(path: &std::path::Path) -> Vec<f64> {
    let (vertices, faces) = read_ply(path);
    let mut parent: Vec<usize> = (0..vertices.len()).collect();
    fn root(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            x = parent[x];
        }
        x
    }
    for f in &faces {
        for k in 1..3 {
            let (a, b) = (root(&mut parent, f[0]), root(&mut parent, f[k]));
            parent[a.max(b)] = a.min(b);
        }
    }
    let mut order = Vec::new();
    let mut volume = std::collections::HashMap::new();
    for f in &faces {
        let r = root(&mut parent, f[0]);
        let [a, b, c] = f.map(|v| vertices[v]);
        let v = (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0]))
            / 6.0;
        *volume.entry(r).or_insert_with(|| {
            order.push(r);
            0.0
        }) += v;
    }
    order.iter().map(|r| volume[r]).collect()
}

fn one(reports: &serde_json::Value) -> &serde_json::Value {
    &reports.as_array().expect("reports")[0]
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs())
}

#[test]
fn keeping_the_largest_of_tiled_balls_keeps_exactly_it() {
    let project = Project::new(MANIFEST);
    let all = one(&project.build(&["balls"])).clone();
    assert_eq!(all["components"], 12);
    let mut balls = surface_volumes(&project.out("balls.ply"));
    assert_eq!(balls.len(), 12);
    assert!(balls.iter().all(|&v| v > 0.0));
    balls.sort_by(f64::total_cmp);
    // Twelve sizes: the grading made the largest unique.
    assert!(balls.windows(2).all(|w| w[1] > w[0] * 1.001), "{balls:?}");
    let total: f64 = balls.iter().sum();
    assert!(close(number(&all, "volume"), total));
    assert!(all.get("removed").is_none());

    let keep = project.build(&["balls", "--set", "outputs.balls.keep=largest"]);
    let kept = one(&keep);
    assert_eq!(kept["components"], 1);
    assert_eq!(kept["watertight"], true);
    assert_eq!(kept["manifold"], true);
    assert!(kept["warnings"].is_null(), "{kept}");
    let largest = balls[11];
    assert!(close(number(kept, "volume"), largest), "{kept}");
    assert_eq!(surface_volumes(&project.out("balls.ply")).len(), 1);
    assert!(close(
        surface_volumes(&project.out("balls.ply"))[0],
        largest
    ));
    let removed = &kept["removed"];
    assert_eq!(removed["pieces"], 11);
    assert!((number(removed, "volume") - (total - largest)).abs() < 1e-9 * total);
    assert!(close(number(removed, "largest_piece"), balls[10]));
    assert_eq!(ran(&keep), ["islands:balls", "write:balls"]);

    // A threshold between the fifth and sixth smallest drops exactly the five smallest.
    let v = 0.5 * (balls[4] + balls[5]);
    let set = format!("outputs.balls.min_island_volume={v}");
    let reports = project.build(&["balls", "--set", "outputs.balls.keep=all", "--set", &set]);
    let kept = one(&reports);
    assert_eq!(kept["components"], 7);
    assert_eq!(kept["removed"]["pieces"], 5);
    let expected: f64 = balls[5..].iter().sum();
    assert!((number(kept, "volume") - expected).abs() < 1e-9 * total);
    let mut written = surface_volumes(&project.out("balls.ply"));
    written.sort_by(f64::total_cmp);
    assert_eq!(written.len(), 7);
    for (w, b) in written.iter().zip(&balls[5..]) {
        assert!(close(*w, *b), "{written:?} vs {balls:?}");
    }
    // Only the filter and the write ran: the tiling is the cached one.
    assert_eq!(ran(&reports), ["islands:balls", "write:balls"]);
    // And with neither key the tiling's own entry is written again.
    assert_eq!(ran(&project.build(&["balls"])), ["write:balls"]);
}

#[test]
fn a_hollow_ball_keeps_its_cavity_and_loses_the_island_in_it() {
    let project = Project::new(MANIFEST);
    project.build(&["hollow"]);
    // Outer wall, cavity (negative) and the small ball inside the cavity.
    let surfaces = surface_volumes(&project.out("hollow.ply"));
    assert_eq!(surfaces.len(), 3, "{surfaces:?}");
    let outer = surfaces.iter().copied().fold(f64::MIN, f64::max);
    let cavity = surfaces.iter().copied().fold(f64::MAX, f64::min);
    let island = surfaces
        .iter()
        .copied()
        .find(|&v| v != outer && v != cavity);
    let island = island.expect("island");
    assert!(cavity < 0.0 && island > 0.0 && island < outer + cavity);

    let reports = project.build(&["hollow", "--set", "outputs.hollow.keep=largest"]);
    let kept = one(&reports);
    assert_eq!(kept["components"], 1);
    assert_eq!(kept["watertight"], true);
    assert!(close(number(kept, "volume"), outer + cavity), "{kept}");
    let written = surface_volumes(&project.out("hollow.ply"));
    assert_eq!(written.len(), 2, "the cavity stays");
    assert_eq!(kept["removed"]["pieces"], 1);
    assert!(close(number(&kept["removed"], "volume"), island));
    // About the spheres' volumes: 4/3 π (0.35³ − 0.25³).
    let shell = 4.0 / 3.0 * std::f64::consts::PI * (0.35f64.powi(3) - 0.25f64.powi(3));
    assert!((number(kept, "volume") / shell - 1.0).abs() < 0.03);

    // A threshold under the island's volume removes nothing; over the shell's, everything,
    // which is an error, not an empty file.
    let under = format!("outputs.hollow.min_island_volume={}", island * 0.5);
    let kept = project.build(&["hollow", "--set", &under]);
    assert_eq!(one(&kept)["removed"]["pieces"], 0);
    assert_eq!(one(&kept)["components"], 2);
    std::fs::remove_file(project.out("hollow.ply")).expect("rm");
    let over = format!("outputs.hollow.min_island_volume={}", outer * 2.0);
    let out = project.run(&["build", "lattice.toml", "hollow", "--set", &over]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("would remove every piece"), "{stderr}");
    assert!(stderr.contains("min_island_volume"), "{stderr}");
    assert!(!project.out("hollow.ply").exists());
}

#[test]
fn bad_values_are_errors_at_their_place() {
    for (value, says) in [
        (
            "keep = \"biggest\"",
            "unknown value `biggest` for `outputs.hollow.keep`",
        ),
        ("keep = \"largets\"", "did you mean `\"largest\"`?"),
        ("keep = 1", "outputs.hollow.keep"),
        (
            "min_island_volume = 0",
            "`outputs.hollow.min_island_volume` must be greater than 0",
        ),
        ("min_island_volume = -2.5", "must be greater than 0"),
        ("min_island_volume = nan", "must be a finite number"),
        ("min_island_volume = inf", "must be a finite number"),
    ] {
        let manifest = MANIFEST.replace("samples = 41\n", &format!("samples = 41\n{value}\n"));
        let line = manifest.lines().position(|l| l == value).expect("line") + 1;
        let project = Project::new(&manifest);
        let out = project.run(&["build", "lattice.toml", "hollow"]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{value}: {stderr}");
        assert!(stderr.contains(says), "{value}: {stderr}");
        assert!(
            stderr.contains(&format!("lattice.toml:{line}:")),
            "{value}: {stderr}"
        );
    }
}

/// SDF outputs take the keys too: two balls, the smaller removed.
#[test]
fn an_sdf_outputs_smaller_ball_is_removed() {
    let project = Project::new(
        "[outputs.two]\nsdf = \"ball ball scale 1/2 move 3,0,0 union\"\nsamples = \"80^3\"\n\
         formats = [\"ply\"]\nascii = true\nkeep = \"largest\"\n",
    );
    let reports = project.build(&[]);
    let kept = one(&reports);
    assert_eq!(kept["components"], 1);
    assert_eq!(kept["removed"]["pieces"], 1);
    let ball = 4.0 / 3.0 * std::f64::consts::PI;
    assert!((number(kept, "volume") / ball - 1.0).abs() < 0.03, "{kept}");
    assert!((number(&kept["removed"], "volume") / (ball / 8.0) - 1.0).abs() < 0.05);
    let written = surface_volumes(&project.out("two.ply"));
    assert_eq!(written.len(), 1);
    assert!(close(written[0], number(kept, "volume")));
    assert_eq!(ran(&reports), ["islands:two", "sdf:two", "write:two"]);
}

/// A planar region's pieces have no volume: the keys are errors where they are written.
#[test]
fn a_planar_region_refuses_the_keys() {
    let project = Project::new(
        "[cells.sq]\nexpr = \"cos(tau*x) + cos(tau*y)\"\nsymmetry = \"D4\"\n\n\
         [outputs.panel]\ncell = \"sq\"\ndomain = { min = [0, 0], max = [2, 2] }\n\
         samples = 41\nkeep = \"largest\"\n",
    );
    let out = project.run(&["build", "lattice.toml"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("`outputs.panel.keep` does not apply to a planar region"),
        "{stderr}"
    );
    assert!(stderr.contains("lattice.toml:9:1"), "{stderr}");
}

/// The kept mesh's bytes do not depend on the thread count (streamed tiling and filter).
#[test]
fn the_kept_bytes_are_the_same_for_any_thread_count() {
    let mut files = Vec::new();
    for jobs in ["1", "2", "3"] {
        let project = Project::new(MANIFEST);
        project.build(&["balls", "-j", jobs, "--set", "outputs.balls.keep=largest"]);
        files.push(std::fs::read(project.out("balls.ply")).expect("ply"));
    }
    assert!(files.windows(2).all(|w| w[0] == w[1]));
}

/// Tiled hollow balls (an eccentric shell about P's level 2 in each element): the streamed
/// filter must find each cavity's ball (the ray pass) and keep the largest hollow.
#[test]
fn tiled_hollow_balls_keep_their_cavities() {
    let project = Project::new(MANIFEST);
    project.build(&["hollow_balls"]);
    let surfaces = surface_volumes(&project.out("hollow_balls.ply"));
    assert_eq!(surfaces.len(), 24, "{surfaces:?}");
    // Each hollow ball (outer and inner surface) lies inside its own unit element: its net
    // volume is the signed volume of the triangles in that element.
    let (vertices, faces) = read_ply(&project.out("hollow_balls.ply"));
    let mut net = std::collections::BTreeMap::<[i64; 3], f64>::new();
    for f in &faces {
        let [a, b, c] = f.map(|v| vertices[v]);
        let centre = [0, 1, 2].map(|k| ((a[k] + b[k] + c[k]) / 3.0).floor() as i64);
        let v = (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0]))
            / 6.0;
        *net.entry(centre).or_default() += v;
    }
    assert_eq!(net.len(), 12);
    let mut balls: Vec<f64> = net.values().copied().collect();
    balls.sort_by(f64::total_cmp);
    let reports = project.build(&["hollow_balls", "--set", "outputs.hollow_balls.keep=largest"]);
    let kept = one(&reports);
    assert_eq!(kept["components"], 1);
    assert_eq!(kept["watertight"], true);
    assert!(
        close(number(kept, "volume"), balls[11]),
        "{kept} vs {balls:?}"
    );
    let written = surface_volumes(&project.out("hollow_balls.ply"));
    assert_eq!(written.len(), 2, "the cavity stays");
    assert!(written.iter().any(|&v| v < 0.0));
    assert_eq!(kept["removed"]["pieces"], 11);
}

/// The chunked cache entries (a 48-byte header, then `LBCHUNK1`), largest first.
fn chunked_entries(project: &Project) -> Vec<std::path::PathBuf> {
    let mut stack = vec![project.path().join(".latticebuild")];
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
    found.sort_by_key(|p| std::cmp::Reverse(std::fs::metadata(p).expect("meta").len()));
    found
}

/// A damaged tiling entry found by the filter's passes reruns the tiling, then the filter;
/// the kept mesh is the same.
#[test]
fn a_corrupt_tiling_read_by_the_filter_reruns_the_tiling() {
    let project = Project::new(MANIFEST);
    project.build(&["balls", "--set", "outputs.balls.keep=largest"]);
    let before = std::fs::read(project.out("balls.ply")).expect("ply");
    let entries = chunked_entries(&project);
    assert_eq!(entries.len(), 2, "the tiling's and the filter's");
    let tiling = &entries[0];
    let mut bytes = std::fs::read(tiling).expect("read");
    let at = 56 + (bytes.len() - 56) / 3;
    bytes[at] ^= 0x10;
    std::fs::write(tiling, bytes).expect("write");
    // Another threshold: the filter runs again and reads the damaged entry.
    let out = project.run(&[
        "build",
        "lattice.toml",
        "balls",
        "-v",
        "--report",
        "report.json",
        "--set",
        "outputs.balls.keep=largest",
        "--set",
        "outputs.balls.min_island_volume=1e-9",
    ]);
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("corrupt"), "{text}");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(project.path().join("report.json")).expect("json"))
            .expect("report");
    // The kept mesh is the same bytes, so the write stops there (early cutoff).
    assert_eq!(ran(&report), ["islands:balls", "tile:balls"], "{text}");
    assert!(
        text.contains("tile:balls: ran") && text.contains("its cache entry was corrupt"),
        "{text}"
    );
    assert_eq!(
        std::fs::read(project.out("balls.ply")).expect("ply"),
        before
    );
}
