//! Contouring over a simplex reference element (the tetrahedron, the triangle) on a subdivision
//! of the element that its symmetry group maps onto itself.
//!
//! Why: a grid laid from one vertex of the element (the element's skew lattice, clipped by a
//! linear function at the far face) treats one face differently from the others. The far face's
//! crossings then come from a clip combined with the field, which leaves a sawtooth where the
//! field's surface meets it, and the samples miss the corners that are not grid nodes (a
//! triangle cell kept a one-triangle piece at the vertex that was a node, and not at the other
//! two). Here every face is alike.
//!
//! The subdivision, with `M` cells along each edge:
//! - **Triangle**: the nodes `q0 + (i e1 + j e2)/M`, `i + j ≤ M` (the triangle's vertices among
//!   them), and its `M²` small triangles, `M(M+1)/2` pointing up and `M(M−1)/2` down.
//! - **Tetrahedron**: the nodes `p0 + (i e1 + j e2 + k e3)/M`, `i + j + k ≤ M`, and the standard
//!   split into small tetrahedra (upright and inverted) and octahedra. Each octahedron is split
//!   into the 8 tetrahedra joining its centre to its faces, one more sample per octahedron; the
//!   usual choice of a diagonal would pick one of three directions and break the symmetry.
//!
//! The point set and the cells are invariant under the element's group, so for a field with that
//! symmetry the output is symmetric up to rounding. The element's boundary is made of cell faces
//! (edges), so the solid's faces on the element's boundary lie on its planes to rounding: their
//! vertices are boundary nodes or crossings on boundary edges.
//!
//! In each cell the solid is the part where the linear interpolant of the samples is negative
//! (marching tetrahedra / triangles): no ambiguous cases, and cells sharing a face agree on it,
//! so a 3D result is closed and manifold (the isosurface plus the caps on the element's faces)
//! and a planar region is edge-manifold. Crossings sit at the interpolant's zero, kept 1/256
//! of an edge from its ends as in the other contourers, so no two vertices coincide; a zero or
//! NaN sample counts as outside. Vertices are shared by every cell that uses them (keyed by
//! their node or edge); positions are kept in `f64` beside the mesh's `f32`. Triangles wind
//! counter-clockwise seen from outside (from +z in 2D). The tetrahedron is sampled one layer of
//! nodes at a time, so memory grows with the surface and `M²`, not `M³`.

use crate::contour::crossing_fraction;
use crate::field::ScalarField;
use crate::mesh::Mesh;
use std::collections::HashMap;

/// `√3`.
const SQRT3: f64 = 1.732_050_807_568_877_2;

/// A mesh with its vertices' `f64` positions (`mesh.vertices[i]` is `positions[i]` rounded).
pub(crate) struct Contoured<const D: usize> {
    pub(crate) mesh: Mesh,
    pub(crate) positions: Vec<[f64; D]>,
}

/// NaN compares false: outside.
#[inline]
fn inside(v: f64) -> bool {
    v < 0.0
}

/// A sample: its key (unique over the subdivision), position and value.
#[derive(Clone, Copy)]
struct Node<const D: usize> {
    key: u64,
    at: [f64; D],
    value: f64,
}

/// Vertices created on demand and shared: inside nodes, and crossings keyed by their edge.
struct Vertices<const D: usize> {
    nodes: HashMap<u64, u32>,
    edges: HashMap<(u64, u64), u32>,
    positions: Vec<[f64; D]>,
    rounded: Vec<[f32; 3]>,
}

impl<const D: usize> Vertices<D> {
    fn new() -> Self {
        Vertices {
            nodes: HashMap::new(),
            edges: HashMap::new(),
            positions: Vec::new(),
            rounded: Vec::new(),
        }
    }

    fn add(&mut self, p: [f64; D]) -> u32 {
        let id = self.positions.len() as u32;
        self.positions.push(p);
        self.rounded.push(std::array::from_fn(
            |d| if d < D { p[d] as f32 } else { 0.0 },
        ));
        id
    }

    fn node(&mut self, n: &Node<D>) -> u32 {
        if let Some(&id) = self.nodes.get(&n.key) {
            return id;
        }
        let id = self.add(n.at);
        self.nodes.insert(n.key, id);
        id
    }

