//! The isoparametric map of an element, its Jacobian, and quadrature over reference elements.
//!
//! Invariants:
//! - x = X_e(ξ) = Σ_i N_i(ξ) x_i through all the element's nodes (curved quadratic elements are
//!   followed, not straightened).
//! - Quadrature rules integrate over the reference element of `element.rs` (weights sum to its
//!   measure: 1 for the cube and square, ⅓ for the tetrahedron, √3/4 for the triangle). The rules
//!   used by [`Scaffold::measure`] are exact for the polynomial |det J| of every 3D kind and of
//!   tri3 (constant); other 2D kinds, which may be curved surfaces (a square root), use 8
//!   points per direction.
//! - Simplex rules are collapsed (Duffy) tensor Gauss–Legendre rules, all points inside.

use rayon::prelude::*;

use super::{ElementKind, Scaffold};

/// A quadrature rule on a reference element: points ξ and weights.
#[derive(Clone, Debug)]
pub struct Quadrature {
    pub points: Vec<[f64; 3]>,
    pub weights: Vec<f64>,
}

/// Gauss–Legendre points and weights on [-1, 1] (Newton on the Legendre recurrence).
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut rule = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut derivative = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            if n == 1 {
                p0 = 1.0;
            }
            derivative = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let step = p1 / derivative;
            x -= step;
            if step.abs() < 1e-16 {
                break;
            }
        }
        rule.push((x, 2.0 / ((1.0 - x * x) * derivative * derivative)));
    }
    rule
}

impl Quadrature {
    /// A rule with `n` Gauss points per direction on the reference element of `kind`.
    pub fn new(kind: ElementKind, n: usize) -> Quadrature {
        // On [0, 1]: t = (x + 1)/2, w/2.
        let line: Vec<(f64, f64)> = gauss_legendre(n)
            .into_iter()
            .map(|(x, w)| ((x + 1.0) / 2.0, w / 2.0))
            .collect();
        let mut points = Vec::new();
        let mut weights = Vec::new();
        let linear = kind.linear();
        match linear {
            ElementKind::Quad4 | ElementKind::Hex8 => {
                let depth = if linear == ElementKind::Hex8 { n } else { 1 };
                for k in 0..depth {
                    for j in 0..n {
                        for i in 0..n {
                            let (z, wz) = if linear == ElementKind::Hex8 {
                                (line[k].0 - 0.5, line[k].1)
                            } else {
                                (0.0, 1.0)
                            };
                            points.push([line[i].0 - 0.5, line[j].0 - 0.5, z]);
                            weights.push(line[i].1 * line[j].1 * wz);
                        }
                    }
                }
            }
            ElementKind::Tri3 => {
                let c: [[f64; 3]; 3] = [0, 1, 2].map(|i| kind.reference_node(i));
                // Unit simplex (r, s) by Duffy: r = u, s = v(1 - u); area ratio √3/4 / ½.
                let scale = 3f64.sqrt() / 2.0;
                for &(u, wu) in &line {
                    for &(v, wv) in &line {
                        let (r, s) = (u, v * (1.0 - u));
                        points.push(affine(&c, &[r, s]));
                        weights.push(wu * wv * (1.0 - u) * scale);
                    }
                }
            }
            _ => {
                let c: [[f64; 3]; 4] = [0, 1, 2, 3].map(|i| kind.reference_node(i));
                // Unit tetrahedron by Duffy; volume ratio ⅓ / ⅙.
                for &(u, wu) in &line {
                    for &(v, wv) in &line {
                        for &(w, ww) in &line {
                            let r = u;
                            let s = v * (1.0 - u);
                            let t = w * (1.0 - u) * (1.0 - v);
                            points.push(affine(&c, &[r, s, t]));
                            weights.push(wu * wv * ww * (1.0 - u) * (1.0 - u) * (1.0 - v) * 2.0);
                        }
                    }
                }
            }
        }
        Quadrature { points, weights }
    }
}

/// c0 + Σ_k t_k (c_{k+1} - c0).
fn affine(c: &[[f64; 3]], t: &[f64]) -> [f64; 3] {
    let mut p = c[0];
    for (k, &tk) in t.iter().enumerate() {
        for a in 0..3 {
            p[a] += tk * (c[k + 1][a] - c[0][a]);
        }
    }
    p
}

/// The Jacobian's measure: |det J| in 3D, |J_1 × J_2| in 2D.
pub fn jacobian_measure(kind: ElementKind, j: &[[f64; 3]; 3]) -> f64 {
    if kind.dimension() == 3 {
        det3(j).abs()
    } else {
        norm(cross2(j))
    }
}

