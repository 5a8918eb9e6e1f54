//! Round trips of every writer through independent readers (stl_io, ply-rs-bw, tobj, and small
//! parsers written here from the format descriptions for OFF and legacy VTK).

use crate::common;

use common::torus;
use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::mesh_io::{Encoding, Format, write_mesh};
use std::io::{self, Write};

// ---------------------------------------------------------------------------------------------
// Meshes

/// The unit cube [0, 1]³, 12 triangles wound counter-clockwise seen from outside.
fn unit_cube() -> Mesh {
    let vertices = (0..8)
        .map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32])
        .collect();
    let quads = [
        [0, 2, 3, 1], // z = 0, normal -z
        [4, 5, 7, 6], // z = 1, normal +z
        [0, 1, 5, 4], // y = 0, normal -y
        [2, 6, 7, 3], // y = 1, normal +y
        [0, 4, 6, 2], // x = 0, normal -x
        [1, 3, 7, 5], // x = 1, normal +x
    ];
    let triangles = quads
        .iter()
        .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
        .collect();
    Mesh {
        vertices,
        triangles,
    }
}

/// Awkward values for text formatting (tiny, huge, subnormal, negative zero, non-terminating
/// binary fractions), a degenerate triangle and an unreferenced vertex (the last one).
fn awkward() -> Mesh {
    let vertices = vec![
        [0.0, -0.0, 1.0 / 3.0],
        [1e-7, -2.5e-12, 0.1],
        [3.0e38, -1.0e20, 123_456.79],
        [f32::MIN_POSITIVE / 16.0, 1e-5, 9.99e-6],
        [-7.25, 1e16, 0.3],
        [1.0, 2.0, 3.0],
        [2.0, 4.0, 6.0],    // collinear with the previous and the next
        [3.0, 6.0, 9.0],    // so triangle [5, 6, 7] is degenerate
        [42.0, 42.0, 42.0], // unreferenced
    ];
    let triangles = vec![
        [0, 1, 2],
        [2, 3, 4],
        [4, 0, 3],
        [1, 3, 0],
        [5, 6, 7],
        [0, 2, 4],
    ];
    Mesh {
        vertices,
        triangles,
    }
}

fn test_meshes() -> Vec<(&'static str, Mesh)> {
    vec![
        ("cube", unit_cube()),
        ("torus", torus(24, 12, 3.0, 1.0, [0.0; 3])),
        ("awkward", awkward()),
        ("empty", Mesh::default()),
    ]
}

fn write(mesh: &Mesh, format: Format, encoding: Encoding) -> Vec<u8> {
    let mut out = Vec::new();
    write_mesh(mesh, format, encoding, &mut out).expect("writing to a Vec succeeds");
    out
}

fn bits(p: [f32; 3]) -> [u32; 3] {
    p.map(f32::to_bits)
}

fn all_bits(points: &[[f32; 3]]) -> Vec<[u32; 3]> {
    points.iter().map(|&p| bits(p)).collect()
}

// ---------------------------------------------------------------------------------------------
// STL

/// Facets as (normal, corners), read by stl_io (which detects ASCII or binary itself).
fn read_stl(bytes: &[u8]) -> Vec<([f32; 3], [[f32; 3]; 3])> {
    let mut cursor = io::Cursor::new(bytes);
    stl_io::create_stl_reader(&mut cursor)
        .expect("stl_io accepts the file")
        .map(|facet| {
            let facet = facet.expect("facet parses");
            (facet.normal.0, facet.vertices.map(|v| v.0))
        })
        .collect()
}

