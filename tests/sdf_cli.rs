//! `latticebuild sdf` end to end: Cesogen command lines with the program name replaced, the
//! written files, `@file` includes, and the errors a user sees.

use crate::common;

use std::f64::consts::PI;
use std::path::Path;
use std::process::{Command, Output};

use common::BIN;
use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::{mesh_read, validate};

fn sdf(dir: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .arg("sdf")
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run latticebuild")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The numbers of the summary line: triangles, vertices and volume.
fn summary(out: &Output) -> (u64, u64, f64) {
    let text = stderr(out);
    assert!(out.status.success(), "failed: {}\n{text}", out.status);
    assert!(text.contains("watertight, manifold"), "{text}");
    let number_before = |label: &str| -> f64 {
        let at = text
            .find(label)
            .unwrap_or_else(|| panic!("no `{label}` in {text}"));
        let start = text[..at].trim_end().rfind([' ', ':']).map_or(0, |i| i + 1);
        text[start..at].trim().parse().expect(label)
    };
    let volume_at = text.find("volume ").expect("volume") + "volume ".len();
    let volume_end = text[volume_at..].find(',').expect("comma") + volume_at;
    (
        number_before(" triangles") as u64,
        number_before(" vertices") as u64,
        text[volume_at..volume_end].parse().expect("volume"),
    )
}

/// The `element NAME COUNT` of a PLY header.
fn ply_count(path: &Path, element: &str) -> u64 {
    let bytes = std::fs::read(path).expect("read ply");
    let end = bytes
        .windows(10)
        .position(|w| w == b"end_header")
        .expect("header");
    let header = String::from_utf8_lossy(&bytes[..end]).into_owned();
    header
        .lines()
        .find_map(|l| l.strip_prefix(&format!("element {element} ")))
        .expect("element line")
        .trim()
        .parse()
        .expect("count")
}

#[test]
fn figure_6_writes_out_ply_by_default() {
    let dir = tempfile::tempdir().unwrap();
    let out = sdf(
        dir.path(),
        &[
            "-b",
            "-4,-4,-4,4,4,4",
            "-s",
            "130^3",
            "ball",
            "scale",
            "5",
            "tpms.p",
            "scale",
            "4",
            "tpms.d",
            "scale",
            "3.75",
            "tpms.gyroid",
            "scale",
            "1.25",
            "intersection",
            "intersection",
            "intersection",
        ],
    );
    let (triangles, vertices, volume) = summary(&out);
    let ply = dir.path().join("out.ply");
    assert_eq!(ply_count(&ply, "face"), triangles);
    assert_eq!(ply_count(&ply, "vertex"), vertices);
    // Converges to about 55.9 (the share of points inside); 130³ marching cubes is ~2% low.
    assert!((volume - 55.9).abs() < 0.03 * 55.9, "{volume}");
    assert!(stderr(&out).contains("of [-4,4]×[-4,4]×[-4,4] at 130×130×130 samples"));
}

#[test]
fn the_hourglass_to_stl_with_options_after_the_words() {
    let dir = tempfile::tempdir().unwrap();
    let words = "cylinder move 0,-2,0 cylinder move 0,2,0 union scale 1/2 orient 1,0,0 \
                 complement box intersection";
    let mut args: Vec<&str> = words.split_whitespace().collect();
    args.extend(["-o", "hourglass.STL", "-s", "40^3"]);
    let out = sdf(dir.path(), &args);
    let (triangles, _, volume) = summary(&out);
    let stl = std::fs::metadata(dir.path().join("hourglass.STL")).unwrap();
    // Binary STL: an 80-byte header, a count, 50 bytes per triangle.
    assert_eq!(stl.len(), 84 + 50 * triangles);
    assert!((volume - (8.0 - PI / 2.0)).abs() < 0.01 * 8.0, "{volume}");
    assert!(!dir.path().join("out.ply").exists());
}

#[test]
fn includes_nest_relative_to_their_file_and_may_hold_options() {
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("parts");
    std::fs::create_dir(&sub).unwrap();
    // A cylinder of radius 1/2 along x, named once and used twice.
    std::fs::write(sub.join("rod.txt"), "cylinder orient 1,0,0\n  scale 1/2\n").unwrap();
    std::fs::write(
        sub.join("pair.txt"),
        "@rod.txt move 0,-2,0\n@rod.txt move 0,2,0\nunion\n-s 80^3",
    )
    .unwrap();
    let out = sdf(dir.path(), &["@parts/pair.txt", "-o", "pair.obj"]);
    let (_, _, volume) = summary(&out);
    // Two cylinders of radius 1/2 and length 2 (the box rule cuts them to [-1, 1]).
    assert!((volume - PI).abs() < 0.02 * PI, "{volume}");
    assert!(stderr(&out).contains("at 80×80×80 samples"));
    assert!(dir.path().join("pair.obj").exists());
}

#[test]
fn a_file_that_includes_itself_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("a.txt"), "ball @b.txt").unwrap();
    std::fs::write(dir.path().join("b.txt"), "@./a.txt union").unwrap();
    let out = sdf(dir.path(), &["@a.txt"]);
    assert_eq!(out.status.code(), Some(2));
    let text = stderr(&out);
    let a = dir.path().join("a.txt").canonicalize().unwrap();
    let b = dir.path().join("b.txt").canonicalize().unwrap();
    assert_eq!(
        text,
        format!(
            "error: word 1 of `{b}` `@./a.txt`: the file includes itself: {a} → {b} → {a}\n",
            a = a.display(),
            b = b.display()
        )
    );
    std::fs::write(dir.path().join("self.txt"), "ball @self.txt").unwrap();
    let out = sdf(dir.path(), &["@self.txt"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("the file includes itself"));
}

