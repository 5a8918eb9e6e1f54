//! Generated meshes as `f64` soups with their analytic solids (exact signed distances), and a
//! small seeded RNG: the fixtures of the crate's tests and benchmarks, which measure the mesh
//! readers and the mesh SDF against known answers. The tool itself never uses them.
//! Every mesh winds counter-clockwise seen from outside.

use crate::mesh_read::TriangleSoup;
use std::collections::HashMap;
use std::f64::consts::TAU;

/// A deterministic generator (SplitMix64), so failures reproduce.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    pub fn point(&mut self, lo: f64, hi: f64) -> [f64; 3] {
        [self.range(lo, hi), self.range(lo, hi), self.range(lo, hi)]
    }

    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

pub fn norm(p: [f64; 3]) -> f64 {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// An icosphere of `radius` about the origin: the icosahedron with each triangle split into 4,
/// `levels` times, vertices pushed onto the sphere (20·4^levels triangles).
pub fn icosphere(levels: u32, radius: f64) -> TriangleSoup {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut positions: Vec<[f64; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .to_vec();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<[f64; 3]>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (p, q) = (positions[a as usize], positions[b as usize]);
                positions.push([
                    (p[0] + q[0]) / 2.0,
                    (p[1] + q[1]) / 2.0,
                    (p[2] + q[2]) / 2.0,
                ]);
                positions.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(4 * triangles.len());
        for [a, b, c] in triangles {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = next;
    }
    for p in &mut positions {
        let s = radius / norm(*p);
        *p = p.map(|c| c * s);
    }
    // Outward: the normal points away from the centre.
    for t in &mut triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        if dot(cross(sub(b, a), sub(c, a)), a) < 0.0 {
            t.swap(1, 2);
        }
    }
    TriangleSoup {
        positions,
        triangles,
    }
}

/// The largest distance between the icosphere's triangles and its sphere: for a triangle
/// inscribed in a sphere of radius R with circumradius ρ, the plane lies at √(R² − ρ²) from
/// the centre, and the triangle's nearest point to the centre is in its interior for these
/// near-equilateral triangles.
pub fn chord_error(soup: &TriangleSoup, radius: f64) -> f64 {
    soup.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| soup.positions[i as usize]);
            let (la, lb, lc) = (norm(sub(b, c)), norm(sub(c, a)), norm(sub(a, b)));
            let area2 = norm(cross(sub(b, a), sub(c, a)));
            let rho = la * lb * lc / (2.0 * area2);
            radius - (radius * radius - rho * rho).max(0.0).sqrt()
        })
        .fold(0.0, f64::max)
}

/// A torus about the z axis: `n` segments around the axis, `m` around the tube.
pub fn torus(n: u32, m: u32, big_r: f64, r: f64) -> TriangleSoup {
    let mut positions = Vec::with_capacity((n * m) as usize);
    for i in 0..n {
        let theta = TAU * f64::from(i) / f64::from(n);
        for j in 0..m {
            let phi = TAU * f64::from(j) / f64::from(m);
            let rho = big_r + r * phi.cos();
            positions.push([rho * theta.cos(), rho * theta.sin(), r * phi.sin()]);
        }
    }
    let id = |i: u32, j: u32| (i % n) * m + (j % m);
    let mut triangles = Vec::with_capacity(2 * (n * m) as usize);
    for i in 0..n {
        for j in 0..m {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    TriangleSoup {
        positions,
        triangles,
    }
}

pub fn torus_sd(p: [f64; 3], big_r: f64, r: f64) -> f64 {
    let q = (p[0] * p[0] + p[1] * p[1]).sqrt() - big_r;
    (q * q + p[2] * p[2]).sqrt() - r
}

/// The longest edge of a soup: every point of a triangle is within it of a vertex.
pub fn longest_edge(soup: &TriangleSoup) -> f64 {
    soup.triangles
        .iter()
        .flat_map(|t| {
            (0..3).map(move |k| {
                norm(sub(
                    soup.positions[t[k] as usize],
                    soup.positions[t[(k + 1) % 3] as usize],
                ))
            })
        })
        .fold(0.0, f64::max)
}

/// The cube `[-h, h]³` with each face cut into slivers: along every edge of a face, a triangle
/// from the edge to a point `eps` inside the face (aspect ratio `1/eps`), and a fan from the
/// face centre filling the rest. The surface is exactly the cube.
pub fn sliver_cube(h: f64, eps: f64) -> TriangleSoup {
    let mut soup = TriangleSoup::default();
    let push = |p: [f64; 3], soup: &mut TriangleSoup| {
        soup.positions.push(p);
        soup.positions.len() as u32 - 1
    };
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let (mut u, mut v) = ((axis + 1) % 3, (axis + 2) % 3);
            if sign < 0.0 {
                std::mem::swap(&mut u, &mut v);
            }
            let at = |a: f64, b: f64| {
                let mut p = [0.0; 3];
                p[axis] = sign * h;
                p[u] = a;
                p[v] = b;
                p
            };
            let corners = [at(-h, -h), at(h, -h), at(h, h), at(-h, h)];
            let c: Vec<u32> = corners.iter().map(|&p| push(p, &mut soup)).collect();
            let center = push(at(0.0, 0.0), &mut soup);
            for k in 0..4 {
                let (p, q) = (corners[k], corners[(k + 1) % 4]);
                let m: [f64; 3] = std::array::from_fn(|a| {
                    // Midpoint, moved toward the face centre by eps.
                    let mid = (p[a] + q[a]) / 2.0;
                    if a == axis {
                        mid
                    } else {
                        mid - eps * mid.signum() * (mid.abs() > 0.0) as u8 as f64
                    }
                });
                let mi = push(m, &mut soup);
                let (ci, cj) = (c[k], c[(k + 1) % 4]);
                soup.triangles.push([ci, cj, mi]);
                soup.triangles.push([center, ci, mi]);
                soup.triangles.push([center, mi, cj]);
            }
        }
    }
    soup
}

pub fn box_sd(p: [f64; 3], h: f64) -> f64 {
    let q = p.map(|c| c.abs() - h);
    let outside = norm(q.map(|c| c.max(0.0)));
    outside + q[0].max(q[1]).max(q[2]).min(0.0)
}

/// Reverses the winding of the triangles `which` picks.
pub fn flip_some(soup: &mut TriangleSoup, mut which: impl FnMut(usize) -> bool) -> usize {
    let mut n = 0;
    for (k, t) in soup.triangles.iter_mut().enumerate() {
        if which(k) {
            t.swap(1, 2);
            n += 1;
        }
    }
    n
}
