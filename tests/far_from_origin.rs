//! Outputs placed far from the origin stay watertight and manifold as written: the STL file,
//! welded by position as its readers do, is the same closed surface, with as many distinct
//! positions as the mesh has vertices. Where 32-bit positions cannot keep samples apart at
//! all, the build is refused with the reason.

use crate::common;

use common::Project;
use std::collections::{HashMap, HashSet};

/// The triangles of a binary STL file as corner positions (their `f32` bits).
fn stl_triangles(bytes: &[u8]) -> Vec<[[u32; 3]; 3]> {
    assert!(bytes.len() >= 84, "short STL");
    let count = u32::from_le_bytes(bytes[80..84].try_into().expect("4 bytes")) as usize;
    assert_eq!(bytes.len(), 84 + 50 * count, "binary STL of {count} facets");
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    (0..count)
        .map(|f| {
            // 12 bytes of normal, then three corners of three f32 each.
            let base = 84 + 50 * f + 12;
            std::array::from_fn(|c| std::array::from_fn(|a| word(base + 12 * c + 4 * a)))
        })
        .collect()
}

/// Welds the facets by position, as an STL reader does, and checks the result is a closed,
/// consistently oriented 2-manifold: no facet with two equal corners, every directed edge
/// once and its reverse once, and the facets around every position one fan. Returns the
/// number of distinct positions.
fn assert_welded_closed_manifold(triangles: &[[[u32; 3]; 3]], what: &str) -> usize {
    let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
    let welded: Vec<[u32; 3]> = triangles
        .iter()
        .map(|t| {
            t.map(|p| {
                let next = ids.len() as u32;
                *ids.entry(p).or_insert(next)
            })
        })
        .collect();
    let mut directed: HashSet<(u32, u32)> = HashSet::new();
    // Around each position: the facet sides opposite it, `next → following`.
    let mut fans: HashMap<u32, HashMap<u32, u32>> = HashMap::new();
    for t in &welded {
        assert!(
            t[0] != t[1] && t[1] != t[2] && t[0] != t[2],
            "{what}: a facet has two corners at one position"
        );
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            assert!(directed.insert((a, b)), "{what}: edge {a}->{b} used twice");
            assert!(
                fans.entry(a).or_default().insert(b, c).is_none(),
                "{what}: pinched fan at position {a}"
            );
        }
    }
    for &(a, b) in &directed {
        assert!(directed.contains(&(b, a)), "{what}: open edge {a}->{b}");
    }
    for (v, next) in &fans {
        let start = *next.keys().next().expect("a side");
        let (mut at, mut steps) = (start, 0);
        loop {
            at = next[&at];
            steps += 1;
            if at == start {
                break;
            }
        }
        assert_eq!(steps, next.len(), "{what}: position {v} is not one fan");
    }
    ids.len()
}

#[test]
fn far_placed_gyroids_are_written_watertight_and_manifold() {
    // The 1/256-of-an-edge margin (2/199/256 ≈ 3.9e-5) is less than an f32 step at 1000
    // (2⁻¹⁴ ≈ 6.1e-5): before crossings were kept inside their edges in f32, the first block
    // had 366 duplicate positions and 747 flat triangles.
    let p = Project::new(
        r#"
[cells.g]
tpms = "gyroid"

[outputs.at_1000]
cell = "g"
domain = { min = [1000, 1000, 1000], max = [1002, 1002, 1002] }
cell_size = 1
samples = 200

[outputs.mixed_signs]
cell = "g"
domain = { min = [-1002, 1000, -2], max = [-1000, 1002, 0] }
cell_size = 1
samples = 120

[outputs.at_4000_shell]
cell = "g"
domain = { min = [4000, 4000, 4000], max = [4001, 4001, 4001] }
cell_size = 0.5
solid = "shell"
thickness = 0.5
samples = 100
"#,
    );
    let reports = p.build(&[]);
    let reports = reports.as_array().expect("array");
    assert_eq!(reports.len(), 3);
    for r in reports {
        let name = r["name"].as_str().expect("name");
        assert_eq!(r["watertight"], true, "{name}: {r}");
        assert_eq!(r["manifold"], true, "{name}: {r}");
        let bytes = std::fs::read(p.out(&format!("{name}.stl"))).expect("STL");
        let triangles = stl_triangles(&bytes);
        assert_eq!(
            triangles.len() as u64,
            r["triangles"].as_u64().expect("count")
        );
        let positions = assert_welded_closed_manifold(&triangles, name);
        assert_eq!(
            positions as u64,
            r["vertices"].as_u64().expect("count"),
            "{name}: distinct positions in the STL against the mesh's vertices"
        );
    }
}

#[test]
fn grids_too_fine_for_f32_where_they_lie_are_refused() {
    // Near a million f32 steps are 1/16: samples 0.01 apart have no f32 between them.
    let p = Project::new(
        r#"
[cells.g]
tpms = "gyroid"

[outputs.far]
cell = "g"
domain = { min = [1000000, 0, 0], max = [1000000.2, 1, 1] }
cell_size = 1
samples = [21, 5, 5]
"#,
    );
    let out = p.run(&["build", "lattice.toml", "-q"]);
    assert!(!out.status.success(), "the build succeeded");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("too close together for 32-bit positions")
            && stderr.contains("along x samples 0 and 1"),
        "{stderr}"
    );
    assert!(!p.out("far.stl").exists(), "a refused output was written");
}