#[test]
fn bad_input_exits_2_with_the_word_at_fault() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&[&str], &str); 6] = [
        (
            &["bal"],
            "error: word 1 `bal`: unknown word; did you mean `ball`?\n",
        ),
        (
            &["-s", "60^3", "ball", "intersection"],
            "error: word 4 `intersection`: intersection needs two solids, found one\n",
        ),
        (
            &["ball", "-s", "10.5"],
            "error: word 2 `-s`: `10.5` is not a whole number of samples\n",
        ),
        (
            &["ball", "-b", "1,1,1,0,0,0"],
            "error: word 2 `-b`: `1,1,1,0,0,0`: the lower corner must be below the upper one on \
             every axis\n",
        ),
        (
            &["ball", "@missing.txt"],
            "error: word 2 `@missing.txt`: cannot include it: cannot read `missing.txt`: No such \
             file or directory (os error 2)\n",
        ),
        (
            &[
                "tpms.neovius",
                "scale",
                "0.065",
                "file",
                "part.stl",
                "intersection",
            ],
            "error: word 4 `file`: `file` cannot be used: cannot read `part.stl`: No such file or \
             directory (os error 2)\n",
        ),
    ];
    for (args, want) in cases {
        let out = sdf(dir.path(), args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert_eq!(stderr(&out), want, "{args:?}");
    }
    assert!(!dir.path().join("out.ply").exists());
}

#[test]
fn an_empty_solid_exits_1_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = sdf(dir.path(), &["ball", "offset", "-2"]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        stderr(&out),
        "error: the solid has no surface in the box [-1,1]×[-1,1]×[-1,1]: `out.ply` was not \
         written\n"
    );
    assert!(!dir.path().join("out.ply").exists());
}

