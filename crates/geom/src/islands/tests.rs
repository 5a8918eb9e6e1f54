use super::*;
use crate::mesh::MeshChunk;
use crate::test_meshes::cube;
use crate::validate::{check, pieces};

/// The boxes `(min, size, inward)` as one mesh, in order.
fn boxes(list: &[([f32; 3], f32, bool)]) -> Mesh {
    let mut mesh = Mesh::default();
    for &(min, size, inward) in list {
        let c = cube(min, size, mesh.vertices.len() as u32, inward);
        mesh.vertices.extend(c.vertices);
        mesh.triangles.extend(c.triangles);
    }
    mesh
}

const LARGEST: IslandFilter = IslandFilter {
    largest: true,
    min_volume: None,
};

fn at_least(v: f64) -> IslandFilter {
    IslandFilter {
        largest: false,
        min_volume: Some(v),
    }
}

fn volume(mesh: &Mesh) -> f64 {
    check(mesh).volume
}

/// Volumes summed over tetrahedra from the origin are exact only to rounding.
fn near(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9 * a.abs().max(b.abs()).max(1.0)
}

#[test]
fn the_largest_of_separate_cubes_is_kept_alone_renumbered_in_order() {
    let mesh = boxes(&[
        ([0.0; 3], 2.0, false),
        ([10.0, 0.0, 0.0], 4.0, false),
        ([20.0, 0.0, 0.0], 1.0, false),
    ]);
    let out = remove_islands(&mesh, &LARGEST, false).expect("kept");
    // Bit for bit the second cube, numbered from 0: order kept, unused vertices gone.
    assert_eq!(out.mesh, cube([10.0, 0.0, 0.0], 4.0, 0, false));
    assert_eq!(out.removal.pieces, 3);
    assert_eq!(out.removal.pieces_removed, 2);
    assert!(near(out.removal.removed, 9.0), "{:?}", out.removal.removed);
    assert!(
        near(out.removal.largest_removed, 8.0),
        "{:?}",
        out.removal.largest_removed
    );
    assert_eq!(out.removal.triangles_removed, 24);
    assert!(
        near(volume(&out.mesh) + out.removal.removed, volume(&mesh)),
        "{:?}",
        volume(&out.mesh) + out.removal.removed
    );
}

#[test]
fn a_minimum_volume_drops_exactly_the_smaller_pieces() {
    let sizes = [1.0f32, 3.0, 2.0, 0.5, 4.0];
    let list: Vec<_> = sizes
        .iter()
        .enumerate()
        .map(|(k, &s)| ([10.0 * k as f32, 0.0, 0.0], s, false))
        .collect();
    let mesh = boxes(&list);
    let out = remove_islands(&mesh, &at_least(7.5), false).expect("kept");
    let kept: Vec<_> = list.iter().copied().filter(|l| l.1 >= 2.0).collect();
    assert_eq!(out.mesh, boxes(&kept));
    assert_eq!(out.removal.pieces_removed, 2);
    assert!(
        near(out.removal.removed, 1.0 + 0.125),
        "{:?}",
        out.removal.removed
    );
    // Both: the largest, if it reaches the threshold.
    let both = IslandFilter {
        largest: true,
        min_volume: Some(7.5),
    };
    let out = remove_islands(&mesh, &both, false).expect("kept");
    assert_eq!(out.mesh, cube([40.0, 0.0, 0.0], 4.0, 0, false));
    let none = IslandFilter {
        largest: true,
        min_volume: Some(65.0),
    };
    match remove_islands(&mesh, &none, false) {
        Err(IslandError::NothingKept {
            pieces: 5, largest, ..
        }) => assert!(near(largest, 64.0)),
        other => panic!("{other:?}"),
    }
    assert!(remove_islands(&mesh, &at_least(100.0), false).is_err());
    assert_eq!(
        remove_islands(&Mesh::default(), &LARGEST, false),
        Err(IslandError::NoPieces)
    );
}

/// A hollow box with an island in its cavity, the island hollow too, and a loose cube
/// outside: cavities stay with the piece around them, islands in a cavity are pieces.
#[test]
fn cavities_stay_with_the_innermost_solid_around_them() {
    let mesh = boxes(&[
        ([3.0; 3], 4.0, false),  // island B, inside A's cavity
        ([0.0; 3], 10.0, false), // A
        ([4.0; 3], 2.0, true),   // D, B's cavity
        ([1.0; 3], 8.0, true),   // C, A's cavity
        ([20.0; 3], 1.0, false), // loose
    ]);
    assert_eq!(pieces(&mesh).count(false), 3);
    let out = remove_islands(&mesh, &LARGEST, false).expect("kept");
    // A and its cavity: 1000 − 512.
    let expected = boxes(&[([0.0; 3], 10.0, false), ([1.0; 3], 8.0, true)]);
    assert_eq!(out.mesh, expected);
    assert!(near(volume(&out.mesh), 488.0), "{:?}", volume(&out.mesh));
    // B with D (64 − 8), and the loose cube.
    assert!(
        near(out.removal.removed, 56.0 + 1.0),
        "{:?}",
        out.removal.removed
    );
    assert!(
        near(out.removal.largest_removed, 56.0),
        "{:?}",
        out.removal.largest_removed
    );
    // 50 keeps B (56) with its cavity; 60 drops it with its cavity.
    let out = remove_islands(&mesh, &at_least(50.0), false).expect("kept");
    assert_eq!(out.removal.pieces_removed, 1);
    assert!(
        near(volume(&out.mesh), 488.0 + 56.0),
        "{:?}",
        volume(&out.mesh)
    );
    let out = remove_islands(&mesh, &at_least(60.0), false).expect("kept");
    assert_eq!(out.mesh, expected);
}