    /// The crossing on edge `a b`, computed from the endpoint with the smaller key so that both
    /// cells sharing the edge (and the edge's images under the group) agree.
    fn crossing(&mut self, a: &Node<D>, b: &Node<D>) -> u32 {
        let (a, b) = if a.key < b.key { (a, b) } else { (b, a) };
        if let Some(&id) = self.edges.get(&(a.key, b.key)) {
            return id;
        }
        let t = crossing_fraction(a.value, b.value);
        let id = self.add(std::array::from_fn(|d| a.at[d] + t * (b.at[d] - a.at[d])));
        self.edges.insert((a.key, b.key), id);
        id
    }

    fn into_contoured(self, triangles: Vec<[u32; 3]>) -> Contoured<D> {
        Contoured {
            mesh: Mesh {
                vertices: self.rounded,
                triangles,
            },
            positions: self.positions,
        }
    }
}

/// The inside part of a convex polygon of nodes (given in order), as a polygon of vertices in
/// the same order: inside nodes and the crossings of its sides.
fn clip_polygon<const D: usize>(corners: &[Node<D>], verts: &mut Vertices<D>) -> Vec<u32> {
    let mut out = Vec::with_capacity(corners.len() + 1);
    for (c, a) in corners.iter().enumerate() {
        let b = &corners[(c + 1) % corners.len()];
        if inside(a.value) {
            out.push(verts.node(a));
        }
        if inside(a.value) != inside(b.value) {
            out.push(verts.crossing(a, b));
        }
    }
    out
}

/// Fans a convex polygon from its first vertex.
fn fan(polygon: &[u32], triangles: &mut Vec<[u32; 3]>) {
    for w in 1..polygon.len().saturating_sub(1) {
        triangles.push([polygon[0], polygon[w], polygon[w + 1]]);
    }
}

// ---------------------------------------------------------------------------------------------
// The triangle.

/// The triangle's node `(i, j)` of a subdivision into `m` cells per side (module docs):
/// `x = (2i + j − m)/(2m)`, `y = √3 (3j − m)/(6m)`, so the mirror `x ↦ −x` is exact.
fn triangle_node(i: usize, j: usize, m: usize) -> [f64; 2] {
    let (i, j, m) = (i as f64, j as f64, m as f64);
    [
        (2.0 * i + j - m) / (2.0 * m),
        SQRT3 * (3.0 * j - m) / (6.0 * m),
    ]
}

/// The region `{Φ < 0}` of `field` over the equilateral triangle of side 1 centred at the
/// origin (vertices `(−½, −√3/6)`, `(½, −√3/6)`, `(0, √3/3)`), on its subdivision into
/// `cells²` triangles (`cells ≥ 1`).
pub(crate) fn contour_triangle(
    field: &(dyn Fn([f64; 2]) -> f64 + Sync),
    cells: usize,
) -> Contoured<2> {
    let m = cells;
    let row = m + 1;
    let mut values = vec![f64::NAN; row * row];
    for j in 0..=m {
        for i in 0..=m - j {
            values[i + row * j] = field(triangle_node(i, j, m));
        }
    }
    let node = |i: usize, j: usize| Node {
        key: (i + row * j) as u64,
        at: triangle_node(i, j, m),
        value: values[i + row * j],
    };
    let mut verts = Vertices::new();
    let mut triangles = Vec::new();
    for j in 0..m {
        for i in 0..m - j {
            // Both counter-clockwise, so the clipped polygon is too.
            let up = [node(i, j), node(i + 1, j), node(i, j + 1)];
            fan(&clip_polygon(&up, &mut verts), &mut triangles);
            if i + j + 2 <= m {
                let down = [node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)];
                fan(&clip_polygon(&down, &mut verts), &mut triangles);
            }
        }
    }
    verts.into_contoured(triangles)
}

// ---------------------------------------------------------------------------------------------
// The tetrahedron.

/// The tetrahedron's point with DOUBLED lattice coordinates `d` (nodes even, octahedron
/// centres odd) in a subdivision into `m` cells per edge: `p0 + (d0 e1 + d1 e2 + d2 e3)/(2m)`
/// with `p0 = (−½,−½,−½)`, `e1 = (1,1,0)`, `e2 = (0,1,1)`, `e3 = (1,0,1)` — computed as
/// `(integer − m)/(2m)` so that the group's sign changes and permutations map points exactly.
fn tetrahedron_node(d: [i64; 3], m: i64) -> [f64; 3] {
    let c = |a: i64, b: i64| (a + b - m) as f64 / (2 * m) as f64;
    [c(d[0], d[2]), c(d[0], d[1]), c(d[1], d[2])]
}

