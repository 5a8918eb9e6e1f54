//! Welding the elements' local meshes into one mesh, by the intrinsic names of boundary
//! vertices (module docs of [`super`], step 3). For a uniform cell, vertices inside a face
//! are paired by structure instead ([`super::face_plan`]): the same pairs the names would
//! make, without hashing and sorting the bulk of the shared vertices; those on element edges
//! and nodes (shared by any number of elements) keep their names.
//!
//! Invariants: a boundary vertex's name depends only on global node ids and lattice weights,
//! never on the element's frame; the lowest element using a vertex places and numbers it;
//! ids are assigned element by element in local order, so the mesh does not depend on the
//! thread count — nor on how the elements are cut into chunks: a vertex a later chunk uses is
//! kept open (with its id and position) until the last element containing its node, edge or
//! face has been welded, and a chunk that meets it again borrows it.

use rayon::prelude::*;
use std::collections::HashMap;

use super::face_plan::{FacePlan, NO_FACE};
use super::lattice::{Lattice, Weights};
use super::local::{LocalMesh, LocalVertex, POINT};
use super::{ElementShape, Elements, TileError, TileStats};

/// What the weld needs of a set of elements, of any dimension: their count, each one's
/// global corner nodes (in its lattice's corner order) and where a reference point goes.
pub trait Corners: Sync {
    fn count(&self) -> usize;
    fn element(&self, e: usize) -> &[u32];
    /// The model position of reference point `xi` in element `e`.
    fn place(&self, e: usize, xi: [f64; 3]) -> [f64; 3];
}

impl<S: ElementShape> Corners for Elements<'_, S> {
    fn count(&self) -> usize {
        Elements::count(self)
    }

    fn element(&self, e: usize) -> &[u32] {
        Elements::element(self, e)
    }

    fn place(&self, e: usize, xi: [f64; 3]) -> [f64; 3] {
        self.map.map(e, xi)
    }
}
use crate::mesh::{MeshChunk, SpareArrays};

/// A local vertex on the element boundary: the weights of its lattice ends, and the faces
/// whose caps alone use it (0 when surface triangles use it).
struct SharedVertex {
    a: Weights,
    b: Option<Weights>,
    /// A band's upper level's crossing (its lower level's crossing on the same edge differs).
    upper: bool,
    caps: u8,
}

/// The scaffold's faces as the elements see them: which lie on the boundary (one bit per face
/// and element) and, for an interior face, the element on its other side.
struct FaceTable {
    boundary: Vec<u8>,
    /// Per `(element, face)`: the other element sharing the face, or [`NONE`].
    neighbour: Vec<u32>,
    /// Per `(element, face)` with a neighbour: the face's index in the neighbour.
    neighbour_face: Vec<u8>,
    stats: TileStats,
}

impl FaceTable {
    fn new(elements: &dyn Corners, face_masks: &[u8]) -> Result<FaceTable, TileError> {
        let n = elements.count();
        let per = face_masks.len();
        let mut faces: Vec<([u32; 4], u32)> = (0..n)
            .into_par_iter()
            .flat_map_iter(|e| {
                let corners = elements.element(e);
                face_masks.iter().enumerate().map(move |(f, &mask)| {
                    let mut nodes = [u32::MAX; 4];
                    let on_face = (0..corners.len()).filter(|c| mask & 1 << c != 0);
                    for (slot, c) in nodes.iter_mut().zip(on_face) {
                        *slot = corners[c];
                    }
                    nodes.sort_unstable();
                    (nodes, (e * per + f) as u32)
                })
            })
            .collect();
        faces.par_sort_unstable();
        let mut table = FaceTable {
            boundary: vec![0u8; n],
            neighbour: vec![NONE; n * per],
            neighbour_face: vec![0; n * per],
            stats: TileStats {
                elements: n,
                ..TileStats::default()
            },
        };
        let mut i = 0;
        while i < faces.len() {
            let mut j = i + 1;
            while j < faces.len() && faces[j].0 == faces[i].0 {
                j += 1;
            }
            match j - i {
                1 => {
                    let slot = faces[i].1 as usize;
                    table.boundary[slot / per] |= 1 << (slot % per);
                    table.stats.boundary_faces += 1;
                }
                2 => {
                    let (a, b) = (faces[i].1 as usize, faces[i + 1].1 as usize);
                    table.neighbour[a] = (b / per) as u32;
                    table.neighbour[b] = (a / per) as u32;
                    table.neighbour_face[a] = (b % per) as u8;
                    table.neighbour_face[b] = (a % per) as u8;
                    table.stats.interior_faces += 1;
                }
                count => {
                    return Err(TileError::NonConforming {
                        nodes: faces[i]
                            .0
                            .iter()
                            .copied()
                            .filter(|&v| v != u32::MAX)
                            .collect(),
                        count,
                    });
                }
            }
            i = j;
        }
        Ok(table)
    }
}

/// The last element (highest index) that contains each corner set a boundary vertex can lie
/// on — a scaffold node, edge or face — so a chunk knows which of its vertices later chunks
/// may still use. Which one a vertex lies on follows from its corner mask: one corner is a
/// node; a mask inside exactly one face is on that face (whose elements are this one and its
/// neighbour); a mask inside two or more faces is an element edge (3D).
struct LastUsers {
    node: Vec<u32>,
    /// Sorted `(lo << 32 | hi, last element)` over the scaffold's element edges.
    edges: Vec<(u64, u32)>,
}

impl LastUsers {
    fn new(elements: &dyn Corners, face_masks: &[u8]) -> LastUsers {
        let n = elements.count();
        let mut node = Vec::new();
        for e in 0..n {
            for &c in elements.element(e) {
                let c = c as usize;
                if c >= node.len() {
                    node.resize(c + 1, 0);
                }
                node[c] = e as u32;
            }
        }
        let local_edges = element_edges(face_masks);
        let mut edges: Vec<(u64, u32)> = (0..n)
            .into_par_iter()
            .flat_map_iter(|e| {
                let corners = elements.element(e);
                local_edges
                    .iter()
                    .map(move |&(i, j)| (edge_key(corners[i], corners[j]), e as u32))
            })
            .collect();
        edges.par_sort_unstable();
        // Sorted by (key, element): the last of each run is the edge's last element.
        let mut last: Vec<(u64, u32)> = Vec::with_capacity(edges.len() / 2);
        for (key, e) in edges {
            match last.last_mut() {
                Some(l) if l.0 == key => l.1 = e,
                _ => last.push((key, e)),
            }
        }
        LastUsers { node, edges: last }
    }

