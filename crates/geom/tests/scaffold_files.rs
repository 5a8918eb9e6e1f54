//! Every scaffold in `tests/data/scaffolds` (copied from the shared Gmsh-made set) reads with
//! the counts, facets and measures its `manifest.json` states; formats of the same mesh agree.

use std::path::PathBuf;

use latticebuild_geom::scaffold::{ElementKind, Scaffold, check, read_scaffold};
use serde_json::Value;

fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/scaffolds")
}

fn manifest() -> Vec<Value> {
    let text = std::fs::read_to_string(data_dir().join("manifest.json")).expect("manifest.json");
    let v: Value = serde_json::from_str(&text).expect("valid JSON");
    v["files"].as_array().expect("files").clone()
}

fn read(file: &str) -> Scaffold {
    let bytes = std::fs::read(data_dir().join(file)).expect("file");
    let ext = file.rsplit('.').next();
    read_scaffold(&bytes, file, ext).unwrap_or_else(|e| panic!("{e}"))
}

/// The manifest entries of files shipped with the tests (the 100k benchmark mesh is not).
fn entries() -> Vec<Value> {
    manifest()
        .into_iter()
        .filter(|f| data_dir().join(f["file"].as_str().unwrap_or("")).exists())
        .collect()
}

#[test]
fn every_file_reads_with_the_manifest_counts_facets_and_measure() {
    let entries = entries();
    assert_eq!(
        entries.len(),
        27,
        "every shipped scaffold has a manifest entry"
    );
    for f in &entries {
        let name = f["file"].as_str().expect("name");
        let s = read(name);
        assert_eq!(
            s.kind.name(),
            f["element_type"].as_str().expect("type"),
            "{name}"
        );
        assert_eq!(
            s.kind.gmsh_type() as u64,
            f["gmsh_type"].as_u64().expect("gmsh"),
            "{name}"
        );
        assert_eq!(
            s.element_count() as u64,
            f["elements"].as_u64().expect("n"),
            "{name}"
        );
        assert_eq!(
            s.nodes.len() as u64,
            f["nodes"].as_u64().expect("n"),
            "{name}"
        );
        let facets = s.facets();
        assert_eq!(
            facets.interior.len() as u64,
            f["interior_facets"].as_u64().expect("i"),
            "{name}"
        );
        assert_eq!(
            facets.boundary.len() as u64,
            f["boundary_facets"].as_u64().expect("b"),
            "{name}"
        );
        assert!(facets.overused.is_empty(), "{name}");
        let expected = f
            .get("volume")
            .or_else(|| f.get("area"))
            .and_then(Value::as_f64)
            .expect("volume or area");
        let measure = s.measure();
        assert!(
            ((measure - expected) / expected).abs() < 1e-6,
            "{name}: measure {measure} against {expected}"
        );
        // Bounding box as written.
        let (lo, hi) = (&f["bbox_min"], &f["bbox_max"]);
        for a in 0..3 {
            let min = s.nodes.iter().map(|p| p[a]).fold(f64::INFINITY, f64::min);
            let max = s
                .nodes
                .iter()
                .map(|p| p[a])
                .fold(f64::NEG_INFINITY, f64::max);
            assert!(
                (min - lo[a].as_f64().expect("bbox")).abs() < 1e-9,
                "{name} bbox min"
            );
            assert!(
                (max - hi[a].as_f64().expect("bbox")).abs() < 1e-9,
                "{name} bbox max"
            );
        }
        check(&s).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
}

#[test]
fn gmsh_physical_group_domain_is_kept() {
    for name in [
        "sphere_r10_tet4.msh",
        "bracket_tet4_msh22.msh",
        "bracket_tet4_msh41bin.msh",
        "plate_hole_quad9.msh",
    ] {
        let s = read(name);
        assert_eq!(s.physical_names.len(), 1, "{name}");
        let (tag, dim, group) = &s.physical_names[0];
        assert_eq!(group, "domain", "{name}");
        assert_eq!(*dim as usize, s.kind.dimension(), "{name}");
        assert!(
            s.physical.iter().all(|p| p == tag),
            "{name}: every element in `domain`"
        );
    }
    let inp = read("cylinder_r5h20_hex8.inp");
    let domain = inp
        .physical_names
        .iter()
        .find(|(_, _, n)| n == "domain")
        .expect("ELSET domain");
    assert!(inp.physical.iter().all(|&p| p == domain.0));
}

/// Elements as sets of node positions (bits), in file order, with their node order.
fn element_positions(s: &Scaffold) -> Vec<Vec<[u64; 3]>> {
    (0..s.element_count())
        .map(|e| {
            s.element(e)
                .iter()
                .map(|&n| s.nodes[n as usize].map(f64::to_bits))
                .collect()
        })
        .collect()
}

#[test]
fn formats_of_the_same_mesh_give_the_same_elements_and_nodes() {
    let msh = read("sphere_r10_tet4.msh");
    for other in [
        "sphere_r10_tet4.vtk",
        "sphere_r10_tet4.vtu",
        "sphere_r10_tet4_zlib.vtu",
        "sphere_r10_tet4_thickness.msh",
    ] {
        let s = read(other);
        assert_eq!(s.kind, msh.kind, "{other}");
        assert_eq!(s.nodes, msh.nodes, "{other}: node positions in order");
        assert_eq!(s.connectivity, msh.connectivity, "{other}: connectivity");
    }
    let hex = read("cylinder_r5h20_hex8.msh");
    let inp = read("cylinder_r5h20_hex8.inp");
    // Gmsh writes .inp coordinates with 14 significant digits: the same nodes to 1e-12.
    assert_eq!(inp.element_count(), hex.element_count());
    assert_eq!(inp.element_tags, hex.element_tags);
    for e in 0..hex.element_count() {
        for (a, b) in hex.element(e).iter().zip(inp.element(e)) {
            let (p, q) = (hex.nodes[*a as usize], inp.nodes[*b as usize]);
            assert!(
                (0..3).all(|k| (p[k] - q[k]).abs() < 1e-12),
                "element {e}: {p:?} against {q:?}"
            );
        }
    }
}

#[test]
fn binary_and_ascii_msh_give_identical_scaffolds() {
    let ascii41 = read("bracket_tet4.msh");
    let ascii22 = read("bracket_tet4_msh22.msh");
    for name in ["bracket_tet4_msh41bin.msh", "bracket_tet4_msh22bin.msh"] {
        let mut s = read(name);
        s.source = "bracket_tet4.msh".into();
        let reference = if name.contains("22") {
            &ascii22
        } else {
            &ascii41
        };
        let mut r = reference.clone();
        r.source = s.source.clone();
        assert_eq!(s.kind, r.kind, "{name}");
        // Gmsh's ASCII writer prints 16 significant digits (%.16g), which can miss the binary
        // double by an ulp: the same nodes, in the same order, to 1e-15 relative.
        assert_eq!(s.nodes.len(), r.nodes.len());
        let worst = s
            .nodes
            .iter()
            .zip(&r.nodes)
            .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs() / p[k].abs().max(1.0)))
            .fold(0.0f64, f64::max);
        assert!(
            worst < 1e-15,
            "{name}: nodes differ from the ASCII version by {worst}"
        );
        assert!(
            s.connectivity == r.connectivity,
            "{name}: connectivity differs"
        );
        assert!(s.node_tags == r.node_tags, "{name}: node tags differ");
        assert!(
            s.element_tags == r.element_tags,
            "{name}: element tags differ"
        );
        assert!(s.physical == r.physical, "{name}: physical groups differ");
        assert_eq!(s.physical_names, r.physical_names, "{name}");
        assert!(s.node_data == r.node_data);
    }
    assert!(
        element_positions(&ascii41) == element_positions(&ascii22),
        "2.2 and 4.1: same elements"
    );
    assert_eq!(ascii41.element_tags, ascii22.element_tags);
}