#[test]
fn stl_round_trips_through_stl_io_in_both_encodings() {
    for (name, mesh) in test_meshes() {
        let binary = write(&mesh, Format::Stl, Encoding::Binary);
        let ascii = write(&mesh, Format::Stl, Encoding::Ascii);
        assert_eq!(binary.len(), 84 + 50 * mesh.triangles.len(), "{name}");
        assert!(binary.starts_with(b"latticebuild"), "{name}");
        assert_eq!(
            u32::from_le_bytes(binary[80..84].try_into().expect("4 bytes")) as usize,
            mesh.triangles.len()
        );
        assert!(ascii.starts_with(b"solid latticebuild\n"), "{name}");
        assert!(ascii.ends_with(b"endsolid latticebuild\n"), "{name}");

        let from_binary = read_stl(&binary);
        let from_ascii = read_stl(&ascii);
        assert_eq!(from_binary.len(), mesh.triangles.len(), "{name}");
        for (facet, tri) in from_binary.iter().zip(&mesh.triangles) {
            let expected = tri.map(|i| bits(mesh.vertices[i as usize]));
            assert_eq!(facet.1.map(bits), expected, "{name}");
        }
        // Same values, bit for bit, normals included.
        let as_bits = |facets: &[([f32; 3], [[f32; 3]; 3])]| -> Vec<_> {
            facets
                .iter()
                .map(|(n, c)| (bits(*n), c.map(bits)))
                .collect()
        };
        assert_eq!(as_bits(&from_ascii), as_bits(&from_binary), "{name}");
    }
}

#[test]
fn stl_normals_are_unit_and_right_handed_or_zero_when_degenerate() {
    for (name, mesh) in test_meshes() {
        let facets = read_stl(&write(&mesh, Format::Stl, Encoding::Binary));
        for (normal, corners) in facets {
            let [a, b, c] = corners.map(|p| p.map(f64::from));
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let cross = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let len = (cross[0].powi(2) + cross[1].powi(2) + cross[2].powi(2)).sqrt();
            let n = normal.map(f64::from);
            if len == 0.0 {
                assert_eq!(n, [0.0; 3], "{name}: degenerate facet");
                continue;
            }
            let n_len = (n[0].powi(2) + n[1].powi(2) + n[2].powi(2)).sqrt();
            assert!((n_len - 1.0).abs() < 1e-6, "{name}: |n| = {n_len}");
            let cos = (n[0] * cross[0] + n[1] * cross[1] + n[2] * cross[2]) / len;
            assert!(
                cos > 1.0 - 1e-6,
                "{name}: normal not along the right-hand normal: {cos}"
            );
        }
    }
}

#[test]
fn stl_normals_of_the_unit_cube_point_outward_along_the_axes() {
    let facets = read_stl(&write(&unit_cube(), Format::Stl, Encoding::Binary));
    assert_eq!(facets.len(), 12);
    for (normal, corners) in facets {
        let centroid: [f32; 3] =
            std::array::from_fn(|a| (corners[0][a] + corners[1][a] + corners[2][a]) / 3.0);
        // Exactly one axis, exactly ±1, on the side of the face's centroid.
        let axis = (0..3).find(|&a| normal[a] != 0.0).expect("non-zero normal");
        assert_eq!(normal[axis].abs(), 1.0);
        assert_eq!((0..3).filter(|&a| normal[a] != 0.0).count(), 1);
        let outward = if centroid[axis] > 0.5 { 1.0 } else { -1.0 };
        assert_eq!(normal[axis], outward, "facet {corners:?}");
    }
}

// ---------------------------------------------------------------------------------------------
// PLY

fn read_ply(bytes: &[u8]) -> (ply_rs_bw::ply::Header, Vec<[f32; 3]>, Vec<Vec<i32>>) {
    use ply_rs_bw::ply::Property;
    let parser = ply_rs_bw::parser::Parser::<ply_rs_bw::ply::DefaultElement>::new();
    let ply = parser
        .read_ply(&mut io::Cursor::new(bytes))
        .expect("ply-rs-bw accepts the file");
    let float = |e: &ply_rs_bw::ply::DefaultElement, key: &str| match e.get(key) {
        Some(Property::Float(v)) => *v,
        other => panic!("{key} is {other:?}, expected float"),
    };
    let vertices = ply
        .payload
        .get("vertex")
        .map(|elements| {
            elements
                .iter()
                .map(|e| [float(e, "x"), float(e, "y"), float(e, "z")])
                .collect()
        })
        .unwrap_or_default();
    let faces = ply
        .payload
        .get("face")
        .map(|elements| {
            elements
                .iter()
                .map(|e| match e.get("vertex_indices") {
                    Some(Property::ListInt(list)) => list.clone(),
                    other => panic!("vertex_indices is {other:?}, expected list of int"),
                })
                .collect()
        })
        .unwrap_or_default();
    (ply.header, vertices, faces)
}