/// Whether the face with doubled coordinates `face` lies on the tetrahedron's boundary: the
/// planes `d0 = 0`, `d1 = 0`, `d2 = 0` and `d0 + d1 + d2 = 2m`.
fn on_boundary(face: [[i64; 3]; 3], m: i64) -> bool {
    (0..3).any(|a| face.iter().all(|d| d[a] == 0))
        || face.iter().all(|d| d[0] + d[1] + d[2] == 2 * m)
}

/// The solid `{Φ < 0}` of `field` over the tetrahedron with vertices `(−½,−½,−½)`,
/// `(½,½,−½)`, `(−½,½,½)`, `(½,−½,½)`, on its symmetric subdivision with `cells` cells per
/// edge (`cells ≥ 1`): a closed, manifold, outward mesh. `progress(1)` after each layer.
pub(crate) fn contour_tetrahedron(
    field: &dyn ScalarField,
    cells: usize,
    progress: &(dyn Fn(usize) + Sync),
) -> Contoured<3> {
    let m = cells as i64;
    let side = 2 * m + 1;
    let key = |d: [i64; 3]| (d[0] + side * (d[1] + side * d[2])) as u64;
    let mut march = Tetrahedra {
        m,
        verts: Vertices::new(),
        triangles: Vec::new(),
    };
    let mut lower = sample_layer(field, m, 0, 0);
    for k in 0..m {
        let upper = sample_layer(field, m, 2 * k + 2, 0);
        let centres = sample_layer(field, m, 2 * k + 1, 1);
        let value = |d: [i64; 3]| -> f64 {
            let layer = if d[2] == 2 * k {
                &lower
            } else if d[2] == 2 * k + 2 {
                &upper
            } else {
                &centres
            };
            layer[layer_index(d, m)]
        };
        let node = |d: [i64; 3]| Node {
            key: key(d),
            at: tetrahedron_node(d, m),
            value: value(d),
        };
        for j in 0..m - k {
            for i in 0..m - k - j {
                let b = [2 * i, 2 * j, 2 * k];
                let at = |o: [i64; 3]| node([b[0] + 2 * o[0], b[1] + 2 * o[1], b[2] + 2 * o[2]]);
                let s = i + j + k;
                march.tet([at([0, 0, 0]), at([1, 0, 0]), at([0, 1, 0]), at([0, 0, 1])]);
                if s + 2 <= m {
                    // The octahedron between layers s + 1 and s + 2 of the base's parallelepiped:
                    // each face takes one vertex of each opposite pair.
                    let centre = node([b[0] + 1, b[1] + 1, b[2] + 1]);
                    let pairs = [
                        [at([1, 0, 0]), at([0, 1, 1])],
                        [at([0, 1, 0]), at([1, 0, 1])],
                        [at([0, 0, 1]), at([1, 1, 0])],
                    ];
                    for f in 0..8 {
                        let pick = |a: usize| pairs[a][(f >> a) & 1];
                        march.tet([centre, pick(0), pick(1), pick(2)]);
                    }
                }
                if s + 3 <= m {
                    march.tet([at([1, 1, 0]), at([1, 0, 1]), at([0, 1, 1]), at([1, 1, 1])]);
                }
            }
        }
        lower = upper;
        progress(1);
    }
    march.verts.into_contoured(march.triangles)
}

/// Index of a point of a layer in [`sample_layer`]'s output.
fn layer_index(d: [i64; 3], m: i64) -> usize {
    ((d[0] / 2) + (m + 1) * (d[1] / 2)) as usize
}

