//! `StreamCheck` against `check` on whole meshes cut by `MeshChunk::split`, an independent
//! model of the windowed duplicate count, the held-state bound, and malformed chunks.

use super::StreamCheck;
use crate::mesh::{Mesh, MeshChunk};
use crate::validate::{MeshCheck, check};
use std::collections::{BTreeSet, HashMap};
use std::f64::consts::TAU;

/// Chunk sizes every mesh is cut into (triangles per chunk); `usize::MAX` is the whole mesh.
const SIZES: [usize; 5] = [1, 7, 1000, 40_000, usize::MAX];

/// SplitMix64, so failures reproduce.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

// ---------------------------------------------------------------------------------------------
// Meshes

/// A torus of `n × m` quads, outward winding; vertex `(i, j)` is `i * m + j`.
fn torus(n: u32, m: u32, big_r: f64, r: f64) -> Mesh {
    let mut mesh = Mesh::default();
    for i in 0..n {
        let theta = TAU * f64::from(i) / f64::from(n);
        for j in 0..m {
            let phi = TAU * f64::from(j) / f64::from(m);
            let rho = big_r + r * phi.cos();
            mesh.vertices
                .push([rho * theta.cos(), rho * theta.sin(), r * phi.sin()].map(|x| x as f32));
        }
    }
    let id = |i: u32, j: u32| (i % n) * m + (j % m);
    for i in 0..n {
        for j in 0..m {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            mesh.triangles.push([a, b, c]);
            mesh.triangles.push([a, c, d]);
        }
    }
    mesh
}

/// A UV sphere with poles: `rings` latitude rings of `segments` vertices, outward winding.
fn sphere(rings: u32, segments: u32, radius: f64) -> Mesh {
    let mut mesh = Mesh::default();
    mesh.vertices.push([0.0, 0.0, radius as f32]);
    for i in 1..=rings {
        let polar = TAU / 2.0 * f64::from(i) / f64::from(rings + 1);
        for j in 0..segments {
            let azimuth = TAU * f64::from(j) / f64::from(segments);
            mesh.vertices.push(
                [
                    radius * polar.sin() * azimuth.cos(),
                    radius * polar.sin() * azimuth.sin(),
                    radius * polar.cos(),
                ]
                .map(|x| x as f32),
            );
        }
    }
    let south = mesh.vertices.len() as u32;
    mesh.vertices.push([0.0, 0.0, -radius as f32]);
    let id = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
    for j in 0..segments {
        mesh.triangles.push([0, id(1, j), id(1, j + 1)]);
        mesh.triangles.push([south, id(rings, j + 1), id(rings, j)]);
    }
    for i in 1..rings {
        for j in 0..segments {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            mesh.triangles.push([a, b, c]);
            mesh.triangles.push([a, c, d]);
        }
    }
    mesh
}

/// The unit cube, outward winding; vertex `i` at `(i & 1, i >> 1 & 1, i >> 2 & 1)`.
fn cube() -> Mesh {
    let vertices = (0..8)
        .map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32])
        .collect();
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
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

fn translated(mesh: &Mesh, by: [f32; 3]) -> Mesh {
    Mesh {
        vertices: mesh
            .vertices
            .iter()
            .map(|p| [p[0] + by[0], p[1] + by[1], p[2] + by[2]])
            .collect(),
        triangles: mesh.triangles.clone(),
    }
}

fn append(mesh: &mut Mesh, other: &Mesh) {
    let base = mesh.vertices.len() as u32;
    mesh.vertices.extend_from_slice(&other.vertices);
    mesh.triangles
        .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
}

/// Renumbers the vertices by a random permutation and shuffles the triangles, so vertices stay
/// open over many chunks and chunks borrow far back.
fn scrambled(mesh: &Mesh, rng: &mut Rng) -> Mesh {
    let n = mesh.vertices.len();
    let mut order: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        order.swap(i, rng.below(i + 1));
    }
    let mut new_id = vec![0u32; n];
    for (new, &old) in order.iter().enumerate() {
        new_id[old] = new as u32;
    }
    let mut triangles: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|v| new_id.get(v as usize).copied().unwrap_or(v)))
        .collect();
    for i in (1..triangles.len()).rev() {
        triangles.swap(i, rng.below(i + 1));
    }
    Mesh {
        vertices: order.iter().map(|&old| mesh.vertices[old]).collect(),
        triangles,
    }
}