/// The ray from a cavity's corner runs exactly along the diagonals and edges of the outer
/// box's faces: each crossing must still count once.
#[test]
fn rays_through_edges_and_vertices_count_once() {
    for (outer, inner, size) in [
        ([0.0f32; 3], [1.0f32; 3], 1.0f32),
        ([0.0; 3], [2.0, 0.5, 0.5], 1.0),
        ([0.0; 3], [0.5, 2.0, 2.0], 0.5),
    ] {
        let mesh = boxes(&[
            ([30.0, 0.0, 0.0], 5.0, false),
            (outer, 4.0, false),
            (inner, size, true),
        ]);
        // The bigger loose cube wins by volume; the hollow box keeps its cavity or loses both.
        let out = remove_islands(&mesh, &LARGEST, false).expect("kept");
        assert_eq!(out.mesh, cube([30.0, 0.0, 0.0], 5.0, 0, false));
        let hollow = 64.0 - f64::from(size).powi(3);
        assert!(
            near(out.removal.removed, hollow),
            "{:?}",
            out.removal.removed
        );
        let out = remove_islands(&mesh, &at_least(hollow - 0.01), false).expect("kept");
        assert_eq!(out.mesh, mesh, "{inner:?}");
    }
}

/// A non-solid surface inside a solid's box but outside the solid belongs to no piece (and is
/// removed); one inside it is its cavity.
#[test]
fn a_surface_in_a_solids_box_but_outside_it_is_no_cavity_of_it() {
    // The tetrahedron x, y, z ≥ 0, x + y + z ≤ 10, outward.
    let mut mesh = Mesh {
        vertices: vec![
            [0.0; 3],
            [10.0, 0.0, 0.0],
            [0.0, 10.0, 0.0],
            [0.0, 0.0, 10.0],
        ],
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    };
    let rest = boxes(&[
        ([6.0; 3], 1.0, true),   // in the box, outside the solid: a stray
        ([1.0; 3], 1.0, true),   // inside: a cavity
        ([20.0; 3], 1.0, false), // loose, kept by the threshold
    ]);
    mesh.triangles
        .extend(rest.triangles.iter().map(|t| t.map(|v| v + 4)));
    mesh.vertices.extend(rest.vertices);
    let out = remove_islands(&mesh, &at_least(0.5), false).expect("kept");
    assert_eq!(out.removal.pieces, 2);
    assert_eq!(out.removal.pieces_removed, 0);
    assert!(near(out.removal.removed, -1.0), "{:?}", out.removal.removed);
    assert_eq!(out.mesh.triangles.len(), 4 + 12 + 12);
    assert!((volume(&out.mesh) - (1000.0 / 6.0 - 1.0 + 1.0)).abs() < 1e-9);
    // Largest: the tetrahedron keeps its cavity.
    let out = remove_islands(&mesh, &LARGEST, false).expect("kept");
    assert_eq!(out.mesh.triangles.len(), 4 + 12);
    assert!((volume(&out.mesh) - (1000.0 / 6.0 - 1.0)).abs() < 1e-9);
}

#[test]
fn a_planar_regions_pieces_are_measured_by_area() {
    // Two squares in z = 0, sides 1 and 2, and a volume threshold refused.
    let mut mesh = Mesh::default();
    for (x, s) in [(0.0f32, 1.0f32), (5.0, 2.0)] {
        let b = mesh.vertices.len() as u32;
        mesh.vertices.extend([
            [x, 0.0, 0.0],
            [x + s, 0.0, 0.0],
            [x + s, s, 0.0],
            [x, s, 0.0],
        ]);
        mesh.triangles
            .extend([[b, b + 1, b + 2], [b, b + 2, b + 3]]);
    }
    let out = remove_islands(&mesh, &LARGEST, true).expect("kept");
    assert_eq!(out.mesh.triangles, [[0, 1, 2], [0, 2, 3]]);
    assert_eq!(out.mesh.vertices[0], [5.0, 0.0, 0.0]);
    assert!(near(out.removal.removed, 1.0), "{:?}", out.removal.removed);
    assert_eq!(
        remove_islands(&mesh, &at_least(1.0), true),
        Err(IslandError::VolumeOfRegion)
    );
}

