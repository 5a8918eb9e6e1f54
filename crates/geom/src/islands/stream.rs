//! [`super::remove_islands`] over a mesh that arrives as [`MeshChunk`]s, without holding it:
//! a labelling pass ([`IslandLabeller`]), an enclosure pass over the chunks again when some
//! non-solid surface needs its ray test ([`IslandPlan::needs_ray_pass`]), and a keeping pass
//! ([`IslandKeeper`]) that hands on the kept mesh as chunks.
//!
//! Invariants:
//! - The pieces, the cavities' owners and the decisions are those of the whole mesh (tested
//!   against [`super::remove_islands`]); surfaces are ordered by their first triangle and a
//!   cavity's test point is its first triangle's first corner, as there. Only the sums of a
//!   surface's measures are added in another order, so a threshold within rounding of a
//!   piece's volume may decide otherwise.
//! - The kept chunks concatenate to the whole mesh's output, bit for bit, and keep the
//!   [`MeshChunk`] invariants (borrowed: the earlier ids the kept triangles use; open: the
//!   kept ids among the input's open ones).
//! - Memory: one chunk's union-find and maps, the open vertices' labels, and a few numbers
//!   per *fragment* — a part of a surface first seen in one chunk (a surface spread over many
//!   chunks is a few fragments each, joined as later chunks connect them).
//!
//! Method: each chunk is labelled by a union-find over the open vertices carried from the
//! chunk before and its own vertices. A set that holds a carried vertex continues that
//! vertex's fragment (several carried fragments in one set are joined, in a union-find over
//! fragments kept for the whole mesh); any other set with a triangle or an open vertex is a
//! new fragment, numbered in order. The later passes label every chunk again the same way —
//! the same fragments in the same order — and read each fragment's final surface from the
//! first pass's result.

use super::{
    IslandError, IslandFilter, Queries, Removal, Surface, cross, decide, dot, find, norm, sub,
};
use crate::mesh::MeshChunk;

const NONE: u32 = u32::MAX;

/// What the first pass learns of a fragment (merged into its root when fragments join).
#[derive(Clone, Copy, Debug)]
struct Fragment {
    volume: f64,
    area: f64,
    min: [f64; 3],
    max: [f64; 3],
    /// The global index of its first triangle (`u64::MAX`: none yet) and that triangle's
    /// first corner.
    first: u64,
    point: [f64; 3],
}

impl Fragment {
    fn empty() -> Fragment {
        Fragment {
            volume: 0.0,
            area: 0.0,
            min: [f64::INFINITY; 3],
            max: [f64::NEG_INFINITY; 3],
            first: u64::MAX,
            point: [0.0; 3],
        }
    }

    fn absorb(&mut self, other: &Fragment) {
        self.volume += other.volume;
        self.area += other.area;
        for a in 0..3 {
            self.min[a] = self.min[a].min(other.min[a]);
            self.max[a] = self.max[a].max(other.max[a]);
        }
        if other.first < self.first {
            self.first = other.first;
            self.point = other.point;
        }
    }
}

/// One chunk labelled: each node's set root and each root's fragment.
struct Labelled {
    /// Nodes: the carried open vertices, the chunk's own vertices, then earlier ids the
    /// chunk borrows that were not open (a chunk breaking the invariants).
    root: Vec<u32>,
    carried: usize,
    /// The carried open ids, sorted: node `k` is `carried_ids[k]`.
    carried_ids: Vec<u32>,
    /// Per borrowed entry, its node.
    borrowed: Vec<u32>,
    /// Per node (meaningful at roots): its fragment, or `NONE`.
    fragment: Vec<u32>,
}

impl Labelled {
    /// The node of vertex `id` in `chunk`, if the chunk has or borrows it.
    fn node(&self, chunk: &MeshChunk, id: u32) -> Option<u32> {
        if id >= chunk.first_vertex {
            let k = (id - chunk.first_vertex) as usize;
            (k < chunk.vertices.len()).then_some((self.carried + k) as u32)
        } else if let Ok(k) = self.carried_ids.binary_search(&id) {
            Some(k as u32)
        } else {
            let k = chunk.borrowed.binary_search_by_key(&id, |&(i, _)| i).ok()?;
            Some(self.borrowed[k])
        }
    }