    /// The last element containing the corners `mask` of element `e` (corner nodes `corners`).
    fn of(&self, e: usize, corners: &[u32], mask: u8, faces: &FaceTable, face_masks: &[u8]) -> u32 {
        let e32 = e as u32;
        if mask.count_ones() == 1 {
            return self.node[corners[mask.trailing_zeros() as usize] as usize];
        }
        let mut containing = face_masks
            .iter()
            .enumerate()
            .filter(|&(_, &f)| mask & !f == 0);
        match (containing.next(), containing.next()) {
            (Some((f, _)), None) => {
                let other = faces.neighbour[e * face_masks.len() + f];
                if other == NONE { e32 } else { e32.max(other) }
            }
            (Some(_), Some(_)) => {
                let (i, j) = (mask.trailing_zeros(), 7 - mask.leading_zeros());
                let key = edge_key(corners[i as usize], corners[j as usize]);
                self.edges
                    .binary_search_by_key(&key, |&(k, _)| k)
                    .map_or(e32, |k| self.edges[k].1)
            }
            // Not on the element's boundary: only this element uses it.
            (None, _) => e32,
        }
    }
}

/// The corner pairs of an element that lie in two or more faces: its edges (3D elements; a 2D
/// element's edges are its faces).
fn element_edges(face_masks: &[u8]) -> Vec<(usize, usize)> {
    let corners = face_masks.iter().fold(0u8, |m, &f| m | f);
    let mut edges = Vec::new();
    for i in 0..8 {
        for j in i + 1..8 {
            let pair = 1u8 << i | 1 << j;
            if corners & pair == pair
                && face_masks.iter().filter(|&&f| f & pair == pair).count() >= 2
            {
                edges.push((i, j));
            }
        }
    }
    edges
}

fn edge_key(a: u32, b: u32) -> u64 {
    u64::from(a.min(b)) << 32 | u64::from(a.max(b))
}

/// 128-bit name of a shared vertex in element `corners`: a hash of its ends' `(global node,
/// weight)` lists that does not depend on the order of either list or of the two ends. A list
/// hashes to the sum of its items' hashes (each item mixed to 128 bits), so no list is sorted
/// (this runs for every shared vertex of every element); the two ends' sums are then taken
/// smaller first. Collisions between distinct names are as likely as for any 128-bit hash of a
/// few million keys (about 2⁻⁸⁰): not a concern.
fn vertex_name(corners: &[u32], v: &SharedVertex) -> u128 {
    let list = |w: &Weights| {
        w.as_slice()
            .iter()
            .fold([0u64; 2], |[lo, hi], &(c, weight)| {
                let x = u64::from(corners[c as usize]) << 32 | u64::from(weight);
                [
                    lo.wrapping_add(fmix64(x ^ 0x9E37_79B9_7F4A_7C15)),
                    hi.wrapping_add(fmix64(x.rotate_left(29) ^ 0xC2B2_AE3D_27D4_EB4F)),
                ]
            })
    };
    let a = list(&v.a);
    let mut h = Hasher128::new(u64::from(v.b.is_some()) | u64::from(v.upper) << 1);
    match &v.b {
        None => a.iter().for_each(|&x| h.add(x)),
        Some(b) => {
            let b = list(b);
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            for &x in lo.iter().chain(hi.iter()) {
                h.add(x);
            }
        }
    }
    h.finish()
}

/// Sorts `(name, element, slot)` triples — as `sort_unstable` would: names are uniform hashes,
/// so one counting pass on their top bits spreads them into buckets of a few entries each,
/// sorted in parallel (a comparison sort of millions of 32-byte triples was a fifth of the
/// tiling's instructions).
///
/// The scatter into buckets is parallel too, without shared writes: the output is cut at
/// bucket boundaries into one range per thread, and each thread reads every name but places
/// only those of its own range. (A serial scatter was a quarter of the weld's serial time.)
/// The result is the sorted order whatever the thread count.
fn sort_names(names: &mut Vec<(u128, u32, u32)>, spare: &mut Vec<(u128, u32, u32)>) {
    if names.len() < 1 << 12 {
        names.sort_unstable();
        return;
    }
    let bits = (names.len() / 4).ilog2().clamp(8, 20);
    let buckets = 1usize << bits;
    let bucket = |name: u128| (name >> (128 - bits)) as usize;
    let counts = names
        .par_chunks(1 << 16)
        .fold(
            || vec![0u32; buckets],
            |mut counts, part| {
                for &(name, ..) in part {
                    counts[bucket(name)] += 1;
                }
                counts
            },
        )
        .reduce_with(|mut a, b| {
            a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
            a
        })
        .unwrap_or_default();
    let mut start = Vec::with_capacity(buckets + 1);
    start.push(0usize);
    for &c in &counts {
        start.push(start[start.len() - 1] + c as usize);
    }
    // Bucket ranges of about equal item counts, one per thread.
    let ranges = rayon::current_num_threads().clamp(1, 16);
    let mut cuts = vec![0usize];
    for r in 1..ranges {
        let target = names.len() * r / ranges;
        let b = start.partition_point(|&s| s < target).min(buckets);
        if b > cuts[cuts.len() - 1] {
            cuts.push(b);
        }
    }
    cuts.push(buckets);
    spare.clear();
    spare.resize(names.len(), (0, 0, 0));
    let sorted = spare;
    let lengths = cuts.windows(2).map(|w| start[w[1]] - start[w[0]]);
    let parts: Vec<_> = split_by(sorted, lengths)
        .into_iter()
        .zip(cuts.windows(2).map(|w| w[0]..w[1]))
        .collect();
    let (names_read, start) = (&*names, &start);
    parts.into_par_iter().for_each(|(out, range)| {
        let base = start[range.start];
        let mut next: Vec<usize> = start[range.clone()].iter().map(|&s| s - base).collect();
        for &item in names_read {
            let b = bucket(item.0);
            if range.contains(&b) {
                let slot = &mut next[b - range.start];
                out[*slot] = item;
                *slot += 1;
            }
        }
        let mut at = 0;
        for b in range {
            let len = start[b + 1] - start[b];
            out[at..at + len].sort_unstable();
            at += len;
        }
    });
    std::mem::swap(names, sorted);
}

