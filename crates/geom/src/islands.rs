//! Removing loose pieces from a mesh: keep only the largest solid piece, or drop the pieces
//! smaller than a volume (issue 24's `keep = "largest"` and `min_island_volume`).
//!
//! Definitions (the same as [`crate::validate::pieces`], so what is removed is what the
//! report counted):
//! - A *surface* is a set of valid triangles connected through shared vertex ids.
//! - A surface of positive signed volume is *solid*: it bounds a piece. A surface of zero or
//!   negative volume (a cavity's inner wall, in an outward mesh) belongs to the innermost solid
//!   surface that encloses it: among the solid surfaces whose bounding box contains its own,
//!   those that contain its first vertex by ray parity, the one of least volume (nested
//!   solids enclose strictly less volume the deeper they are). A piece is a solid surface and
//!   the surfaces it owns, and its volume is theirs together (outer minus cavities). A
//!   non-solid surface no solid encloses (an inverted stray) belongs to no piece and is
//!   removed with the pieces.
//! - For a planar region (`by_area`), every surface is a piece, measured by its area; there
//!   are no cavities (a hole is part of the surface around it). A volume threshold means
//!   nothing there and is refused ([`IslandError::VolumeOfRegion`]).
//!
//! Invariants:
//! - A piece is kept when it passes every test asked: it is the largest (by volume, or area;
//!   ties go to the piece whose first triangle comes first), and its volume is at least the
//!   threshold. With both, the largest is kept only if it reaches the threshold.
//! - The output is the kept pieces' triangles in their input order, with their vertices in
//!   input order renumbered densely: unused vertices (and invalid triangles, naming an id past
//!   the end) are dropped. Everything is serial and in mesh order, so the same input gives the
//!   same output whatever the thread count.
//! - Removing every piece is an error ([`IslandError::NothingKept`]), never an empty mesh.
//!
//! Ray parity (the enclosure test) is exact in its tie-breaking: the ray runs along +x from
//! the query point, displaced symbolically by (ε, ε²) in (y, z), and each edge's side is
//! computed from its endpoints in one canonical order, so a ray through a shared edge or
//! vertex is counted once, by exactly one of the triangles around it. Solid surfaces are
//! disjoint from the query point's surface, so a crossing's x is never the query's.
//!
//! Memory: besides input and output, a label per vertex and a few numbers per surface. A mesh
//! streamed as chunks is filtered without holding it by [`IslandLabeller`], [`IslandPlan`]
//! and [`IslandKeeper`] (`stream.rs`): two or three passes over the chunks, the same result.

use crate::mesh::Mesh;
use crate::validate::find;
use crate::vec3::{cross, dot, norm, sub};

/// What to keep of a mesh's pieces.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IslandFilter {
    /// Keep only the largest piece.
    pub largest: bool,
    /// Drop pieces of volume below this (model units³); positive and finite.
    pub min_volume: Option<f64>,
}

impl IslandFilter {
    /// Whether the filter removes anything at all (it is a stage only then).
    pub fn is_active(&self) -> bool {
        self.largest || self.min_volume.is_some()
    }
}

/// What the filter removed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Removal {
    /// Pieces in the input, and removed (solid pieces, or a region's parts).
    pub pieces: usize,
    pub pieces_removed: usize,
    /// The volume of what was removed (signed, so the kept volume plus this is the input's;
    /// for a planar region, the area).
    pub removed: f64,
    /// The largest removed piece's volume (area), 0 when none was.
    pub largest_removed: f64,
    pub triangles_removed: usize,
}

/// Why nothing could be kept.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum IslandError {
    #[error(
        "every piece would be removed: the largest of the {pieces} is {largest:.6e} (model \
         units{unit}), under the minimum {min:.6e}"
    )]
    NothingKept {
        pieces: usize,
        largest: f64,
        min: f64,
        unit: &'static str,
    },
    #[error("the mesh has no solid piece (no closed surface of positive volume) to keep")]
    NoPieces,
    #[error(
        "a planar region's pieces have an area, not a volume: a minimum island volume does \
         not apply (use keep = \"largest\", or make the region a solid)"
    )]
    VolumeOfRegion,
}

/// The mesh without the removed pieces, and what was removed.
#[derive(Clone, Debug, PartialEq)]
pub struct Filtered {
    pub mesh: Mesh,
    pub removal: Removal,
}

/// One surface's measures.
#[derive(Clone, Copy, Debug)]
struct Surface {
    volume: f64,
    area: f64,
    min: [f64; 3],
    max: [f64; 3],
    /// Its first triangle's first corner: the point tested for enclosure.
    point: [f64; 3],
    /// The solid surface whose piece it is part of (itself, for a solid).
    owner: Option<u32>,
}

