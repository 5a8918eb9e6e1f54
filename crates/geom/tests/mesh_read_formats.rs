//! Readers on hand-written files with known contents, round trips through the crate's own
//! writers, and tobj as an independent OBJ reader.

use crate::common;

use common::torus;
use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::mesh_io::{self, Encoding, write_mesh};
use latticebuild_geom::mesh_read::{Format, TriangleSoup, detect, read, read_auto};

fn written(mesh: &Mesh, format: mesh_io::Format, encoding: Encoding) -> Vec<u8> {
    let mut bytes = Vec::new();
    write_mesh(mesh, format, encoding, &mut bytes).expect("in memory");
    bytes
}

/// The triangles as corner positions, for comparing soups that index differently.
fn corners(soup: &TriangleSoup) -> Vec<[[f64; 3]; 3]> {
    soup.triangles
        .iter()
        .map(|t| t.map(|i| soup.positions[i as usize]))
        .collect()
}

#[test]
fn ascii_ply_with_a_quad_extra_properties_and_an_extra_element() {
    let text = b"ply\nformat ascii 1.0\ncomment a unit square and a triangle\n\
element vertex 5\nproperty float x\nproperty float y\nproperty float z\n\
property uchar red\nproperty float nx\n\
element face 2\nproperty list uchar int vertex_indices\nproperty int flags\n\
element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n\
0 0 0 255 0.5\n1 0 0 0 0.5\n1 1 0 0 0.5\n0 1 0 7 0.5\n0.5 0.5 2.25 1 0\n\
4 0 1 2 3 9\n3 0 1 4 0\n0 1\n";
    let soup = read(text, Format::Ply).expect("valid PLY");
    assert_eq!(soup.positions.len(), 5);
    assert_eq!(soup.positions[4], [0.5, 0.5, 2.25]);
    // The quad fans from its first corner, keeping its winding.
    assert_eq!(soup.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]]);
}

/// A big-endian binary PLY built byte by byte: `double` coordinates, a `ushort` count and
/// `uint` indices, a pentagon, and an ignored `float` property between the lists.
#[test]
fn big_endian_binary_ply() {
    let mut bytes = b"ply\nformat binary_big_endian 1.0\nelement vertex 5\n\
property double x\nproperty double y\nproperty double z\n\
element face 2\nproperty list ushort uint vertex_indices\nproperty float quality\n\
end_header\n"
        .to_vec();
    let points = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.5, 1.0, 0.0],
        [0.5, 1.75, 0.0],
        [-0.5, 1.0, 1e-3],
    ];
    for p in points {
        for c in p {
            bytes.extend_from_slice(&f64::to_be_bytes(c));
        }
    }
    let faces: [&[u32]; 2] = [&[0, 1, 2, 3, 4], &[4, 3, 2]];
    for face in faces {
        bytes.extend_from_slice(&(face.len() as u16).to_be_bytes());
        for &i in face {
            bytes.extend_from_slice(&i.to_be_bytes());
        }
        bytes.extend_from_slice(&1.5f32.to_be_bytes());
    }
    let soup = read(&bytes, Format::Ply).expect("valid PLY");
    assert_eq!(soup.positions, points.to_vec());
    assert_eq!(
        soup.triangles,
        vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [4, 3, 2]]
    );
    assert_eq!(detect(&bytes), Some(Format::Ply));
}

const OBJ: &str = "# polygons of every corner syntax
mtllib box.mtl
o thing
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vn 0 0 1
v 0.5 0.5 1.5 1.0
g quads
usemtl red
f 1/1/1 2/1/1 3/1/1 4/1/1
s off
f 1//1 2//1 5//1
f -4/1 -3/1 -1/1
l 1 2
f 3 4 5
";

#[test]
fn obj_with_polygons_relative_indices_and_every_corner_syntax() {
    let soup = read(OBJ.as_bytes(), Format::Obj).expect("valid OBJ");
    assert_eq!(soup.positions.len(), 5);
    assert_eq!(soup.positions[4], [0.5, 0.5, 1.5]);
    assert_eq!(
        soup.triangles,
        vec![[0, 1, 2], [0, 2, 3], [0, 1, 4], [1, 2, 4], [2, 3, 4]]
    );
    assert_eq!(detect(OBJ.as_bytes()), Some(Format::Obj));
    assert_eq!(
        read_auto(OBJ.as_bytes(), Some("OBJ")).map(|s| s.triangles.len()),
        Ok(5)
    );
}