#[test]
fn a_mesh_filled_with_a_gyroid_by_a_file_word() {
    let dir = tempfile::tempdir().unwrap();
    let (stl, sphere) = common::sphere_stl(10.0, [0.0; 3], 32, 64);
    std::fs::write(dir.path().join("part.stl"), stl).unwrap();
    let out = sdf(
        dir.path(),
        &[
            "-b",
            "-11,-11,-11,11,11,11",
            "-s",
            "96^3",
            "tpms.gyroid",
            "scale",
            "4",
            "file",
            "part.stl",
            "intersection",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let (triangles, _, volume) = summary(&out);
    assert!(triangles > 0);
    // The gyroid fills half of the sphere (its period 4 is small next to the radius 10).
    let fraction = volume / sphere;
    assert!((fraction - 0.5).abs() < 0.02, "fraction {fraction}");
}

#[test]
fn file_words_in_includes_are_relative_to_their_file() {
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("parts");
    std::fs::create_dir(&sub).unwrap();
    let (stl, sphere) = common::sphere_stl(1.0, [0.0; 3], 24, 48);
    std::fs::write(sub.join("ball.stl"), stl).unwrap();
    // `ball.stl` is beside the include, not in the working directory.
    std::fs::write(sub.join("part.txt"), "file ball.stl").unwrap();
    let out = sdf(dir.path(), &["@parts/part.txt", "-s", "40^3", "-q"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(dir.path().join("out.ply").exists());
    let out = sdf(dir.path(), &["@parts/part.txt", "-s", "40^3"]);
    let (_, _, volume) = summary(&out);
    assert!(
        (volume - sphere).abs() < 0.03 * sphere,
        "{volume} vs {sphere}"
    );
    // On the command line a path is still relative to the working directory.
    let out = sdf(dir.path(), &["file", "ball.stl"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("cannot read `ball.stl`"),
        "{}",
        stderr(&out)
    );
}

/// The written PLY as a mesh.
fn read_ply(path: &Path) -> Mesh {
    let bytes = std::fs::read(path).expect("read ply");
    let soup = mesh_read::read(&bytes, mesh_read::Format::Ply).expect("PLY");
    Mesh {
        vertices: soup.positions.iter().map(|p| p.map(|c| c as f32)).collect(),
        triangles: soup.triangles,
    }
}

/// Figure 6 as the paper prints it in its list of figures (three intersections for four
/// solids; the caption's `-s 1303 … intersection intersection` lost the exponent and one
/// word, and leaves two solids), at a coarse 48³: a watertight solid inside each of its four
/// constituents (contoured alone on the same grid), whose largest piece is nearly all of it,
/// by marching cubes and by marching tetrahedra.
#[test]
fn figure_6_as_printed_is_inside_each_constituent() {
    let dir = tempfile::tempdir().unwrap();
    let grid = ["-b", "-4,-4,-4,4,4,4", "-s", "48^3"];
    let solid = |words: &str, contour: &str, out: &str| {
        let mut args: Vec<&str> = grid.to_vec();
        args.extend(words.split(' '));
        args.extend(["--contour", contour, "-o", out]);
        summary(&sdf(dir.path(), &args)).2
    };
    let constituents = [
        "ball scale 5",
        "tpms.p scale 4",
        "tpms.d scale 3.75",
        "tpms.gyroid scale 1.25",
    ];
    let figure = format!(
        "{} intersection intersection intersection",
        constituents.join(" ")
    );
    for contour in ["cubes", "tetrahedra"] {
        let volume = solid(&figure, contour, "figure.ply");
        assert!(volume > 0.05 * 512.0, "{contour}: {volume}");
        for c in constituents {
            let alone = solid(c, contour, "alone.ply");
            assert!(volume < 0.9 * alone, "{contour}: {volume} vs {c}: {alone}");
        }
        let mesh = read_ply(&dir.path().join("figure.ply"));
        let pieces = validate::pieces(&mesh);
        assert!(
            pieces.largest_fraction(false) > 0.97,
            "{contour}: {pieces:?}"
        );
    }
    // The caption's spelling is refused with what is wrong.
    let caption = format!(
        "-b -4,-4,-4,4,4,4 -s 1303 {} intersection intersection",
        constituents.join(" ")
    );
    let out = sdf(dir.path(), &caption.split(' ').collect::<Vec<_>>());
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("ends with 2 solids on the stack"),
        "{}",
        stderr(&out)
    );
}

/// `--contour tetrahedra`: a ball of radius 2 has the sphere's volume to grid accuracy, and
/// agrees with marching cubes; an unknown method is a usage error.
#[test]
fn marching_tetrahedra_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let run = |contour: &str| {
        summary(&sdf(
            dir.path(),
            &["ball", "scale", "2", "-s", "41^3", "--contour", contour],
        ))
    };
    let (tets, _, v_tets) = run("tetrahedra");
    let (cubes, _, v_cubes) = run("cubes");
    let exact = 4.0 / 3.0 * PI * 8.0;
    let h: f64 = 4.0 / 40.0;
    let grid_error = 0.5 * h * h * 4.0 * PI * 4.0;
    assert!((v_tets - exact).abs() < grid_error, "{v_tets} vs {exact}");
    assert!(
        (v_tets - v_cubes).abs() < grid_error,
        "{v_tets} vs {v_cubes}"
    );
    assert!(tets > cubes);
    let out = sdf(dir.path(), &["ball", "--contour", "tetrahedron"]);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        stderr(&out),
        "error: word 2 `--contour tetrahedron`: expected `cubes` (marching cubes, the default) \
         or `tetrahedra` (marching tetrahedra)\n"
    );
}
