//! Nodal values (transition weights, graded thickness and offset) interpolated at lattice
//! points by the element's own shape functions — linear or quadratic, through all its nodes in
//! Gmsh's order — with the same bits from every element that sees the point.
//!
//! **Integer numerators.** At a lattice point every shape function of every kind is a rational
//! with an integer numerator over one fixed power of `m`, the lattice's segments per edge:
//! - simplices (barycentric integers `a`, `Σ a = m`): corner `λ = a/m` (linear) or
//!   `λ(2λ − 1) = a(2a − m)/m²`, mid-edge `4λᵢλⱼ = 4aᵢaⱼ/m²`;
//! - tensor kinds (per axis `c ∈ [0, m]`, `u = (2c − m)/m`, node coordinate `s ∈ {−1, 0, 1}`):
//!   the linear factor `(1 + us)/2` is `L/m` with `L = m − c` or `c`; the quadratic Lagrange
//!   factor is `Q/m²` with `Q = (2c − m)(c − m)`, `4c(m − c)`, `(2c − m)c` for `s = −1, 0, 1`;
//!   multilinear is `Π L / mᵈ`, Lagrange (quad9, hex27) `Π Q / m²ᵈ`, serendipity (quad8, hex20)
//!   corners `Π L · (Σ (2c − m)s − (d − 1)m) / mᵈ⁺¹` and mid-edge nodes
//!   `4c_z(m − c_z) Π_{a≠z} L / mᵈ⁺¹` (`z` the node's zero axis).
//!
//! A value is `Σ nᵢ·vᵢ / D` over the nodes with a nonzero numerator `nᵢ`, summed in increasing
//! global node id, divided once by the kind's common denominator `D`.
//!
//! **Why both sides of a face agree bitwise.** On a face, a node off the face has numerator
//! exactly 0 (a factor `a`, `c` or `m − c` vanishes), and the numerators of the face's own
//! nodes depend only on the point's position in the face, which the weld already names
//! intrinsically (equal `(global corner, weight)` lists): both elements list the same
//! `(global node, numerator)` pairs, sum them in the same order, and divide by the same `D`.
//! The same holds on edges shared by more elements.
//!
//! Invariants: `|n| ≤ 5m⁶ < 2⁵³` for `m ≤ 255`, so every `n as f64` is exact; numerators sum to
//! `D` at every point (partition of unity, in integers); for the linear kinds the numerators
//! are the lattice's corner weights and `D` their sum, so linear elements interpolate exactly
//! (bitwise) as by the corner weights.

use super::lattice::Weights;
use crate::scaffold::ElementKind;

/// Most nodes of any element (hex27).
pub const MAX_NODES: usize = ElementKind::MAX_NODES;

/// Every node of each element: its kind and, element after element, its `kind.node_count()`
/// global node ids in Gmsh's order (corners first, in the reference element's corner order).
#[derive(Clone, Copy, Debug)]
pub struct Nodes<'a> {
    pub kind: ElementKind,
    pub ids: &'a [u32],
}

impl<'a> Nodes<'a> {
    /// The nodes of element `e`.
    pub fn element(&self, e: usize) -> &'a [u32] {
        let n = self.kind.node_count();
        &self.ids[e * n..(e + 1) * n]
    }

    pub fn count(&self) -> usize {
        self.ids.len() / self.kind.node_count()
    }
}

/// A lattice point's integer coordinates: barycentric `a₀..a₃` for simplices (unused trailing
/// entries 0), `c_x, c_y, c_z` for tensor kinds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Point([i64; 4]);

/// How a kind's shape functions are built from the point's integer coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Family {
    Simplex { quadratic: bool },
    Multilinear,
    Lagrange,
    Serendipity,
}

/// What a node contributes: for simplices the barycentric indices it is the product of (equal
/// for a corner), for tensor kinds its coordinates `s ∈ {−1, 0, 1}` per axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Node {
    pair: [u8; 2],
    s: [i8; 3],
}

/// The integer shape-function numerators of one element kind on a lattice with `m` segments
/// per edge.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Shape {
    family: Family,
    dim: usize,
    m: i64,
    denominator: i64,
    corners: usize,
    nodes: Vec<Node>,
}

