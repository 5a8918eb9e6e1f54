//! A binary bounding-volume hierarchy over triangles, built by binned SAH.
//!
//! Layout: nodes in depth-first preorder, so a node's first child is the next node and its
//! second child is at `first`; leaves hold `count` (1 to [`LEAF`]) consecutive triangles of
//! [`Bvh::triangles`] from `first`. Children always come after their parent, so one backward
//! sweep computes anything bottom-up (bounds here, multipole moments in `winding.rs`).
//!
//! Splits: 16 bins along the longest axis of the triangle centroids' bounds, minimising the
//! surface-area cost. Split decisions use `f32` copies of the triangles normalised to the
//! soup's bounding box (half the memory traffic of `f64`; a split only needs to be good, not
//! exact), while node bounds are computed from the `f64` triangles afterwards, so they are
//! exact. Below depth [`MEDIAN_DEPTH`] a split falls back to the median, which bounds the depth
//! by `MEDIAN_DEPTH + log2 n` ([`MAX_DEPTH`]), so traversal stacks can be fixed arrays.
//!
//! Bounds: every node has an axis-aligned box ([`Bvh::boxes`]), and the box a distance query
//! uses ([`Node`]) is oriented along the mean normal for nodes of at most [`OBB_MAX`]
//! triangles ([`fit_oriented`] says why), aligned for larger ones. On smooth patches the
//! oriented box is much the tighter, and intersecting it with the aligned one cost more in
//! arithmetic than it saved in pruning. Boxes are stored in `f32` rounded outward, so they
//! still contain their triangles.
//!
//! Subtrees above [`PARALLEL`] triangles are built on rayon in parallel, each into its own
//! node list, and the lists are stitched in preorder once at the end. The result is the same
//! whatever the thread count.

use super::prepare::Tri;
use crate::vec3::{V3, add, cross, dot, max, min, norm, scale, sub};
use rayon::prelude::*;

/// Most triangles in a leaf. Measured on the benchmark torus: 2 beats 1 (more nodes to
/// visit) and 4 (looser leaf boxes, 15% slower distance queries).
pub(super) const LEAF: usize = 2;
const BINS: usize = 16;
const PARALLEL: usize = 1 << 13;
const MEDIAN_DEPTH: usize = 48;
/// Deepest possible node (root at 0): median splits halve, and counts fit in 30 bits
/// ([`MAX_TRIANGLES`]).
pub(super) const MAX_DEPTH: usize = MEDIAN_DEPTH + 33;

/// One node, one cache line (queries are bound by memory traffic, not arithmetic): a box in
/// the orthonormal frame `(u, v, n)`, stored in `f32` rounded outward, so it still contains
/// the node's triangles. `v` is stored rather than derived as `n × u` at each box test (that
/// cross product was a seventh of a test's arithmetic), which needs `first` and `count` packed
/// into one word: hence [`MAX_TRIANGLES`]. Nodes without an oriented box use the axis frame,
/// where the box is the aligned one.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct Node {
    u: [f32; 3],
    v: [f32; 3],
    n: [f32; 3],
    /// `extent[a][0] ≤ axis_a·x ≤ extent[a][1]` for the axes `u, v, n`, computed in `f64`
    /// with the stored axes.
    extent: [[f32; 2]; 3],
    /// `first | count << COUNT_SHIFT`. `first`: a leaf's first triangle, an interior node's
    /// second child; `count`: a leaf's number of triangles (1 to [`LEAF`]), 0 for interior.
    link: u32,
}

const COUNT_SHIFT: u32 = 30;
const FIRST_MASK: u32 = (1 << COUNT_SHIFT) - 1;
const _: () = assert!(LEAF < 1 << (32 - COUNT_SHIFT));

/// Most triangles a hierarchy takes: node and triangle indices must fit in [`FIRST_MASK`],
/// and a tree over `n` triangles has fewer than `2n` nodes.
pub(super) const MAX_TRIANGLES: usize = 1 << (COUNT_SHIFT - 1);

impl Default for Node {
    fn default() -> Node {
        Node {
            u: [1.0, 0.0, 0.0],
            v: [0.0, 1.0, 0.0],
            n: [0.0, 0.0, 1.0],
            extent: [[f32::NEG_INFINITY, f32::INFINITY]; 3],
            link: 0,
        }
    }
}

