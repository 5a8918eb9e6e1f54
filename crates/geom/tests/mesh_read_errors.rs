//! Malformed input: each error says what and where; truncated files are errors; no prefix or
//! corruption of a valid file makes a reader panic.

use crate::common;

use common::torus;
use latticebuild_geom::mesh_io::{self, Encoding, write_mesh};
use latticebuild_geom::mesh_read::{Format, Location, MeshReadError, read, read_auto};
use latticebuild_geom::synthetic::Rng;

fn small_files() -> Vec<(Format, &'static str, Vec<u8>)> {
    let mesh = torus(6, 4, 2.0, 0.5, [0.0; 3]);
    let write = |format, encoding| {
        let mut bytes = Vec::new();
        write_mesh(&mesh, format, encoding, &mut bytes).expect("in memory");
        bytes
    };
    vec![
        (
            Format::Stl,
            "binary STL",
            write(mesh_io::Format::Stl, Encoding::Binary),
        ),
        (
            Format::Stl,
            "ASCII STL",
            write(mesh_io::Format::Stl, Encoding::Ascii),
        ),
        (
            Format::Ply,
            "binary PLY",
            write(mesh_io::Format::Ply, Encoding::Binary),
        ),
        (
            Format::Ply,
            "ASCII PLY",
            write(mesh_io::Format::Ply, Encoding::Ascii),
        ),
        (
            Format::Obj,
            "OBJ",
            write(mesh_io::Format::Obj, Encoding::Ascii),
        ),
        (
            Format::Off,
            "OFF",
            write(mesh_io::Format::Off, Encoding::Ascii),
        ),
    ]
}

#[test]
fn truncated_binary_stl_reports_the_declared_and_actual_sizes() {
    let (_, _, bytes) = small_files().swap_remove(0);
    let n = (bytes.len() - 84) / 50;
    let cut = &bytes[..bytes.len() - 30];
    assert_eq!(
        read(cut, Format::Stl),
        Err(MeshReadError::StlSize {
            declared: n as u64,
            needed: bytes.len() as u64,
            actual: cut.len() as u64,
        })
    );
    assert_eq!(
        read(&bytes[..50], Format::Stl),
        Err(MeshReadError::Truncated {
            format: Format::Stl,
            at: Location::Byte(50),
            expected: "the 84-byte binary STL header with its facet count".into(),
        })
    );
}

#[test]
fn truncated_ascii_stl_is_an_error_even_between_facets() {
    let text = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n\
endloop\nendfacet\nendsolid t\n";
    // Cut inside the second vertex line.
    let cut = &text[..text.find("vertex 1").unwrap_or(0) + 9];
    let err = read(cut.as_bytes(), Format::Stl).expect_err("truncated");
    assert!(
        matches!(
            err,
            MeshReadError::Truncated {
                at: Location::Line(5),
                ..
            }
        ),
        "{err}"
    );
    // Cut after a complete facet: only the missing `endsolid` tells.
    let cut = &text[..text.find("endsolid").unwrap_or(0)];
    let err = read(cut.as_bytes(), Format::Stl).expect_err("truncated");
    assert_eq!(
        err.to_string(),
        "STL ends at line 9 where `facet` or `endsolid` was expected: the file is truncated"
    );
}

#[test]
fn ply_with_fewer_elements_than_declared() {
    let text = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let err = read(text, Format::Ply).expect_err("one face missing");
    assert_eq!(
        err.to_string(),
        "PLY ends at line 14 where face 1 of the 2 declared was expected: the file is truncated"
    );
    let (_, _, binary) = small_files().swap_remove(2);
    let err = read(&binary[..binary.len() - 7], Format::Ply).expect_err("truncated");
    assert!(
        matches!(err, MeshReadError::Truncated { at: Location::Byte(b), .. } if b == binary.len() - 7),
        "{err}"
    );
}