/// MurmurHash3's 64-bit finalizer: every input bit flips each output bit with probability ½.
#[inline]
fn fmix64(mut x: u64) -> u64 {
    x ^= x >> 33;
    x = x.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    x ^= x >> 33;
    x = x.wrapping_mul(0xC4CE_B9FE_1A85_EC53);
    x ^ x >> 33
}

/// Two independent 64-bit multiply–xorshift lanes.
struct Hasher128 {
    lo: u64,
    hi: u64,
}

impl Hasher128 {
    fn new(seed: u64) -> Hasher128 {
        Hasher128 {
            lo: 0x9E37_79B9_7F4A_7C15 ^ seed,
            hi: 0xC2B2_AE3D_27D4_EB4F ^ seed.rotate_left(17),
        }
    }

    #[inline]
    fn add(&mut self, x: u64) {
        self.lo = (self.lo ^ x).wrapping_mul(0xFF51_AFD7_ED55_8CCD);
        self.lo ^= self.lo >> 33;
        self.hi = (self.hi ^ x.rotate_left(29)).wrapping_mul(0xC4CE_B9FE_1A85_EC53);
        self.hi ^= self.hi >> 29;
    }

    fn finish(mut self) -> u128 {
        self.add(0x2545_F491_4F6C_DD1D);
        u128::from(self.hi) << 64 | u128::from(self.lo)
    }
}

/// The local mesh of each element of a chunk: one for all (a uniform cell) or one each, in
/// the chunk's element order.
pub enum Locals<'a> {
    Uniform(&'a LocalMesh),
    PerElement(&'a [LocalMesh]),
}

impl Locals<'_> {
    /// The local mesh of the chunk's `i`-th element.
    fn get(&self, i: usize) -> &LocalMesh {
        match self {
            Locals::Uniform(local) => local,
            Locals::PerElement(all) => &all[i],
        }
    }
}

/// A local mesh's vertices sorted into interior ones and shared (boundary) ones.
struct Classified {
    /// Per local vertex: its index in `shared`, or [`NONE`] for interior vertices.
    shared_index: Vec<u32>,
    shared: Vec<SharedVertex>,
    /// Per local vertex: its reference coordinates.
    xi: Vec<[f64; 3]>,
}

const NONE: u32 = u32::MAX;

impl Classified {
    fn new(lattice: &dyn Lattice, local: &LocalMesh) -> Classified {
        // On the boundary: the lattice edge (or point) lies in one face, i.e. its corner
        // support is inside a face's corners.
        let face_masks = lattice.face_masks();
        let on_face = |mask: u8| face_masks.iter().any(|&f| mask & !f == 0);
        let mut shared = Vec::new();
        let mut shared_index = vec![NONE; local.vertices.len()];
        for (i, v) in local.vertices.iter().enumerate() {
            let a = lattice.weights(v.a);
            let b = (v.b != POINT).then(|| lattice.weights(v.b));
            let mask = a.mask() | b.map_or(0, |b| b.mask());
            if on_face(mask) {
                shared_index[i] = shared.len() as u32;
                shared.push(SharedVertex {
                    a,
                    b,
                    upper: v.upper,
                    caps: 0,
                });
            }
        }
        // Vertices only caps use (inside lattice points on faces) exist in an element only
        // where one of those caps is kept. Interior vertices are always on surface triangles.
        let mut surface = vec![false; local.vertices.len()];
        for t in &local.triangles {
            for &v in t {
                surface[v as usize] = true;
            }
        }
        for (f, cap) in local.caps.iter().enumerate() {
            for t in cap {
                for &v in t {
                    if !surface[v as usize] {
                        shared[shared_index[v as usize] as usize].caps |= 1 << f;
                    }
                }
            }
        }
        Classified {
            shared_index,
            shared,
            xi: local
                .vertices
                .iter()
                .map(|v| reference_point(lattice, v))
                .collect(),
        }
    }
}

/// What an element does with one of its shared vertices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    /// Only caps on interior faces use it: it is not in the output.
    Unused,
    /// The lowest element using it: it places and numbers it.
    Owner,
    /// A lower element of the same chunk owns it.
    Borrower,
    /// An element of an earlier chunk owns it (its id is known).
    Earlier,
    /// Not yet known: to be welded by name.
    Named,
}

/// The classified local meshes of a chunk's elements: one for all, or one each.
enum Classes<'c> {
    Uniform(&'c Classified),
    Each(Vec<Classified>),
}

impl Classes<'_> {
    fn get(&self, i: usize) -> &Classified {
        match self {
            Classes::Uniform(c) => c,
            Classes::Each(all) => &all[i],
        }
    }
}

/// A vertex of an earlier chunk that later elements may still use.
struct OpenVertex {
    id: u32,
    position: [f32; 3],
    /// The last element that may use it.
    last: u32,
}

/// What one element welded by structure, besides its slots' roles.
#[derive(Default)]
struct FaceWelds {
    /// The earlier chunks' vertices it borrows.
    borrowed: Vec<(u32, [f32; 3])>,
    /// Its owned slots that an element of a later chunk borrows, with that element.
    opens: Vec<(u32, u32)>,
    /// How many of its slots it borrows.
    paired: u64,
}

/// Most faces an element has (the cube's six).
const MAX_FACES: usize = 6;

/// How an element meets the scaffold through one of its faces, for the vertices inside it.
#[derive(Clone, Copy)]
enum FaceView {
    /// Weld by name (no plan, no neighbour, or lists that do not pair).
    Named,
    /// A boundary face: only this element uses its vertices.
    Alone,
    /// Paired slot by slot with `neighbour`, which sees the face as its face `face`; `code`
    /// and `other` are the two sides' rank codes ([`FacePlan::code`]).
    Paired {
        neighbour: u32,
        face: u8,
        code: u8,
        other: u8,
    },
}