/// `x` as `f32`, rounded toward −∞ (`down`) or +∞, so a box stays around its contents.
fn round_f32(x: f64, down: bool) -> f32 {
    let r = x as f32;
    match (down, f64::from(r).partial_cmp(&x)) {
        (true, Some(std::cmp::Ordering::Greater)) => r.next_down(),
        (false, Some(std::cmp::Ordering::Less)) => r.next_up(),
        _ => r,
    }
}

fn widen(v: [f32; 3]) -> V3 {
    v.map(f64::from)
}

impl Node {
    fn leaf(first: u32, count: u32) -> Node {
        Node {
            link: first | count << COUNT_SHIFT,
            ..Node::default()
        }
    }

    /// A leaf's first triangle, an interior node's second child.
    #[inline(always)]
    pub(super) fn first(&self) -> u32 {
        self.link & FIRST_MASK
    }

    /// A leaf's number of triangles; 0 for an interior node.
    #[inline(always)]
    pub(super) fn count(&self) -> u32 {
        self.link >> COUNT_SHIFT
    }

    fn set_first(&mut self, first: u32) {
        debug_assert!(first <= FIRST_MASK);
        self.link = (self.link & !FIRST_MASK) | first;
    }

    #[inline]
    pub(super) fn is_leaf(&self) -> bool {
        self.count() > 0
    }

    /// The stored frame `u, v, n` in `f64`: extents are computed with exactly these axes.
    #[inline]
    fn axes(&self) -> [V3; 3] {
        [widen(self.u), widen(self.v), widen(self.n)]
    }

    /// A lower bound on the squared distance from `p` to the node's triangles, in `f64` (the
    /// searches compute it in `f32` lanes, `nearest.rs`). Shrunk by 1e-6 because the `f32`
    /// axes are orthonormal only to about 1e-7.
    #[cfg(test)]
    pub(super) fn dist2(&self, p: V3) -> f64 {
        let mut d2 = 0.0;
        for (axis, [lo, hi]) in self.axes().iter().zip(self.extent) {
            let s = dot(*axis, p);
            let d = (f64::from(lo) - s).max(s - f64::from(hi)).max(0.0);
            d2 += d * d;
        }
        d2 * (1.0 - 1e-6)
    }

    /// The stored frame and extents, as they are (`f32`): `([u, v, n], extent)`.
    #[inline(always)]
    pub(super) fn frame(&self) -> ([[f32; 3]; 3], [[f32; 2]; 3]) {
        ([self.u, self.v, self.n], self.extent)
    }

    /// Sets the frame `u, n × u, n` and the box of `points` in it.
    fn fit<'a>(&mut self, u: V3, n: V3, points: impl Iterator<Item = &'a V3>) {
        self.u = u.map(|c| c as f32);
        self.n = n.map(|c| c as f32);
        self.v = cross(widen(self.n), widen(self.u)).map(|c| c as f32);
        let axes = self.axes();
        let mut extent = [[f64::INFINITY, f64::NEG_INFINITY]; 3];
        for v in points {
            for (axis, [lo, hi]) in axes.iter().zip(&mut extent) {
                let s = dot(*axis, *v);
                *lo = lo.min(s);
                *hi = hi.max(s);
            }
        }
        // Rounding in the projections must not lift the bound above a true distance.
        self.extent = extent.map(|[lo, hi]| {
            let pad = 1e-12 * (lo.abs().max(hi.abs()) + (hi - lo));
            [round_f32(lo - pad, true), round_f32(hi + pad, false)]
        });
    }
}

/// An axis-aligned box in `f32`, rounded outward.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Aabb {
    lo: [f32; 3],
    hi: [f32; 3],
}

impl Aabb {
    fn new(lo: V3, hi: V3) -> Aabb {
        Aabb {
            lo: lo.map(|c| round_f32(c, true)),
            hi: hi.map(|c| round_f32(c, false)),
        }
    }

    pub(super) fn lo(&self) -> V3 {
        widen(self.lo)
    }

    pub(super) fn hi(&self) -> V3 {
        widen(self.hi)
    }
}

