//! C¹ element maps for quad4 and hex8 scaffolds (docs/method.md §Smooth element maps): each
//! element is mapped by a tensor-product cubic Hermite patch through its corners, whose corner
//! derivatives are shared by the elements on either side of every "grid line" through a node,
//! so that the tiled field's gradient is continuous across faces.
//!
//! **The map.** With `u_a = ½ − σ_a ξ_a ∈ [0, 1]` the distance from corner `c` (reference
//! signs `σ`) along axis `a`, `H₀(t) = 1 − 3t² + 2t³` and `H₁(t) = t(1 − t)²`,
//!
//! ```text
//! X(ξ) = Σ_c [ Π_a H₀(u_a) P_c + Σ_a H₁(u_a) Π_{b≠a} H₀(u_b) T_{c,a} ]
//! ```
//!
//! where `T_{c,a}` is the derivative of `X` at corner `c` along its edge on axis `a`, toward
//! the neighbour corner. Cross derivatives are zero. Every term is written per corner and edge,
//! so the formula is the same under every symmetry of the square or cube.
//!
//! **Corner derivatives.** At node `v`, an edge `v→w` and another edge `v→u` are *opposite*
//! when no element holds both and each is the only such edge for the other (a regular node:
//! four edges in a quad mesh, six in a hex mesh, or a boundary node along the boundary). Then
//! `T(v→w) = λ d` and `T(v→u) = −λ d` with `d` the unit bisector of `ŵ − û` and `λ` the mean
//! of the two edge lengths: the derivatives of the two elements across a face are exactly
//! opposite. Otherwise (an irregular node, an edge leaving the boundary) `T(v→w) = w − v`.
//!
//! Invariants: the face of an element is mapped through that face's corners and their in-face
//! derivatives only (off-face terms vanish with `H₀(1) = H₁(1) = 0`), so neighbours place a
//! shared face at the same points (to rounding); the derivative across a face is the bilinear
//! blend of its corners' transversal `T`, so where all four corners pair their transversal
//! edges it is exactly opposite from the two sides; on an affine grid (every `T` the edge
//! vector) the map is the affine map.

use super::{ElementKind, Location, Scaffold, ScaffoldError};

/// The corner derivatives of every element of a quad4 or hex8 scaffold.
#[derive(Clone, Debug, PartialEq)]
pub struct SmoothMap {
    dim: usize,
    corners: usize,
    /// Per corner, the sign of each reference coordinate (±1).
    signs: [[f64; 3]; 8],
    /// `T_{c,a}`: element by element, corner by corner, axis by axis.
    tangents: Vec<[f64; 3]>,
    /// Per element and corner, bit `a` set when the axis-`a` edge has an opposite edge.
    paired: Vec<u8>,
}

fn h0(t: f64) -> f64 {
    1.0 - t * t * (3.0 - 2.0 * t)
}

fn h1(t: f64) -> f64 {
    t * (1.0 - t) * (1.0 - t)
}

fn dh0(t: f64) -> f64 {
    6.0 * t * (t - 1.0)
}