/// Welds elements chunk by chunk, in element order, into the [`MeshChunk`]s of one mesh (see
/// the module docs). Between chunks it holds only per-element face data and the vertices open
/// across the chunk boundary (`frontier`, `face_frontier`), so memory follows the chunk, not
/// the scaffold's size.
pub struct Welder<'a> {
    elements: &'a dyn Corners,
    lattice: &'a dyn Lattice,
    /// Where each chunk's vertex and triangle arrays come from.
    spare: &'a SpareArrays,
    faces: FaceTable,
    /// `None` when one chunk takes every element: nothing is ever open.
    last: Option<LastUsers>,
    /// Open vertices welded by name, by name.
    frontier: HashMap<u128, OpenVertex, NameHasher>,
    /// Open vertices welded by structure, by `owner element << 32 | owner slot`.
    face_frontier: HashMap<u64, OpenVertex, NameHasher>,
    /// The frontier's `(id, last)`, by id: each chunk keeps the still-open ones and appends its
    /// own (all with higher ids), so the chunk's `open` list needs no sort of the whole front.
    open: Vec<(u32, u32)>,
    /// The element the next chunk starts at, and the id of its first vertex.
    next_element: usize,
    next_id: u64,
    /// A uniform cell's classified local mesh and its structural weld plan.
    uniform: Option<(Classified, Option<FacePlan>)>,
    /// Slots that took another element's vertex, welded by structure and by name.
    #[cfg_attr(not(test), allow(dead_code))]
    borrowed_by: [u64; 2],
    /// Buffers of the chunk being welded, reused by the next.
    scratch: Scratch,
}