pub(super) struct Bvh {
    pub nodes: Vec<Node>,
    /// Each node's aligned box (for box queries and construction; distance queries use
    /// `nodes`).
    pub boxes: Vec<Aabb>,
    /// The exact bounding box of all triangles.
    pub bounds: (V3, V3),
    /// The triangles in leaf order.
    pub triangles: Vec<Tri>,
    /// The largest `|x| + |y| + |z|` of the triangles' points: the scale of the rounding in
    /// `f32` box bounds.
    pub reach: f64,
}

#[derive(Clone, Copy)]
struct Item {
    centroid: [f32; 3],
    lo: [f32; 3],
    hi: [f32; 3],
    id: u32,
}

enum Built {
    /// A subtree built serially: preorder nodes whose interior `first` counts from the start
    /// of this list, leaf `first` from the start of the whole triangle list.
    Nodes(Vec<Node>),
    Split(Box<Built>, Box<Built>),
}

/// Builds the hierarchy over `triangles` (at least one, at most [`MAX_TRIANGLES`]).
pub(super) fn build(triangles: Vec<Tri>) -> Bvh {
    let (lo, hi) = triangles
        .par_iter()
        .map(|t| (min(min(t[0], t[1]), t[2]), max(max(t[0], t[1]), t[2])))
        .reduce(
            || ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
            |a, b| (min(a.0, b.0), max(a.1, b.1)),
        );
    let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    let inv = if extent > 0.0 { 1.0 / extent } else { 1.0 };
    let normal = |p: V3| -> [f32; 3] { std::array::from_fn(|a| ((p[a] - lo[a]) * inv) as f32) };
    let mut items: Vec<Item> = triangles
        .par_iter()
        .enumerate()
        .map(|(id, t)| {
            let [a, b, c] = t.map(normal);
            let lo = std::array::from_fn(|k| a[k].min(b[k]).min(c[k]));
            let hi = std::array::from_fn(|k| a[k].max(b[k]).max(c[k]));
            Item {
                centroid: std::array::from_fn(|k| (a[k] + b[k] + c[k]) / 3.0),
                lo,
                hi,
                id: id as u32,
            }
        })
        .collect();
    let built = subtree(&mut items, 0, 0);
    let mut nodes = Vec::with_capacity(items.len());
    flatten(built, &mut nodes);
    let ordered: Vec<Tri> = items
        .par_iter()
        .map(|it| triangles[it.id as usize])
        .collect();
    let boxes = fit_bounds(&mut nodes, &ordered);
    fit_oriented(&mut nodes, &ordered);
    Bvh {
        nodes,
        boxes,
        triangles: ordered,
        bounds: (lo, hi),
        reach: (0..3).map(|a| lo[a].abs().max(hi[a].abs())).sum(),
    }
}

fn subtree(items: &mut [Item], offset: usize, depth: usize) -> Built {
    if items.len() <= PARALLEL {
        let mut nodes = Vec::with_capacity(items.len());
        serial(items, offset, depth, &mut nodes);
        return Built::Nodes(nodes);
    }
    let mid = split(items, depth);
    let (left, right) = items.split_at_mut(mid);
    let (l, r) = rayon::join(
        || subtree(left, offset, depth + 1),
        || subtree(right, offset + mid, depth + 1),
    );
    Built::Split(Box::new(l), Box::new(r))
}

fn serial(items: &mut [Item], offset: usize, depth: usize, nodes: &mut Vec<Node>) {
    let me = nodes.len();
    if items.len() <= LEAF {
        nodes.push(Node::leaf(offset as u32, items.len() as u32));
        return;
    }
    nodes.push(Node::default());
    let mid = split(items, depth);
    let (left, right) = items.split_at_mut(mid);
    serial(left, offset, depth + 1, nodes);
    let second = nodes.len() as u32;
    nodes[me].set_first(second);
    serial(right, offset + mid, depth + 1, nodes);
}

fn flatten(built: Built, nodes: &mut Vec<Node>) {
    match built {
        Built::Nodes(list) => {
            let base = nodes.len() as u32;
            nodes.extend(list.into_iter().map(|mut n| {
                if !n.is_leaf() {
                    n.set_first(n.first() + base);
                }
                n
            }));
        }
        Built::Split(l, r) => {
            let me = nodes.len();
            nodes.push(Node::default());
            flatten(*l, nodes);
            let second = nodes.len() as u32;
            nodes[me].set_first(second);
            flatten(*r, nodes);
        }
    }
}

