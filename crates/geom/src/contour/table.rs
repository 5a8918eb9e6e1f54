//! Marching-cubes case tables, derived at first use from one face rule instead of typed in.
//!
//! ```text
//!        6 ────────── 7          corner c = dx | dy << 1 | dz << 2
//!       ╱│           ╱│          edge slots 0..12:
//!      4 ────────── 5 │            x-edges 0..4   (index y + 2z)
//!      │ │          │ │            y-edges 4..8   (index x + 2z)
//!      │ 2 ─────────│─ 3           z-edges 8..12  (index x + 2y)
//!      │╱           │╱           corner slots 12..20 (12 + c), used by caps only
//!      0 ────────── 1   → x
//! ```
//!
//! The face rule: on each square face, the segments separate inside corners from outside
//! ones; on an ambiguous face (two inside corners on a diagonal) each inside corner is cut
//! off on its own. Because the rule looks only at the face's four corners, the two cubes
//! sharing a face always draw the same segments there: no cracks, and every mesh edge on a
//! face is used by exactly one triangle from each side. Segments are directed so the inside
//! of the face lies on their right seen from outside the cube; the loops they form are
//! triangulated in that order, which makes triangle normals point from inside to outside.
//!
//! Loops are triangulated without any diagonal joining two vertices on a common cube face:
//! the neighbouring cube might draw the same diagonal, and that edge would then belong to four
//! triangles. Among the allowed triangulations the shortest (by total diagonal length on edge
//! midpoints) is taken, which avoids slivers.
//!
//! Caps: for a cube face on the domain boundary, `caps` holds the inside part of the face
//! (inside corners and crossing points, with the same face rule), counter-clockwise seen from
//! outside, so the caps close the solid exactly along the surface's boundary.
//!
//! Bands (shells, `lo < f < hi`): each corner is below, between or above, given as two
//! configurations `p` (corners above `lo`) and `q ⊆ p` (corners at or above `hi`). The band's
//! surface is that of `p` on the lower level's crossings (slots `0..12`, normals towards the
//! corners below) plus that of `q`, reversed, on the upper level's crossings (slots
//! `HI_SLOT + e`, normals towards the corners above): no new surface table is needed, because
//! the two levels never meet inside a cube, so every loop belongs to one level. Both levels
//! use the same face rule in terms of `f` (on an ambiguous face the corners with the larger
//! `f` are cut off one by one), which keeps their segments on a face nested instead of
//! crossing. The band's cap on a face is the face's between part: its boundary runs along the
//! face's sides (between corners and crossings) and along the two levels' segments; all its
//! vertices lie on the square's perimeter in order, so each of its loops is a convex polygon
//! and a fan triangulates it.

use std::sync::OnceLock;

/// The two corners of each edge slot, lower corner first.
pub const EDGE_CORNERS: [[u8; 2]; 12] = {
    let mut table = [[0u8; 2]; 12];
    let mut e = 0;
    while e < 12 {
        let axis = e / 4;
        let r = (e % 4) as u8;
        // The two fixed bits of the edge, in axis order, spread around the varying axis.
        let (lo, hi) = (r & 1, r >> 1);
        let base = match axis {
            0 => (lo << 1) | (hi << 2),
            1 => lo | (hi << 2),
            _ => lo | (hi << 1),
        };
        table[e] = [base, base | (1 << axis)];
        e += 1;
    }
    table
};

/// First slot index of the corner slots.
pub const CORNER_SLOT: u8 = 12;

/// First slot index of the upper level's edge slots in a band: slot `HI_SLOT + e` is the
/// crossing of the upper level on edge `e` (slot `e` being the lower level's).
pub const HI_SLOT: u8 = 20;

/// The tables: per configuration, the surface triangles; per configuration and face, the cap.
pub struct Tables {
    tri_start: Vec<u32>,
    tri_slots: Vec<[u8; 3]>,
    cap_start: Vec<u32>,
    cap_slots: Vec<[u8; 3]>,
    /// Per face, its corners counter-clockwise seen from outside (the band caps' index order).
    face_corners: [[u8; 4]; 6],
    /// Band caps per face and per (`p`, `q`) restricted to the face's corners, 256 per face.
    band_cap_start: Vec<u32>,
    band_cap_slots: Vec<[u8; 3]>,
}