impl<'a> Welder<'a> {
    /// A welder over `elements` on `lattice`; `chunked` when it will be fed more than one chunk.
    pub fn new(
        elements: &'a dyn Corners,
        lattice: &'a dyn Lattice,
        chunked: bool,
        spare: &'a SpareArrays,
    ) -> Result<Welder<'a>, TileError> {
        let faces = FaceTable::new(elements, lattice.face_masks())?;
        let last = chunked.then(|| LastUsers::new(elements, lattice.face_masks()));
        Ok(Welder {
            elements,
            lattice,
            spare,
            faces,
            last,
            frontier: HashMap::default(),
            face_frontier: HashMap::default(),
            open: Vec::new(),
            next_element: 0,
            next_id: 0,
            uniform: None,
            borrowed_by: [0; 2],
            scratch: Scratch::default(),
        })
    }

    pub fn stats(&self) -> TileStats {
        self.faces.stats.clone()
    }

    /// How element `e` (corner nodes `corners`, boundary bits `boundary`) meets the scaffold
    /// through each face, under `plan`.
    fn face_views(&self, plan: &FacePlan, e: usize, boundary: u8) -> [FaceView; MAX_FACES] {
        let per = self.lattice.face_masks().len();
        let corners = self.elements.element(e);
        let mut views = [FaceView::Named; MAX_FACES];
        for (f, view) in views.iter_mut().enumerate().take(per) {
            let neighbour = self.faces.neighbour[e * per + f];
            *view = if boundary & 1 << f != 0 {
                FaceView::Alone
            } else if neighbour == NONE {
                FaceView::Named
            } else {
                let g = self.faces.neighbour_face[e * per + f];
                let code = plan.code(f, corners);
                let other = plan.code(g as usize, self.elements.element(neighbour as usize));
                match plan.pairs(f, code, g as usize, other) {
                    true => FaceView::Paired {
                        neighbour,
                        face: g,
                        code: code as u8,
                        other: other as u8,
                    },
                    false => FaceView::Named,
                }
            };
        }
        views
    }

    /// Welds the next `count` elements (from where the previous chunk ended), whose local
    /// meshes are `locals`, into the next chunk of the mesh.
    pub fn chunk(&mut self, count: usize, locals: Locals) -> Result<MeshChunk, TileError> {
        let start = self.next_element;
        let end = (start + count).min(self.elements.count());
        if let Locals::Uniform(local) = &locals {
            self.classify_uniform(local);
        }
        let mut scratch = std::mem::take(&mut self.scratch);
        let welded = self.weld(start, end, &locals, &mut scratch);
        self.scratch = scratch;
        let welded = welded?;
        let open = self.advance(end, welded.fresh);
        self.borrowed_by[0] += welded.paired;
        self.borrowed_by[1] += welded.named_borrowers;
        self.next_element = end;
        self.next_id = welded.first + welded.vertices.len() as u64;
        Ok(MeshChunk {
            first_vertex: welded.first as u32,
            vertices: welded.vertices,
            triangles: welded.triangles,
            borrowed: welded.borrowed,
            open,
        })
    }

    /// Classifies a uniform cell's local mesh and plans its structural weld, once.
    fn classify_uniform(&mut self, local: &LocalMesh) {
        if self.uniform.is_some() {
            return;
        }
        let lattice = self.lattice;
        let classified = Classified::new(lattice, local);
        let plan = (lattice.face_masks().len() <= MAX_FACES).then(|| {
            let ends: Vec<_> = classified
                .shared
                .iter()
                .map(|v| (v.a, v.b, v.upper))
                .collect();
            let surface: Vec<bool> = classified.shared.iter().map(|v| v.caps == 0).collect();
            FacePlan::new(&ends, &surface, lattice.face_masks())
        });
        self.uniform = Some((classified, plan));
    }

    /// Welds elements `start..end` without changing the welder: their vertices, triangles
    /// and borrowed vertices, and the vertices they leave open.
    fn weld(
        &self,
        start: usize,
        end: usize,
        locals: &Locals,
        scratch: &mut Scratch,
    ) -> Result<Welded, TileError> {
        let span = self.span(start, end, locals);
        let n = end - start;
        scratch.slot_base.clear();
        scratch.slot_base.push(0usize);
        for i in 0..n {
            let next = scratch.slot_base[i] + span.class(i).shared.len();
            scratch.slot_base.push(next);
        }
        let slots = scratch.slot_base[n];
        scratch.role.clear();
        scratch.role.resize(slots, Role::Named);
        scratch.link.clear();
        scratch.link.resize(slots, 0);
        let structural = self.weld_by_structure(&span, scratch);
        let (mut borrowed, named_borrowers) = self.weld_by_name(&span, scratch);
        for welds in &structural {
            borrowed.extend_from_slice(&welds.borrowed);
        }
        borrowed.sort_unstable_by_key(|&(id, _)| id);
        let first = self.next_id;
        let (mut vertices, mut triangles) = self.spare.take();
        self.place_vertices(&span, first, scratch, &mut vertices)?;
        span.triangles(locals, scratch, &mut triangles);
        let fresh = self
            .last
            .as_ref()
            .map(|last| self.fresh_open(&span, last, &structural, scratch, &vertices, first));
        Ok(Welded {
            first,
            vertices,
            triangles,
            borrowed,
            fresh,
            paired: structural.iter().map(|w| w.paired).sum(),
            named_borrowers,
        })
    }

    /// Elements `start..end` with their classified local meshes (`locals`, or the uniform
    /// cell's, classified already).
    fn span<'c>(&'c self, start: usize, end: usize, locals: &Locals) -> Span<'c> {
        let n = end - start;
        let (classes, plan) = match locals {
            Locals::Uniform(_) => {
                let (classified, plan) = self.uniform.as_ref().expect("classified");
                (Classes::Uniform(classified), plan.as_ref())
            }
            Locals::PerElement(all) => (
                Classes::Each(
                    all[..n]
                        .par_iter()
                        .map(|l| Classified::new(self.lattice, l))
                        .collect(),
                ),
                None,
            ),
        };
        Span {
            start,
            end,
            classes,
            plan,
            boundary: &self.faces.boundary[start..end],
        }
    }

    /// Per slot: its role, and the owner's slot (Borrower) or the vertex id (Earlier).
    /// Vertices inside a face the plan pairs are welded by structure here, element by
    /// element; the rest are left Named for [`Self::weld_by_name`]. Returns what each element
    /// welded.
    fn weld_by_structure(&self, span: &Span, scratch: &mut Scratch) -> Vec<FaceWelds> {
        let slot_lengths = || (0..span.len()).map(|i| span.class(i).shared.len());
        let per_element: Vec<_> = split_by(&mut scratch.role, slot_lengths())
            .into_iter()
            .zip(split_by(&mut scratch.link, slot_lengths()))
            .collect();
        let slot_base = &scratch.slot_base;
        per_element
            .into_par_iter()
            .enumerate()
            .map(|(i, (roles, links))| self.weld_faces(span, slot_base, i, roles, links))
            .collect()
    }

    /// [`Self::weld_by_structure`] for the chunk's `i`-th element, whose slots' roles and
    /// links are `roles` and `links`.
    fn weld_faces(
        &self,
        span: &Span,
        slot_base: &[usize],
        i: usize,
        roles: &mut [Role],
        links: &mut [u32],
    ) -> FaceWelds {
        let e = span.start + i;
        let mut welds = FaceWelds::default();
        let views = span
            .plan
            .map(|plan| (plan, self.face_views(plan, e, span.boundary[i])));
        for (s, v) in span.class(i).shared.iter().enumerate() {
            if !span.used(i, v) {
                roles[s] = Role::Unused;
                continue;
            }
            let Some((plan, views)) = &views else {
                continue;
            };
            let f = plan.face_of(s);
            if f == NO_FACE {
                continue;
            }
            match views[f as usize] {
                FaceView::Named => {}
                FaceView::Alone => roles[s] = Role::Owner,
                FaceView::Paired { neighbour, .. } if neighbour as usize > e => {
                    roles[s] = Role::Owner;
                    if neighbour as usize >= span.end {
                        welds.opens.push((s as u32, neighbour));
                    }
                }
                FaceView::Paired {
                    neighbour,
                    face,
                    code,
                    other,
                } => {
                    let (code, other) = (code as usize, other as usize);
                    let theirs = plan.partner(s, f as usize, code, face as usize, other);
                    let owner = neighbour as usize;
                    welds.paired += 1;
                    if owner >= span.start {
                        roles[s] = Role::Borrower;
                        links[s] = (slot_base[owner - span.start] + theirs as usize) as u32;
                    } else if let Some(o) = self.face_frontier.get(&face_key(owner, theirs)) {
                        roles[s] = Role::Earlier;
                        links[s] = o.id;
                        welds.borrowed.push((o.id, o.position));
                    } else {
                        // Not reachable: the owner left it open for this element.
                        debug_assert!(false, "face vertex of {owner} not open");
                        roles[s] = Role::Owner;
                    }
                }
            }
        }
        welds
    }

    /// Names every other shared vertex every element uses; equal names are one vertex,
    /// owned by the lowest element — of an earlier chunk when the frontier has it. Sets the
    /// roles and links of the named slots and leaves the new groups (name and owner) in
    /// `scratch.groups`; returns the earlier chunks' vertices borrowed by name and how many
    /// slots took another's vertex.
    fn weld_by_name(&self, span: &Span, scratch: &mut Scratch) -> (Vec<(u32, [f32; 3])>, u64) {
        self.collect_names(span, scratch);
        let Scratch {
            slot_base,
            role,
            link,
            names,
            starts,
            earlier,
            groups,
            ..
        } = scratch;
        // Runs of equal names, and whether an earlier chunk has each: found in parallel, as
        // these can be millions of lookups a chunk.
        starts.clear();
        starts.par_extend(
            (0..names.len())
                .into_par_iter()
                .filter(|&r| r == 0 || names[r].0 != names[r - 1].0),
        );
        let frontier = &self.frontier;
        starts
            .par_iter()
            .map(|&r| match frontier.is_empty() {
                true => None,
                false => frontier.get(&names[r].0).map(|o| (o.id, o.position)),
            })
            .collect_into_vec(earlier);
        // The new groups, for the frontier; every run's slots get their role.
        groups.clear();
        let mut borrowed: Vec<(u32, [f32; 3])> = Vec::new();
        for (k, &r) in starts.iter().enumerate() {
            let run_end = starts.get(k + 1).copied().unwrap_or(names.len());
            let (_, i0, s0) = names[r];
            let owner_slot = (slot_base[i0 as usize] + s0 as usize) as u32;
            match earlier[k] {
                Some(vertex) => borrowed.push(vertex),
                None => groups.push(names[r]),
            }
            for (at, &(_, i, s)) in names[r..run_end].iter().enumerate() {
                let slot = slot_base[i as usize] + s as usize;
                (role[slot], link[slot]) = match earlier[k] {
                    Some((id, _)) => (Role::Earlier, id),
                    None if at == 0 => (Role::Owner, 0),
                    None => (Role::Borrower, owner_slot),
                };
            }
        }
        (borrowed, (names.len() - groups.len()) as u64)
    }

    /// The `(name, element, slot)` of every slot still Named, element by element in slot
    /// order, sorted by name into `scratch.names`.
    fn collect_names(&self, span: &Span, scratch: &mut Scratch) {
        let Scratch {
            slot_base,
            role,
            named,
            names,
            sorted,
            ..
        } = scratch;
        let roles = |i: usize| &role[slot_base[i]..slot_base[i + 1]];
        (0..span.len())
            .into_par_iter()
            .map(|i| roles(i).iter().filter(|&&r| r == Role::Named).count())
            .collect_into_vec(named);
        names.clear();
        names.resize(named.iter().sum(), (0, 0, 0));
        split_by(names, named.iter().copied())
            .into_par_iter()
            .enumerate()
            .for_each(|(i, out)| {
                let corners = self.elements.element(span.start + i);
                let roles = roles(i);
                let items = span.class(i).shared.iter().enumerate();
                let items = items
                    .filter(|&(s, _)| roles[s] == Role::Named)
                    .map(|(s, v)| (vertex_name(corners, v), i as u32, s as u32));
                for (slot, item) in out.iter_mut().zip(items) {
                    *slot = item;
                }
            });
        sort_names(names, sorted);
    }

    /// Vertex ids, element by element: its interior vertices and the shared ones it owns, in
    /// local order, from `first`. Fills `scratch.base` (each element's first id) and
    /// `scratch.slot_id` (the id each owner slot gave its vertex), and `vertices` (empty) with
    /// their positions.
    fn place_vertices(
        &self,
        span: &Span,
        first: u64,
        scratch: &mut Scratch,
        vertices: &mut Vec<[f32; 3]>,
    ) -> Result<(), TileError> {
        let n = span.len();
        let Scratch {
            slot_base,
            role,
            owned,
            base,
            slot_id,
            ..
        } = scratch;
        (0..n)
            .into_par_iter()
            .map(|i| {
                let c = span.class(i);
                let interior = c.shared_index.len() - c.shared.len();
                let roles = &role[slot_base[i]..slot_base[i + 1]];
                interior + roles.iter().filter(|&&r| r == Role::Owner).count()
            })
            .collect_into_vec(owned);
        base.clear();
        base.push(first);
        for &c in owned.iter() {
            base.push(base[base.len() - 1] + c as u64);
        }
        if base[n] > u64::from(u32::MAX) {
            return Err(TileError::TooManyVertices(base[n]));
        }
        slot_id.clear();
        slot_id.resize(slot_base[n], 0);
        // Written in place, element by element in parallel: each element's vertices have a
        // known range of the chunk.
        vertices.resize((base[n] - first) as usize, [0.0; 3]);
        let vertex_ranges = split_by(vertices, owned.iter().copied());
        let id_ranges = split_by(slot_id, (0..n).map(|i| span.class(i).shared.len()));
        let (role, slot_base, base) = (&*role, &*slot_base, &*base);
        vertex_ranges
            .into_par_iter()
            .zip(id_ranges)
            .enumerate()
            .for_each(|(i, (out, ids))| {
                let c = span.class(i);
                let mut next = base[i] as u32;
                let mut out = out.iter_mut();
                for (v, xi) in c.xi.iter().enumerate() {
                    let s = c.shared_index[v];
                    if s != NONE {
                        if role[slot_base[i] + s as usize] != Role::Owner {
                            continue;
                        }
                        ids[s as usize] = next;
                    }
                    next += 1;
                    if let Some(v) = out.next() {
                        *v = self.elements.place(span.start + i, *xi).map(|c| c as f32);
                    }
                }
            });
        Ok(())
    }

    /// The vertices of this chunk that later chunks may still use: the new shared ones whose
    /// node, edge or face reaches past it, by name and by face key.
    fn fresh_open(
        &self,
        span: &Span,
        last: &LastUsers,
        structural: &[FaceWelds],
        scratch: &Scratch,
        vertices: &[[f32; 3]],
        first: u64,
    ) -> FreshOpen {
        let face_masks = self.lattice.face_masks();
        // The last element each new named vertex reaches: a lookup per vertex, in parallel;
        // the few that stay open are then kept in order.
        let until: Vec<u32> = scratch
            .groups
            .par_iter()
            .map(|&(_, i, s)| {
                let e = span.start + i as usize;
                let v = &span.class(i as usize).shared[s as usize];
                let mask = v.a.mask() | v.b.map_or(0, |b| b.mask());
                last.of(e, self.elements.element(e), mask, &self.faces, face_masks)
            })
            .collect();
        let owner_id = |i: usize, s: u32| scratch.slot_id[scratch.slot_base[i] + s as usize];
        let open_vertex = |id: u32, last: u32| OpenVertex {
            id,
            position: vertices[(u64::from(id) - first) as usize],
            last,
        };
        let mut fresh = FreshOpen::default();
        for (g, &(name, i, s)) in scratch.groups.iter().enumerate() {
            if until[g] as usize >= span.end {
                let id = owner_id(i as usize, s);
                fresh.named.push((name, open_vertex(id, until[g])));
            }
        }
        for (i, welds) in structural.iter().enumerate() {
            for &(s, last) in &welds.opens {
                let id = owner_id(i, s);
                let key = face_key(span.start + i, s);
                fresh.faces.push((key, open_vertex(id, last)));
            }
        }
        fresh
    }

    /// Takes a chunk ending at element `end` that leaves `fresh` open (`None`: the welder
    /// keeps nothing open); returns the ids open after it, in order.
    fn advance(&mut self, end: usize, fresh: Option<FreshOpen>) -> Vec<u32> {
        let Some(fresh) = fresh else {
            return Vec::new();
        };
        let mut ids = Vec::with_capacity(fresh.named.len() + fresh.faces.len());
        for (name, vertex) in fresh.named {
            ids.push((vertex.id, vertex.last));
            self.frontier.insert(name, vertex);
        }
        for (key, vertex) in fresh.faces {
            ids.push((vertex.id, vertex.last));
            self.face_frontier.insert(key, vertex);
        }
        self.frontier.retain(|_, v| v.last as usize >= end);
        self.face_frontier.retain(|_, v| v.last as usize >= end);
        // Earlier ids are all below this chunk's first, so appending the sorted new ones
        // keeps the list sorted.
        self.open.retain(|&(_, last)| last as usize >= end);
        ids.sort_unstable();
        self.open.extend(ids);
        self.open.iter().map(|&(id, _)| id).collect()
    }
}

