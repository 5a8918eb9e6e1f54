//! The ten element kinds of a scaffold: reference elements, Gmsh node orders, shape functions.
//!
//! Invariants:
//! - The reference elements are the cell domains of docs/method.md §Reference elements (centre 0,
//!   size 1): the cube
//!   and square [-½,½]^d, the tetrahedron p0=(-½,-½,-½), p1=(½,½,-½), p2=(-½,½,½), p3=(½,-½,½),
//!   and the equilateral triangle of side 1 with its centroid at 0, pointing to +y. A cell's
//!   reference domain is therefore exactly an element's reference element.
//! - Local node i sits at [`ElementKind::reference_node`]`(i)`, in Gmsh's local order (corners
//!   first, then edges, faces, centre: see the scaffolds README), so N_i(node_j) = δ_ij.
//! - The reference orientation matches Gmsh's: a positive Gmsh Jacobian stays positive.
//! - [`ElementKind::faces`] lists the corners of each facet (faces in 3D, edges in 2D) so that
//!   the right-hand normal points out of the element; hex faces follow Gmsh's hex27 face order
//!   (0123, 0145, 0347, 1256, 2367, 4567), tet face i is opposite corner i.

use std::fmt;
use std::sync::OnceLock;

/// A scaffold element type (Gmsh's names and node orders).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ElementKind {
    Tri3,
    Tri6,
    Quad4,
    Quad8,
    Quad9,
    Tet4,
    Tet10,
    Hex8,
    Hex20,
    Hex27,
}

const SQRT3: f64 = 1.732_050_807_568_877_2;

/// Corners of the reference triangle: side 1, centroid 0, counter-clockwise.
const TRI: [[f64; 3]; 3] = [
    [-0.5, -SQRT3 / 6.0, 0.0],
    [0.5, -SQRT3 / 6.0, 0.0],
    [0.0, SQRT3 / 3.0, 0.0],
];
/// Corners of the reference tetrahedron (docs/method.md §Reference elements).
const TET: [[f64; 3]; 4] = [
    [-0.5, -0.5, -0.5],
    [0.5, 0.5, -0.5],
    [-0.5, 0.5, 0.5],
    [0.5, -0.5, 0.5],
];
/// Outward normals of the tetrahedron's faces (face i opposite p_i is n_i·x = ½), so that the
/// barycentric coordinate of p_i is λ_i = (½ - n_i·x) / 2.
const TET_NORMALS: [[f64; 3]; 4] = [
    [1.0, 1.0, 1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, -1.0],
    [-1.0, 1.0, -1.0],
];
/// Hex corners in Gmsh order, as signs.
const HEX: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

const TRI_EDGES: [[usize; 2]; 3] = [[0, 1], [1, 2], [2, 0]];
const QUAD_EDGES: [[usize; 2]; 4] = [[0, 1], [1, 2], [2, 3], [3, 0]];
const TET_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [3, 0], [2, 3], [3, 1]];
const HEX_EDGES: [[usize; 2]; 12] = [
    [0, 1],
    [0, 3],
    [0, 4],
    [1, 2],
    [1, 5],
    [2, 3],
    [2, 6],
    [3, 7],
    [4, 5],
    [4, 7],
    [5, 6],
    [6, 7],
];
/// Hex faces in Gmsh's hex27 face-node order, wound outward.
const HEX_FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [0, 1, 5, 4],
    [0, 4, 7, 3],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [4, 5, 6, 7],
];

static TRI_FACETS: [&[usize]; 3] = [&[0, 1], &[1, 2], &[2, 0]];
static QUAD_FACETS: [&[usize]; 4] = [&[0, 1], &[1, 2], &[2, 3], &[3, 0]];
static TET_FACETS: [&[usize]; 4] = [&[1, 2, 3], &[0, 3, 2], &[0, 1, 3], &[0, 2, 1]];
static HEX_FACETS: [&[usize]; 6] = [
    &HEX_FACES[0],
    &HEX_FACES[1],
    &HEX_FACES[2],
    &HEX_FACES[3],
    &HEX_FACES[4],
    &HEX_FACES[5],
];