fn area(lo: [f32; 3], hi: [f32; 3]) -> f32 {
    let d: [f32; 3] = std::array::from_fn(|a| (hi[a] - lo[a]).max(0.0));
    d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
}

/// Partitions `items` (more than one) into two non-empty parts and returns the size of the
/// first.
fn split(items: &mut [Item], depth: usize) -> usize {
    let n = items.len();
    let (clo, chi) = items.iter().fold(
        ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
        |(lo, hi), it| {
            (
                std::array::from_fn(|a| lo[a].min(it.centroid[a])),
                std::array::from_fn(|a| hi[a].max(it.centroid[a])),
            )
        },
    );
    let axis = (0..3)
        .max_by(|&a, &b| (chi[a] - clo[a]).total_cmp(&(chi[b] - clo[b])))
        .unwrap_or(0);
    let extent = chi[axis] - clo[axis];
    let median = |items: &mut [Item]| {
        items.select_nth_unstable_by(n / 2, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
        n / 2
    };
    if depth >= MEDIAN_DEPTH || extent.is_nan() || extent <= 0.0 {
        return median(items);
    }
    let to_bin = BINS as f32 / extent;
    let bin = |it: &Item| (((it.centroid[axis] - clo[axis]) * to_bin) as usize).min(BINS - 1);
    let mut counts = [0usize; BINS];
    let mut bounds = [([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]); BINS];
    for it in items.iter() {
        let b = bin(it);
        counts[b] += 1;
        let (lo, hi) = &mut bounds[b];
        for a in 0..3 {
            lo[a] = lo[a].min(it.lo[a]);
            hi[a] = hi[a].max(it.hi[a]);
        }
    }
    // Cost of splitting after bin i: area·count on each side.
    let mut right_cost = [0.0f32; BINS];
    let (mut lo, mut hi, mut count) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3], 0);
    for i in (1..BINS).rev() {
        lo = std::array::from_fn(|a| lo[a].min(bounds[i].0[a]));
        hi = std::array::from_fn(|a| hi[a].max(bounds[i].1[a]));
        count += counts[i];
        right_cost[i] = area(lo, hi) * count as f32;
    }
    let (mut lo, mut hi, mut count) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3], 0);
    let mut best = (f32::INFINITY, usize::MAX);
    for i in 0..BINS - 1 {
        lo = std::array::from_fn(|a| lo[a].min(bounds[i].0[a]));
        hi = std::array::from_fn(|a| hi[a].max(bounds[i].1[a]));
        count += counts[i];
        if count == 0 || count == n {
            continue;
        }
        let cost = area(lo, hi) * count as f32 + right_cost[i + 1];
        if cost < best.0 {
            best = (cost, i);
        }
    }
    if best.1 == usize::MAX {
        return median(items);
    }
    let mut mid = 0;
    for k in 0..n {
        if bin(&items[k]) <= best.1 {
            items.swap(k, mid);
            mid += 1;
        }
    }
    mid
}

