//! The topology of a closed mesh's surfaces: Euler characteristic and genus per connected
//! surface, and per solid piece.
//!
//! Invariants:
//! - Surfaces are connected through shared vertex ids, as in [`crate::validate::pieces`]
//!   (so two solids touching at one vertex are one surface; read meshes must be welded).
//! - A surface's `χ = V − E + F` counts its used vertices, distinct undirected edges and
//!   valid triangles. It is closed when every edge has exactly two triangles; only then is
//!   `genus = (2 − χ) / 2` given (`None` for an open or non-manifold surface, or an odd χ).
//! - A solid piece is a surface of positive signed volume (a cavity's surface, wound inward,
//!   has negative volume). [`solid_genera`] reports per solid piece the genus of its outer
//!   surface, largest volume first: the handles a user sees. A cavity is not a handle: it is
//!   counted by [`Topology::cavities`], and the genus of a cavity (a buried torus-shaped void)
//!   is not added to its piece (which piece holds it is not known here).

use rayon::slice::ParallelSliceMut;

use crate::mesh::Mesh;
use crate::validate::find;

/// One connected surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceTopology {
    pub euler: i64,
    pub closed: bool,
    pub volume: f64,
    pub area: f64,
}

impl SurfaceTopology {
    /// `1 − χ/2` for a closed surface of even χ.
    pub fn genus(&self) -> Option<i64> {
        (self.closed && self.euler % 2 == 0).then_some(1 - self.euler / 2)
    }
}

/// The connected surfaces of a mesh, largest volume first.
pub fn surfaces(mesh: &Mesh) -> Vec<SurfaceTopology> {
    let nv = mesh.vertices.len();
    let valid: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .copied()
        .filter(|t| {
            t.iter().all(|&v| (v as usize) < nv) && t[0] != t[1] && t[1] != t[2] && t[0] != t[2]
        })
        .collect();
    let mut parent: Vec<u32> = (0..nv as u32).collect();
    for t in &valid {
        let a = find(&mut parent, t[0]);
        for &v in &t[1..] {
            let b = find(&mut parent, v);
            if a != b {
                parent[b as usize] = a;
            }
        }
    }
    let mut label = vec![u32::MAX; nv];
    let mut out: Vec<SurfaceTopology> = Vec::new();
    let mut of_root = |parent: &mut Vec<u32>, v: u32, out: &mut Vec<SurfaceTopology>| {
        let r = find(parent, v) as usize;
        if label[r] == u32::MAX {
            label[r] = out.len() as u32;
            out.push(SurfaceTopology {
                euler: 0,
                closed: true,
                volume: 0.0,
                area: 0.0,
            });
        }
        label[r] as usize
    };
    let mut used = vec![false; nv];
    let mut edges: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * valid.len());
    for t in &valid {
        let s = of_root(&mut parent, t[0], &mut out);
        let p = t.map(|v| mesh.vertices[v as usize].map(f64::from));
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let c = cross(p[1], p[2]);
        out[s].volume += (p[0][0] * c[0] + p[0][1] * c[1] + p[0][2] * c[2]) / 6.0;
        let e1 = std::array::from_fn(|k| p[1][k] - p[0][k]);
        let e2 = std::array::from_fn(|k| p[2][k] - p[0][k]);
        let n = cross(e1, e2);
        out[s].area += 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        out[s].euler += 1;
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.push((s as u32, a.min(b), a.max(b)));
            for v in [a, b] {
                if !used[v as usize] {
                    used[v as usize] = true;
                    out[s].euler += 1;
                }
            }
        }
    }
    // The sort is most of the time on a large mesh: both threads take it.
    edges.par_sort_unstable();
    let mut k = 0;
    while k < edges.len() {
        let mut m = k + 1;
        while m < edges.len() && edges[m] == edges[k] {
            m += 1;
        }
        let s = edges[k].0 as usize;
        out[s].euler -= 1;
        if m - k != 2 {
            out[s].closed = false;
        }
        k = m;
    }
    out.sort_by(|a, b| b.volume.total_cmp(&a.volume));
    out
}

/// A mesh's topology summary (see the module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Topology {
    /// Per solid piece, largest first: the genus of its outer surface (`None` when that
    /// surface is not closed and manifold).
    pub genus: Vec<Option<i64>>,
    /// Surfaces of negative volume: voids sealed inside a solid.
    pub cavities: usize,
}

/// Genus per solid piece and the number of cavities (see the module docs).
pub fn solid_genera(mesh: &Mesh) -> Topology {
    let all = surfaces(mesh);
    Topology {
        genus: all
            .iter()
            .filter(|s| s.volume > 0.0)
            .map(SurfaceTopology::genus)
            .collect(),
        cavities: all.iter().filter(|s| s.volume < 0.0).count(),
    }
}