#[test]
fn node_data_views_equal_their_formulas() {
    let s = read("sphere_r10_tet4_thickness.msh");
    let t = s.node_data("thickness").expect("thickness view");
    assert_eq!(t.values.len(), s.nodes.len());
    for (p, v) in s.nodes.iter().zip(&t.values) {
        assert!((v - (0.2 + 0.01 * p[2])).abs() < 1e-15, "{v} at {p:?}");
    }
    let s = read("bracket_tet4_weight.msh");
    let w = s.node_data("weight").expect("weight view");
    for (p, v) in s.nodes.iter().zip(&w.values) {
        let f = 0.5 * (1.0 - (std::f64::consts::PI * p[0] / 60.0).cos());
        assert!((v - f).abs() < 1e-15, "{v} against {f} at {p:?}");
    }
}

#[test]
fn quadratic_meshes_share_corners_and_follow_curved_boundaries() {
    // Elevated meshes keep the elements and corner coordinates of their linear parents.
    for (linear, quadratic) in [
        ("sphere_r10_tet4.msh", "sphere_r10_tet10.msh"),
        ("cylinder_r5h20_hex8.msh", "cylinder_r5h20_hex20.msh"),
        ("cylinder_r5h20_hex8.msh", "cylinder_r5h20_hex27.msh"),
        ("plate_hole_tri3.msh", "plate_hole_tri6.msh"),
        ("plate_hole_quad4.msh", "plate_hole_quad8.msh"),
        ("sphere_surface_tri3.msh", "sphere_surface_tri6.msh"),
    ] {
        let l = read(linear);
        let q = read(quadratic);
        assert_eq!(l.element_count(), q.element_count());
        let c = q.kind.corner_count();
        for e in 0..l.element_count() {
            for k in 0..c {
                assert_eq!(
                    l.nodes[l.element(e)[k] as usize],
                    q.nodes[q.element(e)[k] as usize],
                    "{quadratic} element {e} corner {k}"
                );
            }
        }
    }
    // tet10 sphere: boundary mid-edge nodes lie on the sphere, and so do maps of boundary face
    // points to within the quadratic map's accuracy.
    let s = read("sphere_r10_tet10.msh");
    let facets = s.facets();
    let mut worst: f64 = 0.0;
    for f in &facets.boundary {
        let side = f.sides[0];
        let e = side.element as usize;
        let face = s.kind.faces()[side.face as usize];
        let c: Vec<[f64; 3]> = face.iter().map(|&k| s.kind.reference_node(k)).collect();
        let centre = [0, 1, 2].map(|a| (c[0][a] + c[1][a] + c[2][a]) / 3.0);
        let x = s.map(e, centre);
        let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
        worst = worst.max((r - 10.0).abs());
    }
    // Straight faces would miss by h²/(8R)-ish ≈ 0.1; the quadratic map is far closer.
    assert!(worst < 0.02, "face centres within {worst} of the sphere");
}