impl Tables {
    /// Surface triangles of configuration `config` (bit c set when corner c is inside).
    #[inline]
    pub fn triangles(&self, config: u8) -> &[[u8; 3]] {
        let c = config as usize;
        &self.tri_slots[self.tri_start[c] as usize..self.tri_start[c + 1] as usize]
    }

    /// Cap triangles on face `face` (= 2 · axis + side) of configuration `config`.
    #[inline]
    pub fn cap(&self, config: u8, face: usize) -> &[[u8; 3]] {
        let c = config as usize * 6 + face;
        &self.cap_slots[self.cap_start[c] as usize..self.cap_start[c + 1] as usize]
    }

    /// Cap triangles of a band on face `face`, for the corners above the lower level `p` and
    /// those at or above the upper level `q` (`q ⊆ p`), counter-clockwise seen from outside.
    #[inline]
    pub fn band_cap(&self, p: u8, q: u8, face: usize) -> &[[u8; 3]] {
        let c = face * 256 + face_index(&self.face_corners[face], p, q);
        &self.band_cap_slots[self.band_cap_start[c] as usize..self.band_cap_start[c + 1] as usize]
    }
}

/// The 8-bit index of a face's corner states: bit `k` from `p`, bit `4 + k` from `q`, for the
/// face's `k`-th corner.
#[inline]
fn face_index(corners: &[u8; 4], p: u8, q: u8) -> usize {
    corners.iter().enumerate().fold(0, |index, (k, &c)| {
        index | usize::from((p >> c) & 1) << k | usize::from((q >> c) & 1) << (k + 4)
    })
}

/// The tables, built once per process.
pub fn tables() -> &'static Tables {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    TABLES.get_or_init(build)
}

type P3 = [f64; 3];

fn corner_pos(c: u8) -> P3 {
    [
        f64::from(c & 1),
        f64::from((c >> 1) & 1),
        f64::from((c >> 2) & 1),
    ]
}

fn edge_mid(e: u8) -> P3 {
    let [a, b] = EDGE_CORNERS[e as usize];
    let (pa, pb) = (corner_pos(a), corner_pos(b));
    [
        (pa[0] + pb[0]) / 2.0,
        (pa[1] + pb[1]) / 2.0,
        (pa[2] + pb[2]) / 2.0,
    ]
}

fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: P3, b: P3) -> P3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn edge_between(a: u8, b: u8) -> u8 {
    let (lo, hi) = (a.min(b), a.max(b));
    EDGE_CORNERS
        .iter()
        .position(|&[x, y]| x == lo && y == hi)
        .expect("corners share an edge") as u8
}

/// A face: its outward normal, its corners counter-clockwise seen from outside, and the edge
/// from each corner to the next.
struct Face {
    normal: P3,
    corners: [u8; 4],
    edges: [u8; 4],
}

fn faces() -> Vec<Face> {
    (0..6)
        .map(|f| {
            let (axis, side) = (f / 2, (f % 2) as u8);
            let mut normal = [0.0; 3];
            normal[axis] = if side == 1 { 1.0 } else { -1.0 };
            // Walk the face's square in the plane of the two other axes, then flip the walk
            // if it turns clockwise about the outward normal.
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let at = |du: u8, dv: u8| (side << axis) | (du << u) | (dv << v);
            let mut corners = [at(0, 0), at(1, 0), at(1, 1), at(0, 1)];
            let turn = cross(
                sub(corner_pos(corners[1]), corner_pos(corners[0])),
                sub(corner_pos(corners[2]), corner_pos(corners[1])),
            );
            if dot(turn, normal) < 0.0 {
                corners.reverse();
            }
            let edges = std::array::from_fn(|k| edge_between(corners[k], corners[(k + 1) % 4]));
            Face {
                normal,
                corners,
                edges,
            }
        })
        .collect()
}

