//! The tetrahedron's lattice: points with barycentric coordinates `a/m` (`a ∈ ℕ⁴`,
//! `Σ a = m`), i.e. `ξ = Σ a_i p_i / m` over the vertices `p_i` of
//! docs/method.md §Reference elements, contoured by marching
//! tetrahedra over the standard subdivision of the tetrahedron into `m³` small cells (upward
//! tetrahedra, octahedra split into four along one diagonal, downward tetrahedra).
//!
//! Why this lattice and not the corner grid of [`crate::element`]: it is invariant under all of
//! Td (S4 on the barycentric coordinates), so the samples on a face are the same set of points,
//! with the same values, whichever neighbour looks at it. The subdivision cuts every face into
//! the standard triangular grid, whatever diagonals are chosen inside, so two elements sharing a
//! face draw the same segments on it; marching tetrahedra has no ambiguous cases.
//!
//! Indices are dense over `(u, v, w) = (a1, a2, a3)` in `[0, m]³` (the points with
//! `u + v + w ≤ m` are used). Corner `i` is the point with `a_i = m`; face `i` is opposite
//! corner `i`.

use super::lattice::{Lattice, Weights};
use super::local::{LocalBuilder, LocalMesh, Samples, band_state, band_triangle_walk, inside};

pub struct TetLattice {
    /// Cells per edge.
    m: u32,
}

type P3 = [f64; 3];

impl TetLattice {
    /// `n ≥ 2` points per edge.
    pub fn new(n: usize) -> TetLattice {
        TetLattice { m: n as u32 - 1 }
    }

    #[inline]
    fn index(&self, [u, v, w]: [u32; 3]) -> u32 {
        let n = self.m + 1;
        u + n * (v + n * w)
    }

    #[inline]
    fn coords(&self, p: u32) -> [u32; 3] {
        let n = self.m + 1;
        [p % n, (p / n) % n, p / (n * n)]
    }

    /// Barycentric integers `(a0, a1, a2, a3)` of a valid point.
    #[inline]
    fn barycentric(&self, p: u32) -> [u32; 4] {
        let [u, v, w] = self.coords(p);
        [self.m - u - v - w, u, v, w]
    }

    fn barycentric_index(&self, a: [u32; 4]) -> u32 {
        self.index([a[1], a[2], a[3]])
    }

    fn position(&self, p: u32) -> P3 {
        self.coords(p).map(f64::from)
    }
}

impl Lattice for TetLattice {
    fn index_len(&self) -> usize {
        (self.m as usize + 1).pow(3)
    }

    fn is_point(&self, p: u32) -> bool {
        (p as usize) < self.index_len() && self.coords(p).iter().sum::<u32>() <= self.m
    }

    fn xi(&self, p: u32) -> [f64; 3] {
        let m = f64::from(self.m);
        let [u, v, w] = self.coords(p).map(|c| f64::from(c) / m);
        crate::element::tetrahedron_point([u, v, w])
    }

    fn representative(&self, p: u32) -> u32 {
        let mut a = self.barycentric(p);
        a.sort_unstable_by(|x, y| y.cmp(x));
        self.barycentric_index(a)
    }

    fn weights(&self, p: u32) -> Weights {
        Weights::barycentric(&self.barycentric(p))
    }

    fn face_masks(&self) -> &[u8] {
        &[0b1110, 0b1101, 0b1011, 0b0111]
    }

    fn takes_bands(&self) -> bool {
        true
    }