/// A chunk's elements as the weld sees them: elements `start..end`, their classified local
/// meshes, the uniform cell's structural plan and their boundary faces.
struct Span<'c> {
    start: usize,
    end: usize,
    classes: Classes<'c>,
    plan: Option<&'c FacePlan>,
    boundary: &'c [u8],
}

impl Span<'_> {
    fn len(&self) -> usize {
        self.end - self.start
    }

    fn class(&self, i: usize) -> &Classified {
        self.classes.get(i)
    }

    /// Whether the chunk's `i`-th element uses shared vertex `s`: surface triangles do, or a
    /// cap on one of its boundary faces.
    fn used(&self, i: usize, s: &SharedVertex) -> bool {
        s.caps == 0 || s.caps & self.boundary[i] != 0
    }

    /// The triangles of the chunk's elements into `triangles` (empty), element by element
    /// (surface, then the caps of boundary faces), in the ids [`Welder::place_vertices`] gave.
    fn triangles(&self, locals: &Locals, scratch: &mut Scratch, triangles: &mut Vec<[u32; 3]>) {
        let Scratch {
            slot_base,
            role,
            link,
            base,
            slot_id,
            triangle_counts,
            ..
        } = scratch;
        let boundary = self.boundary;
        (0..self.len())
            .into_par_iter()
            .map(|i| {
                let local = locals.get(i);
                let caps = local.caps.iter().enumerate();
                local.triangles.len()
                    + caps
                        .filter(|(f, _)| boundary[i] & 1 << f != 0)
                        .map(|(_, cap)| cap.len())
                        .sum::<usize>()
            })
            .collect_into_vec(triangle_counts);
        triangles.resize(triangle_counts.iter().sum(), [0; 3]);
        let triangle_ranges = split_by(triangles, triangle_counts.iter().copied());
        let (role, link, slot_id, slot_base, base) =
            (&*role, &*link, &*slot_id, &*slot_base, &*base);
        triangle_ranges.into_par_iter().enumerate().for_each_init(
            Vec::new,
            |ids: &mut Vec<u32>, (i, out)| {
                let (local, c) = (locals.get(i), self.class(i));
                let mut next = base[i] as u32;
                ids.clear();
                ids.extend((0..local.vertices.len()).map(|v| {
                    let s = c.shared_index[v];
                    if s != NONE {
                        let slot = slot_base[i] + s as usize;
                        match role[slot] {
                            Role::Owner => {}
                            // Only dropped caps use it: never referenced.
                            Role::Unused | Role::Named => return u32::MAX,
                            Role::Borrower => return slot_id[link[slot] as usize],
                            Role::Earlier => return link[slot],
                        }
                    }
                    next += 1;
                    next - 1
                }));
                let caps = local
                    .caps
                    .iter()
                    .enumerate()
                    .filter(|(f, _)| boundary[i] & 1 << f != 0)
                    .flat_map(|(_, cap)| cap.iter());
                for (slot, t) in out.iter_mut().zip(local.triangles.iter().chain(caps)) {
                    *slot = t.map(|v| ids[v as usize]);
                }
            },
        );
    }
}

