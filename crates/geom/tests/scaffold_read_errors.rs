//! Scaffold readers on small hand-written files: each format gives the same mesh, bad input
//! gives an exact message naming the file and where, and no prefix or corruption panics.

use latticebuild_geom::scaffold::{
    ElementKind, Location, Scaffold, ScaffoldError, check, read_scaffold,
};

/// Two positive tets (volumes 1/6 and 1/3) and a boundary triangle, MSH 2.2 ASCII.
const MSH22: &str = "$MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
5
1 0 0 0
2 1 0 0
3 0 1 0
4 0 0 1
5 1 1 1
$EndNodes
$Elements
3
1 4 2 1 1 1 2 3 4
2 4 2 1 1 2 3 4 5
3 2 2 2 2 1 2 3
$EndElements
";

/// The same tets in MSH 4.1 ASCII with node tags 10, 20, …, 50 in two entity blocks.
const MSH41: &str = "$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
1
3 1 \"domain\"
$EndPhysicalNames
$Entities
0 0 0 1
1 0 0 0 1 1 1 1 1 0
$EndEntities
$Nodes
2 5 10 50
3 1 0 3
10
20
30
0 0 0
1 0 0
0 1 0
3 1 0 2
40
50
0 0 1
1 1 1
$EndNodes
$Elements
2 3 1 3
2 1 2 1
7 10 20 30
3 1 4 2
1 10 20 30 40
2 20 30 40 50
$EndElements
";

const VTK: &str = "# vtk DataFile Version 2.0
two tets
ASCII
DATASET UNSTRUCTURED_GRID
POINTS 5 double
0 0 0 1 0 0 0 1 0
0 0 1 1 1 1
CELLS 3 14
4 0 1 2 3
4 1 2 3 4
3 0 1 2
CELL_TYPES 3
10
10
5
";

const VTU: &str = r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian">
  <UnstructuredGrid>
    <Piece NumberOfPoints="5" NumberOfCells="2">
      <PointData>
        <DataArray type="Float64" Name="weight" format="ascii">0 0.25 0.5 0.75 1</DataArray>
      </PointData>
      <Points>
        <DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0 0 0 1 1 1 1</DataArray>
      </Points>
      <Cells>
        <DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3 1 2 3 4</DataArray>
        <DataArray type="Int32" Name="offsets" format="ascii">4 8</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">10 10</DataArray>
      </Cells>
    </Piece>
  </UnstructuredGrid>
</VTKFile>
"#;

const INP: &str = "*Heading
 two tets
** a comment
*NODE
1, 0, 0, 0
2, 1, 0, 0
3, 0, 1, 0
4, 0, 0, 1
5, 1, 1, 1
*ELEMENT, type=CPS3, ELSET=face
3, 1, 2, 3
*ELEMENT, type=C3D4, ELSET=Volume1
1, 1, 2, 3,
 4
2, 2, 3, 4, 5
*ELSET,ELSET=domain, GENERATE
1, 2, 1
";

fn read(text: &[u8], name: &str) -> Result<Scaffold, ScaffoldError> {
    read_scaffold(text, name, name.rsplit('.').next())
}

fn message(text: &str, name: &str) -> String {
    match read(text.as_bytes(), name) {
        Ok(s) => panic!("{name} read as {} elements", s.element_count()),
        Err(e) => e.to_string(),
    }
}

/// The two tets, as positions per element (so differently numbered files compare).
fn tets(s: &Scaffold) -> Vec<Vec<[f64; 3]>> {
    (0..s.element_count())
        .map(|e| s.element(e).iter().map(|&n| s.nodes[n as usize]).collect())
        .collect()
}

fn expected_tets() -> Vec<Vec<[f64; 3]>> {
    let p = [
        [0., 0., 0.],
        [1., 0., 0.],
        [0., 1., 0.],
        [0., 0., 1.],
        [1., 1., 1.],
    ];
    vec![vec![p[0], p[1], p[2], p[3]], vec![p[1], p[2], p[3], p[4]]]
}