#[test]
fn ply_round_trips_through_ply_rs_in_both_encodings() {
    use ply_rs_bw::ply::Encoding as PlyEncoding;
    for (name, mesh) in test_meshes() {
        for (encoding, expected) in [
            (Encoding::Binary, PlyEncoding::BinaryLittleEndian),
            (Encoding::Ascii, PlyEncoding::Ascii),
        ] {
            let bytes = write(&mesh, Format::Ply, encoding);
            let (header, vertices, faces) = read_ply(&bytes);
            assert_eq!(header.encoding, expected, "{name}");
            assert!(
                header
                    .comments
                    .iter()
                    .any(|c| c == "generated by latticebuild"),
                "{name}"
            );
            assert_eq!(
                header.elements["vertex"].count,
                mesh.vertices.len(),
                "{name}"
            );
            assert_eq!(
                header.elements["face"].count,
                mesh.triangles.len(),
                "{name}"
            );
            assert_eq!(
                all_bits(&vertices),
                all_bits(&mesh.vertices),
                "{name} {encoding:?}"
            );
            let expected_faces: Vec<Vec<i32>> = mesh
                .triangles
                .iter()
                .map(|t| t.iter().map(|&i| i as i32).collect())
                .collect();
            assert_eq!(faces, expected_faces, "{name} {encoding:?}");
        }
    }
}

#[test]
fn ply_header_is_exactly_as_documented() {
    let bytes = write(&unit_cube(), Format::Ply, Encoding::Binary);
    let header = "ply\nformat binary_little_endian 1.0\ncomment generated by latticebuild\n\
                  element vertex 8\nproperty float x\nproperty float y\nproperty float z\n\
                  element face 12\nproperty list uchar int vertex_indices\nend_header\n";
    assert!(bytes.starts_with(header.as_bytes()));
    assert_eq!(bytes.len(), header.len() + 8 * 12 + 12 * 13);
}

// ---------------------------------------------------------------------------------------------
// OBJ

#[test]
fn obj_round_trips_through_tobj() {
    for (name, mesh) in test_meshes() {
        let bytes = write(&mesh, Format::Obj, Encoding::Binary);
        assert_eq!(
            bytes,
            write(&mesh, Format::Obj, Encoding::Ascii),
            "encoding is ignored"
        );
        let options = tobj::LoadOptions {
            single_index: false,
            ..Default::default()
        };
        let (models, _materials) =
            tobj::load_obj_buf(&mut io::Cursor::new(&bytes), &options, |_| {
                Err(tobj::LoadError::OpenFileFailed)
            })
            .expect("tobj accepts the file");
        if mesh.triangles.is_empty() {
            assert!(models.iter().all(|m| m.mesh.indices.is_empty()), "{name}");
            continue;
        }
        assert_eq!(models.len(), 1, "{name}");
        let loaded = &models[0].mesh;
        assert_eq!(loaded.indices.len(), 3 * mesh.triangles.len(), "{name}");
        // tobj renumbers vertices in order of first use; the renumbering must be a bijection
        // between the referenced vertices that keeps every position bit for bit.
        let mut renumbered = vec![None; mesh.vertices.len()];
        for (corner, &original) in mesh.triangles.iter().flatten().enumerate() {
            let new = loaded.indices[corner] as usize;
            let position = [
                loaded.positions[3 * new],
                loaded.positions[3 * new + 1],
                loaded.positions[3 * new + 2],
            ];
            assert_eq!(
                bits(position),
                bits(mesh.vertices[original as usize]),
                "{name}"
            );
            let seen = renumbered[original as usize].get_or_insert(new);
            assert_eq!(*seen, new, "{name}: vertex {original} split");
        }
        let mut targets: Vec<usize> = renumbered.iter().flatten().copied().collect();
        targets.sort_unstable();
        targets.dedup();
        assert_eq!(
            targets.len(),
            renumbered.iter().flatten().count(),
            "{name}: vertices merged"
        );
        // Unreferenced vertices are still in the file (tobj drops them).
        let v_lines = bytes
            .split(|&b| b == b'\n')
            .filter(|l| l.starts_with(b"v "))
            .count();
        assert_eq!(v_lines, mesh.vertices.len(), "{name}");
    }
}