/// Exact `f64` bounds, children before parents.
/// Exact aligned boxes, children before parents; every node starts with its aligned box in
/// the axis frame.
fn fit_bounds(nodes: &mut [Node], triangles: &[Tri]) -> Vec<Aabb> {
    let mut exact = vec![([0.0; 3], [0.0; 3]); nodes.len()];
    for i in (0..nodes.len()).rev() {
        let node = nodes[i];
        exact[i] = if node.is_leaf() {
            let tris = &triangles[node.first() as usize..(node.first() + node.count()) as usize];
            tris.iter().fold(
                ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
                |(lo, hi), t| {
                    (
                        min(min(min(lo, t[0]), t[1]), t[2]),
                        max(max(max(hi, t[0]), t[1]), t[2]),
                    )
                },
            )
        } else {
            let (l, r) = (exact[i + 1], exact[node.first() as usize]);
            (min(l.0, r.0), max(l.1, r.1))
        };
    }
    nodes
        .par_iter_mut()
        .zip(&exact)
        .map(|(node, &(lo, hi))| {
            node.fit([1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [lo, hi].iter());
            Aabb::new(lo, hi)
        })
        .collect()
}

/// Nodes above this many triangles get no oriented box: a large patch is too curved for one
/// to be much tighter than the aligned box, and skipping them keeps the cost near
/// `O(n log OBB_MAX)`.
const OBB_MAX: u32 = 1 << 12;

/// Oriented boxes along each node's mean normal, tight around its triangles.
///
/// Why: far from a finely tessellated smooth surface, the aligned boxes of many leaves come
/// within the nearest distance plus a box width, and a nearest-triangle search must open them
/// all: a cap of the surface whose area grows with the distance times the box size. A patch's
/// oriented box is a thin plate hugging it (thickness: patch size squared over curvature
/// radius), so its distance bound is nearly the patch's own, and only true near ties are
/// opened.
fn fit_oriented(nodes: &mut [Node], triangles: &[Tri]) {
    let mut range = vec![(0u32, 0u32); nodes.len()];
    let mut area = vec![[0.0; 3]; nodes.len()];
    for i in (0..nodes.len()).rev() {
        let node = nodes[i];
        if node.is_leaf() {
            range[i] = (node.first(), node.first() + node.count());
            area[i] = triangles[node.first() as usize..(node.first() + node.count()) as usize]
                .iter()
                .fold([0.0; 3], |a, t| {
                    add(a, cross(sub(t[1], t[0]), sub(t[2], t[0])))
                });
        } else {
            let (l, r) = (i + 1, node.first() as usize);
            range[i] = (range[l].0, range[r].1);
            area[i] = add(area[l], area[r]);
        }
    }
    nodes.par_iter_mut().enumerate().for_each(|(i, node)| {
        let (start, end) = range[i];
        let len = norm(area[i]);
        if end - start > OBB_MAX || !(len > 0.0 && len.is_finite()) {
            return;
        }
        let n = scale(area[i], 1.0 / len);
        // Any unit vector across n: cross with the axis n is least along.
        let axis = (0..3)
            .min_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
            .unwrap_or(0);
        let mut e = [0.0; 3];
        e[axis] = 1.0;
        let u = cross(n, e);
        let u = scale(u, 1.0 / norm(u));
        node.fit(
            u,
            n,
            triangles[start as usize..end as usize].iter().flatten(),
        );
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(bvh: &Bvh, i: usize, depth: usize, seen: &mut Vec<bool>) {
        assert!(depth <= MAX_DEPTH);
        let n = bvh.nodes[i];
        if n.is_leaf() {
            assert!((1..=LEAF as u32).contains(&n.count()));
            for t in &bvh.triangles[n.first() as usize..(n.first() + n.count()) as usize] {
                for p in t {
                    let b = bvh.boxes[i];
                    assert!((0..3).all(|a| b.lo()[a] <= p[a] && p[a] <= b.hi()[a]));
                    assert!(n.dist2(*p) < 1e-20);
                }
            }
            for s in n.first()..n.first() + n.count() {
                assert!(!seen[s as usize], "triangle {s} in two leaves");
                seen[s as usize] = true;
            }
        } else {
            for c in [i + 1, n.first() as usize] {
                assert!(c > i);
                let (b, cb) = (bvh.boxes[i], bvh.boxes[c]);
                assert!((0..3).all(|a| b.lo()[a] <= cb.lo()[a] && cb.hi()[a] <= b.hi()[a]));
                check(bvh, c, depth + 1, seen);
            }
        }
    }

    fn triangles(n: usize, spread: impl Fn(usize) -> f64) -> Vec<Tri> {
        (0..n)
            .map(|i| {
                let x = spread(i);
                [[x, 0.0, 0.0], [x + 0.5, 1.0, 0.0], [x, 0.0, 1.0]]
            })
            .collect()
    }

    #[test]
    fn every_triangle_sits_in_one_leaf_inside_every_ancestor_box() {
        // Uniform, exponentially spread (deep SAH trees) and all-equal centroids.
        for tris in [
            triangles(20_000, |i| i as f64),
            triangles(3000, |i| 1.01f64.powi(i as i32)),
            triangles(100, |_| 1.0),
        ] {
            let n = tris.len();
            let bvh = build(tris);
            let mut seen = vec![false; n];
            check(&bvh, 0, 0, &mut seen);
            assert!(seen.iter().all(|&s| s));
        }
    }
}
