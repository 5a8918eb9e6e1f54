//! Properties of `validate::check` on meshes whose answers are known by construction or by
//! hand, plus a brute-force reference implementation for randomly damaged meshes.

use crate::common;

use common::torus;
use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::validate::{MeshCheck, check};
use std::collections::{HashMap, HashSet};
use std::f64::consts::{PI, TAU};

// ---------------------------------------------------------------------------------------------
// Meshes

/// The unit cube [0, 1]³, 12 triangles wound counter-clockwise seen from outside.
/// Vertex `i` sits at `(i & 1, (i >> 1) & 1, (i >> 2) & 1)`.
fn unit_cube() -> Mesh {
    let vertices = (0..8)
        .map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32])
        .collect();
    let quads = [
        [0, 2, 3, 1], // z = 0
        [4, 5, 7, 6], // z = 1
        [0, 1, 5, 4], // y = 0
        [2, 6, 7, 3], // y = 1
        [0, 4, 6, 2], // x = 0
        [1, 3, 7, 5], // x = 1
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

/// Appends `other` to `mesh`, renumbering its indices.
fn append(mesh: &mut Mesh, other: &Mesh) {
    let base = mesh.vertices.len() as u32;
    mesh.vertices.extend_from_slice(&other.vertices);
    mesh.triangles
        .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
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

/// A flat `n × m` grid of unit squares in z = 0, two triangles per square, normal +z.
fn grid(n: u32, m: u32) -> Mesh {
    let vertices = (0..=m)
        .flat_map(|j| (0..=n).map(move |i| [i as f32, j as f32, 0.0]))
        .collect();
    let id = |i: u32, j: u32| j * (n + 1) + i;
    let triangles = (0..m)
        .flat_map(|j| {
            (0..n).flat_map(move |i| {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                [[a, b, c], [a, c, d]]
            })
        })
        .collect();
    Mesh {
        vertices,
        triangles,
    }
}

/// The tetrahedron (0,0,0), (s,0,0), (0,s,0), (0,0,s), outward winding; volume s³/6 · sign.
fn corner_tetrahedron(s: f32) -> Mesh {
    let vertices = vec![[0.0, 0.0, 0.0], [s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s]];
    let mut triangles = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    if s < 0.0 {
        // A point reflection reverses orientation; reversing the winding restores "outward".
        for t in &mut triangles {
            t.swap(1, 2);
        }
    }
    Mesh {
        vertices,
        triangles,
    }
}

fn clean(check: &MeshCheck) -> bool {
    check.boundary_edges == 0
        && check.nonmanifold_edges == 0
        && check.misoriented_edges == 0
        && check.nonmanifold_vertices == 0
        && check.degenerate_triangles == 0
        && check.duplicate_positions == 0
        && check.invalid_triangles == 0
}

// ---------------------------------------------------------------------------------------------
// Closed meshes

#[test]
fn unit_cube_is_a_watertight_manifold_sphere_of_volume_one() {
    let c = check(&unit_cube());
    assert!(c.watertight && c.manifold && clean(&c), "{c:?}");
    assert_eq!((c.triangles, c.vertices, c.edges), (12, 8, 18));
    assert_eq!(c.euler_characteristic, 2);
    assert_eq!(c.volume, 1.0);
    assert_eq!(c.area, 6.0);
    assert_eq!((c.bbox_min, c.bbox_max), ([0.0; 3], [1.0; 3]));
    assert_eq!(c.unreferenced_vertices, 0);
}

#[test]
fn inverted_cube_has_volume_minus_one_and_is_still_consistent() {
    let mut mesh = unit_cube();
    for t in &mut mesh.triangles {
        t.swap(1, 2);
    }
    let c = check(&mesh);
    assert_eq!(c.volume, -1.0);
    assert_eq!(c.area, 6.0);
    assert!(c.watertight && c.manifold && clean(&c), "{c:?}");
}

#[test]
fn closed_volume_does_not_depend_on_position() {
    let cube = unit_cube();
    for offset in [
        [10.0, -20.0, 30.0],
        [1000.0, 1000.0, -1000.0],
        [-0.5, -0.5, -0.5],
    ] {
        let c = check(&translated(&cube, offset));
        assert_eq!(c.volume, 1.0, "offset {offset:?}");
        assert_eq!(c.area, 6.0);
        assert_eq!(c.bbox_min, offset.map(f64::from));
    }
}

/// Exact volume and area of the polyhedral torus of `torus(n, m, R, r)` (before `f32`
/// rounding). Between two meridian planes the solid sweeps the inscribed m-gon (area
/// `A = m/2 r² sin(2π/m)`, centroid at distance R from the axis) along horizontal chords, whose
/// Jacobian is `ρ sin Δθ`; so the volume is `n sin(2π/n) · R · A` (Pappus with `sin Δθ` for
/// `Δθ`). Each quad is a planar isosceles trapezoid with parallel sides `2ρ sin(Δθ/2)` at
/// heights `r sin φ`, a distance `√((Δρ cos(Δθ/2))² + Δz²)` apart.
fn polyhedral_torus(n: u32, m: u32, big_r: f64, r: f64) -> (f64, f64) {
    let (dt, dp) = (TAU / f64::from(n), TAU / f64::from(m));
    let volume = f64::from(n) * dt.sin() * big_r * f64::from(m) / 2.0 * r * r * dp.sin();
    let mut area = 0.0;
    for j in 0..m {
        let (p0, p1) = (dp * f64::from(j), dp * f64::from(j + 1));
        let (rho0, rho1) = (big_r + r * p0.cos(), big_r + r * p1.cos());
        let (z0, z1) = (r * p0.sin(), r * p1.sin());
        let half = (dt / 2.0).sin();
        let height = (((rho1 - rho0) * (dt / 2.0).cos()).powi(2) + (z1 - z0).powi(2)).sqrt();
        area += f64::from(n) * (rho0 + rho1) * half * height;
    }
    (volume, area)
}

#[test]
fn torus_has_euler_characteristic_zero_and_the_polyhedral_volume() {
    let (n, m, big_r, r) = (192, 96, 3.0, 1.0);
    for offset in [[0.0; 3], [250.0, -125.0, 40.0]] {
        let c = check(&torus(n, m, big_r, r, offset));
        assert!(c.watertight && c.manifold && clean(&c), "{c:?}");
        assert_eq!(c.euler_characteristic, 0);
        assert_eq!((c.vertices, c.edges, c.triangles), (18432, 55296, 36864));

        let (volume, area) = polyhedral_torus(n, m, big_r, r);
        // Only f32 rounding of the vertices separates the mesh from the exact polyhedron; it
        // grows with the distance from the origin (observed: 5e-9 at 0, 2e-7 at 280).
        let distance = offset.iter().map(|x| x * x).sum::<f64>().sqrt();
        let rounding = 1e-7 * (1.0 + distance);
        assert!(
            (c.volume - volume).abs() <= rounding * volume,
            "{} vs {volume}",
            c.volume
        );
        assert!(
            (c.area - area).abs() <= rounding * area,
            "{} vs {area}",
            c.area
        );

        // Against the smooth torus: the polyhedron is inscribed, so it falls short by exactly
        // the factor sinc(2π/n) sinc(2π/m); the tessellation error is that shortfall.
        let smooth = 2.0 * PI * PI * big_r * r * r;
        let sinc = |k: u32| (TAU / f64::from(k)).sin() / (TAU / f64::from(k));
        let tessellation_error = smooth * (1.0 - sinc(n) * sinc(m));
        assert!(tessellation_error / smooth < 2e-3, "fine tessellation");
        let shortfall = smooth - c.volume;
        assert!(shortfall > 0.0);
        assert!(
            (shortfall - tessellation_error).abs() <= rounding * smooth,
            "{shortfall}"
        );
        let smooth_area = 4.0 * PI * PI * big_r * r;
        assert!(
            c.area < smooth_area
                && c.area > smooth_area * (1.0 - 2.0 * tessellation_error / smooth)
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Open and damaged meshes

#[test]
fn open_meshes_count_boundary_edges_exactly() {
    // Cube without its top face: a disk, boundary = the top square.
    let mut open_box = unit_cube();
    open_box.triangles.drain(2..4);
    let c = check(&open_box);
    assert_eq!(c.boundary_edges, 4);
    assert_eq!(c.euler_characteristic, 1);
    assert!(!c.watertight && c.manifold, "{c:?}");
    assert_eq!(
        c.volume,
        2.0 / 3.0,
        "the top face contributed (1/3)·area·height"
    );

    for (n, m) in [(1, 1), (5, 3), (40, 17)] {
        let c = check(&grid(n, m));
        assert_eq!(c.boundary_edges as u32, 2 * (n + m), "{n}×{m}");
        assert_eq!(c.edges as u32, n * (m + 1) + m * (n + 1) + n * m);
        assert_eq!(c.euler_characteristic, 1);
        assert_eq!(c.area, f64::from(n * m));
        assert_eq!(c.volume, 0.0);
        assert!(!c.watertight && c.manifold);
    }

    let single = Mesh {
        vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        triangles: vec![[0, 1, 2]],
    };
    let c = check(&single);
    assert_eq!(
        (c.boundary_edges, c.edges, c.euler_characteristic),
        (3, 3, 1)
    );
    assert_eq!(c.area, 0.5);
}

#[test]
fn one_flipped_triangle_makes_three_misoriented_edges() {
    // Triangle 2 is [4, 5, 7] on the top face z = 1: its tetrahedron with the origin has
    // volume det[(0,0,1), (1,0,1), (1,1,1)] / 6 = 1/6, so flipping it removes 2/6.
    let mut mesh = unit_cube();
    assert_eq!(mesh.triangles[2], [4, 5, 7]);
    mesh.triangles[2].swap(1, 2);
    let c = check(&mesh);
    assert_eq!(c.misoriented_edges, 3);
    assert_eq!((c.boundary_edges, c.nonmanifold_edges), (0, 0));
    assert!(!c.watertight && !c.manifold);
    assert_eq!(c.volume, 2.0 / 3.0);
    assert_eq!(c.area, 6.0);

    // On the bottom face z = 0 the tetrahedron with the origin is flat: the volume stays 1.
    let mut mesh = unit_cube();
    mesh.triangles[0].swap(1, 2);
    let c = check(&mesh);
    assert_eq!(c.misoriented_edges, 3);
    assert_eq!(c.volume, 1.0);
}

#[test]
fn two_cubes_sharing_an_edge_have_one_nonmanifold_edge() {
    // Second cube [1, 2] × [1, 2] × [0, 1]; its corners (1,1,0) and (1,1,1) are vertices 3 and
    // 7 of the first cube, so they are shared, not duplicated.
    let mut mesh = unit_cube();
    let second = translated(&unit_cube(), [1.0, 1.0, 0.0]);
    let mut map = [0u32; 8];
    for (i, p) in second.vertices.iter().enumerate() {
        map[i] = match mesh.vertices.iter().position(|q| q == p) {
            Some(shared) => shared as u32,
            None => {
                mesh.vertices.push(*p);
                (mesh.vertices.len() - 1) as u32
            }
        };
    }
    mesh.triangles
        .extend(second.triangles.iter().map(|t| t.map(|i| map[i as usize])));
    assert_eq!(mesh.vertices.len(), 14);

    let c = check(&mesh);
    assert_eq!(c.nonmanifold_edges, 1);
    assert_eq!(
        (c.boundary_edges, c.misoriented_edges, c.duplicate_positions),
        (0, 0, 0)
    );
    // The endpoints' fans stay connected through the shared edge itself.
    assert_eq!(c.nonmanifold_vertices, 0);
    assert!(!c.watertight && !c.manifold);
    assert_eq!(c.euler_characteristic, 14 - 35 + 24);
    assert_eq!(c.volume, 2.0);
}

#[test]
fn two_tetrahedra_touching_at_a_vertex_have_one_nonmanifold_vertex() {
    let mut mesh = corner_tetrahedron(1.0);
    let other = corner_tetrahedron(-1.0);
    // Share the apex (vertex 0 of both).
    let base = mesh.vertices.len() as u32 - 1;
    mesh.vertices.extend_from_slice(&other.vertices[1..]);
    mesh.triangles.extend(
        other
            .triangles
            .iter()
            .map(|t| t.map(|i| if i == 0 { 0 } else { i + base })),
    );

    let c = check(&mesh);
    assert_eq!(c.nonmanifold_vertices, 1);
    assert_eq!(
        (c.boundary_edges, c.nonmanifold_edges, c.misoriented_edges),
        (0, 0, 0)
    );
    assert!(
        c.watertight,
        "every edge is fine, so the edge-based verdict holds"
    );
    assert!(!c.manifold);
    assert_eq!(c.euler_characteristic, 7 - 12 + 8);
    assert_eq!(c.volume, 2.0 / 6.0);
}

#[test]
fn duplicate_positions_are_counted_among_referenced_vertices() {
    // A separate triangle with one corner on the cube's corner (1, 1, 1) = vertex 7.
    let mut mesh = unit_cube();
    append(
        &mut mesh,
        &Mesh {
            vertices: vec![[1.0, 1.0, 1.0], [2.0, 1.0, 1.0], [2.0, 2.0, 1.0]],
            triangles: vec![[0, 1, 2]],
        },
    );
    let c = check(&mesh);
    assert_eq!(c.duplicate_positions, 1);
    assert_eq!((c.boundary_edges, c.nonmanifold_vertices), (3, 0));
    assert!(!c.manifold && !c.watertight);

    // Three more copies: a position shared by k vertices counts k - 1.
    for _ in 0..3 {
        mesh.vertices.push([1.0, 1.0, 1.0]);
        let v = mesh.vertices.len() as u32 - 1;
        mesh.triangles.push([v, 9, 10]);
    }
    assert_eq!(check(&mesh).duplicate_positions, 4);

    // An unreferenced copy is not a duplicate (it is never written to an STL).
    let mut mesh = unit_cube();
    mesh.vertices.push([1.0, 1.0, 1.0]);
    let c = check(&mesh);
    assert_eq!(
        (c.duplicate_positions, c.unreferenced_vertices, c.vertices),
        (0, 1, 8)
    );
    assert!(c.watertight && c.manifold);

    // Bit-identical means bit-identical: 0.0 and -0.0 differ.
    let mut mesh = unit_cube();
    append(
        &mut mesh,
        &Mesh {
            vertices: vec![[-0.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, -1.0, -1.0]],
            triangles: vec![[0, 1, 2]],
        },
    );
    assert_eq!(check(&mesh).duplicate_positions, 0);
}

#[test]
fn degenerate_triangles_are_counted() {
    // Collinear corners, distinct indices: zero area.
    let mut mesh = unit_cube();
    append(
        &mut mesh,
        &Mesh {
            vertices: vec![[2.0, 0.0, 0.0], [3.0, 0.5, 0.0], [5.0, 1.5, 0.0]],
            triangles: vec![[0, 1, 2]],
        },
    );
    let c = check(&mesh);
    assert_eq!(c.degenerate_triangles, 1);
    assert_eq!(c.boundary_edges, 3);
    assert!(!c.manifold);
    assert_eq!(c.area, 6.0);

    // A repeated index on a cube edge: {0, 1} gains one use in each direction.
    let mut mesh = unit_cube();
    mesh.triangles.push([0, 0, 1]);
    let c = check(&mesh);
    assert_eq!(c.degenerate_triangles, 1);
    assert_eq!(c.nonmanifold_edges, 1);
    assert!(!c.manifold && !c.watertight);
    assert_eq!(c.volume, 1.0);

    // A triangle with all three indices equal has no edges; it makes its vertex's fan two pieces.
    let mut mesh = unit_cube();
    mesh.triangles.push([5, 5, 5]);
    let c = check(&mesh);
    assert_eq!(c.degenerate_triangles, 1);
    assert_eq!((c.edges, c.nonmanifold_vertices), (18, 1));
}

#[test]
fn empty_and_invalid_meshes_do_not_panic() {
    let c = check(&Mesh::default());
    assert_eq!(
        (c.triangles, c.vertices, c.edges, c.euler_characteristic),
        (0, 0, 0, 0)
    );
    assert_eq!(
        (c.volume, c.area, c.bbox_min, c.bbox_max),
        (0.0, 0.0, [0.0; 3], [0.0; 3])
    );
    assert!(!c.watertight && c.manifold);

    let vertices_only = Mesh {
        vertices: vec![[1.0; 3]; 4],
        triangles: vec![],
    };
    let c = check(&vertices_only);
    assert_eq!(
        (c.vertices, c.unreferenced_vertices, c.bbox_max),
        (0, 4, [0.0; 3])
    );

    let mut mesh = unit_cube();
    mesh.triangles.push([0, 1, 99]);
    let c = check(&mesh);
    assert_eq!(
        (c.invalid_triangles, c.triangles, c.euler_characteristic),
        (1, 13, 2)
    );
    assert_eq!(c.volume, 1.0);
    assert!(!c.watertight && !c.manifold);

    let mut mesh = unit_cube();
    mesh.vertices[6] = [f32::NAN, 0.0, 0.0];
    let c = check(&mesh);
    assert!(c.degenerate_triangles > 0 && !c.manifold);
    assert!(c.volume.is_nan());
}

// ---------------------------------------------------------------------------------------------
// Against a brute-force reference

/// Straightforward reference: global edge map, per-vertex BFS over incident triangles.
fn reference(mesh: &Mesh) -> (usize, usize, usize, usize, usize, usize, i64) {
    let mut uses: HashMap<(u32, u32), (usize, usize)> = HashMap::new();
    let mut incident: HashMap<u32, Vec<usize>> = HashMap::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            incident.entry(a).or_default().push(t);
            if a == b {
                continue;
            }
            let entry = uses.entry((a.min(b), a.max(b))).or_default();
            if a < b { entry.0 += 1 } else { entry.1 += 1 }
        }
    }
    let boundary = uses.values().filter(|(f, b)| f + b == 1).count();
    let nonmanifold = uses.values().filter(|(f, b)| f + b > 2).count();
    let misoriented = uses
        .values()
        .filter(|&&(f, b)| f + b == 2 && f != 1)
        .count();
    let mut bad_vertices = 0;
    for (&v, triangles) in &incident {
        let triangles: Vec<usize> = triangles
            .iter()
            .copied()
            .collect::<HashSet<_>>()
            .into_iter()
            .collect();
        let others = |t: usize| -> HashSet<u32> {
            mesh.triangles[t]
                .iter()
                .copied()
                .filter(|&w| w != v)
                .collect()
        };
        let mut seen = vec![false; triangles.len()];
        let mut stack = vec![0];
        seen[0] = true;
        while let Some(k) = stack.pop() {
            let mine = others(triangles[k]);
            for j in 0..triangles.len() {
                if !seen[j] && !mine.is_disjoint(&others(triangles[j])) {
                    seen[j] = true;
                    stack.push(j);
                }
            }
        }
        if seen.iter().any(|s| !s) {
            bad_vertices += 1;
        }
    }
    let mut positions: HashMap<[u32; 3], usize> = HashMap::new();
    for &v in incident.keys() {
        *positions
            .entry(mesh.vertices[v as usize].map(f32::to_bits))
            .or_default() += 1;
    }
    let duplicates = positions.values().map(|k| k - 1).sum();
    let euler = incident.len() as i64 - uses.len() as i64 + mesh.triangles.len() as i64;
    (
        boundary,
        nonmanifold,
        misoriented,
        bad_vertices,
        duplicates,
        uses.len(),
        euler,
    )
}

/// A small deterministic generator (64-bit LCG, high bits).
struct Lcg(u64);
impl Lcg {
    fn below(&mut self, n: usize) -> usize {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 33) as usize) % n
    }
}

#[test]
fn damaged_meshes_agree_with_a_brute_force_reference() {
    let mut rng = Lcg(7);
    for round in 0..40 {
        let mut mesh = torus(12, 8, 3.0, 1.0, [0.0; 3]);
        append(&mut mesh, &translated(&unit_cube(), [5.0, 0.0, 0.0]));
        let v = mesh.vertices.len();
        for _ in 0..1 + rng.below(6) {
            let t = rng.below(mesh.triangles.len());
            match rng.below(6) {
                0 => {
                    mesh.triangles.swap_remove(t);
                }
                1 => mesh.triangles[t].swap(0, 2),
                2 => {
                    let copy = mesh.triangles[t];
                    mesh.triangles.push(copy);
                }
                3 => {
                    // Pinch two vertices together: glues fans, may create non-manifold edges.
                    let (a, b) = (rng.below(v) as u32, rng.below(v) as u32);
                    for tri in &mut mesh.triangles {
                        for i in tri.iter_mut() {
                            if *i == b {
                                *i = a;
                            }
                        }
                    }
                }
                4 => {
                    let p = mesh.vertices[rng.below(v)];
                    mesh.vertices.push(p);
                    let new = mesh.vertices.len() as u32 - 1;
                    mesh.triangles[t][rng.below(3)] = new;
                }
                _ => {
                    let extra = [
                        rng.below(v) as u32,
                        rng.below(v) as u32,
                        rng.below(v) as u32,
                    ];
                    mesh.triangles.push(extra);
                }
            }
        }
        let c = check(&mesh);
        let (boundary, nonmanifold, misoriented, bad_vertices, duplicates, edges, euler) =
            reference(&mesh);
        let found = (
            c.boundary_edges,
            c.nonmanifold_edges,
            c.misoriented_edges,
            c.nonmanifold_vertices,
            c.duplicate_positions,
            c.edges,
            c.euler_characteristic,
        );
        assert_eq!(
            found,
            (
                boundary,
                nonmanifold,
                misoriented,
                bad_vertices,
                duplicates,
                edges,
                euler
            ),
            "round {round}"
        );
        assert_eq!(
            c.watertight,
            boundary + nonmanifold + misoriented == 0,
            "round {round}"
        );
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let mut mesh = torus(300, 200, 30.0, 7.0, [3.0, -4.0, 5.0]);
    mesh.triangles.truncate(mesh.triangles.len() - 1000);
    mesh.triangles[40_017].swap(0, 1);
    let single = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let triple = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .expect("pool");
    let one = single.install(|| check(&mesh));
    let three = triple.install(|| check(&mesh));
    assert_eq!(one, three);
    assert_eq!(one, check(&mesh));
    assert_eq!(one.misoriented_edges, 3);
}
