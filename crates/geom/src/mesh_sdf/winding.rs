//! Generalized winding numbers: exact per triangle, hierarchical over the BVH.
//!
//! The winding number of a query point `q` is the signed solid angle the surface subtends at
//! `q`, over 4π: 1 inside a closed counter-clockwise-outward surface, 0 outside, and a smooth
//! "how much inside" for open surfaces and soups.
//!
//! Exact: the Van Oosterom–Strackee formula for a triangle with corners `a, b, c` relative to
//! `q`: `tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| + (b·c)|a| + (c·a)|b|)`, evaluated with
//! `atan2`, which stays correct for any position of `q` (no division).
//!
//! Hierarchical (Barill et al. 2018, "Fast winding numbers for soups and clouds"): seen from
//! afar, a node's surface is a layer of dipoles `n dA`. With `X = p̃ − q` (`p̃` the node's
//! area-weighted centre), `d = y − p̃` for surface points `y`, and `f(x) = x/|x|³`,
//!
//! ```text
//! 4π w = ∫ n·f(X + d) dA ≈ M₁·f(X) + Σ M₂ⱼₖ ∂ₖfⱼ(X) + ½ Σ M₃ⱼₖₗ ∂ₖ∂ₗfⱼ(X)
//! M₁ = ∫ n dA,   M₂ⱼₖ = ∫ nⱼ dₖ dA,   M₃ⱼₖₗ = ∫ nⱼ dₖ dₗ dA
//! ```
//!
//! All three moments are exact for flat triangles: `∫ d dA = a (c − p̃)` and
//! `∫ d dᵀ dA = a/12 (Σ vᵢvᵢᵀ + s sᵀ)` with corners `vᵢ` relative to `p̃` and `s = Σ vᵢ`; with
//! `a n = (b − a) × (c − a) / 2` no area is ever divided by. A node is taken from afar when
//! `|X| > β r`, `r` bounding the distance from `p̃` to its triangles; otherwise its children are
//! visited, down to exact leaves. The truncation error of a node is about `(1/β)³` of its
//! contribution; `tests/mesh_sdf_winding.rs` states the resulting bound for β = 2.

use super::bvh::{Aabb, Bvh, MAX_DEPTH};
use super::prepare::Tri;
use crate::vec3::{V3, add, cross, dot, max, norm, scale, sub};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Far-field data of one node.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Moments {
    /// Area-weighted centre of the triangles' centroids.
    pub center: V3,
    /// Squared radius `r`: from the squared distance `β² r²` on, the node is seen from afar.
    pub radius2: f64,
    pub m1: V3,
    pub m2: [V3; 3],
    /// `M₃` as one symmetric matrix per `j`, stored `[kk=00, 11, 22, 01, 02, 12]`.
    pub m3: [[f64; 6]; 3],
    /// Total (unsigned) area, the weight for the parent's centre.
    pub area: f64,
}

/// The moments of every node, computed bottom-up.
pub(super) fn moments(bvh: &Bvh) -> Vec<Moments> {
    let nodes = &bvh.nodes;
    let mut out = vec![Moments::default(); nodes.len()];
    // Radius bounds, kept apart from `radius2` until the end.
    let mut radius = vec![0.0f64; nodes.len()];
    // Leaves hold the triangle work and are independent; interior nodes only combine.
    out.par_iter_mut()
        .zip(radius.par_iter_mut())
        .zip(nodes.par_iter())
        .filter(|(_, node)| node.is_leaf())
        .for_each(|((m, r), node)| {
            let range = node.first() as usize..(node.first() + node.count()) as usize;
            (*m, *r) = leaf_moments(&bvh.triangles[range]);
        });
    for i in (0..nodes.len()).rev() {
        let node = nodes[i];
        if node.is_leaf() {
            continue;
        }
        let (l, rr) = (i + 1, node.first() as usize);
        let m = combine(&out[l], &out[rr]);
        let through_children = [l, rr]
            .map(|c| norm(sub(out[c].center, m.center)) + radius[c])
            .into_iter()
            .fold(0.0, f64::max);
        radius[i] = through_children.min(corner_radius(&bvh.boxes[i], m.center));
        out[i] = m;
    }
    out.par_iter_mut()
        .zip(&radius)
        .for_each(|(m, &r)| m.radius2 = r * r);
    out
}