#[test]
fn malformed_numbers_name_the_line_and_the_token() {
    let cases: [(Format, &[u8], &str); 4] = [
        (Format::Obj, b"v 0 0 0\nv 1 0.0.0 0\n", "OBJ line 2: expected three vertex coordinates, found `0.0.0`"),
        (Format::Off, b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 zero\n3 0 1 2\n", "OFF line 5: expected three vertex coordinates, found `zero`"),
        (Format::Stl, b"solid\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0x1\n", "STL line 4: expected a vertex coordinate, found `0x1`"),
        (Format::Ply, b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n0 1,5 0\n", "PLY line 10: expected vertex 0 of the 1 declared (F32), found `1,5`"),
    ];
    for (format, bytes, message) in cases {
        let err = read(bytes, format).expect_err(message);
        assert_eq!(err.to_string(), message);
    }
}

#[test]
fn non_finite_coordinates_are_rejected_where_they_are() {
    let err = read(b"v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", Format::Obj).expect_err("NaN");
    assert!(
        matches!(
            err,
            MeshReadError::NonFinite {
                at: Location::Line(2),
                vertex: 1,
                ..
            }
        ),
        "{err}"
    );
    let err = read(b"OFF\n3 1 0\n0 0 0\ninf 0 0\n0 1 0\n3 0 1 2\n", Format::Off).expect_err("inf");
    assert!(matches!(
        err,
        MeshReadError::NonFinite {
            at: Location::Line(4),
            vertex: 1,
            ..
        }
    ));
    // A binary STL with a NaN in its second facet's third corner, y coordinate.
    let mut stl = vec![0u8; 80];
    stl.extend_from_slice(&2u32.to_le_bytes());
    stl.extend_from_slice(&[0u8; 100]);
    let at = 84 + 50 + 12 + 2 * 12 + 4;
    stl[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let err = read(&stl, Format::Stl).expect_err("NaN");
    assert!(
        matches!(err, MeshReadError::NonFinite { at: Location::Byte(b), vertex: 5, .. } if b == at),
        "{err}"
    );
}

#[test]
fn out_of_range_indices_name_the_face() {
    let err = read(
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n",
        Format::Obj,
    )
    .expect_err("4");
    assert_eq!(
        err.to_string(),
        "OBJ line 5: face 1 refers to vertex 4, but the file has 3 vertices"
    );
    let err = read(b"v 0 0 0\nf -1 -2 -3\n", Format::Obj).expect_err("relative");
    assert!(matches!(
        err,
        MeshReadError::IndexOutOfRange {
            face: 0,
            index: -2,
            count: 1,
            ..
        }
    ));
    let err = read(
        b"OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 3\n",
        Format::Off,
    )
    .expect_err("3");
    assert!(matches!(
        err,
        MeshReadError::IndexOutOfRange {
            at: Location::Line(7),
            face: 1,
            index: 3,
            count: 3,
            ..
        }
    ));
    let text = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n";
    let err = read(text, Format::Ply).expect_err("-1");
    assert!(matches!(
        err,
        MeshReadError::IndexOutOfRange {
            face: 0,
            index: -1,
            ..
        }
    ));
}

#[test]
fn files_without_triangles_are_empty() {
    let cases: [(Format, &[u8]); 4] = [
        (Format::Obj, b"v 0 0 0\nv 1 0 0\n"),
        (Format::Off, b"OFF\n1 0 0\n0 0 0\n"),
        (Format::Stl, b"solid\nendsolid\n"),
        (Format::Ply, b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n"),
    ];
    for (format, bytes) in cases {
        assert_eq!(read(bytes, format), Err(MeshReadError::Empty { format }));
    }
    let mut stl = vec![0u8; 80];
    stl.extend_from_slice(&0u32.to_le_bytes());
    assert_eq!(
        read(&stl, Format::Stl),
        Err(MeshReadError::Empty {
            format: Format::Stl
        })
    );
}

#[test]
fn unknown_content_without_a_usable_extension() {
    assert_eq!(
        read_auto(b"\x00\x01garbage", None),
        Err(MeshReadError::UnknownFormat)
    );
    assert_eq!(
        read_auto(b"hello", Some("txt")),
        Err(MeshReadError::UnknownFormat)
    );
}

/// A header that declares more than the file could hold is not trusted for allocation.
#[test]
fn huge_declared_counts_fail_cleanly() {
    let ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n\
property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
\x00\x00";
    assert!(matches!(
        read(ply, Format::Ply),
        Err(MeshReadError::Truncated { .. })
    ));
    let off = b"OFF\n4000000000 4000000000 0\n0 0 0\n";
    assert!(matches!(
        read(off, Format::Off),
        Err(MeshReadError::Truncated { .. })
    ));
}

/// Found by `cargo xtask fuzz` (tests/fuzz_corpus/mesh-ply): an element without properties
/// declared 4294967295 times was read instance by instance, 12 s of nothing.
#[test]
fn elements_without_properties_cost_nothing_however_many() {
    let header = |extra: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\n{extra}element face 1\nproperty list uchar int vertex_indices\n\
             end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
        )
    };
    let started = std::time::Instant::now();
    let soup = read(
        header("element nothing 4294967295\n").as_bytes(),
        Format::Ply,
    )
    .expect("the empty element is read past");
    assert_eq!(soup.triangles, vec![[0, 1, 2]]);
    assert!(started.elapsed() < std::time::Duration::from_secs(1));
    // A `face` element without properties still has no `vertex_indices`.
    let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                property float z\nelement face 4294967295\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    assert!(matches!(
        read(text.as_bytes(), Format::Ply),
        Err(MeshReadError::Unsupported { .. })
    ));
}

/// Every prefix of every small file, and random corruptions of them: a result, never a panic.
/// Prefixes of the formats that declare their counts or an end marker are errors, except
/// those that only lose part of the last line (digits of the last index, the solid's name).
#[test]
fn prefixes_and_corruptions_never_panic() {
    let mut rng = Rng::new(11);
    for (format, name, bytes) in small_files() {
        let last_line_start = bytes[..bytes.len() - 1]
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |i| i + 1);
        for cut in 0..bytes.len() {
            let result = read(&bytes[..cut], format);
            let must_fail = match name {
                "binary STL" | "binary PLY" => true,
                // The name after `endsolid` is optional.
                "ASCII STL" => cut < last_line_start + "endsolid".len(),
                "ASCII PLY" | "OFF" => cut < last_line_start,
                _ => false,
            };
            if must_fail {
                assert!(
                    result.is_err(),
                    "{name} cut at {cut} of {} read",
                    bytes.len()
                );
            }
            let _ = read_auto(&bytes[..cut], None);
        }
        for _ in 0..300 {
            let mut corrupt = bytes.clone();
            for _ in 0..1 + rng.below(4) {
                let at = rng.below(corrupt.len());
                corrupt[at] = rng.next_u64() as u8;
            }
            let _ = read(&corrupt, format);
            let _ = read_auto(&corrupt, Some("stl"));
        }
    }
}