impl ElementKind {
    pub const ALL: [ElementKind; 10] = [
        ElementKind::Tri3,
        ElementKind::Tri6,
        ElementKind::Quad4,
        ElementKind::Quad8,
        ElementKind::Quad9,
        ElementKind::Tet4,
        ElementKind::Tet10,
        ElementKind::Hex8,
        ElementKind::Hex20,
        ElementKind::Hex27,
    ];
    /// The most nodes any kind has (hex27).
    pub const MAX_NODES: usize = 27;

    pub fn name(self) -> &'static str {
        match self {
            ElementKind::Tri3 => "tri3",
            ElementKind::Tri6 => "tri6",
            ElementKind::Quad4 => "quad4",
            ElementKind::Quad8 => "quad8",
            ElementKind::Quad9 => "quad9",
            ElementKind::Tet4 => "tet4",
            ElementKind::Tet10 => "tet10",
            ElementKind::Hex8 => "hex8",
            ElementKind::Hex20 => "hex20",
            ElementKind::Hex27 => "hex27",
        }
    }

    pub fn node_count(self) -> usize {
        match self {
            ElementKind::Tri3 => 3,
            ElementKind::Tri6 => 6,
            ElementKind::Quad4 => 4,
            ElementKind::Quad8 => 8,
            ElementKind::Quad9 => 9,
            ElementKind::Tet4 => 4,
            ElementKind::Tet10 => 10,
            ElementKind::Hex8 => 8,
            ElementKind::Hex20 => 20,
            ElementKind::Hex27 => 27,
        }
    }

    pub fn corner_count(self) -> usize {
        match self {
            ElementKind::Tri3 | ElementKind::Tri6 => 3,
            ElementKind::Quad4 | ElementKind::Quad8 | ElementKind::Quad9 => 4,
            ElementKind::Tet4 | ElementKind::Tet10 => 4,
            ElementKind::Hex8 | ElementKind::Hex20 | ElementKind::Hex27 => 8,
        }
    }

    /// The dimension of the reference element.
    pub fn dimension(self) -> usize {
        match self {
            ElementKind::Tri3
            | ElementKind::Tri6
            | ElementKind::Quad4
            | ElementKind::Quad8
            | ElementKind::Quad9 => 2,
            _ => 3,
        }
    }

    pub fn is_simplex(self) -> bool {
        matches!(
            self,
            ElementKind::Tri3 | ElementKind::Tri6 | ElementKind::Tet4 | ElementKind::Tet10
        )
    }

    /// Polynomial order of the map: 1 (linear) or 2 (quadratic).
    pub fn order(self) -> usize {
        if self.node_count() == self.corner_count() {
            1
        } else {
            2
        }
    }

    /// The linear kind with the same corners (tet10 → tet4, …).
    pub fn linear(self) -> ElementKind {
        match self {
            ElementKind::Tri3 | ElementKind::Tri6 => ElementKind::Tri3,
            ElementKind::Quad4 | ElementKind::Quad8 | ElementKind::Quad9 => ElementKind::Quad4,
            ElementKind::Tet4 | ElementKind::Tet10 => ElementKind::Tet4,
            _ => ElementKind::Hex8,
        }
    }

    pub fn gmsh_type(self) -> u32 {
        match self {
            ElementKind::Tri3 => 2,
            ElementKind::Tri6 => 9,
            ElementKind::Quad4 => 3,
            ElementKind::Quad8 => 16,
            ElementKind::Quad9 => 10,
            ElementKind::Tet4 => 4,
            ElementKind::Tet10 => 11,
            ElementKind::Hex8 => 5,
            ElementKind::Hex20 => 17,
            ElementKind::Hex27 => 12,
        }
    }

    pub fn from_gmsh_type(gmsh_type: u32) -> Option<ElementKind> {
        ElementKind::ALL
            .into_iter()
            .find(|k| k.gmsh_type() == gmsh_type)
    }

    /// The kind a name (as [`ElementKind::name`] gives it) names.
    pub fn from_name(name: &str) -> Option<ElementKind> {
        ElementKind::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Reference position of local node i (corners, then mid-edge, mid-face and centre nodes at
    /// the midpoints/centres of their corners).
    ///
    /// # Panics
    /// If `i >= self.node_count()` (a programming error, never user input).
    pub fn reference_node(self, i: usize) -> [f64; 3] {
        assert!(i < self.node_count(), "{} has no node {i}", self.name());
        let corners = self.corner_count();
        if i < corners {
            return self.corner(i);
        }
        let mean = |ids: &[usize]| {
            let mut p = [0.0; 3];
            for &c in ids {
                let q = self.corner(c);
                for a in 0..3 {
                    p[a] += q[a];
                }
            }
            p.map(|v| v / ids.len() as f64)
        };
        let edges = self.edges();
        let j = i - corners;
        if j < edges.len() {
            return mean(&edges[j]);
        }
        let f = j - edges.len();
        match self {
            ElementKind::Quad9 => [0.0; 3],
            ElementKind::Hex27 if f < 6 => mean(&HEX_FACES[f]),
            _ => [0.0; 3],
        }
    }

    fn corner(self, i: usize) -> [f64; 3] {
        match self.linear() {
            ElementKind::Tri3 => TRI[i],
            ElementKind::Quad4 => [HEX[i][0] * 0.5, HEX[i][1] * 0.5, 0.0],
            ElementKind::Tet4 => TET[i],
            _ => HEX[i].map(|s| s * 0.5),
        }
    }

    /// Local corner indices of each facet (3D faces, 2D edges), wound so that the right-hand
    /// normal points out of the element (for 2D: edge direction × +z points out).
    pub fn faces(self) -> &'static [&'static [usize]] {
        match self.linear() {
            ElementKind::Tri3 => &TRI_FACETS,
            ElementKind::Quad4 => &QUAD_FACETS,
            ElementKind::Tet4 => &TET_FACETS,
            _ => &HEX_FACETS,
        }
    }

    /// The corner edges, in the order of the mid-edge nodes of the quadratic kinds.
    pub fn edges(self) -> &'static [[usize; 2]] {
        match self.linear() {
            ElementKind::Tri3 => &TRI_EDGES,
            ElementKind::Quad4 => &QUAD_EDGES,
            ElementKind::Tet4 => &TET_EDGES,
            _ => &HEX_EDGES,
        }
    }

    /// Shape functions at reference point `xi` into `out[..node_count]`: the same values as
    /// [`ElementKind::evaluate`]'s, without the gradients (the map runs this for every output
    /// vertex of a tiling, where zeroing a gradient table per call cost more than the map).
    pub fn shape(self, xi: [f64; 3], out: &mut [f64]) {
        let l = match self {
            ElementKind::Tri3 | ElementKind::Tri6 => tri_barycentric(xi).0,
            ElementKind::Tet4 | ElementKind::Tet10 => tet_barycentric(xi).0,
            _ => {
                let mut grad = [[0.0; 3]; ElementKind::MAX_NODES];
                return self.evaluate(xi, &mut out[..self.node_count()], &mut grad);
            }
        };
        let corners = self.corner_count();
        if self.order() == 1 {
            out[..corners].copy_from_slice(&l[..corners]);
            return;
        }
        for i in 0..corners {
            out[i] = l[i] * (2.0 * l[i] - 1.0);
        }
        for (j, &[a, b]) in self.edges().iter().enumerate() {
            out[corners + j] = 4.0 * l[a] * l[b];
        }
    }

    /// The tet4 shape functions (its barycentric coordinates) at `xi`: [`ElementKind::shape`]'s
    /// values for `Tet4`, as a fixed-size array.
    #[inline]
    pub fn linear_tet_shape(xi: [f64; 3]) -> [f64; 4] {
        tet_barycentric(xi).0
    }

    /// Derivatives dN_i/dξ_a into `out[i][a]` (the unused reference coordinates get 0).
    pub fn shape_gradients(self, xi: [f64; 3], out: &mut [[f64; 3]]) {
        let mut values = [0.0; ElementKind::MAX_NODES];
        self.evaluate(xi, &mut values, &mut out[..self.node_count()]);
    }

    /// Values and gradients together (what the map and its Jacobian need).
    pub fn evaluate(self, xi: [f64; 3], value: &mut [f64], grad: &mut [[f64; 3]]) {
        let n = self.node_count();
        match self {
            ElementKind::Tri3 | ElementKind::Tri6 => {
                let (l, dl) = tri_barycentric(xi);
                simplex_shapes(self, &l[..], &dl[..], value, grad);
            }
            ElementKind::Tet4 | ElementKind::Tet10 => {
                let (l, dl) = tet_barycentric(xi);
                simplex_shapes(self, &l[..], &dl[..], value, grad);
            }
            _ => {
                let dim = self.dimension();
                // Tensor coordinates u = 2ξ on [-1,1]^d; the node's own coordinates are ±1 or 0.
                let u = [
                    2.0 * xi[0],
                    2.0 * xi[1],
                    if dim == 3 { 2.0 * xi[2] } else { 0.0 },
                ];
                let nodes = &tensor_nodes()[self as usize];
                for i in 0..n {
                    let node = nodes[i];
                    let (v, g) = match self {
                        ElementKind::Quad8 | ElementKind::Hex20 => serendipity(dim, u, node),
                        ElementKind::Quad4 | ElementKind::Hex8 => multilinear(dim, u, node),
                        _ => lagrange2(dim, u, node),
                    };
                    value[i] = v;
                    // d/dξ = 2 d/du.
                    grad[i] = g.map(|d| 2.0 * d);
                }
            }
        }
    }
}