    /// The fragment of a triangle whose corners all resolve (else `None`: skipped, as the
    /// check counts it invalid).
    fn triangle(&self, chunk: &MeshChunk, t: &[u32; 3]) -> Option<u32> {
        let mut node = None;
        for &v in t {
            node = Some(self.node(chunk, v)?);
        }
        node.map(|n| self.fragment[self.root[n as usize] as usize])
    }
}

/// The chunk labelling shared by the passes: the open vertices' fragments and the count of
/// fragments made.
#[derive(Default)]
struct Labeller {
    /// Open vertex ids after the last chunk, sorted, with their fragment.
    open: Vec<(u32, u32)>,
    fragments: u32,
}

impl Labeller {
    /// Labels `chunk`. `join(a, b)` joins two fragments met in one set and returns the one
    /// the set continues.
    fn label(&mut self, chunk: &MeshChunk, join: &mut dyn FnMut(u32, u32) -> u32) -> Labelled {
        let carried = self.open.len();
        let own = chunk.vertices.len();
        let mut parent: Vec<u32> = (0..(carried + own) as u32).collect();
        let borrowed: Vec<u32> = chunk
            .borrowed
            .iter()
            .map(
                |&(id, _)| match self.open.binary_search_by_key(&id, |&(v, _)| v) {
                    Ok(k) => k as u32,
                    Err(_) => {
                        parent.push(parent.len() as u32);
                        (parent.len() - 1) as u32
                    }
                },
            )
            .collect();
        let mut labelled = Labelled {
            root: Vec::new(),
            carried,
            carried_ids: self.open.iter().map(|&(id, _)| id).collect(),
            borrowed,
            fragment: Vec::new(),
        };
        let mut has_triangle = vec![false; parent.len()];
        for t in &chunk.triangles {
            let nodes = t.map(|v| labelled.node(chunk, v));
            let [Some(a), Some(b), Some(c)] = nodes else {
                continue;
            };
            let mut root = find(&mut parent, a);
            for other in [b, c] {
                let other = find(&mut parent, other);
                if other != root {
                    let (keep, gone) = (root.min(other), root.max(other));
                    parent[gone as usize] = keep;
                    root = keep;
                }
            }
            has_triangle[a as usize] = true;
        }
        let n = parent.len();
        let root: Vec<u32> = (0..n as u32).map(|x| find(&mut parent, x)).collect();
        let mut fragment = vec![NONE; n];
        for (k, &(_, f)) in self.open.iter().enumerate() {
            let r = root[k] as usize;
            fragment[r] = match fragment[r] {
                NONE => f,
                g => join(g, f),
            };
        }
        let mut alive = vec![false; n];
        for x in 0..n {
            alive[root[x] as usize] |= has_triangle[x];
        }
        let mut next_open: Vec<(u32, u32)> = Vec::with_capacity(chunk.open.len());
        for &id in &chunk.open {
            if let Some(x) = labelled.node(chunk, id) {
                alive[root[x as usize] as usize] = true;
                next_open.push((id, x));
            }
        }
        // New fragments, in node order: the same in every pass.
        for x in 0..n {
            if root[x] == x as u32 && fragment[x] == NONE && alive[x] {
                fragment[x] = self.fragments;
                self.fragments += 1;
            }
        }
        for entry in &mut next_open {
            entry.1 = fragment[root[entry.1 as usize] as usize];
        }
        next_open.sort_unstable();
        next_open.dedup();
        self.open = next_open;
        labelled.root = root;
        labelled.fragment = fragment;
        labelled
    }
}

/// The first pass: pushes every chunk in order, then [`IslandLabeller::finish`].
pub struct IslandLabeller {
    by_area: bool,
    labeller: Labeller,
    /// The union-find over fragments, and each one's measures (whole at roots).
    parent: Vec<u32>,
    measures: Vec<Fragment>,
    triangles: u64,
}

impl IslandLabeller {
    /// A labeller of a solid's pieces, or of a planar region's (`by_area`).
    pub fn new(by_area: bool) -> IslandLabeller {
        IslandLabeller {
            by_area,
            labeller: Labeller::default(),
            parent: Vec::new(),
            measures: Vec::new(),
            triangles: 0,
        }
    }