/// Random triangles over `n` vertices whose positions come from a small lattice (so
/// duplicate positions and degenerate triangles occur), with repeated and invalid indices.
fn random_mesh(rng: &mut Rng, n: usize, triangles: usize) -> Mesh {
    let vertices = (0..n)
        .map(|_| [0; 3].map(|_: i32| rng.below(4) as f32 * 0.5))
        .collect();
    let triangles = (0..triangles)
        .map(|_| {
            [0; 3].map(|_: i32| match rng.below(50) {
                0 => (n + rng.below(3)) as u32,
                1 => u32::MAX,
                _ => rng.below(n) as u32,
            })
        })
        .collect();
    Mesh {
        vertices,
        triangles,
    }
}

/// Every structured case: name, mesh, and whether its duplicate positions (if any) lie close
/// enough in id and triangle order for every chunking to see them together.
fn cases() -> Vec<(&'static str, Mesh)> {
    let mut cases = Vec::new();
    cases.push(("torus", torus(24, 12, 3.0, 1.0)));
    cases.push(("sphere", sphere(9, 14, 2.0)));
    cases.push(("cube", cube()));

    let mut hole = torus(16, 8, 3.0, 1.0);
    hole.triangles.remove(37);
    cases.push(("torus with a hole", hole));

    let mut flipped = sphere(6, 10, 1.0);
    flipped.triangles[17].swap(1, 2);
    cases.push(("sphere with a flipped triangle", flipped));

    // Two cubes sharing corner 7 of the first as corner 0 of the second.
    let mut touching = cube();
    let other = translated(&cube(), [1.0, 1.0, 1.0]);
    let base = touching.vertices.len() as u32 - 1;
    touching.vertices.extend_from_slice(&other.vertices[1..]);
    touching.triangles.extend(
        other
            .triangles
            .iter()
            .map(|t| t.map(|v| if v == 0 { 7 } else { v + base })),
    );
    cases.push(("two cubes touching at a vertex", touching));

    // Three sheets on one edge, and a fin: non-manifold edges.
    let mut fins = cube();
    fins.vertices.push([0.5, 0.5, 2.0]);
    fins.triangles.push([4, 5, 8]);
    fins.triangles.push([5, 4, 8]);
    cases.push(("cube with fins", fins));

    let mut degenerate = sphere(5, 8, 1.0);
    let a = degenerate.vertices.len() as u32;
    degenerate
        .vertices
        .extend([[5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [7.0, 0.0, 0.0]]);
    degenerate.triangles.push([a, a + 1, a + 2]); // collinear
    degenerate.triangles.push([3, 3, 4]); // repeated index
    degenerate.triangles.push([6, 6, 6]);
    degenerate.triangles.insert(5, [a + 2, a + 1, a + 1]);
    cases.push(("sphere with degenerate triangles", degenerate));

    let mut invalid = torus(10, 6, 2.0, 0.5);
    let n = invalid.vertices.len() as u32;
    invalid.triangles.insert(3, [0, 1, n]);
    invalid.triangles.push([u32::MAX, 2, 3]);
    invalid.triangles.insert(40, [n + 7, n + 8, n + 9]);
    cases.push(("torus with invalid indices", invalid));

    // Unreferenced vertices at the start, in the middle and at the end.
    let mut unreferenced = Mesh {
        vertices: vec![[9.0; 3], [8.0; 3]],
        triangles: Vec::new(),
    };
    append(&mut unreferenced, &sphere(4, 6, 1.0));
    unreferenced.vertices.push([7.0; 3]);
    append(&mut unreferenced, &translated(&cube(), [3.0, 0.0, 0.0]));
    unreferenced.vertices.extend([[6.0; 3], [5.0; 3]]);
    cases.push(("unreferenced vertices", unreferenced));

    // Two cubes face to face, not welded: four positions used twice. An unreferenced vertex at
    // a used position does not count.
    let mut stacked = cube();
    append(&mut stacked, &translated(&cube(), [0.0, 0.0, 1.0]));
    stacked.vertices.push([0.0, 0.0, 1.0]);
    cases.push(("two cubes face to face", stacked));

    let mut rng = Rng(7);
    cases.push((
        "scrambled torus",
        scrambled(&torus(20, 10, 3.0, 1.0), &mut rng),
    ));
    cases.push(("scrambled stacked cubes", {
        let mut stacked = cube();
        append(&mut stacked, &translated(&cube(), [0.0, 0.0, 1.0]));
        scrambled(&stacked, &mut rng)
    }));
    cases.push(("empty", Mesh::default()));
    cases.push((
        "vertices only",
        Mesh {
            vertices: vec![[1.0; 3]; 4],
            triangles: Vec::new(),
        },
    ));
    cases.push((
        "invalid only",
        Mesh {
            vertices: vec![[1.0; 3]; 2],
            triangles: vec![[0, 1, 2]],
        },
    ));
    cases
}

// ---------------------------------------------------------------------------------------------
// Running and comparing

fn stream(chunks: &[MeshChunk]) -> MeshCheck {
    let mut checker = StreamCheck::new();
    for chunk in chunks {
        checker.push(chunk);
    }
    checker.finish()
}

/// `a == b` with floating-point fields compared bitwise (NaN-safe).
fn assert_same(a: &MeshCheck, b: &MeshCheck, what: &str) {
    let bits = |c: &MeshCheck| {
        (
            c.volume.to_bits(),
            c.area.to_bits(),
            c.bbox_min.map(f64::to_bits),
            c.bbox_max.map(f64::to_bits),
        )
    };
    let mut a_rest = a.clone();
    let mut b_rest = b.clone();
    for c in [&mut a_rest, &mut b_rest] {
        c.volume = 0.0;
        c.area = 0.0;
        c.bbox_min = [0.0; 3];
        c.bbox_max = [0.0; 3];
    }
    assert_eq!(a_rest, b_rest, "{what}");
    assert_eq!(bits(a), bits(b), "{what}: {a:?} vs {b:?}");
}

/// The windowed duplicate count from first principles: a vertex lives from the chunk that owns
/// it to the first chunk after which it is not open; vertices of one position whose lifetimes
/// overlap (for an unreferenced one, without its last chunk, where it is dropped) form a class,
/// which counts its referenced members less one.
fn windowed_duplicates(mesh: &Mesh, chunks: &[MeshChunk]) -> usize {
    let n = mesh.vertices.len();
    let mut referenced = vec![false; n];
    for t in &mesh.triangles {
        if t.iter().all(|&v| (v as usize) < n) {
            for &v in t {
                referenced[v as usize] = true;
            }
        }
    }
    let mut lifetimes: HashMap<[u32; 3], Vec<(usize, usize, bool)>> = HashMap::new();
    for (k, chunk) in chunks.iter().enumerate() {
        for (i, p) in chunk.vertices.iter().enumerate() {
            let v = chunk.first_vertex + i as u32;
            let death = (k..chunks.len())
                .find(|&m| chunks[m].open.binary_search(&v).is_err())
                .unwrap_or(chunks.len() - 1);
            let r = referenced[v as usize];
            let last = if r { death } else { death.wrapping_sub(1) };
            if last >= k && last != usize::MAX {
                lifetimes
                    .entry(p.map(f32::to_bits))
                    .or_default()
                    .push((k, last, r));
            }
        }
    }
    let mut duplicates = 0;
    for (_, mut members) in lifetimes {
        members.sort_unstable();
        let (mut reach, mut count) = (0, 0usize);
        for (i, &(born, last, r)) in members.iter().enumerate() {
            if i > 0 && born > reach {
                duplicates += count.saturating_sub(1);
                count = 0;
            }
            reach = if i == 0 { last } else { reach.max(last) };
            count += usize::from(r);
        }
        duplicates += count.saturating_sub(1);
    }
    duplicates
}

/// Streams `mesh` cut every way, checking the held state after each push, and compares with
/// `check`: everything equal, duplicates equal to the windowed model (and to `check` whole).
fn compare(name: &str, mesh: &Mesh) -> MeshCheck {
    let whole = check(mesh);
    for per in SIZES {
        let chunks = MeshChunk::split(mesh, per);
        let mut checker = StreamCheck::new();
        let mut seen: Vec<[u32; 3]> = Vec::new();
        for chunk in &chunks {
            checker.push(chunk);
            let n = mesh.vertices.len();
            seen.extend(
                chunk
                    .triangles
                    .iter()
                    .filter(|t| t.iter().all(|&v| (v as usize) < n)),
            );
            assert_held(&checker, &seen, &chunk.open, name);
        }
        let streamed = checker.finish();
        let what = format!("{name}, {per} triangles per chunk");
        let windowed = windowed_duplicates(mesh, &chunks);
        assert_eq!(streamed.duplicate_positions, windowed, "{what}");
        assert!(streamed.duplicate_positions <= whole.duplicate_positions);
        let mut expected = whole.clone();
        expected.duplicate_positions = windowed;
        expected.manifold = whole.invalid_triangles == 0
            && whole.nonmanifold_edges == 0
            && whole.misoriented_edges == 0
            && whole.nonmanifold_vertices == 0
            && whole.degenerate_triangles == 0
            && windowed == 0;
        if whole.duplicate_positions == 0 || chunks.len() == 1 {
            assert_eq!(windowed, whole.duplicate_positions, "{what}");
        }
        assert_same(&streamed, &expected, &what);
    }
    whole
}

/// The memory property: after a push, the held corners are exactly the corners of the valid
/// triangles seen so far at the ids still open.
fn assert_held(checker: &StreamCheck, seen: &[[u32; 3]], open: &[u32], name: &str) {
    let is_open = |v: u32| open.binary_search(&v).is_ok();
    let mut corners = 0;
    let mut triangles = BTreeSet::new();
    for t in seen {
        for c in 0..3 {
            if is_open(t[c]) {
                corners += 1;
                let mut tri = [t[c], t[(c + 1) % 3], t[(c + 2) % 3]];
                let smallest = (0..3).min_by_key(|&i| tri[i]).unwrap_or(0);
                tri.rotate_left(smallest);
                triangles.insert(tri);
            }
        }
    }
    assert_eq!(checker.held_corners(), corners, "{name}");
    assert_eq!(checker.held_triangles(), triangles, "{name}");
    assert_eq!(checker.open_vertices(), open.len(), "{name}");
}

// ---------------------------------------------------------------------------------------------
// Tests

#[test]
fn structured_meshes_match_check_for_every_chunking() {
    for (name, mesh) in cases() {
        compare(name, &mesh);
    }
}

#[test]
fn the_structured_cases_exercise_every_count() {
    // The comparison above is only as strong as the cases: each count is non-zero somewhere.
    let results: Vec<(&str, MeshCheck)> = cases()
        .into_iter()
        .map(|(name, mesh)| (name, check(&mesh)))
        .collect();
    let get = |name: &str| {
        results
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, c)| c.clone())
            .expect("a case of that name")
    };
    let t = get("torus");
    assert!(t.watertight && t.manifold && t.euler_characteristic == 0);
    let s = get("sphere");
    assert!(s.watertight && s.manifold && s.euler_characteristic == 2);
    assert_eq!(get("torus with a hole").boundary_edges, 3);
    assert_eq!(get("sphere with a flipped triangle").misoriented_edges, 3);
    let touching = get("two cubes touching at a vertex");
    assert!(touching.watertight && !touching.manifold);
    assert_eq!(touching.nonmanifold_vertices, 1);
    assert!(get("cube with fins").nonmanifold_edges > 0);
    assert_eq!(
        get("sphere with degenerate triangles").degenerate_triangles,
        4
    );
    assert_eq!(get("torus with invalid indices").invalid_triangles, 3);
    assert_eq!(get("unreferenced vertices").unreferenced_vertices, 5);
    assert_eq!(get("two cubes face to face").duplicate_positions, 4);
    assert_eq!(get("scrambled stacked cubes").duplicate_positions, 4);
}