fn leaf_moments(tris: &[Tri]) -> (Moments, f64) {
    let mut m = Moments::default();
    let mut weighted = [0.0; 3];
    let mut plain = [0.0; 3];
    for t in tris {
        let av = scale(cross(sub(t[1], t[0]), sub(t[2], t[0])), 0.5);
        let c = centroid(t);
        let a = norm(av);
        m.m1 = add(m.m1, av);
        m.area += a;
        weighted = add(weighted, scale(c, a));
        plain = add(plain, c);
    }
    m.center = if m.area > 0.0 {
        scale(weighted, 1.0 / m.area)
    } else {
        scale(plain, 1.0 / tris.len() as f64)
    };
    let mut r: f64 = 0.0;
    for t in tris {
        let av = scale(cross(sub(t[1], t[0]), sub(t[2], t[0])), 0.5);
        let d = sub(centroid(t), m.center);
        let v = t.map(|p| sub(p, m.center));
        let sum = add(add(v[0], v[1]), v[2]);
        // ∫ d dᵀ dA over the triangle, divided by its area.
        let second = sym(|k, l| {
            (v[0][k] * v[0][l] + v[1][k] * v[1][l] + v[2][k] * v[2][l] + sum[k] * sum[l]) / 12.0
        });
        for ((m2, m3), a) in m.m2.iter_mut().zip(&mut m.m3).zip(av) {
            for (e, dk) in m2.iter_mut().zip(d) {
                *e += a * dk;
            }
            for (e, s) in m3.iter_mut().zip(second) {
                *e += a * s;
            }
        }
        for p in t {
            r = r.max(norm(sub(*p, m.center)));
        }
    }
    (m, r)
}

/// The six distinct entries of a symmetric matrix, in `m3`'s order.
const SYM: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

fn sym(f: impl Fn(usize, usize) -> f64) -> [f64; 6] {
    SYM.map(|(k, l)| f(k, l))
}

fn centroid(t: &Tri) -> V3 {
    scale(add(add(t[0], t[1]), t[2]), 1.0 / 3.0)
}

fn combine(l: &Moments, r: &Moments) -> Moments {
    let area = l.area + r.area;
    let center = if area > 0.0 {
        scale(
            add(scale(l.center, l.area), scale(r.center, r.area)),
            1.0 / area,
        )
    } else {
        scale(add(l.center, r.center), 0.5)
    };
    let mut m2 = [[0.0; 3]; 3];
    let mut m3 = [[0.0; 6]; 3];
    // Moving a child's expansion centre to ours (d → d + s, s = p̃_child − p̃):
    // M₂ⱼₖ += M₁ⱼ sₖ and M₃ⱼₖₗ += M₂ⱼₖ sₗ + M₂ⱼₗ sₖ + M₁ⱼ sₖ sₗ.
    for c in [l, r] {
        let s = sub(c.center, center);
        for j in 0..3 {
            for k in 0..3 {
                m2[j][k] += c.m2[j][k] + c.m1[j] * s[k];
            }
            let shifted = sym(|k, l| c.m2[j][k] * s[l] + c.m2[j][l] * s[k] + c.m1[j] * s[k] * s[l]);
            for e in 0..6 {
                m3[j][e] += c.m3[j][e] + shifted[e];
            }
        }
    }
    Moments {
        center,
        radius2: 0.0,
        m1: add(l.m1, r.m1),
        m2,
        m3,
        area,
    }
}

/// Farthest corner of the node's box from `c`: a bound on the distance to its triangles.
fn corner_radius(b: &Aabb, c: V3) -> f64 {
    let (lo, hi) = (b.lo(), b.hi());
    let d: V3 = std::array::from_fn(|a| (c[a] - lo[a]).abs().max((hi[a] - c[a]).abs()));
    norm(max(d, [0.0; 3]))
}