/// tobj, an independent reader, triangulates the same file into the same triangles (without
/// the polyline, which tobj turns into a degenerate triangle).
#[test]
fn obj_agrees_with_tobj() {
    let text = OBJ.replace("l 1 2\n", "");
    let ours = read(text.as_bytes(), Format::Obj).expect("valid OBJ");
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..tobj::LoadOptions::default()
    };
    let (models, _) = tobj::load_obj_buf(&mut text.as_bytes(), &options, |_| {
        Ok((Vec::new(), Default::default()))
    })
    .expect("tobj reads it");
    let mut theirs = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let at = |i: u32| {
            let i = i as usize * 3;
            [0, 1, 2].map(|k| f64::from(m.positions[i + k]))
        };
        for t in m.indices.chunks(3) {
            theirs.push([at(t[0]), at(t[1]), at(t[2])]);
        }
    }
    assert_eq!(corners(&ours), theirs);
}

#[test]
fn off_with_comments_colours_and_counts_on_the_keyword_line() {
    let text = b"COFF 4 2 0\n# a tetrahedron's two faces\n\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n\
0 1 0 0 0 255 255 # trailing comment\n0 0 1 1 1 1 1\n3 0 2 1\n4 0 1 3 2 0.5 0.5 0.5\n";
    let soup = read(text, Format::Off).expect("valid OFF");
    assert_eq!(soup.positions[3], [0.0, 0.0, 1.0]);
    assert_eq!(soup.triangles, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2]]);
    assert_eq!(detect(text), Some(Format::Off));
}

#[test]
fn ascii_stl_with_two_solids() {
    let text = b"solid first part\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   \
vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid first part\n\
solid\nfacet normal 0 0 0\nouter loop\nvertex 1e0 2.5E-1 -0\nvertex 2 0 0\nvertex 2 1 0\n\
endloop\nendfacet\nendsolid\n";
    let soup = read(text, Format::Stl).expect("valid STL");
    assert_eq!(soup.triangles, vec![[0, 1, 2], [3, 4, 5]]);
    assert_eq!(soup.positions[3], [1.0, 0.25, 0.0]);
    assert_eq!(detect(text), Some(Format::Stl));
}

/// Binary STLs may begin with `solid`: the size decides.
#[test]
fn binary_stl_whose_header_begins_with_solid() {
    let mut bytes = vec![b' '; 80];
    bytes[..12].copy_from_slice(b"solid binary");
    bytes.extend_from_slice(&1u32.to_le_bytes());
    let values = [
        0.0f32, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0,
    ];
    for v in values {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    bytes.extend_from_slice(&[0, 0]);
    assert_eq!(bytes.len(), 84 + 50);
    let soup = read(&bytes, Format::Stl).expect("valid binary STL");
    assert_eq!(
        soup.positions,
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    );
    assert_eq!(detect(&bytes), Some(Format::Stl));
}

/// Every writer's output reads back to the mesh it wrote: binary positions widen exactly,
/// text ones (the shortest decimal of each `f32`) round back to the same `f32`; the indexed
/// formats keep the indices, STL keeps the corners in order.
#[test]
fn round_trips_through_the_crate_writers() {
    let mesh = torus(24, 12, 2.0, 0.5, [0.25, -1.0, 3.0]);
    let expected = TriangleSoup::from(&mesh);
    let cases = [
        (mesh_io::Format::Stl, Encoding::Binary, Format::Stl),
        (mesh_io::Format::Stl, Encoding::Ascii, Format::Stl),
        (mesh_io::Format::Ply, Encoding::Binary, Format::Ply),
        (mesh_io::Format::Ply, Encoding::Ascii, Format::Ply),
        (mesh_io::Format::Obj, Encoding::Ascii, Format::Obj),
        (mesh_io::Format::Off, Encoding::Ascii, Format::Off),
    ];
    for (written_as, encoding, format) in cases {
        let bytes = written(&mesh, written_as, encoding);
        assert_eq!(detect(&bytes), Some(format), "{written_as:?} {encoding:?}");
        let mut soup = read_auto(&bytes, None).expect("own output");
        if encoding == Encoding::Ascii {
            for p in &mut soup.positions {
                *p = p.map(|c| f64::from(c as f32));
            }
        }
        if format == Format::Stl {
            assert_eq!(corners(&soup), corners(&expected), "{encoding:?} STL");
        } else {
            assert_eq!(soup, expected, "{written_as:?} {encoding:?}");
        }
    }
}

#[test]
fn extensions_name_formats_in_any_case() {
    assert_eq!(Format::from_extension("STL"), Some(Format::Stl));
    assert_eq!(Format::from_extension(".ply"), Some(Format::Ply));
    assert_eq!(Format::from_extension("Off"), Some(Format::Off));
    assert_eq!(Format::from_extension("vtk"), None);
}