/// Tensor-product kinds' nodes in u = 2ξ coordinates (±1 or 0), computed once: the map is
/// evaluated for every output vertex of a tiling.
fn tensor_nodes() -> &'static [Vec<[f64; 3]>; 10] {
    static NODES: OnceLock<[Vec<[f64; 3]>; 10]> = OnceLock::new();
    NODES.get_or_init(|| {
        ElementKind::ALL.map(|kind| {
            (0..kind.node_count())
                .map(|i| kind.reference_node(i).map(|c| 2.0 * c))
                .collect()
        })
    })
}

impl fmt::Display for ElementKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Barycentric coordinates of the reference triangle and their (constant) gradients.
fn tri_barycentric(xi: [f64; 3]) -> ([f64; 4], [[f64; 3]; 4]) {
    let l2 = 2.0 * xi[1] / SQRT3 + 1.0 / 3.0;
    let l1 = (1.0 - l2 + 2.0 * xi[0]) / 2.0;
    let l0 = (1.0 - l2 - 2.0 * xi[0]) / 2.0;
    (
        [l0, l1, l2, 0.0],
        [
            [-1.0, -1.0 / SQRT3, 0.0],
            [1.0, -1.0 / SQRT3, 0.0],
            [0.0, 2.0 / SQRT3, 0.0],
            [0.0; 3],
        ],
    )
}