#[test]
fn random_meshes_match_check_for_every_chunking() {
    let mut rng = Rng(2026);
    for round in 0..60 {
        let n = 1 + rng.below(40);
        let triangles = rng.below(300);
        let mesh = random_mesh(&mut rng, n, triangles);
        compare(&format!("random mesh {round}"), &mesh);
    }
}

#[test]
fn large_meshes_sum_volume_and_area_bit_for_bit_across_global_chunks() {
    // More triangles than two of the sums' fixed chunks, cut at sizes unrelated to them, on a
    // torus far from the origin (where the reference point matters).
    let mesh = translated(&torus(300, 160, 30.0, 10.0), [250.0, -125.0, 40.0]);
    let whole = check(&mesh);
    assert!(whole.watertight && whole.manifold);
    for per in [9_999, 40_000, 65_536] {
        let streamed = stream(&MeshChunk::split(&mesh, per));
        assert_same(&streamed, &whole, &format!("{per} per chunk"));
    }
    let mut rng = Rng(3);
    let scrambled = scrambled(&mesh, &mut rng);
    let streamed = stream(&MeshChunk::split(&scrambled, 20_000));
    assert_same(&streamed, &check(&scrambled), "scrambled");
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let mut rng = Rng(5);
    let mesh = scrambled(&torus(200, 100, 3.0, 1.0), &mut rng);
    let chunks = MeshChunk::split(&mesh, 30_000);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map(|pool| pool.install(|| stream(&chunks)))
            .expect("a thread pool")
    };
    let one = run(1);
    for threads in [2, 3, 8] {
        assert_same(&run(threads), &one, &format!("{threads} threads"));
    }
    assert_same(&one, &check(&mesh), "against check");
}