pub fn det3(j: &[[f64; 3]; 3]) -> f64 {
    j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
        - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
        + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0])
}

/// J_1 × J_2 (the columns dx/dξ_1 and dx/dξ_2).
pub fn cross2(j: &[[f64; 3]; 3]) -> [f64; 3] {
    let a = [j[0][0], j[1][0], j[2][0]];
    let b = [j[0][1], j[1][1], j[2][1]];
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

impl Scaffold {
    /// x = X_e(ξ): the isoparametric map through all the element's nodes, or the C¹ map
    /// ([`Scaffold::make_c1`]) when made.
    pub fn map(&self, e: usize, xi: [f64; 3]) -> [f64; 3] {
        if let Some(smooth) = &self.smooth {
            return smooth.map(self, e, xi);
        }
        if self.kind == ElementKind::Tet4 {
            // The tiling's common case, without the general path's table of weights: zeroing
            // and copying it took longer than the sum. Same sum, same order, same bits.
            return self.combine(e, &ElementKind::linear_tet_shape(xi));
        }
        let mut n = [0.0; ElementKind::MAX_NODES];
        self.kind.shape(xi, &mut n);
        self.combine(e, &n)
    }

    /// Σ_i w_i x_i over element `e`'s nodes, in node order.
    #[inline(always)]
    fn combine(&self, e: usize, weights: &[f64]) -> [f64; 3] {
        let mut x = [0.0; 3];
        for (node, &w) in self.element(e).iter().zip(weights) {
            let p = self.nodes[*node as usize];
            for a in 0..3 {
                x[a] += w * p[a];
            }
        }
        x
    }

    /// dx_i/dξ_a in `[i][a]` (2D kinds: columns 0 and 1; column 2 is zero).
    pub fn jacobian(&self, e: usize, xi: [f64; 3]) -> [[f64; 3]; 3] {
        if let Some(smooth) = &self.smooth {
            return smooth.jacobian(self, e, xi);
        }
        let mut g = [[0.0; 3]; ElementKind::MAX_NODES];
        self.kind.shape_gradients(xi, &mut g);
        let mut j = [[0.0; 3]; 3];
        for (node, d) in self.element(e).iter().zip(&g) {
            let p = self.nodes[*node as usize];
            for i in 0..3 {
                for a in 0..3 {
                    j[i][a] += p[i] * d[a];
                }
            }
        }
        j
    }

    /// The rule [`Scaffold::measure`] uses for this scaffold's kind.
    pub fn measure_rule(&self) -> Quadrature {
        // Points per direction for an exact |det J|: tet4/tri3 have a constant Jacobian, but the
        // Duffy factor (1-u)²(1-v) needs 2 points on the tet (1 on the triangle); tet10's det J
        // has degree 3 (+2 from Duffy); hex8 degree 2 per axis, hex20/hex27 degree 5. Other 2D
        // elements may be curved surfaces (a square root): 8 points.
        let n = match self.kind {
            // A C¹ map's det J has degree 8 per axis (hex): 5 points integrate it exactly.
            _ if self.smooth.is_some() => 5,
            ElementKind::Tri3 => 1,
            ElementKind::Tet4 | ElementKind::Hex8 => 2,
            ElementKind::Tet10 | ElementKind::Hex20 | ElementKind::Hex27 => 3,
            _ => 8,
        };
        Quadrature::new(self.kind, n)
    }

    /// Measure of element `e` under `rule`: ∫ |det J| (2D: |J_1 × J_2|) over the reference element.
    pub fn element_measure(&self, e: usize, rule: &Quadrature) -> f64 {
        rule.points
            .iter()
            .zip(&rule.weights)
            .map(|(&xi, &w)| w * jacobian_measure(self.kind, &self.jacobian(e, xi)))
            .sum()
    }

    /// Volume (3D) or area (2D) of the whole mesh by Gauss quadrature.
    pub fn measure(&self) -> f64 {
        // Summed by fixed blocks of elements, then the block sums in order: in parallel (it
        // ran alone after a 100k-element tiling, a twentieth of a second on one core), yet
        // the same bits whatever the thread count.
        const BLOCK: usize = 4096;
        let rule = self.measure_rule();
        let n = self.element_count();
        let block_sums: Vec<f64> = (0..n.div_ceil(BLOCK))
            .into_par_iter()
            .map(|b| {
                (b * BLOCK..n.min((b + 1) * BLOCK))
                    .map(|e| self.element_measure(e, &rule))
                    .sum()
            })
            .collect();
        block_sums.iter().sum()
    }
}