    fn contour(&self, samples: Samples) -> LocalMesh {
        let mut builder = LocalBuilder::new(samples, 4);
        let m = self.m;
        for w in 0..m {
            for v in 0..m - w {
                for u in 0..m - w - v {
                    let s = u + v + w;
                    let at = |du: u32, dv: u32, dw: u32| self.index([u + du, v + dv, w + dw]);
                    self.march(
                        &mut builder,
                        [at(0, 0, 0), at(1, 0, 0), at(0, 1, 0), at(0, 0, 1)],
                    );
                    if s + 2 <= m {
                        // The octahedron, split around its diagonal A–D into four tetrahedra
                        // over the cycle B, F, E, C of its other vertices.
                        let (a, d) = (at(1, 0, 0), at(0, 1, 1));
                        let ring = [at(0, 1, 0), at(1, 1, 0), at(1, 0, 1), at(0, 0, 1)];
                        for r in 0..4 {
                            self.march(&mut builder, [a, d, ring[r], ring[(r + 1) % 4]]);
                        }
                    }
                    if s + 3 <= m {
                        self.march(
                            &mut builder,
                            [at(1, 1, 0), at(1, 0, 1), at(0, 1, 1), at(1, 1, 1)],
                        );
                    }
                }
            }
        }
        for face in 0..4 {
            self.cap_face(&mut builder, face);
        }
        builder.finish()
    }
}

impl TetLattice {
    /// Marching tetrahedra on one small tetrahedron `q`, for each level of the samples.
    fn march(&self, builder: &mut LocalBuilder, q: [u32; 4]) {
        let samples = builder.samples();
        self.march_level(builder, q, samples.lower, false);
        if let Some(upper) = samples.upper {
            self.march_level(builder, q, upper, true);
        }
    }

    /// Marching tetrahedra of one level (negative inside), oriented by positions in lattice
    /// coordinates (an orientation-preserving affine image of ξ). A band's two levels each
    /// bound their own side of the band, so neither is reversed.
    fn march_level(&self, builder: &mut LocalBuilder, q: [u32; 4], level: &[f64], upper: bool) {
        let values = q.map(|p| level[p as usize]);
        let ins: Vec<usize> = (0..4).filter(|&i| inside(values[i])).collect();
        let outs: Vec<usize> = (0..4).filter(|&i| !inside(values[i])).collect();
        let pos = q.map(|p| self.position(p));
        match ins.len() {
            1 | 3 => {
                // One corner alone on its side: a triangle on its three edges.
                let (lone, others, lone_inside) = if ins.len() == 1 {
                    (ins[0], &outs, true)
                } else {
                    (outs[0], &ins, false)
                };
                let tri = [0, 1, 2].map(|k| (lone, others[k]));
                let centroid = mean(&others.iter().map(|&o| pos[o]).collect::<Vec<_>>());
                let (from, to) = if lone_inside {
                    (pos[lone], centroid)
                } else {
                    (centroid, pos[lone])
                };
                self.emit(builder, &q, &pos, tri, [from, to], upper);
            }
            2 => {
                let (a, b, c, d) = (ins[0], ins[1], outs[0], outs[1]);
                let from = mean(&[pos[a], pos[b]]);
                let to = mean(&[pos[c], pos[d]]);
                self.emit(
                    builder,
                    &q,
                    &pos,
                    [(a, c), (a, d), (b, d)],
                    [from, to],
                    upper,
                );
                self.emit(
                    builder,
                    &q,
                    &pos,
                    [(a, c), (b, d), (b, c)],
                    [from, to],
                    upper,
                );
            }
            _ => {}
        }
    }

    /// Emits the triangle on the edges `tri` of `q`, turned so its normal points `from → to`,
    /// on the crossings of the lower (or only) level or, `upper`, a band's upper level.
    fn emit(
        &self,
        builder: &mut LocalBuilder,
        q: &[u32; 4],
        pos: &[P3; 4],
        mut tri: [(usize, usize); 3],
        [from, to]: [P3; 2],
        upper: bool,
    ) {
        let mid = |(i, j): (usize, usize)| mean(&[pos[i], pos[j]]);
        let [p0, p1, p2] = tri.map(mid);
        if det(sub(p1, p0), sub(p2, p0), sub(to, from)) < 0.0 {
            tri.swap(1, 2);
        }
        let ids = tri.map(|(i, j)| builder.level_crossing(q[i], q[j], upper));
        builder.mesh.triangles.push(ids);
    }