#[test]
fn planar_and_surface_meshes_keep_their_orientation() {
    // Planar Gmsh meshes are counter-clockwise from +z: positive signed area everywhere.
    for name in [
        "plate_hole_tri3.msh",
        "plate_hole_quad4.msh",
        "plate_hole_tri6.msh",
        "plate_hole_quad9.msh",
    ] {
        let s = read(name);
        for e in 0..s.element_count() {
            let j = s.jacobian(e, [0.0; 3]);
            let z = j[0][0] * j[1][1] - j[1][0] * j[0][1];
            assert!(z > 0.0, "{name} element {e}");
        }
    }
    // Sphere surface normals (J1 × J2 at the centre) point outward.
    let s = read("sphere_surface_tri6.msh");
    for e in 0..s.element_count() {
        let j = s.jacobian(e, [0.0; 3]);
        let x = s.map(e, [0.0; 3]);
        let n = [
            j[1][0] * j[2][1] - j[2][0] * j[1][1],
            j[2][0] * j[0][1] - j[0][0] * j[2][1],
            j[0][0] * j[1][1] - j[1][0] * j[0][1],
        ];
        assert!(n[0] * x[0] + n[1] * x[1] + n[2] * x[2] > 0.0, "element {e}");
    }
    assert_eq!(read("plate_hole_tri3.msh").kind, ElementKind::Tri3);
}