    pub fn push(&mut self, chunk: &MeshChunk) {
        let (parent, measures) = (&mut self.parent, &mut self.measures);
        let labelled = self.labeller.label(chunk, &mut |a, b| {
            let (ra, rb) = (find(parent, a), find(parent, b));
            if ra == rb {
                return ra;
            }
            let (keep, gone) = (ra.min(rb), ra.max(rb));
            parent[gone as usize] = keep;
            let merged = measures[gone as usize];
            measures[keep as usize].absorb(&merged);
            keep
        });
        while self.parent.len() < self.labeller.fragments as usize {
            self.parent.push(self.parent.len() as u32);
            self.measures.push(Fragment::empty());
        }
        for t in &chunk.triangles {
            let index = self.triangles;
            self.triangles += 1;
            let Some(f) = labelled.triangle(chunk, t) else {
                continue;
            };
            let Some([p0, p1, p2]) = positions(chunk, t) else {
                continue;
            };
            let root = find(&mut self.parent, f);
            let m = &mut self.measures[root as usize];
            m.volume += dot(p0, cross(p1, p2)) / 6.0;
            if self.by_area {
                m.area += 0.5 * norm(cross(sub(p1, p0), sub(p2, p0)));
            }
            for p in [p0, p1, p2] {
                for (a, &x) in p.iter().enumerate() {
                    m.min[a] = m.min[a].min(x);
                    m.max[a] = m.max[a].max(x);
                }
            }
            if index < m.first {
                m.first = index;
                m.point = p0;
            }
        }
    }

    /// The surfaces found; the plan for the passes that follow.
    pub fn finish(mut self) -> IslandPlan {
        // Surfaces: the roots with a triangle, in order of their first triangle.
        let n = self.parent.len();
        let mut roots: Vec<u32> = (0..n as u32)
            .filter(|&f| {
                find(&mut self.parent, f) == f && self.measures[f as usize].first != u64::MAX
            })
            .collect();
        roots.sort_by_key(|&f| self.measures[f as usize].first);
        let mut surface_of_root = vec![NONE; n];
        let mut surfaces: Vec<Surface> = Vec::with_capacity(roots.len());
        for (k, &f) in roots.iter().enumerate() {
            surface_of_root[f as usize] = k as u32;
            let m = &self.measures[f as usize];
            surfaces.push(Surface {
                volume: m.volume,
                area: m.area,
                min: m.min,
                max: m.max,
                point: m.point,
                owner: None,
            });
        }
        let surface: Vec<u32> = (0..n as u32)
            .map(|f| surface_of_root[find(&mut self.parent, f) as usize])
            .collect();
        let queries = if self.by_area {
            for (k, s) in surfaces.iter_mut().enumerate() {
                s.owner = Some(k as u32);
            }
            None
        } else {
            Some(Queries::new(&mut surfaces)).filter(|q| !q.is_empty())
        };
        IslandPlan {
            by_area: self.by_area,
            surfaces,
            surface,
            queries,
            rays: Labeller::default(),
        }
    }
}

/// The surfaces of a labelled mesh, before deciding what to keep.
pub struct IslandPlan {
    by_area: bool,
    surfaces: Vec<Surface>,
    /// Per fragment, its surface (`NONE`: no triangle).
    surface: Vec<u32>,
    /// The enclosure tests left, if any.
    queries: Option<Queries>,
    rays: Labeller,
}

impl IslandPlan {
    /// Whether some non-solid surface lies in a solid's box: then every chunk must be pushed
    /// to [`IslandPlan::ray_pass`] before [`IslandPlan::decide`].
    pub fn needs_ray_pass(&self) -> bool {
        self.queries.is_some()
    }

    /// The enclosure pass: `chunk`'s triangles against the rays of the cavities' points.
    pub fn ray_pass(&mut self, chunk: &MeshChunk) {
        let Some(queries) = self.queries.as_mut() else {
            return;
        };
        let labelled = self.rays.label(chunk, &mut |a, _| a);
        for t in &chunk.triangles {
            let (Some(f), Some(corners)) = (labelled.triangle(chunk, t), positions(chunk, t))
            else {
                continue;
            };
            let s = self.surface.get(f as usize).copied().unwrap_or(NONE);
            if s != NONE {
                queries.cross(&self.surfaces, s, corners);
            }
        }
    }

