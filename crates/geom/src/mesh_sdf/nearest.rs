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
//!
//! The search is branch and bound over the BVH, and its time goes into box tests (about 30
//! node visits per point on the benchmark torus, each testing both children) and waiting for
//! nodes from memory (the tree of a million triangles is far larger than the caches): so a
//! [`Search`] serves [`LANES`] neighbouring points with one node load and one SIMD box test,
//! orders and pushes children without branches, prefetches what its next visit reads, and
//! the grid sampler interleaves several searches ([`nearest_many`]) so that their loads
//! overlap. Eight lanes (two registers) opened 15 % fewer nodes per point but cost more
//! than they saved. None of this changes a value: a result is the exact minimum of the `f64`
//! distances over all triangles (the test compares it bit for bit with an exhaustive
//! search).

use super::bvh::{Bvh, MAX_DEPTH, Node};
use super::lanes::F4;
use super::prepare::Tri;
use crate::vec3::{V3, cross, dot, sub};

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

/// `x` as `f32`, rounded up.
#[inline(always)]
fn up(x: f64) -> f32 {
    let r = x as f32;
    if f64::from(r) < x { r.next_up() } else { r }
}

/// Points searched together by one [`Search`]: neighbours in a grid column, whose searches
/// open mostly the same nodes. One `f32` SIMD register ([`F4`]) holds a bound for each.
pub(super) use super::lanes::LANES;

/// A node waiting on a search's stack: its index, what its visit reads (`first`, `count` as
/// in [`Node`]), and its distance bound for each lane.
#[derive(Clone, Copy)]
struct Entry {
    index: u32,
    first: u32,
    count: u32,
    bound: F4,
}