/// Directed segments `(from, to)` (edge slots) on one face of one configuration.
fn face_segments(face: &Face, config: u8) -> Vec<(u8, u8)> {
    let inside = |c: u8| config & (1 << c) != 0;
    let ins: [bool; 4] = std::array::from_fn(|k| inside(face.corners[k]));
    let crossing: Vec<usize> = (0..4).filter(|&k| ins[k] != ins[(k + 1) % 4]).collect();
    let orient = |a: u8, b: u8, right_of: &[(P3, bool)]| {
        let (pa, pb) = (edge_mid(a), edge_mid(b));
        let d = sub(pb, pa);
        let score: f64 = right_of
            .iter()
            .map(|&(c, is_in)| {
                let side = dot(cross(d, face.normal), sub(c, pa));
                if is_in { side } else { -side }
            })
            .sum();
        if score > 0.0 { (a, b) } else { (b, a) }
    };
    match crossing.len() {
        0 => Vec::new(),
        2 => {
            let corners: Vec<(P3, bool)> = (0..4)
                .map(|k| (corner_pos(face.corners[k]), ins[k]))
                .collect();
            vec![orient(
                face.edges[crossing[0]],
                face.edges[crossing[1]],
                &corners,
            )]
        }
        4 => (0..4)
            .filter(|&k| ins[k])
            .map(|k| {
                let before = face.edges[(k + 3) % 4];
                let after = face.edges[k];
                orient(before, after, &[(corner_pos(face.corners[k]), true)])
            })
            .collect(),
        n => unreachable!("a square has an even number of sign changes, got {n}"),
    }
}

/// The inside part of one face, as triangles of slots, counter-clockwise seen from outside.
fn face_cap(face: &Face, config: u8) -> Vec<[u8; 3]> {
    let inside = |c: u8| config & (1 << c) != 0;
    let ins: [bool; 4] = std::array::from_fn(|k| inside(face.corners[k]));
    let crossings = (0..4).filter(|&k| ins[k] != ins[(k + 1) % 4]).count();
    if crossings == 4 {
        // Ambiguous face: each inside corner is its own triangle, as the face rule says.
        return (0..4)
            .filter(|&k| ins[k])
            .map(|k| {
                [
                    CORNER_SLOT + face.corners[k],
                    face.edges[k],
                    face.edges[(k + 3) % 4],
                ]
            })
            .collect();
    }
    let mut polygon = Vec::new();
    for k in 0..4 {
        if ins[k] {
            polygon.push(CORNER_SLOT + face.corners[k]);
        }
        if ins[k] != ins[(k + 1) % 4] {
            polygon.push(face.edges[k]);
        }
    }
    // The inside part of a square cut by one line is convex: a fan triangulates it.
    (1..polygon.len().saturating_sub(1))
        .map(|i| [polygon[0], polygon[i], polygon[i + 1]])
        .collect()
}

/// Where a point of a face's perimeter is, walking it counter-clockwise, relative to a band.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Walk {
    /// A corner between the levels.
    Corner,
    /// A crossing where the walk enters the band.
    Enter,
    /// A crossing where the walk leaves it.
    Exit,
}