    /// The inside part of face `face` by marching triangles over its triangular grid, turned
    /// outward.
    fn cap_face(&self, builder: &mut LocalBuilder, face: usize) {
        let m = self.m;
        let corners: Vec<usize> = (0..4).filter(|&c| c != face).collect();
        let point = |i: u32, j: u32| {
            let mut a = [0u32; 4];
            a[corners[0]] = m - i - j;
            a[corners[1]] = i;
            a[corners[2]] = j;
            self.barycentric_index(a)
        };
        let opposite = {
            let mut a = [0u32; 4];
            a[face] = m;
            self.position(self.barycentric_index(a))
        };
        let centroid = mean(
            &corners
                .iter()
                .map(|&c| {
                    let mut a = [0u32; 4];
                    a[c] = m;
                    self.position(self.barycentric_index(a))
                })
                .collect::<Vec<_>>(),
        );
        let outward = sub(centroid, opposite);
        let mut small = Vec::new();
        for j in 0..m {
            for i in 0..m - j {
                small.push([point(i, j), point(i + 1, j), point(i, j + 1)]);
                if i + j + 2 <= m {
                    small.push([point(i + 1, j), point(i + 1, j + 1), point(i, j + 1)]);
                }
            }
        }
        for tri in small {
            self.cap_triangle(builder, face, tri, outward);
        }
    }

    /// The solid's part of one small triangle `tri` of a face: its inside corners and
    /// crossings in cyclic order (for a band, the between corners and both levels'
    /// crossings), a convex polygon fanned and turned outward.
    fn cap_triangle(&self, builder: &mut LocalBuilder, face: usize, tri: [u32; 3], outward: P3) {
        let samples = builder.samples();
        // (p, q, upper): a crossing of edge p–q, or the point p when p == q.
        let mut polygon: Vec<(u32, u32, bool)> = Vec::with_capacity(7);
        match samples.upper {
            None => {
                let ins = tri.map(|p| inside(samples.lower[p as usize]));
                for k in 0..3 {
                    let (p, q) = (tri[k], tri[(k + 1) % 3]);
                    if ins[k] {
                        polygon.push((p, p, false));
                    }
                    if ins[k] != ins[(k + 1) % 3] {
                        polygon.push((p, q, false));
                    }
                }
            }
            Some(upper) => {
                let state = tri.map(|p| band_state(samples.lower, upper, p as usize));
                band_triangle_walk(state, |k, level| {
                    let (p, q) = (tri[k], tri[(k + 1) % 3]);
                    polygon.push(match level {
                        None => (p, p, false),
                        Some(upper) => (p, q, upper),
                    });
                });
            }
        }
        if polygon.len() < 3 {
            return;
        }
        // The polygon runs around `tri` in its order: `tri`'s own orientation decides.
        let [p0, p1, p2] = tri.map(|p| self.position(p));
        let flip = det(sub(p1, p0), sub(p2, p0), outward) < 0.0;
        let ids: Vec<u32> = polygon
            .iter()
            .map(|&(p, q, upper)| {
                if p == q {
                    builder.point(p)
                } else {
                    builder.level_crossing(p, q, upper)
                }
            })
            .collect();
        for k in 1..ids.len() - 1 {
            let t = if flip {
                [ids[0], ids[k + 1], ids[k]]
            } else {
                [ids[0], ids[k], ids[k + 1]]
            };
            builder.mesh.caps[face].push(t);
        }
    }
}

fn mean(points: &[P3]) -> P3 {
    let n = points.len() as f64;
    let mut s = [0.0; 3];
    for p in points {
        for a in 0..3 {
            s[a] += p[a];
        }
    }
    s.map(|c| c / n)
}

fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn det(a: P3, b: P3, c: P3) -> f64 {
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
}