/// Removes pieces from `mesh` by `filter`; a planar region's pieces (`by_area`) are measured
/// by area. See the module docs.
pub fn remove_islands(
    mesh: &Mesh,
    filter: &IslandFilter,
    by_area: bool,
) -> Result<Filtered, IslandError> {
    if by_area && filter.min_volume.is_some() {
        return Err(IslandError::VolumeOfRegion);
    }
    let n = mesh.vertices.len();
    let valid = |t: &[u32; 3]| t.iter().all(|&v| (v as usize) < n);
    // Surfaces: union-find over vertex ids, then labelled densely in order of first triangle.
    let mut label: Vec<u32> = (0..n as u32).collect();
    for t in mesh.triangles.iter().filter(|t| valid(t)) {
        let mut root = find(&mut label, t[0]);
        for &v in &t[1..] {
            let other = find(&mut label, v);
            if other != root {
                let (keep, gone) = (root.min(other), root.max(other));
                label[gone as usize] = keep;
                root = keep;
            }
        }
    }
    for v in 0..n as u32 {
        // Roots are the smallest id of their set, so a root is already final here.
        let root = find(&mut label, v);
        label[v as usize] = root;
    }
    const UNSEEN: u32 = u32::MAX;
    let mut surface_of_root = vec![UNSEEN; n];
    let mut surfaces: Vec<Surface> = Vec::new();
    let position = |v: u32| mesh.vertices[v as usize].map(f64::from);
    for t in mesh.triangles.iter().filter(|t| valid(t)) {
        let root = label[t[0] as usize] as usize;
        if surface_of_root[root] == UNSEEN {
            surface_of_root[root] = surfaces.len() as u32;
            surfaces.push(Surface {
                volume: 0.0,
                area: 0.0,
                min: [f64::INFINITY; 3],
                max: [f64::NEG_INFINITY; 3],
                point: position(t[0]),
                owner: None,
            });
        }
        let s = &mut surfaces[surface_of_root[root] as usize];
        let [p0, p1, p2] = t.map(position);
        s.volume += dot(p0, cross(p1, p2)) / 6.0;
        if by_area {
            s.area += 0.5 * norm(cross(sub(p1, p0), sub(p2, p0)));
        }
        for p in [p0, p1, p2] {
            for (a, &x) in p.iter().enumerate() {
                s.min[a] = s.min[a].min(x);
                s.max[a] = s.max[a].max(x);
            }
        }
    }
    // The surface of each vertex (of a valid triangle), replacing the roots.
    let surface_of = |v: u32| surface_of_root[label[v as usize] as usize];
    if by_area {
        for (k, s) in surfaces.iter_mut().enumerate() {
            s.owner = Some(k as u32);
        }
    } else {
        assign_owners(mesh, &mut surfaces, &surface_of);
    }
    let (kept_surface, mut removal) = decide(&surfaces, filter, by_area)?;
    // The kept triangles in order; their vertices renumbered in id order.
    let mut new_id = vec![UNSEEN; n];
    let mut triangles = Vec::new();
    for t in &mesh.triangles {
        if valid(t) && kept_surface[surface_of(t[0]) as usize] {
            triangles.push(*t);
            for &v in t {
                new_id[v as usize] = 0;
            }
        } else {
            removal.triangles_removed += 1;
        }
    }
    let mut vertices = Vec::new();
    for (v, id) in new_id.iter_mut().enumerate() {
        if *id != UNSEEN {
            *id = vertices.len() as u32;
            vertices.push(mesh.vertices[v]);
        }
    }
    for t in &mut triangles {
        *t = t.map(|v| new_id[v as usize]);
    }
    Ok(Filtered {
        mesh: Mesh {
            vertices,
            triangles,
        },
        removal,
    })
}