/// The streamed passes over any chunking: the same kept mesh, bit for bit, as the whole.
fn streamed(mesh: &Mesh, filter: &IslandFilter, per_chunk: usize) -> Result<Filtered, IslandError> {
    let chunks = MeshChunk::split(mesh, per_chunk);
    let mut labeller = IslandLabeller::new(false);
    for chunk in &chunks {
        labeller.push(chunk);
    }
    let mut plan = labeller.finish();
    if plan.needs_ray_pass() {
        for chunk in &chunks {
            plan.ray_pass(chunk);
        }
    }
    let mut keeper = plan.decide(filter)?;
    let mut out = Mesh::default();
    let mut next = 0;
    let mut kept = Vec::new();
    for chunk in &chunks {
        let part = keeper.push(chunk);
        assert_eq!(part.first_vertex, next);
        next = part.end_vertex();
        out.vertices.extend(&part.vertices);
        out.triangles.extend(&part.triangles);
        kept.push(part);
    }
    // The kept chunks keep the chunk invariants: what `MeshChunk::split` makes of the result.
    for (k, part) in kept.iter().enumerate() {
        for t in &part.triangles {
            for &v in t {
                assert!(v < part.end_vertex());
                assert_eq!(part.position(v), Some(out.vertices[v as usize]));
            }
        }
        let later: std::collections::BTreeSet<u32> = kept[k + 1..]
            .iter()
            .flat_map(|c| c.triangles.iter().flatten().copied())
            .filter(|&v| v < part.end_vertex())
            .collect();
        assert!(later.iter().all(|v| part.open.binary_search(v).is_ok()));
        assert!(part.borrowed.windows(2).all(|w| w[0].0 < w[1].0));
    }
    Ok(Filtered {
        mesh: out,
        removal: keeper.removal(),
    })
}

#[test]
fn streamed_chunks_keep_what_the_whole_mesh_keeps() {
    // Nested hollow boxes, a stray, loose cubes; chunked finely enough to split pieces, and
    // with the pieces' triangles interleaved so that fragments join late.
    let mut mesh = boxes(&[
        ([3.0; 3], 4.0, false),
        ([0.0; 3], 10.0, false),
        ([4.0; 3], 2.0, true),
        ([1.0; 3], 8.0, true),
        ([20.0; 3], 1.0, false),
        ([30.0; 3], 2.0, false),
        ([40.0; 3], 1.5, true),
    ]);
    let n = mesh.triangles.len();
    let interleaved: Vec<[u32; 3]> = (0..n).map(|k| mesh.triangles[(k * 37) % n]).collect();
    for triangles in [mesh.triangles.clone(), interleaved] {
        mesh.triangles = triangles;
        for filter in [LARGEST, at_least(1.0), at_least(50.0), at_least(7.0)] {
            let whole = remove_islands(&mesh, &filter, false).expect("whole");
            for per in [1, 5, 12, 30, 1000] {
                let chunked = streamed(&mesh, &filter, per).expect("streamed");
                assert_eq!(chunked.mesh, whole.mesh, "{filter:?}, {per} per chunk");
                let (a, b) = (chunked.removal, whole.removal);
                assert_eq!(
                    (a.pieces, a.pieces_removed, a.triangles_removed),
                    (b.pieces, b.pieces_removed, b.triangles_removed)
                );
                assert!(near(a.removed, b.removed) && near(a.largest_removed, b.largest_removed));
            }
        }
        assert!(matches!(
            streamed(&mesh, &at_least(1e4), 7),
            Err(IslandError::NothingKept { pieces: 4, .. })
        ));
    }
}

/// Many hollow cubes and loose specks (the grid of solids' boxes at work): every cavity stays
/// with its own cube.
#[test]
fn many_hollow_cubes_keep_their_own_cavities() {
    let mut list = Vec::new();
    for i in 0..4 {
        for j in 0..4 {
            for k in 0..4 {
                let at = [2.0 * i as f32, 2.0 * j as f32, 2.0 * k as f32];
                list.push((at, 1.0, false));
                list.push((at.map(|x| x + 0.25), 0.5, true));
                list.push((at.map(|x| x + 1.5), 0.1, false));
            }
        }
    }
    let mesh = boxes(&list);
    let out = remove_islands(&mesh, &at_least(0.5), false).expect("kept");
    assert_eq!(out.removal.pieces, 128);
    assert_eq!(out.removal.pieces_removed, 64);
    assert_eq!(out.mesh.triangles.len(), 64 * 24);
    assert!(
        near(volume(&out.mesh), 64.0 * 0.875),
        "{}",
        volume(&out.mesh)
    );
    // A threshold over a hollow cube's net volume (0.875) but under its outer one (1): the
    // cavity counts, so every piece is under it: an error, not an empty mesh.
    assert!(matches!(
        remove_islands(&mesh, &at_least(0.9), false),
        Err(IslandError::NothingKept { .. })
    ));
}