/// MSH 4.1 binary of the MSH41 mesh; also returns the offsets of the last node tag and of
/// the element block's element count.
fn msh41_binary() -> (Vec<u8>, usize, usize) {
    let mut b: Vec<u8> = b"$MeshFormat\n4.1 1 8\n".to_vec();
    b.extend_from_slice(&1i32.to_le_bytes());
    b.extend_from_slice(b"\n$EndMeshFormat\n$Nodes\n");
    let size = |b: &mut Vec<u8>, v: u64| b.extend_from_slice(&v.to_le_bytes());
    let int = |b: &mut Vec<u8>, v: i32| b.extend_from_slice(&v.to_le_bytes());
    for v in [2, 5, 10, 50] {
        size(&mut b, v);
    }
    let blocks: [(&[u64], &[[f64; 3]]); 2] = [
        (&[10, 20, 30], &[[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]]),
        (&[40, 50], &[[0., 0., 1.], [1., 1., 1.]]),
    ];
    for (tags, points) in blocks {
        int(&mut b, 3);
        int(&mut b, 1);
        int(&mut b, 0);
        size(&mut b, tags.len() as u64);
        for &t in tags {
            size(&mut b, t);
        }
        for p in points {
            for c in p {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    b.extend_from_slice(b"\n$EndNodes\n$Elements\n");
    for v in [1, 2, 1, 2] {
        size(&mut b, v);
    }
    int(&mut b, 3);
    int(&mut b, 1);
    int(&mut b, 4);
    let count_at = b.len();
    size(&mut b, 2);
    let mut last = 0;
    for (tag, nodes) in [(1u64, [10u64, 20, 30, 40]), (2, [20, 30, 40, 50])] {
        size(&mut b, tag);
        for n in nodes {
            last = b.len();
            size(&mut b, n);
        }
    }
    b.extend_from_slice(b"\n$EndElements\n");
    (b, last, count_at)
}

/// Legacy VTK binary (big-endian) of the two tets.
fn vtk_binary() -> Vec<u8> {
    let mut b = b"# vtk DataFile Version 3.0\nbinary tets\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 double\n".to_vec();
    for p in &[
        [0., 0., 0.],
        [1., 0., 0.],
        [0., 1., 0.],
        [0., 0., 1.],
        [1., 1., 1.],
    ] {
        for c in p {
            b.extend_from_slice(&f64::to_be_bytes(*c));
        }
    }
    b.extend_from_slice(b"\nCELLS 2 10\n");
    for v in [4, 0, 1, 2, 3, 4, 1, 2, 3, 4] {
        b.extend_from_slice(&i32::to_be_bytes(v));
    }
    b.extend_from_slice(b"\nCELL_TYPES 2\n");
    for _ in 0..2 {
        b.extend_from_slice(&i32::to_be_bytes(10));
    }
    b.push(b'\n');
    b
}

/// VTU with raw appended data (UInt64 headers).
fn vtu_appended() -> Vec<u8> {
    let mut data = Vec::new();
    let mut offsets = Vec::new();
    let mut array = |bytes: Vec<u8>| {
        offsets.push(data.len());
        data.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
        data.extend_from_slice(&bytes);
    };
    array(
        [0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 1., 1., 1.]
            .iter()
            .flat_map(|v: &f64| v.to_le_bytes())
            .collect(),
    );
    array(
        [0i64, 1, 2, 3, 1, 2, 3, 4]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect(),
    );
    array([4i64, 8].iter().flat_map(|v| v.to_le_bytes()).collect());
    array(vec![10u8, 10]);
    let head = format!(
        r#"<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">
<UnstructuredGrid><Piece NumberOfPoints="5" NumberOfCells="2">
<Points><DataArray type="Float64" NumberOfComponents="3" format="appended" offset="{}"/></Points>
<Cells>
<DataArray type="Int64" Name="connectivity" format="appended" offset="{}"/>
<DataArray type="Int64" Name="offsets" format="appended" offset="{}"/>
<DataArray type="UInt8" Name="types" format="appended" offset="{}"/>
</Cells></Piece></UnstructuredGrid>
<AppendedData encoding="raw">
_"#,
        offsets[0], offsets[1], offsets[2], offsets[3]
    );
    let mut b = head.into_bytes();
    b.extend_from_slice(&data);
    b.extend_from_slice(b"\n</AppendedData>\n</VTKFile>\n");
    b
}

fn base64(bytes: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let v = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(A[(v >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// VTU with inline base64 binary arrays, UInt32 headers encoded separately from the data (as
/// VTK writes them), big-endian.
fn vtu_base64() -> Vec<u8> {
    let array = |data: Vec<u8>| {
        let header = (data.len() as u32).to_be_bytes();
        format!("{}{}", base64(&header), base64(&data))
    };
    let points = array(
        [0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 1., 1., 1.]
            .iter()
            .flat_map(|v: &f64| v.to_be_bytes())
            .collect(),
    );
    let conn = array(
        [0i32, 1, 2, 3, 1, 2, 3, 4]
            .iter()
            .flat_map(|v| v.to_be_bytes())
            .collect(),
    );
    let offsets = array([4i32, 8].iter().flat_map(|v| v.to_be_bytes()).collect());
    let types = array(vec![10u8, 10]);
    format!(
        r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="BigEndian">
<UnstructuredGrid><Piece NumberOfPoints="5" NumberOfCells="2">
<Points><DataArray type="Float64" NumberOfComponents="3" format="binary">
  {points}
</DataArray></Points>
<Cells>
<DataArray type="Int32" Name="connectivity" format="binary">{conn}</DataArray>
<DataArray type="Int32" Name="offsets" format="binary">{offsets}</DataArray>
<DataArray type="UInt8" Name="types" format="binary">{types}</DataArray>
</Cells></Piece></UnstructuredGrid></VTKFile>
"#
    )
    .into_bytes()
}

#[test]
fn every_format_gives_the_same_two_tets() {
    let (bin, _, _) = msh41_binary();
    let files: Vec<(&str, Vec<u8>)> = vec![
        ("t.msh", MSH22.into()),
        ("t41.msh", MSH41.into()),
        ("t41bin.msh", bin),
        ("t.vtk", VTK.into()),
        ("tbin.vtk", vtk_binary()),
        ("t.vtu", VTU.into()),
        ("tapp.vtu", vtu_appended()),
        ("t64.vtu", vtu_base64()),
        ("t.inp", INP.into()),
    ];
    for (name, bytes) in &files {
        let s = read(bytes, name).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.kind, ElementKind::Tet4, "{name}");
        assert_eq!(tets(&s), expected_tets(), "{name}");
        assert!((s.measure() - 0.5).abs() < 1e-15, "{name}");
        check(&s).unwrap_or_else(|e| panic!("{e}"));
    }
    let s = read(MSH41.as_bytes(), "t.msh").expect("reads");
    assert_eq!(s.node_tags, vec![10, 20, 30, 40, 50]);
    assert_eq!(s.element_tags, vec![1, 2]);
    assert_eq!(s.physical, vec![1, 1]);
    assert_eq!(s.physical_names, vec![(1, 3, "domain".to_string())]);
    let inp = read(INP.as_bytes(), "t.inp").expect("reads");
    assert_eq!(inp.physical_names[inp.physical[0] as usize - 1].2, "domain");
    let vtu = read(VTU.as_bytes(), "t.vtu").expect("reads");
    assert_eq!(
        vtu.node_data("weight").expect("point data").values,
        vec![0.0, 0.25, 0.5, 0.75, 1.0]
    );
}

#[test]
fn surface_meshes_keep_quads_and_triangles() {
    let obj = "# two quads\nv 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\nf 1 2 5 4\nf 2/1 3/1 6/1 -2\n";
    let s = read(obj.as_bytes(), "q.obj").expect("reads");
    assert_eq!(s.kind, ElementKind::Quad4);
    assert_eq!(s.connectivity, vec![0, 1, 4, 3, 1, 2, 5, 4]);
    assert!((s.measure() - 2.0).abs() < 1e-14);
    let off = "OFF\n# comment\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3 255 0 0\n";
    let s = read(off.as_bytes(), "t.off").expect("reads");
    assert_eq!(s.kind, ElementKind::Tri3);
    assert_eq!(s.connectivity, vec![0, 1, 2, 0, 2, 3]);
    assert!((s.measure() - 1.0).abs() < 1e-14);
    assert_eq!(
        message(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 2 3 4\nf 1 3 4\n",
            "m.obj"
        ),
        "m.obj: mixed element types: tri3 (2), quad4 (1); a scaffold has one element type"
    );
}

#[test]
fn lower_dimensional_elements_are_dropped_and_tags_need_not_be_contiguous() {
    let s = read(MSH22.as_bytes(), "t.msh").expect("reads");
    assert_eq!(s.element_count(), 2, "the boundary triangle is dropped");
    assert_eq!(s.element_tags, vec![1, 2]);
    let s41 = read(MSH41.as_bytes(), "t.msh").expect("reads");
    assert_eq!(s41.element_count(), 2, "the triangle block is dropped");
    assert_eq!(tets(&s41), tets(&s));
}

#[test]
fn mixed_types_missing_nodes_and_truncation_have_exact_messages() {
    let mixed = MSH22
        .replace("\n3\n1 4", "\n4\n1 4")
        .replace("$EndElements", "4 5 2 1 1 1 2 3 4 5 1 2 3\n$EndElements");
    assert_eq!(
        message(&mixed, "mixed.msh"),
        "mixed.msh: mixed element types: tet4 (2), hex8 (1); a scaffold has one element type"
    );
    assert_eq!(
        message(&MSH22.replace("2 3 4 5\n", "2 3 4 9\n"), "t.msh"),
        "t.msh:15: element 2 refers to node 9, which is not in the file"
    );
    assert_eq!(
        message(&MSH41.replace("2 20 30 40 50", "2 20 30 40 60"), "t.msh"),
        "t.msh:33: element 2 refers to node 60, which is not in the file"
    );
    let cut = &MSH22[..MSH22.find("2 4 2 1 1 2 3").expect("line") + 13];
    assert_eq!(
        message(cut, "t.msh"),
        "t.msh:15: unexpected end of file: expected an element's node tag"
    );
    assert_eq!(
        message(
            &MSH22.replace("1 4 2 1 1 1 2 3 4", "1 99 2 1 1 1 2 3 4"),
            "t.msh"
        ),
        "t.msh:14: unknown Gmsh element type 99 (element 1)"
    );
    assert_eq!(
        message(&MSH22.replace("3 0 1 0", "3 NaN 1 0"), "t.msh"),
        "t.msh:8: expected a node coordinate, found NaN (not a finite number)"
    );
    assert_eq!(
        message(
            &MSH22
                .replace("4 0 0 1\n", "4 0 0 1\n2 5 5 5\n")
                .replace("\n5\n1 0", "\n6\n1 0"),
            "t.msh"
        ),
        "t.msh:10: node 2 is listed twice"
    );
    let empty =
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n0\n$EndNodes\n$Elements\n0\n$EndElements\n";
    assert_eq!(
        message(empty, "e.msh"),
        "e.msh: no elements: expected at least one tri, quad, tet or hex element"
    );
    assert_eq!(
        message(&MSH22.replace("2.2 0 8", "4.0 0 8"), "t.msh"),
        "t.msh:2: unsupported MSH version `4.0`: expected 2.2 or 4.1"
    );
    let big = MSH22.replace("\n5\n1 0", "\n500\n1 0");
    let left = big.len() - (big.find("\n500\n").expect("count") + 4);
    assert_eq!(
        message(&big, "t.msh"),
        format!(
            "t.msh:5: the number of nodes is 500, but only {left} bytes follow (truncated file or bad count)"
        )
    );
    // Binary: byte offsets.
    let (bin, last, count_at) = msh41_binary();
    let e = read(&bin[..last + 3], "b.msh").expect_err("truncated");
    assert_eq!(e.at, Location::Byte(count_at as u64));
    assert_eq!(
        e.to_string(),
        format!(
            "b.msh: byte {count_at}: the number of elements in a block is 2, but only {} bytes follow (truncated file or bad count)",
            last + 3 - count_at - 8
        )
    );
    // Cut inside the last value but with a count that fits: the value is named.
    let mut short = bin[..last + 3].to_vec();
    short[count_at..count_at + 8].copy_from_slice(&1u64.to_le_bytes());
    short[count_at - 24..count_at - 16].copy_from_slice(&1u64.to_le_bytes());
    let e = read(&short, "b.msh").expect_err("truncated");
    assert!(e.to_string().starts_with("b.msh: byte "), "{e}");
    let mut bad = bin.clone();
    bad[last..last + 8].copy_from_slice(&77u64.to_le_bytes());
    // The element's record (its tag) starts 3 node tags and the tag itself before its last node.
    let record = last - 3 * 8 - 8;
    assert_eq!(
        read(&bad, "b.msh").expect_err("missing").to_string(),
        format!("b.msh: byte {record}: element 2 refers to node 77, which is not in the file")
    );
    // VTK and Abaqus name cells and lines.
    assert_eq!(
        message(&VTK.replace("4 1 2 3 4", "4 1 2 3 7"), "t.vtk"),
        "t.vtk:10: element 1 refers to point 7, which is not in the file"
    );
    assert_eq!(
        message(
            &VTK.replace("CELL_TYPES 3\n10\n10", "CELL_TYPES 3\n10\n12"),
            "t.vtk"
        ),
        "t.vtk:10: cell 1 (hex8, VTK cell type 12) has 4 points, expected 8"
    );
    assert_eq!(
        message(&INP.replace("2, 2, 3, 4, 5", "2, 2, 3, 4, 50"), "t.inp"),
        "t.inp:15: element 2 refers to node 50, which is not in the file"
    );
    assert_eq!(
        message(&INP.replace("type=C3D4", "type=C3D7"), "t.inp"),
        "t.inp:12: unknown Abaqus element type C3D7"
    );
}

#[test]
fn inverted_and_degenerate_elements_are_reported_by_tag() {
    let inverted = read(
        MSH22
            .replace("1 4 2 1 1 1 2 3 4", "1 4 2 1 1 2 1 3 4")
            .as_bytes(),
        "t.msh",
    )
    .expect("reads");
    assert_eq!(
        check(&inverted).expect_err("inverted").to_string(),
        "t.msh: element 1 is inverted (det J = -5.000e-1 at local node 0)"
    );
    let flat = MSH22
        .replace("5 1 1 1\n", "5 1 1 1\n6 1 1 0\n")
        .replace("\n5\n1 0", "\n6\n1 0")
        .replace("2 4 2 1 1 2 3 4 5", "2 4 2 1 1 1 2 3 6");
    let flat = read(flat.as_bytes(), "f.msh").expect("reads");
    assert_eq!(
        check(&flat).expect_err("degenerate").to_string(),
        "f.msh: element 2 is degenerate (det J = 0.000e0 at local node 0)"
    );
    // A clockwise triangle among counter-clockwise ones in the plane.
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 3 4\nf 2 3 5\n";
    let s = read(obj.as_bytes(), "p.obj").expect("reads");
    let m = check(&s).expect_err("clockwise").to_string();
    assert!(
        m.starts_with("p.obj: element 3 is inverted (clockwise seen from +z, unlike most elements"),
        "{m}"
    );
}

fn small_files() -> Vec<(&'static str, Vec<u8>)> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/scaffolds");
    let (bin, _, _) = msh41_binary();
    vec![
        ("t.msh", MSH22.into()),
        ("t41.msh", MSH41.into()),
        ("t41bin.msh", bin),
        ("t.vtk", VTK.into()),
        ("tbin.vtk", vtk_binary()),
        ("t.vtu", VTU.into()),
        ("t64.vtu", vtu_base64()),
        ("tapp.vtu", vtu_appended()),
        ("t.inp", INP.into()),
        (
            "box.msh",
            std::fs::read(dir.join("box_4x3x2_hex8.msh")).expect("box"),
        ),
    ]
}

#[test]
fn no_prefix_of_a_valid_file_panics_and_truncations_are_errors() {
    for (name, bytes) in small_files() {
        for end in 0..bytes.len() {
            // Any prefix either reads (a shorter valid file) or is an error; never a panic.
            if let Ok(s) = read(&bytes[..end], name) {
                assert!(s.element_count() > 0);
            }
        }
    }
    // A prefix that ends inside the elements of a Gmsh file is always an error.
    let (bin, last, _) = msh41_binary();
    for end in 0..last {
        assert!(read(&bin[..end], "b.msh").is_err(), "prefix {end}");
    }
}

#[test]
fn random_corruptions_never_panic() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/scaffolds");
    let mut files = small_files();
    for big in [
        "sphere_r10_tet4_zlib.vtu",
        "bracket_tet4_msh22bin.msh",
        "cylinder_r5h20_hex8.inp",
    ] {
        files.push(("big", std::fs::read(dir.join(big)).expect("file")));
    }
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for (name, bytes) in &files {
        let rounds = if bytes.len() > 10_000 { 30 } else { 300 };
        for _ in 0..rounds {
            let mut b = bytes.clone();
            for _ in 0..1 + next() % 4 {
                let i = (next() % b.len() as u64) as usize;
                b[i] = match next() % 4 {
                    0 => b'9',
                    1 => b' ',
                    2 => b'\n',
                    _ => next() as u8,
                };
            }
            let _ = read(&b, name);
        }
    }
}

/// Node 5's `1 1 1` (or the OBJ/OFF vertex `1 1 0`) moved to `x y z` in each text format.
fn with_far_node(x: &str) -> Vec<(&'static str, String)> {
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";
    let off = "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
    vec![
        ("t.msh", MSH22.replace("5 1 1 1", &format!("5 {x} 1 1"))),
        (
            "t41.msh",
            MSH41.replace("\n1 1 1\n", &format!("\n{x} 1 1\n")),
        ),
        (
            "t.vtk",
            VTK.replace("0 0 1 1 1 1", &format!("0 0 1 {x} 1 1")),
        ),
        (
            "t.vtu",
            VTU.replace("0 0 1 1 1 1<", &format!("0 0 1 {x} 1 1<")),
        ),
        ("t.inp", INP.replace("5, 1, 1, 1", &format!("5, {x}, 1, 1"))),
        ("t.obj", obj.replace("v 1 1 0", &format!("v {x} 1 0"))),
        ("t.off", off.replace("\n1 1 0\n", &format!("\n{x} 1 0\n"))),
    ]
}

#[test]
fn coordinates_beyond_single_precision_are_refused_at_the_node_by_every_reader() {
    // 3.4e38 is still a float (f32::MAX is 3.4028235e38); 1e39 would be infinite as one.
    for (name, text) in with_far_node("3.4e38") {
        let s = read(text.as_bytes(), name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(s.nodes.iter().any(|p| p[0] == 3.4e38), "{name}");
    }
    let expected = [
        "t.msh:10: node 5: coordinate x",
        "t41.msh:23: node 50: coordinate x",
        "t.vtk:7: point 4: coordinate x",
        "t.vtu:9: point 4: coordinate x",
        "t.inp:9: node 5: coordinate x",
        "t.obj:3: node 3: coordinate x",
        "t.off:5: point 2: coordinate x",
    ];
    for ((name, text), expected) in with_far_node("1e39").iter().zip(expected) {
        let m = message(text, name);
        assert_eq!(
            m,
            format!(
                "{expected} = 1e39 is beyond ±3.4028235e38, the largest a mesh vertex \
                 (single precision) holds"
            )
        );
    }
    for (name, text) in with_far_node("-1e39") {
        assert!(
            message(&text, name).contains("x = -1e39 is beyond"),
            "{name}"
        );
    }
    // Not finite at all: refused too, at the same node.
    for (name, text) in with_far_node("nan").into_iter().chain(with_far_node("inf")) {
        let m = message(&text, name);
        assert!(m.contains("finite"), "{name}: {m}");
    }
}