// ---------------------------------------------------------------------------------------------
// OFF (parser written here from the format description)

fn parse_off(text: &str) -> Mesh {
    let mut tokens = text.split_whitespace();
    assert_eq!(tokens.next(), Some("OFF"));
    let mut number = || tokens.next().expect("more tokens");
    let vertex_count: usize = number().parse().expect("V");
    let face_count: usize = number().parse().expect("F");
    assert_eq!(number(), "0");
    let vertices = (0..vertex_count)
        .map(|_| std::array::from_fn(|_| number().parse::<f32>().expect("coordinate")))
        .collect();
    let triangles = (0..face_count)
        .map(|_| {
            assert_eq!(number(), "3");
            std::array::from_fn(|_| number().parse::<u32>().expect("index"))
        })
        .collect();
    assert!(tokens.next().is_none(), "trailing data");
    Mesh {
        vertices,
        triangles,
    }
}

#[test]
fn off_round_trips_through_a_reference_parser() {
    for (name, mesh) in test_meshes() {
        let bytes = write(&mesh, Format::Off, Encoding::Binary);
        assert_eq!(
            bytes,
            write(&mesh, Format::Off, Encoding::Ascii),
            "encoding is ignored"
        );
        let text = String::from_utf8(bytes).expect("OFF is text");
        assert!(text.starts_with(&format!(
            "OFF\n{} {} 0\n",
            mesh.vertices.len(),
            mesh.triangles.len()
        )));
        let parsed = parse_off(&text);
        assert_eq!(
            all_bits(&parsed.vertices),
            all_bits(&mesh.vertices),
            "{name}"
        );
        assert_eq!(parsed.triangles, mesh.triangles, "{name}");
    }
}

// ---------------------------------------------------------------------------------------------
// VTK legacy (parser written here from the VTK file-format description)

/// Reads one `\n`-terminated line starting at `*at`.
fn line<'a>(bytes: &'a [u8], at: &mut usize) -> &'a str {
    let end = bytes[*at..]
        .iter()
        .position(|&b| b == b'\n')
        .expect("line end")
        + *at;
    let text = std::str::from_utf8(&bytes[*at..end]).expect("header is text");
    *at = end + 1;
    text
}