/// The between part of one face for a band (module docs), as triangles of slots,
/// counter-clockwise seen from outside. `p`/`q`: corners above the lower level / at or above
/// the upper one (`q ⊆ p`).
fn band_face_cap(face: &Face, p: u8, q: u8) -> Vec<[u8; 3]> {
    // 0 below, 1 between, 2 above.
    let state = |k: usize| {
        let c = face.corners[k];
        u8::from(p & (1 << c) != 0) + u8::from(q & (1 << c) != 0)
    };
    let mut walk: Vec<(u8, Walk)> = Vec::new();
    for k in 0..4 {
        let (from, to) = (state(k), state((k + 1) % 4));
        if from == 1 {
            walk.push((CORNER_SLOT + face.corners[k], Walk::Corner));
        }
        let (lo, hi) = (face.edges[k], HI_SLOT + face.edges[k]);
        match (from, to) {
            (0, 1) => walk.push((lo, Walk::Enter)),
            (1, 0) => walk.push((lo, Walk::Exit)),
            (2, 1) => walk.push((hi, Walk::Enter)),
            (1, 2) => walk.push((hi, Walk::Exit)),
            // Both levels on one side: the band is the stretch between the two crossings.
            (0, 2) => walk.extend([(lo, Walk::Enter), (hi, Walk::Exit)]),
            (2, 0) => walk.extend([(hi, Walk::Enter), (lo, Walk::Exit)]),
            _ => {}
        }
    }
    if walk.iter().all(|&(_, w)| w == Walk::Corner) {
        // No crossing: the whole face is in the band (four corners) or none of it.
        return if walk.len() == 4 {
            let s: Vec<u8> = walk.iter().map(|&(s, _)| s).collect();
            vec![[s[0], s[1], s[2]], [s[0], s[2], s[3]]]
        } else {
            Vec::new()
        };
    }
    // Each crossing's partner across the face: the other end of its level's segment.
    let mut partner = [u8::MAX; 32];
    for (a, b) in face_segments(face, p) {
        (partner[a as usize], partner[b as usize]) = (b, a);
    }
    for (a, b) in face_segments(face, q) {
        let (a, b) = (HI_SLOT + a, HI_SLOT + b);
        (partner[a as usize], partner[b as usize]) = (b, a);
    }
    let at = |slot: u8| {
        walk.iter()
            .position(|&(s, _)| s == slot)
            .expect("a segment ends on the perimeter walk")
    };
    let n = walk.len();
    let mut used = vec![false; n];
    let mut out = Vec::new();
    for start in 0..n {
        if walk[start].1 != Walk::Enter || used[start] {
            continue;
        }
        // Along the perimeter to the next exit, then across the face to the entry that
        // exit's segment leads to, until back at the start.
        let mut polygon = Vec::new();
        let mut i = start;
        loop {
            used[i] = true;
            polygon.push(walk[i].0);
            if walk[i].1 == Walk::Exit {
                i = at(partner[walk[i].0 as usize]);
                assert!(
                    walk[i].1 == Walk::Enter,
                    "a segment joins an exit to an entry"
                );
                if i == start {
                    break;
                }
            } else {
                i = (i + 1) % n;
            }
        }
        // Points of a convex perimeter in its order: a convex polygon (module docs).
        out.extend((1..polygon.len() - 1).map(|k| [polygon[0], polygon[k], polygon[k + 1]]));
    }
    out
}

/// Triangulates one loop of edge slots, avoiding diagonals between vertices on a common face.
fn triangulate_loop(lp: &[u8], edge_faces: &[[usize; 2]; 12]) -> Vec<[u8; 3]> {
    let n = lp.len();
    let share_face = |a: u8, b: u8| {
        let (fa, fb) = (edge_faces[a as usize], edge_faces[b as usize]);
        fa.iter().any(|f| fb.contains(f))
    };
    let weight = |i: usize, j: usize| -> f64 {
        if (i + 1) % n == j || (j + 1) % n == i {
            0.0 // a side of the loop
        } else if share_face(lp[i], lp[j]) {
            f64::INFINITY
        } else {
            let d = sub(edge_mid(lp[i]), edge_mid(lp[j]));
            dot(d, d).sqrt()
        }
    };
    // Classic O(n³) optimal polygon triangulation over the loop's vertex order.
    let mut cost = vec![vec![0.0f64; n]; n];
    let mut split = vec![vec![usize::MAX; n]; n];
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            let best = (i + 1..j)
                .map(|k| (cost[i][k] + cost[k][j] + weight(i, k) + weight(k, j), k))
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .expect("len >= 2 leaves a split vertex");
            cost[i][j] = best.0;
            split[i][j] = best.1;
        }
    }
    assert!(
        cost[0][n - 1].is_finite(),
        "no admissible triangulation for loop {lp:?}"
    );
    let mut out = Vec::new();
    let mut stack = vec![(0, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j - i < 2 {
            continue;
        }
        let k = split[i][j];
        out.push([lp[i], lp[k], lp[j]]);
        stack.push((i, k));
        stack.push((k, j));
    }
    out
}