fn tet_barycentric(xi: [f64; 3]) -> ([f64; 4], [[f64; 3]; 4]) {
    let mut l = [0.0; 4];
    let mut dl = [[0.0; 3]; 4];
    for i in 0..4 {
        let n = TET_NORMALS[i];
        l[i] = (0.5 - (n[0] * xi[0] + n[1] * xi[1] + n[2] * xi[2])) / 2.0;
        dl[i] = n.map(|c| -c / 2.0);
    }
    (l, dl)
}

/// Linear (λ_i) or quadratic (λ_i(2λ_i-1), 4λ_aλ_b) simplex shape functions.
fn simplex_shapes(
    kind: ElementKind,
    l: &[f64],
    dl: &[[f64; 3]],
    value: &mut [f64],
    grad: &mut [[f64; 3]],
) {
    let corners = kind.corner_count();
    if kind.order() == 1 {
        value[..corners].copy_from_slice(&l[..corners]);
        grad[..corners].copy_from_slice(&dl[..corners]);
        return;
    }
    for i in 0..corners {
        value[i] = l[i] * (2.0 * l[i] - 1.0);
        grad[i] = dl[i].map(|d| (4.0 * l[i] - 1.0) * d);
    }
    for (j, &[a, b]) in kind.edges().iter().enumerate() {
        value[corners + j] = 4.0 * l[a] * l[b];
        grad[corners + j] = [0, 1, 2].map(|c| 4.0 * (dl[a][c] * l[b] + l[a] * dl[b][c]));
    }
}