    /// Decides what to keep (after the ray pass, if needed); the keeper of the last pass.
    pub fn decide(mut self, filter: &IslandFilter) -> Result<IslandKeeper, IslandError> {
        if self.by_area && filter.min_volume.is_some() {
            return Err(IslandError::VolumeOfRegion);
        }
        if let Some(queries) = self.queries.take() {
            queries.resolve(&mut self.surfaces);
        }
        let (kept_surface, removal) = decide(&self.surfaces, filter, self.by_area)?;
        let kept = self
            .surface
            .iter()
            .map(|&s| s != NONE && kept_surface[s as usize])
            .collect();
        Ok(IslandKeeper {
            kept,
            labeller: Labeller::default(),
            open: Vec::new(),
            next_vertex: 0,
            removal,
        })
    }
}

/// The last pass: each chunk in, its kept part out.
pub struct IslandKeeper {
    /// Per fragment, whether its surface is kept.
    kept: Vec<bool>,
    labeller: Labeller,
    /// Kept open vertices: (input id, output id), sorted by both.
    open: Vec<(u32, u32)>,
    next_vertex: u32,
    removal: Removal,
}

impl IslandKeeper {
    /// What was removed (triangles counted over the chunks pushed so far).
    pub fn removal(&self) -> Removal {
        self.removal
    }

    /// The kept part of `chunk` (possibly empty), renumbered.
    pub fn push(&mut self, chunk: &MeshChunk) -> MeshChunk {
        let labelled = self.labeller.label(chunk, &mut |a, _| a);
        let kept = |f: u32| f != NONE && self.kept.get(f as usize).copied().unwrap_or(false);
        let first = self.next_vertex;
        let mut out = MeshChunk {
            first_vertex: first,
            ..MeshChunk::default()
        };
        // Own vertices: kept when their set's fragment is.
        let mut own_id = vec![NONE; chunk.vertices.len()];
        for (k, p) in chunk.vertices.iter().enumerate() {
            let x = labelled.carried + k;
            if kept(labelled.fragment[labelled.root[x] as usize]) {
                own_id[k] = self.next_vertex;
                self.next_vertex += 1;
                out.vertices.push(*p);
            }
        }
        let new_id = |id: u32| -> Option<u32> {
            if id >= chunk.first_vertex {
                let k = own_id.get((id - chunk.first_vertex) as usize)?;
                (*k != NONE).then_some(*k)
            } else {
                let k = self.open.binary_search_by_key(&id, |&(v, _)| v).ok()?;
                Some(self.open[k].1)
            }
        };
        let mut borrowed = Vec::new();
        for t in &chunk.triangles {
            let mapped = labelled
                .triangle(chunk, t)
                .filter(|&f| kept(f))
                .and_then(|_| Some([new_id(t[0])?, new_id(t[1])?, new_id(t[2])?]));
            match mapped {
                Some(m) => {
                    out.triangles.push(m);
                    for (&old, &new) in t.iter().zip(&m) {
                        if new < first {
                            borrowed.push((new, old));
                        }
                    }
                }
                None => self.removal.triangles_removed += 1,
            }
        }
        // Ids map in order, so sorting by the output id sorts by the input id too.
        borrowed.sort_unstable();
        borrowed.dedup();
        out.borrowed = borrowed
            .into_iter()
            .filter_map(|(new, old)| Some((new, chunk.position(old)?)))
            .collect();
        let mut open: Vec<(u32, u32)> = chunk
            .open
            .iter()
            .filter_map(|&id| Some((id, new_id(id)?)))
            .collect();
        open.sort_unstable();
        open.dedup();
        out.open = open.iter().map(|&(_, new)| new).collect();
        self.open = open;
        out
    }
}

/// The three corners' positions of a triangle of `chunk`, in `f64`.
fn positions(chunk: &MeshChunk, t: &[u32; 3]) -> Option<[[f64; 3]; 3]> {
    Some([
        chunk.position(t[0])?.map(f64::from),
        chunk.position(t[1])?.map(f64::from),
        chunk.position(t[2])?.map(f64::from),
    ])
}