fn dh1(t: f64) -> f64 {
    (1.0 - t) * (1.0 - 3.0 * t)
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn length(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

impl Scaffold {
    /// Makes this scaffold's maps the C¹ maps of [`SmoothMap`] (its nodes, elements and
    /// everything read from the file unchanged). Only quad4 and hex8 scaffolds can be.
    pub fn make_c1(&mut self) -> Result<(), ScaffoldError> {
        let map = SmoothMap::new(self)?;
        self.smooth = Some(std::sync::Arc::new(map));
        Ok(())
    }
}

impl SmoothMap {
    pub fn new(scaffold: &Scaffold) -> Result<SmoothMap, ScaffoldError> {
        let kind = scaffold.kind;
        if !matches!(kind, ElementKind::Quad4 | ElementKind::Hex8) {
            return Err(ScaffoldError::new(
                &scaffold.source,
                Location::File,
                format!(
                    "C¹ maps (continuity = \"c1\") are made for quad4 and hex8 elements, but this \
                     scaffold has {} elements; export it with linear quadrilaterals or hexahedra",
                    kind.name()
                ),
            ));
        }
        let dim = kind.dimension();
        let corners = kind.corner_count();
        let mut signs = [[0.0; 3]; 8];
        for (c, s) in signs.iter_mut().enumerate().take(corners) {
            *s = kind.reference_node(c).map(|x| x.signum());
        }
        // The corner across each axis from each corner.
        let across = |c: usize, a: usize| {
            (0..corners)
                .find(|&k| (0..dim).all(|b| (signs[k][b] == signs[c][b]) == (a != b)))
                .unwrap_or(c)
        };
        let lines = Lines::new(scaffold, dim, corners, &across);
        let elements = scaffold.element_count();
        let mut tangents = Vec::with_capacity(elements * corners * dim);
        let mut paired = Vec::with_capacity(elements * corners);
        let node = |n: u32| scaffold.nodes[n as usize];
        for e in 0..elements {
            let nodes = scaffold.element(e);
            for c in 0..corners {
                let mut bits = 0u8;
                for a in 0..dim {
                    let (v, w) = (nodes[c], nodes[across(c, a)]);
                    let edge = sub(node(w), node(v));
                    let t = match lines.opposite(v, w) {
                        Some(u) => {
                            let back = sub(node(u), node(v));
                            let (lw, lu) = (length(edge), length(back));
                            let d = std::array::from_fn(|i| edge[i] / lw - back[i] / lu);
                            let ld = length(d);
                            if ld > 1e-3 && lw > 0.0 && lu > 0.0 {
                                bits |= 1 << a;
                                let lambda = 0.5 * (lw + lu);
                                d.map(|x| lambda * x / ld)
                            } else {
                                // The grid line folds back on itself: no direction to share.
                                edge
                            }
                        }
                        None => edge,
                    };
                    tangents.push(t);
                }
                paired.push(bits);
            }
        }
        Ok(SmoothMap {
            dim,
            corners,
            signs,
            tangents,
            paired,
        })
    }

    /// Whether corner `c`'s edge along axis `a` of element `e` has an opposite edge through
    /// the node (so its derivative is shared, negated, with the element across).
    pub fn paired(&self, e: usize, c: usize, a: usize) -> bool {
        self.paired[e * self.corners + c] & (1 << a) != 0
    }

    /// `X_e(ξ)`.
    pub fn map(&self, scaffold: &Scaffold, e: usize, xi: [f64; 3]) -> [f64; 3] {
        let mut x = [0.0; 3];
        self.each_term(scaffold, e, xi, |weight, p| {
            for i in 0..3 {
                x[i] += weight[3] * p[i];
            }
        });
        x
    }

    /// `dx_i/dξ_a` in `[i][a]` (2D: column 2 is zero).
    pub fn jacobian(&self, scaffold: &Scaffold, e: usize, xi: [f64; 3]) -> [[f64; 3]; 3] {
        let mut j = [[0.0; 3]; 3];
        self.each_term(scaffold, e, xi, |weight, p| {
            for (i, row) in j.iter_mut().enumerate() {
                for (a, slot) in row.iter_mut().enumerate() {
                    *slot += weight[a] * p[i];
                }
            }
        });
        j
    }

    /// Calls `f(weights, vector)` for each term of the map: a corner position or a corner
    /// derivative, with its weight's derivatives along the three axes (`[0..3]`) and
    /// the weight itself (`[3]`).
    fn each_term(
        &self,
        scaffold: &Scaffold,
        e: usize,
        xi: [f64; 3],
        mut f: impl FnMut([f64; 4], [f64; 3]),
    ) {
        let nodes = scaffold.element(e);
        let dim = self.dim;
        for (c, &node) in nodes.iter().enumerate().take(self.corners) {
            let s = self.signs[c];
            // Per axis: [H₀, H₁] and their ξ-derivatives (du/dξ = −σ).
            let mut value = [[1.0; 2]; 3];
            let mut slope = [[0.0; 2]; 3];
            for a in 0..dim {
                let u = 0.5 - s[a] * xi[a];
                value[a] = [h0(u), h1(u)];
                slope[a] = [-s[a] * dh0(u), -s[a] * dh1(u)];
            }
            // Term `k`: k = dim is the position (H₀ on every axis), k = a the derivative on a.
            for k in 0..=dim {
                let pick = |b: usize| usize::from(b == k);
                let mut w = [0.0; 4];
                w[3] = (0..dim).map(|b| value[b][pick(b)]).product();
                for (a, slot) in w.iter_mut().enumerate().take(dim) {
                    *slot = (0..dim)
                        .map(|b| {
                            if a == b {
                                slope[b][pick(b)]
                            } else {
                                value[b][pick(b)]
                            }
                        })
                        .product();
                }
                let p = if k == dim {
                    scaffold.nodes[node as usize]
                } else {
                    self.tangents[(e * self.corners + c) * dim + k]
                };
                f(w, p);
            }
        }
    }
}

/// The edges through every node and which pairs of them one element holds.
struct Lines {
    /// Per node, its neighbours (sorted).
    neighbours: Vec<Vec<u32>>,
    /// Per node, the pairs of its neighbours some element joins it to together (sorted).
    together: Vec<Vec<(u32, u32)>>,
}

impl Lines {
    fn new(
        scaffold: &Scaffold,
        dim: usize,
        corners: usize,
        across: &dyn Fn(usize, usize) -> usize,
    ) -> Lines {
        let n = scaffold.nodes.len();
        let mut neighbours = vec![Vec::new(); n];
        let mut together = vec![Vec::new(); n];
        for e in 0..scaffold.element_count() {
            let nodes = scaffold.element(e);
            for c in 0..corners {
                let v = nodes[c] as usize;
                for a in 0..dim {
                    let w = nodes[across(c, a)];
                    neighbours[v].push(w);
                    for b in a + 1..dim {
                        let x = nodes[across(c, b)];
                        together[v].push((w.min(x), w.max(x)));
                    }
                }
            }
        }
        for list in &mut neighbours {
            list.sort_unstable();
            list.dedup();
        }
        for list in &mut together {
            list.sort_unstable();
            list.dedup();
        }
        Lines {
            neighbours,
            together,
        }
    }

    /// The only neighbour `u` of `v` that no element joins to `v` together with `w`, if it
    /// has the same relation back to `w`.
    fn opposite(&self, v: u32, w: u32) -> Option<u32> {
        let u = self.only_apart(v, w)?;
        (self.only_apart(v, u) == Some(w)).then_some(u)
    }

    fn only_apart(&self, v: u32, w: u32) -> Option<u32> {
        let together = &self.together[v as usize];
        let mut apart = self.neighbours[v as usize]
            .iter()
            .copied()
            .filter(|&u| u != w && together.binary_search(&(u.min(w), u.max(w))).is_err());
        let first = apart.next()?;
        apart.next().is_none().then_some(first)
    }
}

#[cfg(test)]
mod tests;