/// Which surfaces are kept (by surface), and what is removed but the triangle count: the
/// pieces are the solids with the surfaces they own (set before), measured together.
fn decide(
    surfaces: &[Surface],
    filter: &IslandFilter,
    by_area: bool,
) -> Result<(Vec<bool>, Removal), IslandError> {
    let mut measure = vec![0.0f64; surfaces.len()];
    for s in surfaces {
        if let Some(o) = s.owner {
            measure[o as usize] += if by_area { s.area } else { s.volume };
        }
    }
    let pieces: Vec<u32> = (0..surfaces.len() as u32)
        .filter(|&k| surfaces[k as usize].owner == Some(k))
        .collect();
    let largest = pieces
        .iter()
        .copied()
        .reduce(|a, b| {
            if measure[b as usize] > measure[a as usize] {
                b
            } else {
                a
            }
        })
        .ok_or(IslandError::NoPieces)?;
    let kept_piece = |k: u32| {
        (!filter.largest || k == largest)
            && filter.min_volume.is_none_or(|v| measure[k as usize] >= v)
    };
    if !pieces.iter().any(|&k| kept_piece(k)) {
        return Err(IslandError::NothingKept {
            pieces: pieces.len(),
            largest: measure[largest as usize],
            min: filter.min_volume.unwrap_or(0.0),
            unit: if by_area { "²" } else { "³" },
        });
    }
    let kept_surface: Vec<bool> = surfaces
        .iter()
        .map(|s| s.owner.is_some_and(kept_piece))
        .collect();
    let mut removal = Removal {
        pieces: pieces.len(),
        ..Removal::default()
    };
    for &k in pieces.iter().filter(|&&k| !kept_piece(k)) {
        removal.pieces_removed += 1;
        removal.largest_removed = removal.largest_removed.max(measure[k as usize]);
    }
    for (s, &kept) in surfaces.iter().zip(&kept_surface) {
        if !kept {
            removal.removed += if by_area { s.area } else { s.volume };
        }
    }
    Ok((kept_surface, removal))
}

/// Sets every surface's owner: a solid owns itself; a non-solid surface is owned by the
/// innermost solid enclosing its point (see the module docs), or by none.
fn assign_owners(mesh: &Mesh, surfaces: &mut [Surface], surface_of: &dyn Fn(u32) -> u32) {
    let mut queries = Queries::new(surfaces);
    if queries.is_empty() {
        return;
    }
    let n = mesh.vertices.len();
    for t in &mesh.triangles {
        if t.iter().all(|&v| (v as usize) < n) {
            let corners = t.map(|v| mesh.vertices[v as usize].map(f64::from));
            queries.cross(surfaces, surface_of(t[0]), corners);
        }
    }
    queries.resolve(surfaces);
}

/// The enclosure tests still open: for each non-solid surface, the solids whose box holds
/// its box, with the parity of the crossings of its point's ray with each so far.
struct Queries {
    /// (non-solid surface, candidate solid).
    pairs: Vec<(u32, u32)>,
    /// Per candidate solid, its queries sorted by the point's y: (y, pair index).
    by_candidate: Vec<Vec<(f64, u32)>>,
    odd: Vec<bool>,
}

impl Queries {
    /// The queries of `surfaces`, whose solids are made their own owners.
    fn new(surfaces: &mut [Surface]) -> Queries {
        let solids: Vec<u32> = (0..surfaces.len() as u32)
            .filter(|&k| surfaces[k as usize].volume > 0.0)
            .collect();
        for &k in &solids {
            surfaces[k as usize].owner = Some(k);
        }
        let contains = |outer: &Surface, inner: &Surface| {
            (0..3).all(|a| outer.min[a] <= inner.min[a] && inner.max[a] <= outer.max[a])
        };
        let grid = SolidGrid::new(surfaces, &solids);
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        let mut by_candidate: Vec<Vec<(f64, u32)>> = vec![Vec::new(); surfaces.len()];
        for k in 0..surfaces.len() as u32 {
            if surfaces[k as usize].volume > 0.0 {
                continue;
            }
            for &s in grid.at(surfaces[k as usize].point) {
                if contains(&surfaces[s as usize], &surfaces[k as usize]) {
                    let y = surfaces[k as usize].point[1];
                    by_candidate[s as usize].push((y, pairs.len() as u32));
                    pairs.push((k, s));
                }
            }
        }
        for list in &mut by_candidate {
            list.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        }
        let odd = vec![false; pairs.len()];
        Queries {
            pairs,
            by_candidate,
            odd,
        }
    }

    fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// Counts a triangle of surface `s` against the rays of the queries `s` is a candidate of.
    fn cross(&mut self, surfaces: &[Surface], s: u32, [a, b, c]: [[f64; 3]; 3]) {
        let Some(list) = self.by_candidate.get(s as usize) else {
            return;
        };
        let (lo, hi) = (a[1].min(b[1]).min(c[1]), a[1].max(b[1]).max(c[1]));
        let start = list.partition_point(|&(y, _)| y < lo);
        for &(y, q) in &list[start..] {
            if y > hi {
                break;
            }
            let p = surfaces[self.pairs[q as usize].0 as usize].point;
            if ray_crosses(p, a, b, c) {
                self.odd[q as usize] ^= true;
            }
        }
    }