fn parse_vtk(bytes: &[u8]) -> (Encoding, Mesh) {
    let mut at = 0;
    assert_eq!(line(bytes, &mut at), "# vtk DataFile Version 3.0");
    assert!(!line(bytes, &mut at).is_empty(), "title line");
    let encoding = match line(bytes, &mut at) {
        "ASCII" => Encoding::Ascii,
        "BINARY" => Encoding::Binary,
        other => panic!("unknown encoding {other}"),
    };
    assert_eq!(line(bytes, &mut at), "DATASET POLYDATA");
    let points: Vec<&str> = line(bytes, &mut at).split(' ').collect();
    assert_eq!((points[0], points[2]), ("POINTS", "float"));
    let point_count: usize = points[1].parse().expect("N");
    let mesh = match encoding {
        Encoding::Binary => {
            let be = |i: usize| -> [u8; 4] { bytes[i..i + 4].try_into().expect("4 bytes") };
            let vertices: Vec<[f32; 3]> = (0..point_count)
                .map(|v| std::array::from_fn(|a| f32::from_be_bytes(be(at + 12 * v + 4 * a))))
                .collect();
            at += 12 * point_count;
            assert_eq!(line(bytes, &mut at), "", "newline after the points");
            let polygons: Vec<&str> = line(bytes, &mut at).split(' ').collect();
            assert_eq!(polygons[0], "POLYGONS");
            let count: usize = polygons[1].parse().expect("M");
            assert_eq!(polygons[2].parse::<usize>().expect("size"), 4 * count);
            let ints: Vec<i32> = (0..4 * count)
                .map(|k| i32::from_be_bytes(be(at + 4 * k)))
                .collect();
            at += 16 * count;
            assert_eq!(line(bytes, &mut at), "", "newline after the polygons");
            let triangles = ints
                .chunks_exact(4)
                .map(|r| {
                    assert_eq!(r[0], 3);
                    [r[1] as u32, r[2] as u32, r[3] as u32]
                })
                .collect();
            Mesh {
                vertices,
                triangles,
            }
        }
        Encoding::Ascii => {
            let rest = std::str::from_utf8(&bytes[at..]).expect("ASCII VTK is text");
            let mut tokens = rest.split_whitespace();
            let mut next = || tokens.next().expect("more tokens");
            let vertices = (0..point_count)
                .map(|_| std::array::from_fn(|_| next().parse::<f32>().expect("coordinate")))
                .collect();
            assert_eq!(next(), "POLYGONS");
            let count: usize = next().parse().expect("M");
            assert_eq!(next().parse::<usize>().expect("size"), 4 * count);
            let triangles = (0..count)
                .map(|_| {
                    assert_eq!(next(), "3");
                    std::array::from_fn(|_| next().parse::<u32>().expect("index"))
                })
                .collect();
            assert!(tokens.next().is_none(), "trailing data");
            assert!(bytes.ends_with(b"\n"));
            at = bytes.len();
            Mesh {
                vertices,
                triangles,
            }
        }
    };
    assert_eq!(at, bytes.len(), "trailing data");
    (encoding, mesh)
}