fn build() -> Tables {
    let faces = faces();
    let mut edge_faces = [[usize::MAX; 2]; 12];
    for (f, face) in faces.iter().enumerate() {
        for &e in &face.edges {
            let slot = &mut edge_faces[e as usize];
            if slot[0] == usize::MAX {
                slot[0] = f
            } else {
                slot[1] = f
            }
        }
    }
    let mut tables = Tables {
        tri_start: vec![0],
        tri_slots: Vec::new(),
        cap_start: vec![0],
        cap_slots: Vec::new(),
        face_corners: std::array::from_fn(|f| faces[f].corners),
        band_cap_start: vec![0],
        band_cap_slots: Vec::new(),
    };
    for config in 0..=255u8 {
        let mut next = [u8::MAX; 12];
        for face in &faces {
            for (a, b) in face_segments(face, config) {
                assert_eq!(next[a as usize], u8::MAX, "edge {a} starts two segments");
                next[a as usize] = b;
            }
        }
        let mut visited = [false; 12];
        for start in 0..12u8 {
            if next[start as usize] == u8::MAX || visited[start as usize] {
                continue;
            }
            let mut lp = Vec::new();
            let mut e = start;
            while !visited[e as usize] {
                visited[e as usize] = true;
                lp.push(e);
                e = next[e as usize];
            }
            assert_eq!(e, start, "segments of configuration {config} do not close");
            tables.tri_slots.extend(triangulate_loop(&lp, &edge_faces));
        }
        tables.tri_start.push(tables.tri_slots.len() as u32);
        for face in &faces {
            tables.cap_slots.extend(face_cap(face, config));
            tables.cap_start.push(tables.cap_slots.len() as u32);
        }
    }
    for face in &faces {
        for index in 0..256usize {
            let (p4, q4) = (index & 15, index >> 4);
            // Only q ⊆ p is a band configuration; other indices stay empty.
            if q4 & !p4 == 0 {
                let spread = |bits: usize| {
                    (0..4)
                        .filter(|&k| bits & (1 << k) != 0)
                        .fold(0u8, |c, k| c | 1 << face.corners[k])
                };
                tables
                    .band_cap_slots
                    .extend(band_face_cap(face, spread(p4), spread(q4)));
            }
            tables
                .band_cap_start
                .push(tables.band_cap_slots.len() as u32);
        }
    }
    tables
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    #[test]
    fn edge_corners_differ_in_exactly_their_axis() {
        for (e, [a, b]) in EDGE_CORNERS.iter().enumerate() {
            assert_eq!(a ^ b, 1 << (e / 4), "edge {e}");
            assert!(a < b);
        }
    }

    #[test]
    fn trivial_configurations_have_no_surface() {
        assert!(tables().triangles(0).is_empty());
        assert!(tables().triangles(255).is_empty());
        // One inside corner: a single triangle across its three edges.
        assert_eq!(tables().triangles(1).len(), 1);
    }

    /// The surface of each configuration plus the caps on all six faces is a closed, consistently
    /// oriented surface around the inside corners: every directed edge has its reverse.
    #[test]
    fn surface_plus_all_caps_is_closed_for_every_configuration() {
        let t = tables();
        for config in 1..=255u8 {
            let mut directed: HashMap<(u8, u8), i32> = HashMap::new();
            let tris = t
                .triangles(config)
                .iter()
                .chain((0..6).flat_map(|f| t.cap(config, f)));
            for tri in tris {
                for k in 0..3 {
                    *directed.entry((tri[k], tri[(k + 1) % 3])).or_default() += 1;
                }
            }
            for (&(a, b), &count) in &directed {
                assert_eq!(
                    count, 1,
                    "config {config}: edge {a}->{b} used {count} times"
                );
                assert_eq!(
                    directed.get(&(b, a)),
                    Some(&1),
                    "config {config}: {a}->{b} has no twin"
                );
            }
        }
    }

    /// Normals point away from inside corners: the closed polyhedron of surface and caps, with
    /// vertices at edge midpoints and corners, has positive volume.
    #[test]
    fn orientation_encloses_positive_volume() {
        let t = tables();
        let pos = |s: u8| {
            if s >= CORNER_SLOT {
                corner_pos(s - CORNER_SLOT)
            } else {
                edge_mid(s)
            }
        };
        for config in 1..=255u8 {
            let volume: f64 = t
                .triangles(config)
                .iter()
                .chain((0..6).flat_map(|f| t.cap(config, f)))
                .map(|tri| dot(pos(tri[0]), cross(pos(tri[1]), pos(tri[2]))) / 6.0)
                .sum();
            assert!(volume > 0.0, "config {config}: volume {volume}");
        }
        // A single inside corner encloses the corner tetrahedron of legs 1/2.
        let v1: f64 = t
            .triangles(1)
            .iter()
            .chain((0..6).flat_map(|f| t.cap(1, f)))
            .map(|tri| dot(pos(tri[0]), cross(pos(tri[1]), pos(tri[2]))) / 6.0)
            .sum();
        assert!((v1 - 1.0 / 48.0).abs() < 1e-15);
    }

    /// Every band configuration (`q ⊆ p`): the lower level's surface, the upper level's
    /// reversed and the band caps on all six faces form a closed, consistently oriented surface
    /// with positive volume, the crossings placed a third of the way from the outer corner.
    #[test]
    fn band_surfaces_plus_caps_are_closed_and_enclose_positive_volume() {
        let t = tables();
        let mut checked = 0;
        for p in 0..=255u8 {
            for q in (0..=255u8).filter(|&q| q & !p == 0) {
                let state = |c: u8| u8::from(p & (1 << c) != 0) + u8::from(q & (1 << c) != 0);
                let pos = |s: u8| -> P3 {
                    if (CORNER_SLOT..HI_SLOT).contains(&s) {
                        return corner_pos(s - CORNER_SLOT);
                    }
                    let (e, upper) = if s >= HI_SLOT {
                        (s - HI_SLOT, true)
                    } else {
                        (s, false)
                    };
                    let [a, b] = EDGE_CORNERS[e as usize];
                    // From the corner beyond this level, a third of the way along.
                    let outer_is_a = if upper { state(a) == 2 } else { state(a) == 0 };
                    let (from, to) = if outer_is_a { (a, b) } else { (b, a) };
                    let (pf, pt) = (corner_pos(from), corner_pos(to));
                    std::array::from_fn(|k| pf[k] + (pt[k] - pf[k]) / 3.0)
                };
                let tris: Vec<[u8; 3]> = t
                    .triangles(p)
                    .iter()
                    .copied()
                    .chain(
                        t.triangles(q)
                            .iter()
                            .map(|s| [HI_SLOT + s[0], HI_SLOT + s[2], HI_SLOT + s[1]]),
                    )
                    .chain((0..6).flat_map(|f| t.band_cap(p, q, f).iter().copied()))
                    .collect();
                let mut directed: HashMap<(u8, u8), i32> = HashMap::new();
                for tri in &tris {
                    for k in 0..3 {
                        *directed.entry((tri[k], tri[(k + 1) % 3])).or_default() += 1;
                    }
                }
                for (&(a, b), &count) in &directed {
                    assert_eq!(count, 1, "p {p} q {q}: edge {a}->{b} used {count} times");
                    assert_eq!(
                        directed.get(&(b, a)),
                        Some(&1),
                        "p {p} q {q}: {a}->{b} open"
                    );
                }
                let volume: f64 = tris
                    .iter()
                    .map(|tri| dot(pos(tri[0]), cross(pos(tri[1]), pos(tri[2]))) / 6.0)
                    .sum();
                let empty = (p == 0) || (q == 255);
                if empty {
                    assert!(tris.is_empty(), "p {p} q {q}: nothing between the levels");
                } else {
                    assert!(volume > 0.0, "p {p} q {q}: volume {volume}");
                    checked += 1;
                }
                if p == 255 && q == 0 {
                    assert!((volume - 1.0).abs() < 1e-15, "the whole cube: {volume}");
                }
            }
        }
        assert_eq!(checked, 6561 - 2);
    }

    #[test]
    fn complementary_configurations_have_opposite_surfaces_except_on_ambiguous_faces() {
        // With no ambiguous face, the surface of the complement is the same set of vertices.
        let t = tables();
        let verts = |c: u8| {
            let mut v: Vec<u8> = t.triangles(c).iter().flatten().copied().collect();
            v.sort_unstable();
            v.dedup();
            v
        };
        for config in 1..=254u8 {
            assert_eq!(verts(config), verts(!config), "config {config}");
        }
    }
}