/// Solid angle of triangle `t` at `q`, in steradians (positive when `q` sees the back, i.e.
/// is on the inner side of a counter-clockwise-outward triangle).
#[inline]
pub(super) fn solid_angle(t: &Tri, q: V3) -> f64 {
    let (a, b, c) = (sub(t[0], q), sub(t[1], q), sub(t[2], q));
    let (la, lb, lc) = (norm(a), norm(b), norm(c));
    let num = dot(a, cross(b, c));
    let den = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
    2.0 * num.atan2(den)
}

/// The far-field value of a node at `x = p̃ − q`, `r2 = |x|²`, times 4π.
///
/// With `∂ₖfⱼ = δⱼₖ/r³ − 3xⱼxₖ/r⁵` and
/// `∂ₖ∂ₗfⱼ = −3(δⱼₗxₖ + δⱼₖxₗ + δₖₗxⱼ)/r⁵ + 15xⱼxₖxₗ/r⁷`, the terms contract to
/// `M₁·x/r³ + (tr M₂)/r³ − 3xᵀM₂x/r⁵ + ½(−3(2A + B)/r⁵ + 15C/r⁷)` where
/// `A = Σ M₃ⱼₖⱼxₖ`, `B = Σ xⱼM₃ⱼₖₖ`, `C = Σ M₃ⱼₖₗxⱼxₖxₗ`.
#[inline]
fn far_field(m: &Moments, x: V3, r2: f64) -> f64 {
    let inv3 = 1.0 / (r2 * r2.sqrt());
    let inv5 = inv3 / r2;
    let inv7 = inv5 / r2;
    let mx: V3 = std::array::from_fn(|j| dot(m.m2[j], x));
    let trace = m.m2[0][0] + m.m2[1][1] + m.m2[2][2];
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for j in 0..3 {
        let [s00, s11, s22, s01, s02, s12] = m.m3[j];
        let sx = [
            s00 * x[0] + s01 * x[1] + s02 * x[2],
            s01 * x[0] + s11 * x[1] + s12 * x[2],
            s02 * x[0] + s12 * x[1] + s22 * x[2],
        ];
        a += sx[j];
        b += x[j] * (s00 + s11 + s22);
        c += x[j] * dot(x, sx);
    }
    (dot(m.m1, x) + trace) * inv3 - 3.0 * dot(x, mx) * inv5
        + 0.5 * (-3.0 * (2.0 * a + b) * inv5 + 15.0 * c * inv7)
}

/// The winding number at `q`, hierarchically, with far-field threshold `β = sqrt(beta2)`.
pub(super) fn fast(bvh: &Bvh, moments: &[Moments], q: V3, beta2: f64) -> f64 {
    let mut stack = [0u32; MAX_DEPTH + 2];
    let mut top = 1;
    let mut sum = 0.0;
    while top > 0 {
        top -= 1;
        let i = stack[top] as usize;
        let m = &moments[i];
        let x = sub(m.center, q);
        let r2 = dot(x, x);
        if r2 > beta2 * m.radius2 {
            sum += far_field(m, x, r2);
            continue;
        }
        let node = &bvh.nodes[i];
        if node.is_leaf() {
            for t in &bvh.triangles[node.first() as usize..(node.first() + node.count()) as usize] {
                sum += solid_angle(t, q);
            }
        } else {
            stack[top] = node.first();
            stack[top + 1] = i as u32 + 1;
            top += 2;
        }
    }
    sum / (4.0 * PI)
}

/// The winding number at `q` summed over every triangle exactly.
pub(super) fn exact(triangles: &[Tri], q: V3) -> f64 {
    // Fixed blocks summed in parallel, then the block sums in order: the same bits for any
    // thread count (rayon's own `sum` splits where its scheduler does).
    const BLOCK: usize = 1 << 14;
    let block_sum = |block: &[Tri]| block.iter().map(|t| solid_angle(t, q)).sum::<f64>();
    let sum: f64 = if triangles.len() > BLOCK {
        let sums: Vec<f64> = triangles.par_chunks(BLOCK).map(block_sum).collect();
        sums.iter().sum()
    } else {
        block_sum(triangles)
    };
    sum / (4.0 * PI)
}