/// (1 + u u_i)/2 per axis: value and d/du.
fn linear_factor(u: f64, ui: f64) -> (f64, f64) {
    ((1.0 + u * ui) / 2.0, ui / 2.0)
}

/// The 1D quadratic Lagrange polynomial through -1, 0, 1 that is 1 at `ui`: value and d/du.
fn lagrange_factor(u: f64, ui: f64) -> (f64, f64) {
    if ui < -0.5 {
        (u * (u - 1.0) / 2.0, u - 0.5)
    } else if ui > 0.5 {
        (u * (u + 1.0) / 2.0, u + 0.5)
    } else {
        (1.0 - u * u, -2.0 * u)
    }
}

fn tensor(
    dim: usize,
    u: [f64; 3],
    node: [f64; 3],
    factor: fn(f64, f64) -> (f64, f64),
) -> (f64, [f64; 3]) {
    let mut f = [(1.0, 0.0); 3];
    for a in 0..dim {
        f[a] = factor(u[a], node[a]);
    }
    let value = f[0].0 * f[1].0 * f[2].0;
    let grad = [
        f[0].1 * f[1].0 * f[2].0,
        f[0].0 * f[1].1 * f[2].0,
        if dim == 3 {
            f[0].0 * f[1].0 * f[2].1
        } else {
            0.0
        },
    ];
    (value, grad)
}

fn multilinear(dim: usize, u: [f64; 3], node: [f64; 3]) -> (f64, [f64; 3]) {
    tensor(dim, u, node, linear_factor)
}

fn lagrange2(dim: usize, u: [f64; 3], node: [f64; 3]) -> (f64, [f64; 3]) {
    tensor(dim, u, node, lagrange_factor)
}

/// Serendipity quad8/hex20 shape functions in u ∈ [-1,1]^d: value and d/du.
fn serendipity(dim: usize, u: [f64; 3], node: [f64; 3]) -> (f64, [f64; 3]) {
    let zero_axis = (0..dim).find(|&a| node[a] == 0.0);
    match zero_axis {
        None => {
            // Corner: Π(1 + u_a n_a)/2 · (Σ u_a n_a - (d - 1)).
            let (p, dp) = multilinear(dim, u, node);
            let s: f64 = (0..dim).map(|a| u[a] * node[a]).sum::<f64>() - (dim as f64 - 1.0);
            let mut g = [0.0; 3];
            for a in 0..dim {
                g[a] = dp[a] * s + p * node[a];
            }
            (p * s, g)
        }
        Some(z) => {
            // Mid-edge: (1 - u_z²) Π_{a≠z} (1 + u_a n_a)/2.
            let mut value = 1.0 - u[z] * u[z];
            let mut factors = [(1.0, 0.0); 3];
            factors[z] = (1.0 - u[z] * u[z], -2.0 * u[z]);
            for a in 0..dim {
                if a != z {
                    factors[a] = linear_factor(u[a], node[a]);
                    value *= factors[a].0;
                }
            }
            let mut g = [0.0; 3];
            for (a, slot) in g.iter_mut().enumerate().take(dim) {
                *slot = factors
                    .iter()
                    .enumerate()
                    .take(dim)
                    .map(|(b, f)| if b == a { f.1 } else { f.0 })
                    .product();
            }
            (value, g)
        }
    }
}

/// Gmsh's hex corners as 0/1 offsets along x, y, z (corner `i` of every hex kind).
pub const HEX_CORNERS: [[u32; 3]; 8] = [
    [0, 0, 0],
    [1, 0, 0],
    [1, 1, 0],
    [0, 1, 0],
    [0, 0, 1],
    [1, 0, 1],
    [1, 1, 1],
    [0, 1, 1],
];