/// What [`Welder::weld`] made of a chunk, for [`Welder::chunk`] to hand on.
struct Welded {
    first: u64,
    vertices: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    borrowed: Vec<(u32, [f32; 3])>,
    /// `None` when nothing is ever open (one chunk).
    fresh: Option<FreshOpen>,
    /// Slots that took another element's vertex, by structure and by name.
    paired: u64,
    named_borrowers: u64,
}

/// A chunk's vertices that later chunks may still use, welded by name and by structure.
#[derive(Default)]
struct FreshOpen {
    named: Vec<(u128, OpenVertex)>,
    faces: Vec<(u64, OpenVertex)>,
}

/// Buffers of a chunk's weld, kept from one chunk to the next: for a big chunk the arrays
/// over its slots and names are megabytes each, and allocating them afresh every chunk had
/// each page of them fault in again (glibc hands large freed blocks back to the kernel).
#[derive(Default)]
struct Scratch {
    /// Slots of the chunk's i-th element's shared vertices: `slot_base[i]..slot_base[i + 1]`.
    slot_base: Vec<usize>,
    /// Per slot: its role, and the owner's slot (Borrower) or the vertex id (Earlier).
    role: Vec<Role>,
    link: Vec<u32>,
    /// Per element: how many of its slots are welded by name.
    named: Vec<usize>,
    /// `(name, element, slot)` of the named slots, sorted by name (`sorted`: sort space).
    names: Vec<(u128, u32, u32)>,
    sorted: Vec<(u128, u32, u32)>,
    /// Where each run of equal names starts, and the earlier chunk's vertex it names.
    starts: Vec<usize>,
    earlier: Vec<Option<(u32, [f32; 3])>>,
    /// The runs no earlier chunk has: `(name, element, slot)` of the owner.
    groups: Vec<(u128, u32, u32)>,
    /// Per element: how many vertices it owns, and its first vertex id.
    owned: Vec<usize>,
    base: Vec<u64>,
    /// Per slot: the id its owner gave it (owner slots only).
    slot_id: Vec<u32>,
    /// Per element: its triangles.
    triangle_counts: Vec<usize>,
}

/// The face frontier's key of slot `slot` of element `e`.
fn face_key(e: usize, slot: u32) -> u64 {
    (e as u64) << 32 | u64::from(slot)
}

/// Hashes a vertex name (already a 128-bit hash) by folding it to 64 bits.
#[derive(Clone, Copy, Default)]
struct NameHasher;

impl std::hash::BuildHasher for NameHasher {
    type Hasher = FoldHasher;
    fn build_hasher(&self) -> FoldHasher {
        FoldHasher(0)
    }
}

struct FoldHasher(u64);

impl std::hash::Hasher for FoldHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01B3);
        }
    }
    fn write_u64(&mut self, key: u64) {
        self.0 = fmix64(key);
    }
    fn write_u128(&mut self, name: u128) {
        self.0 ^= (name as u64) ^ (name >> 64) as u64;
    }
}