impl Shape {
    /// The numerators of `kind` on a lattice with `m ≥ 1` segments per edge.
    pub fn new(kind: ElementKind, m: u32) -> Shape {
        let m = i64::from(m);
        let dim = kind.dimension();
        let family = match kind {
            ElementKind::Tri3 | ElementKind::Tet4 => Family::Simplex { quadratic: false },
            ElementKind::Tri6 | ElementKind::Tet10 => Family::Simplex { quadratic: true },
            ElementKind::Quad4 | ElementKind::Hex8 => Family::Multilinear,
            ElementKind::Quad9 | ElementKind::Hex27 => Family::Lagrange,
            ElementKind::Quad8 | ElementKind::Hex20 => Family::Serendipity,
        };
        let d = dim as u32;
        let denominator = match family {
            Family::Simplex { quadratic: false } => m,
            Family::Simplex { quadratic: true } => m * m,
            Family::Multilinear => m.pow(d),
            Family::Lagrange => m.pow(2 * d),
            Family::Serendipity => m.pow(d + 1),
        };
        let corners = kind.corner_count();
        let edges = kind.edges();
        let nodes = (0..kind.node_count())
            .map(|i| {
                let pair = if i < corners {
                    [i as u8; 2]
                } else {
                    // Only simplices read pairs; their extra nodes are all mid-edge nodes.
                    edges
                        .get(i - corners)
                        .map_or([0; 2], |&[a, b]| [a as u8, b as u8])
                };
                // Tensor reference nodes sit at 0 or ±½: 2ξ is exactly −1, 0 or 1.
                let s = kind.reference_node(i).map(|x| (2.0 * x).round() as i8);
                Node { pair, s }
            })
            .collect();
        Shape {
            family,
            dim,
            m,
            denominator,
            corners,
            nodes,
        }
    }

    /// The shape of `kind` on the lattice whose points have corner weights like `weights`
    /// (any one point's): `m` is recovered from the weights' total, `m` for simplices and `mᵈ`
    /// for tensor kinds, exactly in integers.
    pub fn from_weights(kind: ElementKind, weights: &Weights) -> Shape {
        let total: u64 = weights.as_slice().iter().map(|&(_, w)| u64::from(w)).sum();
        let m = if kind.is_simplex() {
            total
        } else {
            let d = kind.dimension() as u32;
            (1..=total).find(|&m| m.pow(d) >= total).unwrap_or(1)
        };
        Shape::new(kind, u32::try_from(m).unwrap_or(u32::MAX))
    }

    /// The common denominator `D` of every numerator.
    pub fn denominator(&self) -> i64 {
        self.denominator
    }

    /// The integer coordinates of the point with corner weights `weights` (as the lattices
    /// give them: barycentric integers for simplices, products of `c` or `m − c` per axis for
    /// tensor kinds, in Gmsh's corner order).
    pub fn point(&self, weights: &Weights) -> Point {
        let mut p = [0i64; 4];
        if matches!(self.family, Family::Simplex { .. }) {
            for &(corner, w) in weights.as_slice() {
                p[corner as usize] = i64::from(w);
            }
            return Point(p);
        }
        // Σ of the weights of the corners at s = +1 on axis a is c_a · m^(d−1).
        let scale = self.m.pow(self.dim as u32 - 1);
        for &(corner, w) in weights.as_slice() {
            let s = self.nodes[corner as usize].s;
            for (a, slot) in p.iter_mut().enumerate().take(self.dim) {
                if s[a] > 0 {
                    *slot += i64::from(w);
                }
            }
        }
        Point(p.map(|v| v / scale))
    }

    /// The numerator of every node at `point`, in local node order, into
    /// `out[..node_count]`.
    pub fn numerators(&self, point: &Point, out: &mut [i64; MAX_NODES]) {
        let m = self.m;
        let c = point.0;
        let nodes = self.nodes.iter();
        match self.family {
            Family::Simplex { quadratic: false } => {
                for (slot, node) in out.iter_mut().zip(nodes) {
                    *slot = c[usize::from(node.pair[0])];
                }
            }
            Family::Simplex { quadratic: true } => {
                for (slot, node) in out.iter_mut().zip(nodes) {
                    let [i, j] = node.pair.map(usize::from);
                    *slot = if i == j {
                        c[i] * (2 * c[i] - m)
                    } else {
                        4 * c[i] * c[j]
                    };
                }
            }
            family => {
                // Per axis, indexed by s + 1: the linear factors (s = ±1) and the quadratic
                // ones (s = −1, 0, 1). Axes past the dimension are 1 (their s is 0).
                let mut linear = [[1i64; 3]; 3];
                let mut quad = [[1i64; 3]; 3];
                for a in 0..self.dim {
                    let x = c[a];
                    linear[a] = [m - x, 0, x];
                    quad[a] = [(2 * x - m) * (x - m), 4 * x * (m - x), (2 * x - m) * x];
                }
                let idx = |node: &Node, a: usize| (node.s[a] + 1) as usize;
                let product = |table: &[[i64; 3]; 3], node: &Node| {
                    table[0][idx(node, 0)] * table[1][idx(node, 1)] * table[2][idx(node, 2)]
                };
                match family {
                    Family::Multilinear => {
                        for (slot, node) in out.iter_mut().zip(nodes) {
                            *slot = product(&linear, node);
                        }
                    }
                    Family::Lagrange => {
                        for (slot, node) in out.iter_mut().zip(nodes) {
                            *slot = product(&quad, node);
                        }
                    }
                    _ => {
                        let d = self.dim as i64;
                        for (slot, node) in out.iter_mut().zip(nodes) {
                            *slot = match (0..self.dim).find(|&a| node.s[a] == 0) {
                                None => {
                                    let sum: i64 = (0..self.dim)
                                        .map(|a| (2 * c[a] - m) * i64::from(node.s[a]))
                                        .sum();
                                    product(&linear, node) * (sum - (d - 1) * m)
                                }
                                Some(z) => {
                                    // The zero axis takes the bubble 4c(m − c), the others
                                    // their linear factor.
                                    let mut table = linear;
                                    table[z] = [quad[z][1]; 3];
                                    product(&table, node)
                                }
                            };
                        }
                    }
                }
            }
        }
    }

