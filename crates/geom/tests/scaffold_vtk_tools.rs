//! VTK scaffolds as the tools users have write them (`tests/data/vtk`, made by its
//! `make_fixtures.py` with VTK 9, PyVista and meshio): legacy ASCII/BINARY 4.2 and 5.1 with
//! METADATA blocks, dataset FIELD data, string arrays, SCALARS and FIELD point data; `.vtu`
//! ASCII, base64, appended raw/base64, zlib and LZ4 in one or several blocks. Each file gives
//! the very nodes, elements (in Gmsh order) and point data that `reference.json` records,
//! which the script computed itself, apart from any writer or reader.

use std::path::PathBuf;

use latticebuild_geom::scaffold::{ElementKind, Location, Scaffold, check, read_scaffold};
use serde_json::Value;

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk")
}

fn reference() -> Value {
    let text = std::fs::read_to_string(dir().join("reference.json")).expect("reference.json");
    serde_json::from_str(&text).expect("valid JSON")
}

fn bytes(file: &str) -> Vec<u8> {
    std::fs::read(dir().join(file)).unwrap_or_else(|e| panic!("{file}: {e}"))
}

fn read(file: &str) -> Result<Scaffold, latticebuild_geom::scaffold::ScaffoldError> {
    read_scaffold(&bytes(file), file, file.rsplit('.').next())
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

fn kind_of(vtk_type: u64) -> ElementKind {
    match vtk_type {
        10 => ElementKind::Tet4,
        24 => ElementKind::Tet10,
        12 => ElementKind::Hex8,
        25 => ElementKind::Hex20,
        29 => ElementKind::Hex27,
        other => panic!("no fixture has VTK type {other}"),
    }
}

/// Files written with LZMA compression, which the reader refuses by name.
fn is_lzma(file: &str) -> bool {
    file.contains("lzma")
}

#[test]
fn every_file_a_tool_wrote_reads_to_the_reference_mesh_and_point_data() {
    let reference = reference();
    let files = reference["files"].as_object().expect("files");
    // Every fixture on disk is in the reference, and the other way round.
    let mut on_disk: Vec<String> = std::fs::read_dir(dir())
        .expect("dir")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".vtk") || n.ends_with(".vtu"))
        .collect();
    on_disk.sort();
    let mut listed: Vec<String> = files.keys().cloned().collect();
    listed.sort();
    assert_eq!(on_disk, listed);
    for tool in ["vtk", "pyvista", "meshio"] {
        assert!(files.values().any(|f| f["tool"] == tool), "{tool}");
    }
    let mut read_ok = 0;
    for (file, entry) in files {
        if is_lzma(file) {
            continue;
        }
        let mesh = &reference["meshes"][entry["mesh"].as_str().expect("mesh")];
        let s = read(file).unwrap_or_else(|e| panic!("{file} ({}): {e}", entry["variant"]));
        let kind = kind_of(mesh["vtk_cell_type"].as_u64().expect("type"));
        assert_eq!(s.kind, kind, "{file}");
        let points: Vec<[f64; 3]> = mesh["points"]
            .as_array()
            .expect("points")
            .iter()
            .map(|p| {
                let p = floats(p);
                [p[0], p[1], p[2]]
            })
            .collect();
        assert_eq!(s.nodes, points, "{file}: points, exactly and in order");
        let cells: Vec<u32> = mesh["cells_gmsh"]
            .as_array()
            .expect("cells")
            .iter()
            .flat_map(|c| floats(c).into_iter().map(|i| i as u32))
            .collect();
        assert_eq!(s.connectivity, cells, "{file}: cells in Gmsh order");
        assert_eq!(s.element_count() * kind.node_count(), cells.len());
        assert_eq!(
            s.node_tags,
            (0..points.len() as u64).collect::<Vec<_>>(),
            "{file}"
        );
        for name in entry["point_data"].as_array().expect("names") {
            let name = name.as_str().expect("name");
            let data = s
                .node_data(name)
                .unwrap_or_else(|| panic!("{file}: no point data `{name}`: {:?}", names(&s)));
            assert_eq!(
                data.values,
                floats(&mesh["point_data"][name]),
                "{file}: {name}"
            );
        }
        // The weight is x + 2y + 4z at each point, as the script made it.
        let weight = s.node_data("weight").expect("weight");
        for (p, w) in s.nodes.iter().zip(&weight.values) {
            assert_eq!(*w, p[0] + 2.0 * p[1] + 4.0 * p[2], "{file}");
        }
        // Only one-component point data: never the vector, the cell data or the field data.
        for other in [
            "displacement",
            "vtkOriginalIndices",
            "region",
            "TimeValue",
            "notes",
        ] {
            assert!(s.node_data(other).is_none(), "{file}: {other}");
        }
        check(&s).unwrap_or_else(|e| panic!("{file}: {e}"));
        read_ok += 1;
    }
    assert_eq!(read_ok, 73, "files read");
}

fn names(s: &Scaffold) -> Vec<&str> {
    s.node_data.iter().map(|d| d.name.as_str()).collect()
}