/// `items` cut into consecutive slices of the given lengths (which sum to its length).
fn split_by<T>(items: &mut [T], lengths: impl Iterator<Item = usize>) -> Vec<&mut [T]> {
    let mut rest = items;
    let mut slices = Vec::new();
    for len in lengths {
        let (head, tail) = std::mem::take(&mut rest).split_at_mut(len);
        slices.push(head);
        rest = tail;
    }
    slices
}

/// Reference coordinates of a local vertex.
fn reference_point(lattice: &dyn Lattice, v: &LocalVertex) -> [f64; 3] {
    let a = lattice.xi(v.a);
    if v.b == POINT {
        a
    } else {
        let b = lattice.xi(v.b);
        std::array::from_fn(|k| a[k] + v.t * (b[k] - a[k]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Triples with uniform names, some names repeated (as shared vertices are).
    fn triples(n: usize) -> Vec<(u128, u32, u32)> {
        (0..n as u64)
            .map(|i| {
                let name = u128::from(fmix64(i / 3 + 1)) << 64 | u128::from(fmix64(i / 3 + 7));
                (name, fmix64(i) as u32, i as u32)
            })
            .collect()
    }

    /// Corners of a scaffold's elements, placed at a point only the element and `xi` fix.
    struct Plain {
        corners: Vec<u32>,
        per: usize,
    }

    impl Corners for Plain {
        fn count(&self) -> usize {
            self.corners.len() / self.per
        }
        fn element(&self, e: usize) -> &[u32] {
            &self.corners[e * self.per..(e + 1) * self.per]
        }
        fn place(&self, e: usize, xi: [f64; 3]) -> [f64; 3] {
            [xi[0] + e as f64, xi[1] - 0.5 * e as f64, xi[2]]
        }
    }

    /// Schwarz P less an offset, in whatever reference coordinates the lattice has.
    struct SchwarzP(f64);

    impl crate::field::ScalarField for SchwarzP {
        fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
            let tau = std::f64::consts::TAU;
            for i in 0..out.len() {
                out[i] = (tau * xs[i]).cos() + (tau * ys[i]).cos() + (tau * zs[i]).cos() - self.0;
            }
        }
    }

    /// The chunks of a uniform cell welded with the structural plan, and by name only (the
    /// same local mesh given per element), with the counts of slots borrowed each way.
    fn weld_both_ways(
        elements: &dyn Corners,
        lattice: &dyn Lattice,
        local: &LocalMesh,
        per_chunk: usize,
    ) -> ([Vec<MeshChunk>; 2], [u64; 2]) {
        let count = elements.count();
        let chunks = count.div_ceil(per_chunk);
        let all = vec![local.clone(); count];
        let run = |uniform: bool| {
            let spare = SpareArrays::default();
            let mut welder =
                Welder::new(elements, lattice, chunks > 1, &spare).expect("conforming");
            let out: Vec<MeshChunk> = (0..chunks)
                .map(|k| {
                    let locals = match uniform {
                        true => Locals::Uniform(local),
                        false => Locals::PerElement(&all[k * per_chunk..]),
                    };
                    welder.chunk(per_chunk, locals).expect("weld")
                })
                .collect();
            (out, welder.borrowed_by)
        };
        let (structural, by) = run(true);
        let (named, by_name) = run(false);
        assert_eq!(by_name[0], 0, "per-element cells are welded by name");
        assert_eq!(
            by[0] + by[1],
            by_name[1],
            "the same slots borrow either way"
        );
        ([structural, named], by)
    }

    /// The structural weld gives the name weld's mesh bit for bit on the bundled copies of
    /// the Gmsh-made scaffolds in examples/scaffolds (CI has only the repository; seven element
    /// kinds), whole or in
    /// chunks, and pairs shared vertices itself.
    #[test]
    fn structural_weld_equals_the_name_weld_on_every_scaffold() {
        use crate::scaffold::{ElementKind, read_scaffold};
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/scaffolds");
        let mut kinds = std::collections::BTreeSet::new();
        let mut files: Vec<_> = std::fs::read_dir(dir)
            .expect("bundled scaffolds")
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "msh"))
            .collect();
        files.sort();
        for path in files {
            let name = path.display().to_string();
            let bytes = std::fs::read(&path).expect("read");
            let Ok(scaffold) = read_scaffold(&bytes, &name, None) else {
                continue;
            };
            if scaffold.element_count() > 20_000 {
                continue;
            }
            let resolution = 8;
            let lattice: Box<dyn Lattice> = match scaffold.kind {
                ElementKind::Tet4 | ElementKind::Tet10 => {
                    Box::new(super::super::simplex::TetLattice::new(resolution))
                }
                ElementKind::Hex8 | ElementKind::Hex20 | ElementKind::Hex27 => {
                    Box::new(super::super::cube::CubeLattice::new(resolution))
                }
                ElementKind::Quad4 | ElementKind::Quad8 | ElementKind::Quad9 => {
                    Box::new(super::super::square::SquareLattice::new(resolution))
                }
                ElementKind::Tri3 | ElementKind::Tri6 => {
                    Box::new(super::super::triangle::TriangleLattice::new(resolution))
                }
            };
            let per = scaffold.kind.corner_count();
            let elements = Plain {
                corners: (0..scaffold.element_count())
                    .flat_map(|e| scaffold.element(e)[..per].to_vec())
                    .collect(),
                per,
            };
            let samples = super::super::symmetric_samples(lattice.as_ref(), &SchwarzP(0.4));
            let local = lattice.contour(super::super::local::Samples::one(&samples));
            for per_chunk in [elements.count().max(1), 37] {
                let ([structural, named], by) =
                    weld_both_ways(&elements, lattice.as_ref(), &local, per_chunk);
                assert!(structural == named, "{name}, {per_chunk} per chunk");
                assert!(
                    by[0] > 0,
                    "{name}: {} slots paired by structure, {} by name",
                    by[0],
                    by[1]
                );
            }
            kinds.insert(scaffold.kind.name());
        }
        assert!(kinds.len() >= 7, "kinds tested: {kinds:?}");
    }

    #[test]
    fn sort_names_sorts_as_sort_unstable_at_any_thread_count() {
        for n in [0, 100, 5_000, 300_000] {
            let mut expected = triples(n);
            expected.sort_unstable();
            for threads in [1, 3] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("pool");
                let mut names = triples(n);
                pool.install(|| sort_names(&mut names, &mut Vec::new()));
                assert!(names == expected, "{n} names on {threads} threads");
            }
        }
    }
}