#[test]
fn the_scatter_parts_place_every_corner_of_garbage_too() {
    // Chunks of several triangle-pass parts (more than TRIANGLE_CHUNK triangles each), with
    // invalid, repeated and far-apart indices: every part places its own triangles' corners.
    let mut rng = Rng(17);
    let mesh = random_mesh(&mut rng, 3_000, 150_000);
    let whole = check(&mesh);
    for threads in [1, 2, 4] {
        let streamed = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map(|pool| pool.install(|| stream(&MeshChunk::split(&mesh, 100_000))))
            .expect("a thread pool");
        let mut expected = whole.clone();
        // Duplicates are matched within windows only (the documented exception).
        expected.duplicate_positions = streamed.duplicate_positions;
        expected.manifold = false;
        assert_same(&streamed, &expected, &format!("{threads} threads"));
        assert!(streamed.nonmanifold_edges > 0 && streamed.invalid_triangles > 0);
    }
}

#[test]
fn duplicates_far_apart_are_the_documented_exception() {
    // Two unwelded cubes face to face: whole, the four shared positions count; one triangle
    // per chunk, the first cube's vertices have finished before the second's arrive.
    let mut stacked = cube();
    append(&mut stacked, &translated(&cube(), [0.0, 0.0, 1.0]));
    assert_eq!(
        stream(&MeshChunk::split(&stacked, usize::MAX)).duplicate_positions,
        4
    );
    let apart = stream(&MeshChunk::split(&stacked, 1));
    assert_eq!(apart.duplicate_positions, 0);
    assert!(apart.manifold, "the one verdict that can differ");

    // Duplicates alive together are found at any chunking, also when their lifetimes only
    // chain through a third vertex of the same position. One triangle per chunk: vertex 0
    // lives in chunks 0–2, vertex 3 in 1–4, vertex 4 in 3 only.
    let mut close = Mesh {
        vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0; 3]],
        triangles: vec![[0, 1, 2], [3, 2, 1], [0, 2, 1]],
    };
    assert_eq!(stream(&MeshChunk::split(&close, 1)).duplicate_positions, 1);
    close.vertices.push([0.0; 3]);
    close.triangles.push([4, 1, 2]);
    close.triangles.push([3, 1, 2]);
    assert_eq!(check(&close).duplicate_positions, 2);
    for per in [1, 2, 4] {
        assert_eq!(
            stream(&MeshChunk::split(&close, per)),
            check(&close),
            "{per}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Chunks that break the invariants

#[test]
fn extra_open_ids_and_unsorted_lists_change_nothing() {
    let mut rng = Rng(11);
    let mesh = scrambled(&torus(30, 12, 3.0, 1.0), &mut rng);
    let whole = check(&mesh);
    for per in [1, 7, 100] {
        let mut chunks = MeshChunk::split(&mesh, per);
        let count = chunks.len();
        for (k, chunk) in chunks.iter_mut().enumerate() {
            // Ids that no later triangle uses, some not alive at all, repeated and unsorted.
            let end = chunk.end_vertex();
            if end > 0 {
                chunk.open.push(rng.below(end as usize) as u32);
            }
            chunk.open.push(end + 5);
            chunk.open.reverse();
            if let Some(&o) = chunk.open.first() {
                chunk.open.push(o);
            }
            chunk.borrowed.reverse();
            if k + 1 == count {
                chunk.open.push(0);
            }
        }
        let streamed = stream(&chunks);
        // Held longer, the vertices still finish with complete fans.
        assert_same(&streamed, &whole, &format!("{per}"));
    }
}

#[test]
fn ids_used_after_they_finished_keep_the_geometry_exact() {
    let mesh = torus(20, 10, 3.0, 1.0);
    let whole = check(&mesh);
    let mut chunks = MeshChunk::split(&mesh, 13);
    // Forget the open lists: every vertex finishes early and is borrowed again later.
    for chunk in &mut chunks {
        chunk.open.clear();
    }
    let c = stream(&chunks);
    assert_eq!(
        (c.triangles, c.invalid_triangles, c.degenerate_triangles),
        (whole.triangles, 0, 0)
    );
    assert_eq!(c.volume.to_bits(), whole.volume.to_bits());
    assert_eq!(c.area.to_bits(), whole.area.to_bits());
    assert_eq!((c.bbox_min, c.bbox_max), (whole.bbox_min, whole.bbox_max));
    // Each reuse is a separate partial fan: the surface looks cut open along the chunks.
    assert!(c.boundary_edges > 0 && !c.watertight);
}

#[test]
fn missing_borrowed_positions_and_later_ids_make_triangles_invalid() {
    let mesh = torus(12, 6, 3.0, 1.0);
    let mut chunks = MeshChunk::split(&mesh, 10);
    let k = chunks
        .iter()
        .position(|c| !c.borrowed.is_empty())
        .expect("a chunk that borrows");
    let (missing, _) = chunks[k].borrowed.remove(0);
    let using = chunks[k]
        .triangles
        .iter()
        .filter(|t| t.contains(&missing))
        .count();
    // A triangle of the first chunk naming an id of the second.
    let later = chunks[1].first_vertex;
    chunks[0].triangles.push([0, 1, later]);
    let c = stream(&chunks);
    assert_eq!(c.invalid_triangles, using + 1);
    assert_eq!(c.triangles, mesh.triangles.len() + 1);
    assert!(!c.watertight && !c.manifold);
}

#[test]
fn garbage_chunks_never_panic() {
    let mut rng = Rng(99);
    for round in 0..300 {
        let mut checker = StreamCheck::new();
        let mut triangles = 0;
        let mut vertices = 0;
        let mut next = 0u32;
        for _ in 0..1 + rng.below(6) {
            let first = match rng.below(6) {
                0 => rng.next() as u32,
                1 => u32::MAX - rng.below(3) as u32,
                2 => next.saturating_sub(rng.below(5) as u32),
                _ => next,
            };
            let len = rng.below(12);
            let span = (u64::from(first) + len as u64 + 4).min(u64::from(u32::MAX)) as usize;
            let pick = |rng: &mut Rng| match rng.below(8) {
                0 => rng.next() as u32,
                1 => u32::MAX,
                _ => rng.below(span) as u32,
            };
            let chunk = MeshChunk {
                first_vertex: first,
                vertices: (0..len)
                    .map(|_| [0; 3].map(|_: i32| rng.below(3) as f32))
                    .collect(),
                triangles: (0..rng.below(20))
                    .map(|_| [0; 3].map(|_: i32| pick(&mut rng)))
                    .collect(),
                borrowed: (0..rng.below(6))
                    .map(|_| (pick(&mut rng), [rng.below(2) as f32; 3]))
                    .collect(),
                open: (0..rng.below(8)).map(|_| pick(&mut rng)).collect(),
            };
            triangles += chunk.triangles.len();
            vertices += chunk.vertices.len();
            next = first.saturating_add(len as u32);
            checker.push(&chunk);
        }
        let c = checker.finish();
        assert_eq!(c.triangles, triangles, "round {round}");
        assert!(c.invalid_triangles <= triangles);
        assert!(c.unreferenced_vertices <= vertices);
        assert!(c.degenerate_triangles + c.invalid_triangles <= triangles);
    }
}