    /// Sets each non-solid surface's owner: the innermost enclosing solid (least volume,
    /// then first in mesh order), or none.
    fn resolve(self, surfaces: &mut [Surface]) {
        for (q, &(k, s)) in self.pairs.iter().enumerate() {
            if !self.odd[q] {
                continue;
            }
            let better = match surfaces[k as usize].owner {
                None => true,
                Some(o) => {
                    let (vs, vo) = (surfaces[s as usize].volume, surfaces[o as usize].volume);
                    vs < vo || (vs == vo && s < o)
                }
            };
            if better {
                surfaces[k as usize].owner = Some(s);
            }
        }
    }
}

/// The solids' boxes bucketed in a uniform grid over them (about one cell per solid, at most
/// 64 per axis), so that finding the boxes around a cavity's point looks at the few solids
/// listed in its cell, not at every solid (thousands of loose hollow balls would otherwise
/// cost their number squared). Each cell lists its solids in increasing order.
struct SolidGrid {
    lo: [f64; 3],
    scale: [f64; 3],
    n: usize,
    cells: Vec<Vec<u32>>,
}

impl SolidGrid {
    fn new(surfaces: &[Surface], solids: &[u32]) -> SolidGrid {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for &s in solids {
            for a in 0..3 {
                lo[a] = lo[a].min(surfaces[s as usize].min[a]);
                hi[a] = hi[a].max(surfaces[s as usize].max[a]);
            }
        }
        let n = ((solids.len() as f64).cbrt().ceil() as usize).clamp(1, 64);
        let scale = [0, 1, 2].map(|a| {
            let extent = hi[a] - lo[a];
            if extent > 0.0 && extent.is_finite() {
                n as f64 / extent
            } else {
                0.0
            }
        });
        let mut grid = SolidGrid {
            lo,
            scale,
            n,
            cells: vec![Vec::new(); n * n * n],
        };
        for &s in solids {
            let (a, b) = (
                grid.index(surfaces[s as usize].min),
                grid.index(surfaces[s as usize].max),
            );
            for x in a[0]..=b[0] {
                for y in a[1]..=b[1] {
                    for z in a[2]..=b[2] {
                        grid.cells[(x * n + y) * n + z].push(s);
                    }
                }
            }
        }
        grid
    }

    /// The cell of a point, per axis (clamped into the grid).
    fn index(&self, p: [f64; 3]) -> [usize; 3] {
        [0, 1, 2].map(|a| {
            let i = ((p[a] - self.lo[a]) * self.scale[a]).floor();
            if i.is_nan() || i < 0.0 {
                0
            } else {
                (i as usize).min(self.n - 1)
            }
        })
    }

    /// The solids whose boxes may hold `p` (every solid whose box does is listed).
    fn at(&self, p: [f64; 3]) -> &[u32] {
        let [x, y, z] = self.index(p);
        &self.cells[(x * self.n + y) * self.n + z]
    }
}

/// Whether the ray from `p` along +x (displaced by (ε, ε²) in (y, z)) crosses triangle abc.
fn ray_crosses(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> bool {
    let (wa, wb, wc) = (side(p, b, c), side(p, c, a), side(p, a, b));
    let sum = wa.0 + wb.0 + wc.0;
    // Inside the projected triangle: the point is on one side of all three edges, in either
    // orientation (a triangle seen from behind is crossed too); a flat projection never.
    let inside = (wa.1 && wb.1 && wc.1) || (!wa.1 && !wb.1 && !wc.1);
    if !inside || sum == 0.0 {
        return false;
    }
    let x = (wa.0 * a[0] + wb.0 * b[0] + wc.0 * c[0]) / sum;
    x > p[0]
}

/// The edge function of `u → v` at `p` in the (y, z) projection, and which side the displaced
/// point is on (`true`: left, positive). Computed from the endpoints in lexicographic order
/// and negated for the other direction, so the two triangles sharing an edge disagree exactly.
fn side(p: [f64; 3], u: [f64; 3], v: [f64; 3]) -> (f64, bool) {
    let forward = (u[1], u[2]) <= (v[1], v[2]);
    let (s, e) = if forward { (u, v) } else { (v, u) };
    let (dy, dz) = (e[1] - s[1], e[2] - s[2]);
    let value = dy * (p[2] - s[2]) - dz * (p[1] - s[1]);
    // At zero, the displacement decides: ε·(−dz) first, then ε²·dy.
    let positive = value > 0.0 || (value == 0.0 && (dz < 0.0 || (dz == 0.0 && dy > 0.0)));
    if forward {
        (value, positive)
    } else {
        (-value, !positive)
    }
}

mod stream;
pub use stream::{IslandKeeper, IslandLabeller, IslandPlan};

#[cfg(test)]
mod tests;