#[test]
fn vtk_round_trips_through_a_reference_parser_in_both_encodings() {
    for (name, mesh) in test_meshes() {
        for encoding in [Encoding::Binary, Encoding::Ascii] {
            let bytes = write(&mesh, Format::Vtk, encoding);
            let (found, parsed) = parse_vtk(&bytes);
            assert_eq!(found, encoding, "{name}");
            assert_eq!(
                all_bits(&parsed.vertices),
                all_bits(&mesh.vertices),
                "{name} {encoding:?}"
            );
            assert_eq!(parsed.triangles, mesh.triangles, "{name} {encoding:?}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Across formats

#[test]
fn large_meshes_survive_the_block_boundaries() {
    // Several batches of 1 MiB blocks in every encoding.
    let mesh = torus(600, 300, 10.0, 2.5, [0.0; 3]);
    let facets = read_stl(&write(&mesh, Format::Stl, Encoding::Binary));
    assert!(
        facets.iter().zip(&mesh.triangles).all(|(facet, tri)| {
            facet.1.map(bits) == tri.map(|i| bits(mesh.vertices[i as usize]))
        })
    );
    assert_eq!(facets.len(), mesh.triangles.len());
    for encoding in [Encoding::Binary, Encoding::Ascii] {
        let (_, vertices, faces) = read_ply(&write(&mesh, Format::Ply, encoding));
        assert_eq!(all_bits(&vertices), all_bits(&mesh.vertices));
        assert!(
            faces
                .iter()
                .zip(&mesh.triangles)
                .all(|(f, t)| f.len() == 3 && (0..3).all(|k| f[k] == t[k] as i32))
        );
        assert_eq!(faces.len(), mesh.triangles.len());
        let (_, parsed) = parse_vtk(&write(&mesh, Format::Vtk, encoding));
        assert_eq!(parsed.triangles, mesh.triangles);
        assert_eq!(all_bits(&parsed.vertices), all_bits(&mesh.vertices));
    }
    let parsed =
        parse_off(&String::from_utf8(write(&mesh, Format::Off, Encoding::Ascii)).expect("text"));
    assert_eq!(parsed.triangles, mesh.triangles);
    assert_eq!(all_bits(&parsed.vertices), all_bits(&mesh.vertices));
}

#[test]
fn text_and_binary_hold_the_same_values() {
    for (name, mesh) in test_meshes() {
        for format in [Format::Ply, Format::Vtk] {
            let binary = match format {
                Format::Ply => read_ply(&write(&mesh, format, Encoding::Binary)).1,
                _ => {
                    parse_vtk(&write(&mesh, format, Encoding::Binary))
                        .1
                        .vertices
                }
            };
            let ascii = match format {
                Format::Ply => read_ply(&write(&mesh, format, Encoding::Ascii)).1,
                _ => parse_vtk(&write(&mesh, format, Encoding::Ascii)).1.vertices,
            };
            assert_eq!(all_bits(&binary), all_bits(&ascii), "{name} {format:?}");
        }
    }
}

#[test]
fn empty_mesh_files_are_exactly_the_headers() {
    let empty = Mesh::default();
    let stl = write(&empty, Format::Stl, Encoding::Binary);
    assert_eq!(stl.len(), 84);
    assert_eq!(&stl[80..], &[0, 0, 0, 0]);
    assert_eq!(
        write(&empty, Format::Stl, Encoding::Ascii),
        b"solid latticebuild\nendsolid latticebuild\n"
    );
    assert_eq!(write(&empty, Format::Off, Encoding::Ascii), b"OFF\n0 0 0\n");
    assert_eq!(
        write(&empty, Format::Vtk, Encoding::Ascii),
        b"# vtk DataFile Version 3.0\nlatticebuild mesh\nASCII\nDATASET POLYDATA\n\
          POINTS 0 float\nPOLYGONS 0 0\n"
    );
}

// ---------------------------------------------------------------------------------------------
// Errors

/// Accepts `remaining` bytes (in partial writes), then fails every write.
struct FailAfter {
    remaining: usize,
    written: usize,
}

impl Write for FailAfter {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if self.remaining == 0 {
            return Err(io::Error::other("disk full"));
        }
        // Partial writes, to exercise write_all's retry loop too.
        let n = buf.len().min(self.remaining).min(4096);
        self.remaining -= n;
        self.written += n;
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

#[test]
fn writer_errors_are_returned_not_panicked() {
    let mesh = torus(200, 100, 10.0, 2.5, [0.0; 3]);
    for format in Format::ALL {
        for encoding in [Encoding::Binary, Encoding::Ascii] {
            let full = write(&mesh, format, encoding).len();
            let limits = [0, 1, 83, 84, 1000, 1 << 20, (1 << 21) + 17, full - 1];
            for limit in limits.into_iter().filter(|&limit| limit < full) {
                let mut out = FailAfter {
                    remaining: limit,
                    written: 0,
                };
                let error = write_mesh(&mesh, format, encoding, &mut out)
                    .expect_err("a failing writer makes the call fail");
                assert_eq!(
                    error.to_string(),
                    "disk full",
                    "{format:?} {encoding:?} at {limit}"
                );
                assert!(out.written <= limit);
            }
            let mut out = FailAfter {
                remaining: full,
                written: 0,
            };
            write_mesh(&mesh, format, encoding, &mut out).expect("exactly enough room");
            assert_eq!(out.written, full);
        }
    }
}

#[test]
fn invalid_meshes_are_rejected_before_anything_is_written() {
    let mut out_of_range = unit_cube();
    out_of_range.triangles[5][1] = 8;
    let mut not_finite = unit_cube();
    not_finite.vertices[3][2] = f32::NAN;
    let mut infinite = unit_cube();
    infinite.vertices[0][0] = f32::NEG_INFINITY;
    for mesh in [out_of_range, not_finite, infinite] {
        for format in Format::ALL {
            for encoding in [Encoding::Binary, Encoding::Ascii] {
                let mut out = Vec::new();
                let error = write_mesh(&mesh, format, encoding, &mut out).expect_err("rejected");
                assert_eq!(error.kind(), io::ErrorKind::InvalidInput);
                assert!(out.is_empty(), "{format:?} wrote {} bytes", out.len());
            }
        }
    }
}