    /// The most any point's negative numerators add up to, over `D`: an interpolant is at
    /// least `min v − (max v − min v) · this` (0 for the linear kinds).
    pub fn undershoot(&self, points: impl Iterator<Item = Point>) -> f64 {
        let mut out = [0; MAX_NODES];
        let worst = points
            .map(|p| {
                self.numerators(&p, &mut out);
                out[..self.nodes.len()]
                    .iter()
                    .filter(|&&n| n < 0)
                    .map(|n| -n)
                    .sum::<i64>()
            })
            .max()
            .unwrap_or(0);
        worst as f64 / self.denominator as f64
    }

    /// How many of the nodes are corners.
    pub fn corner_count(&self) -> usize {
        self.corners
    }
}

/// One element's nodes in increasing global id (ties, in a degenerate element, by local
/// index): the order every interpolation in it sums in.
#[derive(Clone, Copy, Debug)]
pub struct Order {
    len: usize,
    local: [u8; MAX_NODES],
}

impl Order {
    pub fn of(nodes: &[u32]) -> Order {
        let mut pairs = [(u32::MAX, u8::MAX); MAX_NODES];
        for (i, (slot, &node)) in pairs.iter_mut().zip(nodes).enumerate() {
            *slot = (node, i as u8);
        }
        let len = nodes.len().min(MAX_NODES);
        pairs[..len].sort_unstable();
        Order {
            len,
            local: pairs.map(|(_, i)| i),
        }
    }

    /// `nodal` at the element's nodes `nodes`, in this order.
    pub fn gather(&self, nodes: &[u32], nodal: &[f64]) -> [f64; MAX_NODES] {
        let mut out = [0.0; MAX_NODES];
        for (slot, &i) in out.iter_mut().zip(&self.local[..self.len]) {
            *slot = nodal[nodes[usize::from(i)] as usize];
        }
        out
    }

    /// `numerators` (local order) in this order.
    pub fn arrange(&self, numerators: &[i64; MAX_NODES]) -> [i64; MAX_NODES] {
        let mut out = [0; MAX_NODES];
        for (slot, &i) in out.iter_mut().zip(&self.local[..self.len]) {
            *slot = numerators[usize::from(i)];
        }
        out
    }

    pub fn len(&self) -> usize {
        self.len
    }
}

/// `Σ nᵢ vᵢ / D` over the nonzero numerators, in the given (increasing global node) order.
/// Zero terms are skipped, not added: a node off a face must not contribute even a signed
/// zero or a non-finite value there.
#[inline]
pub fn interpolate(numerators: &[i64], values: &[f64], denominator: i64) -> f64 {
    interpolate_each(numerators, &[values], denominator)[0]
}

/// [`interpolate`] for `K` arrays at once (one pass over the numerators; each sum has the
/// same terms in the same order, so the same bits as alone).
#[inline]
pub fn interpolate_each<const K: usize>(
    numerators: &[i64],
    values: &[&[f64]; K],
    denominator: i64,
) -> [f64; K] {
    let mut sums = [0.0; K];
    for (k, &n) in numerators.iter().enumerate() {
        if n != 0 {
            let n = n as f64;
            for (sum, v) in sums.iter_mut().zip(values) {
                *sum += n * v[k];
            }
        }
    }
    sums.map(|s| s / denominator as f64)
}

/// The node lists against the corner lists: as many elements, the node kind's corner count,
/// and each element's nodes starting with its corners.
pub fn check_nodes(corners: &[u32], per_element: usize, nodes: &Nodes) -> Result<(), String> {
    let kind = nodes.kind;
    if kind.corner_count() != per_element {
        return Err(format!(
            "{} elements have {} corners, not {per_element}",
            kind.name(),
            kind.corner_count()
        ));
    }
    let elements = corners.len() / per_element;
    if nodes.ids.len() != elements * kind.node_count() {
        return Err(format!(
            "{} node ids for {elements} {} elements of {} nodes",
            nodes.ids.len(),
            kind.name(),
            kind.node_count()
        ));
    }
    let per = kind.node_count();
    let mismatch = corners
        .chunks_exact(per_element)
        .zip(nodes.ids.chunks_exact(per))
        .position(|(c, n)| c != &n[..per_element]);
    match mismatch {
        Some(e) => Err(format!("element {e}'s nodes do not start with its corners")),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests;