#[test]
fn lzma_files_are_refused_naming_the_compressor_and_its_line() {
    for file in [
        "tet4_vtk9_lzma.vtu",
        "tet4_meshio_lzma.vtu",
        "hex8_vtk9_lzma.vtu",
    ] {
        let e = read(file).expect_err("LZMA");
        assert_eq!(e.file, file);
        // The VTKFile element is on line 2 of VTK's files, 2 of meshio's.
        assert_eq!(e.at, Location::Line(2), "{file}");
        assert!(
            e.message.starts_with(
                "unsupported compressor \"vtkLZMADataCompressor\": expected \
                 vtkZLibDataCompressor, vtkLZ4DataCompressor or none"
            ),
            "{e}"
        );
    }
}

/// The byte offset just after the first `pattern` in `b`.
fn after(b: &[u8], pattern: &[u8]) -> usize {
    b.windows(pattern.len())
        .position(|w| w == pattern)
        .map(|k| k + pattern.len())
        .unwrap_or_else(|| panic!("no {}", String::from_utf8_lossy(pattern)))
}

#[test]
fn truncated_tool_files_are_errors_at_their_end() {
    // Binary legacy: cut inside the `weight` SCALARS values: its count no longer fits in the
    // bytes left, which is found at the SCALARS line, before reading.
    let b = bytes("tet4_vtk9_binary.vtk");
    let scalars = after(&b, b"POINT_DATA 18\n");
    let start = after(&b, b"LOOKUP_TABLE default\n");
    for cut in [start, start + 3, start + 8 * 17 + 7] {
        let e = read_scaffold(&b[..cut], "t.vtk", None).expect_err("truncated");
        assert_eq!(e.at, Location::Byte(scalars as u64), "cut {cut}: {e}");
        assert_eq!(
            e.message,
            format!(
                "the number of values is 18, but only {} bytes follow (truncated file or bad \
                 count)",
                cut - start
            )
        );
    }
    // Binary legacy: a point data value that is not a finite number, at its byte.
    let mut nan = b.clone();
    nan[start + 16..start + 24].copy_from_slice(&f64::NAN.to_be_bytes());
    let e = read_scaffold(&nan, "t.vtk", None).expect_err("NaN");
    assert_eq!(e.at, Location::Byte(start as u64 + 16));
    assert!(
        e.message.contains("expected a point data value, found NaN"),
        "{e}"
    );
    // ASCII legacy: a cut in the middle of a FIELD array, found at its header line; a cut
    // right after the CELL_TYPES line, at that line.
    let text = String::from_utf8(bytes("tet4_meshio_ascii.vtk")).expect("text");
    let header = text.find("weight 1 18 double\n").expect("weight");
    let cut = after(text.as_bytes(), b"weight 1 18 double\n") + 20;
    let e = read_scaffold(&text.as_bytes()[..cut], "m.vtk", None).expect_err("cut");
    assert_eq!(
        e.at,
        Location::Line(text[..header].lines().count() as u64 + 1),
        "{e}"
    );
    assert!(
        e.message
            .starts_with("the number of values is 18, but only 21 bytes follow"),
        "{e}"
    );
    let cut = text.find("CELL_TYPES").expect("types") + 14;
    let e = read_scaffold(&text.as_bytes()[..cut], "m.vtk", None).expect_err("cut");
    assert_eq!(
        e.at,
        Location::Line(text[..cut].lines().count() as u64),
        "{e}"
    );
    // A declared count larger than the file: refused before reading.
    let big = text.replace("weight 1 18 double", "weight 1 18000 double");
    let e = read_scaffold(big.as_bytes(), "m.vtk", None).expect_err("count");
    assert!(
        e.message
            .contains("the number of tuples is 18000, but only"),
        "{e}"
    );
    // .vtu with LZ4 blocks: a cut in the appended data names the array and its line.
    let b = bytes("hex8_vtk9_appended_lz4.vtu");
    let data = after(&b, b"<AppendedData encoding=\"raw\">\n   _");
    let e = read_scaffold(&b[..data + 40], "a.vtu", None).expect_err("truncated");
    assert!(matches!(e.at, Location::Line(_)), "{e}");
    assert!(
        e.message.starts_with("DataArray \"")
            && (e.message.contains("truncated") || e.message.contains("past the end")),
        "{e}"
    );
}

#[test]
fn corrupt_lz4_blocks_are_errors_not_panics() {
    let b = bytes("tet4_vtk9_appended_lz4.vtu");
    let data = after(&b, b"<AppendedData encoding=\"raw\">\n   _");
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut errors = 0;
    for _ in 0..300 {
        let mut c = b.clone();
        let i = data + (next() % (b.len() - data) as u64) as usize;
        c[i] ^= 1 << (next() % 8);
        if read_scaffold(&c, "c.vtu", None).is_err() {
            errors += 1;
        }
    }
    // Most flips land in headers, tokens or match offsets that LZ4 cannot accept.
    assert!(errors > 0);
    for file in [
        "tet4_vtk9_binary.vtk",
        "hex8_vtk9_ascii.vtk",
        "hex8_vtk9_lz4.vtu",
    ] {
        let b = bytes(file);
        for end in 0..b.len() {
            if let Ok(s) = read_scaffold(&b[..end], file, None) {
                assert!(s.element_count() > 0);
            }
        }
    }
}
