//! `out/NAME.png` previews through the real binary: drawn by a `preview` stage that reruns
//! with its write and nothing else, listed in the report, sized by `[build] preview_size`,
//! left out with `--no-previews`. (`determinism.rs` compares every example's PNGs byte for
//! byte between `-j 1` and `-j 3`.)

use crate::common;

use common::{Project, by_name, ran_all};

const MANIFEST: &str = r#"
[cells.g]
tpms = "gyroid"

[outputs.a]
cell = "g"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 25
formats = ["stl"]
"#;

/// The PNG's width, height and RGB pixels.
fn decode(path: &std::path::Path) -> (u32, u32, Vec<u8>) {
    let file = std::fs::File::open(path).expect("the preview exists");
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .expect("a PNG");
    let mut buffer = vec![0; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buffer).expect("a frame");
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buffer.truncate(info.buffer_size());
    (info.width, info.height, buffer)
}

#[test]
fn every_output_gets_a_png_listed_in_its_report() {
    let p = Project::new(MANIFEST);
    let reports = p.build(&[]);
    let files = by_name(&reports, "a")["files"].clone();
    assert!(
        files
            .as_array()
            .expect("files")
            .iter()
            .any(|f| f.as_str().is_some_and(|f| f.ends_with("a.png"))),
        "{files}"
    );
    let (w, h, rgb) = decode(&p.out("a.png"));
    assert_eq!((w, h), (1024, 768));
    // Something is drawn: shaded surface (grey-blue) and the section's fill.
    let distinct: std::collections::BTreeSet<&[u8]> = rgb.chunks(3).collect();
    assert!(distinct.len() > 20, "{} colours", distinct.len());
    // Nothing reruns, previews included.
    assert!(ran_all(&p.build(&[])).is_empty());
}

#[test]
fn a_format_change_reruns_only_the_write_and_the_preview() {
    let p = Project::new(MANIFEST);
    p.build(&[]);
    let before = std::fs::read(p.out("a.png")).expect("png");
    let reports = p.build(&["--set", "outputs.a.formats=[\"stl\", \"ply\"]"]);
    assert_eq!(ran_all(&reports), ["preview:a", "write:a"]);
    assert_eq!(std::fs::read(p.out("a.png")).expect("png"), before);
    // A removed preview is drawn again, alone.
    std::fs::remove_file(p.out("a.png")).expect("rm");
    let reports = p.build(&["--set", "outputs.a.formats=[\"stl\", \"ply\"]"]);
    assert_eq!(ran_all(&reports), ["preview:a"]);
    assert_eq!(std::fs::read(p.out("a.png")).expect("png"), before);
}

#[test]
fn no_previews_draws_none_and_a_size_is_obeyed() {
    let p = Project::new(MANIFEST);
    let reports = p.build(&["--no-previews"]);
    assert!(!p.out("a.png").exists());
    assert!(!by_name(&reports, "a")["files"].to_string().contains(".png"));
    assert!(ran_all(&reports).iter().all(|n| !n.starts_with("preview:")));
    let reports = p.build(&["--set", "build.preview_size=[320, 200]"]);
    assert_eq!(ran_all(&reports), ["preview:a"], "only the preview is new");
    let (w, h, _) = decode(&p.out("a.png"));
    assert_eq!((w, h), (320, 200));
}

#[test]
fn a_bad_preview_size_is_an_error_at_its_value() {
    let p = Project::new(&format!("[build]\npreview_size = [10, 200]\n{MANIFEST}"));
    let out = p.run(&["build", "lattice.toml"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("`build.preview_size` must be from 64 to 8192 pixels")
            && err.contains("lattice.toml:2:17"),
        "{err}"
    );
}

/// A 3D tiling's picture is drawn from its chunks while it tiles (nothing read back from the
/// cache); drawn again from the cache entry — the PNG removed, or another format asked — it is
/// the same bytes, since both are fitted to the scaffold's box, known before the first chunk.
#[test]
fn a_tiling_drawn_while_it_tiles_is_the_picture_drawn_from_its_entry() {
    let p = Project::new(
        r#"
[cells.p]
tpms = "p"
symmetry = "Oh"
fit = { n = 16 }

[scaffolds.block]
grid = { min = [0, 0, 0], max = [8, 6, 4], divisions = [4, 3, 2], element = "hex" }

[outputs.a]
scaffold = "block"
cell = "p"
offset = 0.3
resolution = 10
formats = ["stl"]
"#,
    );
    let reports = p.build(&[]);
    let bbox = &by_name(&reports, "a")["tiling"]["scaffold_bbox"];
    assert_eq!(bbox.to_string(), "[[0.0,0.0,0.0],[8.0,6.0,4.0]]");
    assert!(ran_all(&reports).contains(&"tile:a".to_string()));
    let early = std::fs::read(p.out("a.png")).expect("png");
    let (_, _, rgb) = decode(&p.out("a.png"));
    let distinct: std::collections::BTreeSet<&[u8]> = rgb.chunks(3).collect();
    assert!(distinct.len() > 20, "{} colours", distinct.len());

    std::fs::remove_file(p.out("a.png")).expect("rm");
    assert_eq!(ran_all(&p.build(&[])), ["preview:a"]);
    assert_eq!(std::fs::read(p.out("a.png")).expect("png"), early);

    let reports = p.build(&["--set", "outputs.a.formats=[\"stl\", \"ply\"]"]);
    assert_eq!(ran_all(&reports), ["preview:a", "write:a"]);
    assert_eq!(std::fs::read(p.out("a.png")).expect("png"), early);
}