/// The field at the points of one layer `d2 = layer` (doubled): the nodes `d0, d1` even with
/// `d0 + d1 + d2 ≤ 2m` for `odd = 0`, or the octahedron centres `d0, d1` odd for `odd = 1`;
/// indexed by [`layer_index`] (unused slots NaN).
fn sample_layer(field: &dyn ScalarField, m: i64, layer: i64, odd: i64) -> Vec<f64> {
    let row = (m + 1) as usize;
    let mut slots = Vec::new();
    let (mut xs, mut ys, mut zs) = (Vec::new(), Vec::new(), Vec::new());
    for j in 0..=m {
        for i in 0..=m {
            let d = [2 * i + odd, 2 * j + odd, layer];
            // Nodes up to the far face; centres strictly inside (their octahedron's top at 2m).
            if d[0] + d[1] + d[2] + odd > 2 * m {
                continue;
            }
            let [x, y, z] = tetrahedron_node(d, m);
            slots.push(layer_index(d, m));
            xs.push(x);
            ys.push(y);
            zs.push(z);
        }
    }
    let mut values = vec![0.0; xs.len()];
    field.eval_points(&xs, &ys, &zs, &mut values);
    let mut out = vec![f64::NAN; row * row];
    for (slot, v) in slots.into_iter().zip(values) {
        out[slot] = v;
    }
    out
}

/// Marching tetrahedra with caps on the element's faces.
struct Tetrahedra {
    m: i64,
    verts: Vertices<3>,
    triangles: Vec<[u32; 3]>,
}

impl Tetrahedra {
    fn tet(&mut self, t: [Node<3>; 4]) {
        self.caps(&t);
        let (ins, outs): (Vec<Node<3>>, Vec<Node<3>>) = t.iter().partition(|n| inside(n.value));
        if ins.is_empty() || outs.is_empty() {
            return;
        }
        // The separating polygon, in cyclic order.
        let polygon: Vec<u32> = match (ins.as_slice(), outs.as_slice()) {
            ([a], [b, c, d]) | ([b, c, d], [a]) => vec![
                self.verts.crossing(a, b),
                self.verts.crossing(a, c),
                self.verts.crossing(a, d),
            ],
            ([a, b], [c, d]) => {
                let q = [
                    self.verts.crossing(a, c),
                    self.verts.crossing(a, d),
                    self.verts.crossing(b, d),
                    self.verts.crossing(b, c),
                ];
                // The shorter diagonal: a choice made on geometry, so images agree.
                let p = |v: u32| self.verts.positions[v as usize];
                if dist2(p(q[1]), p(q[3])) < dist2(p(q[0]), p(q[2])) {
                    vec![q[1], q[2], q[3], q[0]]
                } else {
                    q.to_vec()
                }
            }
            _ => return,
        };
        // Outward: from the inside nodes towards the outside ones.
        let toward = sub(centroid(&outs), centroid(&ins));
        let start = self.triangles.len();
        fan(&polygon, &mut self.triangles);
        self.orient(start, toward);
    }

    /// The inside part of each face of `t` on the element's boundary, facing outward.
    fn caps(&mut self, t: &[Node<3>; 4]) {
        for skip in 0..4 {
            let face: Vec<Node<3>> = (0..4).filter(|&c| c != skip).map(|c| t[c]).collect();
            let doubled = |n: &Node<3>| unkey(n.key, 2 * self.m + 1);
            if !on_boundary(
                [doubled(&face[0]), doubled(&face[1]), doubled(&face[2])],
                self.m,
            ) {
                continue;
            }
            let polygon = clip_polygon(&face, &mut self.verts);
            let start = self.triangles.len();
            fan(&polygon, &mut self.triangles);
            // The element is convex and centred at the origin: outward is away from it.
            let middle = centroid(&face);
            self.orient(start, middle);
        }
    }

    /// Turns the triangles from `start` on so that their normals point along `toward`.
    fn orient(&mut self, start: usize, toward: [f64; 3]) {
        for t in &mut self.triangles[start..] {
            let p = |v: u32| self.verts.positions[v as usize];
            let n = cross(sub(p(t[1]), p(t[0])), sub(p(t[2]), p(t[0])));
            if dot(n, toward) < 0.0 {
                t.swap(1, 2);
            }
        }
    }
}

fn unkey(key: u64, side: i64) -> [i64; 3] {
    let k = key as i64;
    [k % side, (k / side) % side, k / (side * side)]
}

fn centroid(nodes: &[Node<3>]) -> [f64; 3] {
    let s = nodes.len() as f64;
    std::array::from_fn(|d| nodes.iter().map(|n| n.at[d]).sum::<f64>() / s)
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|d| a[d] - b[d])
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = sub(a, b);
    dot(d, d)
}

#[cfg(test)]
mod tests;