/// Asks for the memory that visiting `entry` will read: both children, or its triangles.
/// Needs nothing from the node itself, so it never waits.
#[inline(always)]
fn prefetch(bvh: &Bvh, entry: &Entry) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // SAFETY: a prefetch is a hint that never faults, whatever the address.
        unsafe {
            if entry.count > 0 {
                let t: *const i8 = bvh
                    .triangles
                    .as_ptr()
                    .wrapping_add(entry.first as usize)
                    .cast();
                // Every line from the first byte to the last, without a loop: a leaf's triangles
                // span at most four lines (the last prefetch repeats one for a single triangle).
                const _: () = assert!(super::bvh::LEAF * std::mem::size_of::<Tri>() <= 3 * 64 + 1);
                let last = entry.count as usize * std::mem::size_of::<Tri>() - 1;
                _mm_prefetch(t, _MM_HINT_T0);
                _mm_prefetch(t.wrapping_add(64), _MM_HINT_T0);
                _mm_prefetch(t.wrapping_add(last.min(128)), _MM_HINT_T0);
                _mm_prefetch(t.wrapping_add(last), _MM_HINT_T0);
            } else {
                let n = bvh.nodes.as_ptr();
                _mm_prefetch(n.wrapping_add(entry.index as usize + 1).cast(), _MM_HINT_T0);
                _mm_prefetch(n.wrapping_add(entry.first as usize).cast(), _MM_HINT_T0);
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (bvh, entry);
}

/// The lanes' points in `f32`, and the slack that covers their rounding.
#[derive(Clone, Copy)]
struct Points {
    x: F4,
    y: F4,
    z: F4,
    slack: f32,
}

/// Lower bounds on the squared distances from the lanes' points to `node`'s triangles.
#[inline(always)]
fn lower_bounds(node: &Node, q: &Points) -> F4 {
    let (axes, extent) = node.frame();
    let mut acc = F4::splat(0.0);
    for (a, [lo, hi]) in axes.iter().zip(extent) {
        let s = F4::splat(a[0]) * q.x + F4::splat(a[1]) * q.y + F4::splat(a[2]) * q.z;
        let below = F4::splat(lo - q.slack) - s;
        let above = s - F4::splat(hi + q.slack);
        let d = below.max(above).max(F4::splat(0.0));
        acc = acc + d * d;
    }
    acc * F4::splat(1.0 - 1e-5)
}

/// Nearest-triangle searches for up to [`LANES`] points at once, advanced a node at a time
/// so that several can be interleaved ([`nearest_many`]).
///
/// One node load serves every lane, and its box is tested against all lanes in one SIMD
/// pass. Box bounds are computed in `f32`: points are rounded to `f32`, every extent is
/// widened by a slack of 32 ulps of the largest coordinate sum in play (the rounding of the
/// points, of the widened extents and of the projections is below 8), and squared sums are
/// shrunk by 1e-5 relative (rounding of the squares, near-orthonormality of the stored
/// frame). A lane is pruned only against its own best squared distance rounded up to `f32`.
/// So bounds never exceed true distances, and each lane's result is the exact minimum of the
/// `f64` point–triangle distances over all triangles (which of exactly tied triangles it
/// names may depend on its neighbours). Unused lanes have a best of −∞: never open.
pub(super) struct Search {
    p: [V3; LANES],
    q: Points,
    best2: [f64; LANES],
    best_up: [f32; LANES],
    best: [Option<u32>; LANES],
    /// `stack[..top]` waits, the next to visit last. A visit replaces one entry by at most
    /// two children, so it never holds more than a root-to-leaf path's length plus one.
    stack: Vec<Entry>,
    top: usize,
}

impl Default for Search {
    fn default() -> Search {
        Search {
            p: [[0.0; 3]; LANES],
            q: Points {
                x: F4::splat(0.0),
                y: F4::splat(0.0),
                z: F4::splat(0.0),
                slack: 0.0,
            },
            best2: [0.0; LANES],
            best_up: [f32::NEG_INFINITY; LANES],
            best: [None; LANES],
            stack: vec![
                Entry {
                    index: 0,
                    first: 0,
                    count: 0,
                    bound: F4::splat(f32::INFINITY),
                };
                MAX_DEPTH + 2
            ],
            top: 0,
        }
    }
}

impl Search {
    /// Starts searches for the nearest triangles to `points` (at most [`LANES`]) closer
    /// than `sqrt(bound2)`; `hints[i]`, a triangle likely to be near point `i` (its previous
    /// neighbour's answer), tightens its bound first.
    pub(super) fn start(&mut self, bvh: &Bvh, points: &[V3], hints: &[Option<u32>], bound2: f64) {
        debug_assert!(points.len() <= LANES && hints.len() == points.len());
        self.best_up = [f32::NEG_INFINITY; LANES];
        let mut reach = bvh.reach;
        let mut q = [[0.0f32; LANES]; 3];
        for (i, (&p, &hint)) in points.iter().zip(hints).enumerate() {
            self.p[i] = p;
            self.best2[i] = bound2;
            self.best[i] = None;
            if let Some(h) = hint {
                let d2 = triangle_dist2(&bvh.triangles[h as usize], p);
                if d2 < bound2 {
                    self.best2[i] = d2;
                    self.best[i] = Some(h);
                }
            }
            // A NaN point's lane is closed at once: its bounds would be meaningless.
            if !p.iter().any(|c| c.is_nan()) {
                self.best_up[i] = up(self.best2[i]);
            }
            for a in 0..3 {
                q[a][i] = p[a] as f32;
            }
            reach = reach.max(p[0].abs() + p[1].abs() + p[2].abs() + bvh.reach);
        }
        self.q.x = F4::new(q[0]);
        self.q.y = F4::new(q[1]);
        self.q.z = F4::new(q[2]);
        self.q.slack = (32.0 * f64::from(f32::EPSILON) * reach) as f32;
        let root = &bvh.nodes[0];
        let entry = Entry {
            index: 0,
            first: root.first(),
            count: root.count(),
            bound: lower_bounds(root, &self.q),
        };
        self.top = 0;
        if entry.bound.lt_mask(F4::load(&self.best_up)) != 0 {
            self.stack[0] = entry;
            self.top = 1;
            prefetch(bvh, &entry);
        }
    }

    /// Lane `i`'s result: the squared distance and index in `bvh.triangles` of the nearest
    /// triangle, or `(bound2, None)` when none is closer than the bound.
    pub(super) fn result(&self, i: usize) -> (f64, Option<u32>) {
        (self.best2[i], self.best[i])
    }

    /// Visits one node; false once the search is over.
    #[inline(always)]
    fn step(&mut self, bvh: &Bvh) -> bool {
        if self.top == 0 {
            return false;
        }
        self.top -= 1;
        let entry = self.stack[self.top];
        if entry.bound.lt_mask(F4::load(&self.best_up)) != 0 {
            self.visit(bvh, entry);
        }
        // By the time this search steps again, what its next visit reads is on its way.
        if self.top > 0 {
            prefetch(bvh, &self.stack[self.top - 1]);
        }
        true
    }

    #[inline(always)]
    fn visit(&mut self, bvh: &Bvh, entry: Entry) {
        if entry.count > 0 {
            for k in entry.first..entry.first + entry.count {
                let t = &bvh.triangles[k as usize];
                let mut open = entry.bound.lt_mask(F4::load(&self.best_up));
                while open != 0 {
                    let i = open.trailing_zeros() as usize;
                    open &= open - 1;
                    let d2 = triangle_dist2(t, self.p[i]);
                    if d2 < self.best2[i] {
                        self.best2[i] = d2;
                        self.best[i] = Some(k);
                        self.best_up[i] = up(d2);
                    }
                }
            }
            return;
        }
        let child = |index: u32| {
            let node = &bvh.nodes[index as usize];
            Entry {
                index,
                first: node.first(),
                count: node.count(),
                bound: lower_bounds(node, &self.q),
            }
        };
        let (l, r) = (child(entry.index + 1), child(entry.first));
        let best = F4::load(&self.best_up);
        let (nl, nr) = (l.bound.min_where_lt(best), r.bound.min_where_lt(best));
        // Visit the nearer child first: push it last. Written without branches on the
        // bounds, which are unpredictable: the order by field-wise selects (copying whole
        // entries through memory stalled on store forwarding), and a closed child is written
        // and not counted.
        let swap = nr < nl;
        let pick = |a: &Entry, b: &Entry| Entry {
            index: if swap { a.index } else { b.index },
            first: if swap { a.first } else { b.first },
            count: if swap { a.count } else { b.count },
            bound: F4::select(swap, a.bound, b.bound),
        };
        let (near, far) = (pick(&r, &l), pick(&l, &r));
        self.stack[self.top] = far;
        self.top += usize::from(nl.max(nr) < f32::INFINITY);
        self.stack[self.top] = near;
        self.top += usize::from(nl.min(nr) < f32::INFINITY);
    }
}

/// Runs `searches` (each [`Search::start`]ed) to the end, a node of each in turn: the
/// searches are independent, so their memory loads overlap instead of waiting in line.
pub(super) fn nearest_many(bvh: &Bvh, searches: &mut [Search]) {
    let mut running = searches.len();
    while running > 0 {
        running = 0;
        for s in searches.iter_mut() {
            running += usize::from(s.step(bvh));
        }
    }
}

/// The nearest triangle to `p` closer than `sqrt(bound2)` ([`Search`]), alone.
pub(super) fn nearest(
    bvh: &Bvh,
    p: V3,
    hint: Option<u32>,
    bound2: f64,
    search: &mut Search,
) -> (f64, Option<u32>) {
    search.start(bvh, &[p], &[hint], bound2);
    while search.step(bvh) {}
    search.result(0)
}

/// Whether some triangle's bounding box meets the box `[lo, hi]`: a cheap, conservative test
/// that a segment with these bounds crosses no triangle.
pub(super) fn any_box_overlap(bvh: &Bvh, lo: V3, hi: V3) -> bool {
    box_overlaps(bvh, lo, hi, |_| true)
}

/// Calls `found` with the index (in `bvh.triangles`) of every triangle whose bounding box
/// meets the box `[lo, hi]`, in a fixed order.
pub(super) fn for_each_box_overlap(bvh: &Bvh, lo: V3, hi: V3, mut found: impl FnMut(u32)) {
    box_overlaps(bvh, lo, hi, |t| {
        found(t);
        false
    });
}

/// Visits the triangles whose boxes meet `[lo, hi]` until `stop` says so; whether it did.
#[inline]
fn box_overlaps(bvh: &Bvh, lo: V3, hi: V3, mut stop: impl FnMut(u32) -> bool) -> bool {
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
            let first = node.first();
            for (k, t) in bvh.triangles[first as usize..(first + node.count()) as usize]
                .iter()
                .enumerate()
            {
                let tlo = std::array::from_fn(|k| t[0][k].min(t[1][k]).min(t[2][k]));
                let thi = std::array::from_fn(|k| t[0][k].max(t[1][k]).max(t[2][k]));
                if overlaps(tlo, thi) && stop(first + k as u32) {
                    return true;
                }
            }
        } else {
            stack[top] = node.first();
            stack[top + 1] = i + 1;
            top += 2;
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::super::bvh::build;
    use super::*;

    /// A small deterministic generator (no dependency for tests).
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// A smooth closed surface (a bumpy sphere) of about `2 n²` triangles, centred at `centre`:
    /// many near ties for points far away, and leaves with oriented boxes.
    fn bumpy_sphere(n: usize, centre: V3, radius: f64) -> Vec<Tri> {
        let point = |i: usize, j: usize| {
            let (theta, phi) = (
                std::f64::consts::PI * i as f64 / n as f64,
                std::f64::consts::TAU * j as f64 / n as f64,
            );
            let r = radius * (1.0 + 0.05 * (3.0 * phi).sin() * theta.sin());
            [
                centre[0] + r * theta.sin() * phi.cos(),
                centre[1] + r * theta.sin() * phi.sin(),
                centre[2] + r * theta.cos(),
            ]
        };
        let mut tris = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let (a, b, c, d) = (
                    point(i, j),
                    point(i + 1, j),
                    point(i + 1, j + 1),
                    point(i, j + 1),
                );
                tris.push([a, b, c]);
                tris.push([a, c, d]);
            }
        }
        tris
    }

    /// Every search — alone, in lanes, interleaved, with good, bad and no hints, with and
    /// without a bound — finds exactly the least distance over all triangles, also far from
    /// the origin where the `f32` boxes round coarsely.
    #[test]
    fn searches_find_the_exhaustive_minimum_bit_for_bit() {
        let mut rng = Lcg(7);
        for centre in [[0.0; 3], [1000.0, -2000.0, 500.0]] {
            let tris = bumpy_sphere(40, centre, 1.0);
            let bvh = build(tris);
            let exhaustive = |p: V3| {
                bvh.triangles
                    .iter()
                    .map(|t| triangle_dist2(t, p))
                    .fold(f64::INFINITY, f64::min)
            };
            let points: Vec<V3> = (0..203)
                .map(|_| std::array::from_fn(|a| centre[a] + 4.0 * rng.next() - 2.0))
                .collect();
            let expected: Vec<f64> = points.iter().map(|&p| exhaustive(p)).collect();
            let mut alone = Search::default();
            for (k, &p) in points.iter().enumerate() {
                let hint = Some((k * 37 % bvh.triangles.len()) as u32);
                for h in [None, hint] {
                    let (d2, t) = nearest(&bvh, p, h, f64::INFINITY, &mut alone);
                    assert_eq!(d2.to_bits(), expected[k].to_bits(), "point {p:?}");
                    let t = t.expect("a nearest triangle");
                    assert_eq!(triangle_dist2(&bvh.triangles[t as usize], p), d2);
                }
                // Bounded: the same when the minimum is inside the bound, none otherwise.
                let bound2 = 0.25;
                let (d2, t) = nearest(&bvh, p, None, bound2, &mut alone);
                if expected[k] < bound2 {
                    assert_eq!((d2.to_bits(), t.is_some()), (expected[k].to_bits(), true));
                } else {
                    assert_eq!((d2, t), (bound2, None));
                }
            }
            // Lanes of neighbouring points (partly filled at the end), interleaved.
            let mut searches: Vec<Search> = (0..5).map(|_| Search::default()).collect();
            for group in points.chunks(LANES * searches.len()) {
                let lanes: Vec<&[V3]> = group.chunks(LANES).collect();
                for (search, pts) in searches.iter_mut().zip(&lanes) {
                    let hints: Vec<Option<u32>> = pts.iter().map(|_| Some(0)).collect();
                    search.start(&bvh, pts, &hints, f64::INFINITY);
                }
                nearest_many(&bvh, &mut searches[..lanes.len()]);
                for (s, pts) in searches.iter().zip(&lanes) {
                    for (i, &p) in pts.iter().enumerate() {
                        assert_eq!(s.result(i).0.to_bits(), exhaustive(p).to_bits());
                    }
                }
            }
        }
    }
}
