//! Unsigned distance: the nearest triangle to a point, by BVH branch and bound.
//!
//! Point–triangle distance without barycentric division. The textbook region tests divide by
//! expressions proportional to the squared area, which cancel catastrophically on slivers
//! (aspect ratio 1e6 and worse). Here, with `n = (b − a) × (c − a)`:
//! - if `p` projects inside the triangle (the three edge tests `((vⱼ₊₁ − vⱼ) × (p − vⱼ))·n ≥ 0`,
//!   signs only), the distance is the plane distance `|(p − a)·n| / |n|`;
//! - otherwise the nearest point lies on an edge that `p` sees from outside (an edge test
//!   `≤ 0`): the distance is the least point–segment distance over those edges, which needs
//!   only a division by an edge's squared length.
//!
//! A degenerate triangle (`n` negligible against its edges) has no inside and is measured as
//! its three edges, so zero-area triangles still count as the segments they are. Near the
//! boundary of a sliver the two cases meet continuously, so a misjudged sign test costs only
//! rounding.

use super::bvh::{Bvh, MAX_DEPTH};
use super::prepare::Tri;
use super::vec3::{V3, cross, dot, sub};

/// Squared distance from `p` to segment `a + t·e`, `t ∈ [0, 1]`, given `ap = p − a`.
#[inline(always)]
fn segment_dist2(ap: V3, e: V3) -> f64 {
    let ee = dot(e, e);
    let t = if ee > 0.0 {
        (dot(ap, e) / ee).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let d = [ap[0] - t * e[0], ap[1] - t * e[1], ap[2] - t * e[2]];
    dot(d, d)
}

/// Squared distance from `p` to triangle `t`.
#[inline]
pub(super) fn triangle_dist2(t: &Tri, p: V3) -> f64 {
    let [a, b, c] = *t;
    let (ab, bc, ca) = (sub(b, a), sub(c, b), sub(a, c));
    let n = cross(ab, sub(c, a));
    let (ap, bp, cp) = (sub(p, a), sub(p, b), sub(p, c));
    let sa = dot(cross(ab, ap), n);
    let sb = dot(cross(bc, bp), n);
    let sc = dot(cross(ca, cp), n);
    let nn = dot(n, n);
    // Relative to its edges, an area this small is a segment: its "plane" would be noise.
    let flat = nn > 1e-30 * dot(ab, ab) * dot(ca, ca);
    if flat && sa >= 0.0 && sb >= 0.0 && sc >= 0.0 {
        let h = dot(ap, n);
        return h * h / nn;
    }
    let mut best = f64::INFINITY;
    if !flat || sa <= 0.0 {
        best = best.min(segment_dist2(ap, ab));
    }
    if !flat || sb <= 0.0 {
        best = best.min(segment_dist2(bp, bc));
    }
    if !flat || sc <= 0.0 {
        best = best.min(segment_dist2(cp, ca));
    }
    best
}

/// The nearest triangle to `p` closer than `sqrt(bound2)`: its squared distance and index in
/// `bvh.triangles`, or `(bound2, None)` when there is none. `hint`, a triangle likely to be
/// near (the previous query's answer), tightens the bound before the descent. `stack` is
/// scratch space, reused across queries.
pub(super) fn nearest(
    bvh: &Bvh,
    p: V3,
    hint: Option<u32>,
    bound2: f64,
    stack: &mut Vec<(u32, f64)>,
) -> (f64, Option<u32>) {
    let mut best2 = bound2;
    let mut best = None;
    if let Some(h) = hint {
        let d2 = triangle_dist2(&bvh.triangles[h as usize], p);
        if d2 < best2 {
            best2 = d2;
            best = Some(h);
        }
    }
    let nodes = &bvh.nodes;
    let root = &nodes[0];
    stack.clear();
    let d2 = root.dist2(p);
    if d2 < best2 {
        stack.push((0, d2));
    }
    while let Some((i, d2)) = stack.pop() {
        if d2 >= best2 {
            continue;
        }
        let node = &nodes[i as usize];
        if node.is_leaf() {
            for k in node.first..node.first + node.count {
                let d2 = triangle_dist2(&bvh.triangles[k as usize], p);
                if d2 < best2 {
                    best2 = d2;
                    best = Some(k);
                }
            }
            continue;
        }
        let (l, r) = (i + 1, node.first);
        let dl = nodes[l as usize].dist2(p);
        let dr = nodes[r as usize].dist2(p);
        // Visit the nearer child first: push it last.
        let (near, far) = if dl <= dr {
            ((l, dl), (r, dr))
        } else {
            ((r, dr), (l, dl))
        };
        if far.1 < best2 {
            stack.push(far);
        }
        if near.1 < best2 {
            stack.push(near);
        }
    }
    (best2, best)
}

/// Whether some triangle's bounding box meets the box `[lo, hi]`: a cheap, conservative test
/// that a segment with these bounds crosses no triangle.
pub(super) fn any_box_overlap(bvh: &Bvh, lo: V3, hi: V3) -> bool {
    let overlaps = |a: V3, b: V3| (0..3).all(|k| a[k] <= hi[k] && lo[k] <= b[k]);
    let nodes = &bvh.nodes;
    let mut stack = [0u32; MAX_DEPTH + 2];
    let mut top = 1;
    while top > 0 {
        top -= 1;
        let i = stack[top];
        let node = &nodes[i as usize];
        let b = &bvh.boxes[i as usize];
        if !overlaps(b.lo(), b.hi()) {
            continue;
        }
        if node.is_leaf() {
            for t in &bvh.triangles[node.first as usize..(node.first + node.count) as usize] {
                let tlo = std::array::from_fn(|k| t[0][k].min(t[1][k]).min(t[2][k]));
                let thi = std::array::from_fn(|k| t[0][k].max(t[1][k]).max(t[2][k]));
                if overlaps(tlo, thi) {
                    return true;
                }
            }
        } else {
            stack[top] = node.first;
            stack[top + 1] = i + 1;
            top += 2;
        }
    }
    false
}
