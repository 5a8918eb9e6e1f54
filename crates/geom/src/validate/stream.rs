//! [`StreamCheck`]: the measurements of [`check`](super::check) over a mesh that arrives as
//! [`MeshChunk`]s, holding one chunk and the still-open vertices at a time, never the mesh.
//!
//! Invariants:
//! - For chunks that keep the [`MeshChunk`] invariants, [`StreamCheck::finish`] equals
//!   [`check`](super::check) of the concatenated mesh in every field, bit for bit (volume and
//!   area included: the sums are cut at the same global triangle indices and added in the same
//!   order), with one documented exception, `duplicate_positions` (below).
//! - Between pushes the mesh state is the open vertices only: for each, its id, position, the
//!   corners of the triangles seen so far at it (its partial fan, 8 bytes a corner) and, for a
//!   few, a duplicate-class count. Nothing grows with the finished part of the mesh. The
//!   push's buffers (36 bytes per triangle and 5 + 4 × threads (at most 8) per vertex of the
//!   largest chunk) are kept for the next push.
//! - [`StreamCheck::push`] never panics, whatever the chunk holds, and the result does not
//!   depend on the thread count (sums over fixed global chunks, integer counts, min/max).
//!
//! Method: the vertices *alive* in a push are the ids open after the previous push, the ids
//! the chunk borrows that are not open (see below), and the chunk's own vertices; they get
//! dense local numbers, earlier ids first, so own vertices need no lookup. The chunk's
//! triangles are summed (geometry, as in `check`) and their corners are sorted by vertex
//! (counting sort) together with the corners carried for the open vertices. A vertex that is
//! not open after the push has its complete fan: it is classified exactly as `check` does
//! (closed-fan fast path, else the general fan check; each edge `{a, b}` counted from its
//! smaller end `a` only, which finishes with all the triangles on the edge at hand). The open
//! vertices keep their corners for the next push.
//!
//! **Duplicate positions** need, in general, every position seen so far, which grows with the
//! mesh. Instead, vertices with bit-identical positions are compared while they are alive
//! together: a *class* is a position's vertices linked by overlapping lifetimes (a vertex lives
//! from the push that brings it, as own or borrowed, to the push after which it is no longer
//! open). When the last member of a class finishes, the class adds `referenced members − 1`
//! (the definition's `k − 1`). So the count is exact whenever, for every position, the
//! lifetimes of its vertices chain together (in particular when they all lie in one window:
//! one chunk's own vertices plus the ids open or borrowed at that time); otherwise vertices of
//! one position in windows far apart are not matched, and the count can only be lower than
//! `check`'s, never higher.
//!
//! Chunks that break the [`MeshChunk`] invariants are measured as far as they can be:
//! - a triangle with an id past the chunk's end, or an earlier id missing from `borrowed`, is
//!   invalid (as `check` counts an index past the end);
//! - an earlier id in `borrowed` that is not open (used again after it was finished, or never
//!   listed as open) starts a new fan with the borrowed position: triangles, area and volume
//!   stay exact, its topology is counted as a separate vertex;
//! - ids in `open` that are not alive are ignored; unsorted `open` or `borrowed` are sorted
//!   (the first entry of a repeated borrowed id wins); open ids that a chunk declares as its
//!   own again (`first_vertex` not past them) are finished before that chunk;
//! - open ids left after the last chunk are finished by [`StreamCheck::finish`];
//! - own vertices with ids past `u32::MAX − 1` cannot be named by a triangle and count as
//!   unreferenced.

use super::{
    Entry, FanScratch, FanSums, Index, MAX_PARTS, MeshCheck, NEXT, PARTITION_SIZE, PREV,
    PendingTriangles, SMALL_FAN, TRIANGLE_CHUNK, TriangleSums, VERTEX_BLOCK, VERTEX_CHUNK,
    VertexSums, closed_fan, general_fan, link, report,
};
use crate::mesh::MeshChunk;
use rayon::prelude::*;
use std::borrow::Cow;
use std::sync::atomic::{AtomicU64, Ordering};

/// One past the largest vertex id a triangle can name.
const ID_SPACE: u64 = 1 << 32;

/// Marks an invalid triangle among the local triangles. No local index reaches it: own ids
/// stop below `u32::MAX` and earlier ids are fewer than the first own id.
const INVALID: u32 = u32::MAX;

// Flags of an alive vertex in one push.
/// Still open after the push.
const OPEN: u8 = 1;
/// Finishes in this push with at least one triangle corner.
const REFERENCED: u8 = 2;
/// Holds its duplicate class's count of finished referenced members.
const COUNTED: u8 = 4;

/// Validates a mesh chunk by chunk; see the module documentation.
pub struct StreamCheck {
    triangles: usize,
    /// All vertices of all chunks, referenced or not.
    vertices: usize,
    /// The first corner of the first valid triangle: the volume's reference point, as in
    /// `check`.
    reference: Option<[f64; 3]>,
    /// The sums of the global triangle chunks finished so far, added in order.
    completed: TriangleSums,
    /// The sums of the global triangle chunk in progress.
    partial: TriangleSums,
    fans: FanSums,
    referenced: usize,
    duplicates: usize,
    bbox_min: [f32; 3],
    bbox_max: [f32; 3],
    open: OpenSet,
    scratch: Scratch,
}

/// The buffers of a push, kept for the next one: allocating them afresh costs a page fault
/// per 4 KiB, about a tenth of a push. Their size follows the largest chunk so far.
#[derive(Default)]
struct Scratch {
    locals: Vec<[u32; 3]>,
    links: Vec<u64>,
    state: Vec<u8>,
    /// Cursor and degree arrays, when the index type is `u32`.
    counts: Vec<Vec<u32>>,
}

/// Index types whose count arrays come from [`Scratch`] (`u32`) or are allocated (`u64`,
/// only for chunks of over a billion triangles).
trait Counts: Index {
    /// A zeroed array of `len` counts.
    fn take(pool: &mut Vec<Vec<u32>>, len: usize) -> Vec<Self>;
    fn give(pool: &mut Vec<Vec<u32>>, counts: Vec<Self>);
}

impl Counts for u32 {
    fn take(pool: &mut Vec<Vec<u32>>, len: usize) -> Vec<u32> {
        let mut counts = pool.pop().unwrap_or_default();
        counts.clear();
        counts.resize(len, 0);
        counts
    }

    fn give(pool: &mut Vec<Vec<u32>>, counts: Vec<u32>) {
        pool.push(counts);
    }
}

impl Counts for u64 {
    fn take(_: &mut Vec<Vec<u32>>, len: usize) -> Vec<u64> {
        vec![0; len]
    }

    fn give(_: &mut Vec<Vec<u32>>, _: Vec<u64>) {}
}

/// The open vertices, sorted by id, and what is held for each.
struct OpenSet {
    ids: Vec<u32>,
    positions: Vec<[f32; 3]>,
    /// Vertex `k`'s corners so far are `links[offsets[k]..offsets[k + 1]]`.
    offsets: Vec<usize>,
    links: Vec<u64>,
    /// `(k, count)`, sorted by `k`: vertex `k` holds its duplicate class's count of finished
    /// referenced members (at most one open vertex of a class holds it; most hold none).
    classes: Vec<(u32, usize)>,
}

impl Default for OpenSet {
    fn default() -> Self {
        OpenSet {
            ids: Vec::new(),
            positions: Vec::new(),
            offsets: vec![0],
            links: Vec::new(),
            classes: Vec::new(),
        }
    }
}

/// One step of the stream: a chunk, or (with no vertices and an id space of its own) the
/// finishing of open vertices.
struct View<'a> {
    first: u64,
    vertices: &'a [[f32; 3]],
    triangles: &'a [[u32; 3]],
    /// Sorted by id, ids unique.
    borrowed: Cow<'a, [(u32, [f32; 3])]>,
    /// Sorted, unique.
    open: Cow<'a, [u32]>,
}

impl View<'_> {
    /// A step that brings nothing and keeps `open` (a subset of the open ids) open.
    fn finishing(open: Vec<u32>) -> View<'static> {
        View {
            first: ID_SPACE,
            vertices: &[],
            triangles: &[],
            borrowed: Cow::Borrowed(&[]),
            open: Cow::Owned(open),
        }
    }
}

impl Default for StreamCheck {
    fn default() -> Self {
        StreamCheck::new()
    }
}

impl StreamCheck {
    pub fn new() -> StreamCheck {
        StreamCheck {
            triangles: 0,
            vertices: 0,
            reference: None,
            completed: TriangleSums::default(),
            partial: TriangleSums::default(),
            fans: FanSums::default(),
            referenced: 0,
            duplicates: 0,
            bbox_min: [f32::INFINITY; 3],
            bbox_max: [f32::NEG_INFINITY; 3],
            open: OpenSet::default(),
            scratch: Scratch::default(),
        }
    }

    /// Takes the next chunk of the mesh. Never panics; see the module documentation for
    /// chunks that break the [`MeshChunk`] invariants.
    pub fn push(&mut self, chunk: &MeshChunk) {
        let first = u64::from(chunk.first_vertex);
        if self
            .open
            .ids
            .last()
            .is_some_and(|&id| u64::from(id) >= first)
        {
            let keep = self
                .open
                .ids
                .iter()
                .copied()
                .filter(|&id| u64::from(id) < first)
                .collect();
            self.advance(View::finishing(keep));
        }
        // Own ids stop below u32::MAX (see INVALID); first <= u32::MAX.
        let addressable = chunk
            .vertices
            .len()
            .min((u64::from(u32::MAX) - first) as usize);
        self.vertices = self.vertices.saturating_add(chunk.vertices.len());
        self.advance(View {
            first,
            vertices: &chunk.vertices[..addressable],
            triangles: &chunk.triangles,
            borrowed: sorted_borrowed(&chunk.borrowed),
            open: sorted_ids(&chunk.open),
        });
    }

    /// The measurements of the whole mesh, as [`check`](super::check) gives them.
    pub fn finish(mut self) -> MeshCheck {
        if !self.open.ids.is_empty() {
            self.advance(View::finishing(Vec::new()));
        }
        let mut total = self.completed;
        total.add(&self.partial);
        let geometry = total.geometry(self.reference.unwrap_or([0.0; 3]));
        let vertices = VertexSums {
            referenced: self.referenced,
            duplicates: self.duplicates,
            bbox_min: self.bbox_min,
            bbox_max: self.bbox_max,
        };
        report(
            self.triangles,
            self.vertices,
            &geometry,
            &vertices,
            &self.fans,
        )
    }

    /// Vertices open after the last push: the only vertices whose state is held.
    pub fn open_vertices(&self) -> usize {
        self.open.ids.len()
    }

    /// Triangle corners held for the open vertices (their fans so far), 8 bytes each.
    pub fn held_corners(&self) -> usize {
        self.open.links.len()
    }

    /// The triangles held, each once, in winding order starting from its smallest id.
    #[cfg(test)]
    pub(super) fn held_triangles(&self) -> std::collections::BTreeSet<[u32; 3]> {
        let mut held = std::collections::BTreeSet::new();
        for (k, &v) in self.open.ids.iter().enumerate() {
            for &l in &self.open.links[self.open.offsets[k]..self.open.offsets[k + 1]] {
                let (next, prev) = super::unlink(l);
                let mut tri = [v, next, prev];
                let smallest = (0..3).min_by_key(|&i| tri[i]).unwrap_or(0);
                tri.rotate_left(smallest);
                held.insert(tri);
            }
        }
        held
    }

    fn advance(&mut self, view: View) {
        let links = self.open.links.len() as u64 + 3 * view.triangles.len() as u64;
        if links <= u64::from(u32::MAX) {
            self.advance_with::<u32>(view);
        } else {
            self.advance_with::<u64>(view);
        }
    }

    /// One push; `I` counts the corners held and brought (see `advance`).
    fn advance_with<I: Counts>(&mut self, view: View) {
        let prev = std::mem::take(&mut self.open);
        let mut scratch = std::mem::take(&mut self.scratch);
        let alive = Alive::new(&prev, &view);
        let first = view.first;
        let borrowed = &view.borrowed[..alive.borrowed_local.len()];
        // The position by reference: a copy inside the `Option` went through the stack, where
        // the wider loads of it could not be forwarded from the narrower stores.
        let lookup = |v: u32| -> Option<(u32, &[f32; 3])> {
            let id = u64::from(v);
            if id >= first {
                let k = (id - first) as usize;
                view.vertices
                    .get(k)
                    .map(|p| ((alive.earlier + k) as u32, p))
            } else {
                let j = borrowed.binary_search_by_key(&v, |&(id, _)| id).ok()?;
                Some((alive.borrowed_local[j], &borrowed[j].1))
            }
        };
        let n = alive.earlier + view.vertices.len();

        if self.reference.is_none() {
            self.reference = view.triangles.iter().find_map(|tri| {
                let corners = tri.map(lookup);
                corners
                    .iter()
                    .all(Option::is_some)
                    .then(|| corners[0].map(|(_, p)| p.map(f64::from)))
                    .flatten()
            });
        }
        let reference = self.reference.unwrap_or([0.0; 3]);

        let locals = std::mem::take(&mut scratch.locals);
        let (locals, degrees) =
            self.triangle_pass::<I>(&view, n, &lookup, reference, locals, &mut scratch.counts);
        let links = std::mem::take(&mut scratch.links);
        let (offsets, links) = scatter(&prev, &alive, &view, &locals, degrees, links, &mut scratch);
        scratch.locals = locals;

        let mut state = std::mem::take(&mut scratch.state);
        state.clear();
        state.resize(n, 0);
        for &id in view.open.iter() {
            if let Some(v) = alive.local(id, &view) {
                state[v] |= OPEN;
            }
        }
        let counts: Vec<(u32, usize)> = prev
            .classes
            .iter()
            .map(|&(k, count)| (alive.prev_local[k as usize], count))
            .collect();
        for &(v, _) in &counts {
            state[v as usize] |= COUNTED;
        }
        drop(prev);

        let position = |v: usize| {
            if v < alive.earlier {
                alive.positions[v]
            } else {
                view.vertices[v - alive.earlier]
            }
        };
        let id_of = |v: usize| {
            if v < alive.earlier {
                alive.ids[v]
            } else {
                // Own ids are below u32::MAX (see `push`).
                (first + (v - alive.earlier) as u64) as u32
            }
        };
        let fans = fan_pass(&offsets, &links, &mut state, &position, &id_of);
        self.fans = self.fans.merge(fans.sums);
        self.referenced += fans.referenced;
        for a in 0..3 {
            self.bbox_min[a] = self.bbox_min[a].min(fans.bbox_min[a]);
            self.bbox_max[a] = self.bbox_max[a].max(fans.bbox_max[a]);
        }

        let (duplicates, classes) = duplicate_classes(&state, &position, &counts);
        self.duplicates += duplicates;

        let mut next = OpenSet::default();
        let mut classes = classes.into_iter().peekable();
        for v in (0..n).filter(|&v| state[v] & OPEN != 0) {
            if let Some((_, count)) = classes.next_if(|&(c, _)| c as usize == v) {
                next.classes.push((next.ids.len() as u32, count));
            }
            next.ids.push(id_of(v));
            next.positions.push(position(v));
            next.links
                .extend_from_slice(&links[offsets[v].to_usize()..offsets[v + 1].to_usize()]);
            next.offsets.push(next.links.len());
        }
        self.open = next;
        I::give(&mut scratch.counts, offsets);
        scratch.links = links;
        scratch.state = state;
        self.scratch = scratch;
    }

    /// Sums the geometry of the view's triangles into the global triangle chunks, and gives
    /// each triangle's local corners (`INVALID` for invalid triangles) and, for each part (a
    /// range of triangles, the ranges in order), the corner counts at every alive vertex.
    fn triangle_pass<'p, I: Counts>(
        &mut self,
        view: &View,
        n: usize,
        lookup: &(impl Fn(u32) -> Option<(u32, &'p [f32; 3])> + Sync),
        reference: [f64; 3],
        mut locals: Vec<[u32; 3]>,
        pool: &mut Vec<Vec<u32>>,
    ) -> (Vec<[u32; 3]>, Vec<Part<I>>) {
        let count = view.triangles.len();
        // Segments cut where the global triangle index is a multiple of TRIANGLE_CHUNK, so the
        // sums are check's, term for term and in the same order.
        let offset = self.triangles % TRIANGLE_CHUNK;
        let mut segments = Vec::new();
        let mut start = 0;
        let mut end = TRIANGLE_CHUNK - offset;
        while start < count {
            segments.push((start, end.min(count)));
            start = end;
            end += TRIANGLE_CHUNK;
        }
        let parts = rayon::current_num_threads()
            .clamp(1, MAX_PARTS)
            .min(segments.len().max(1));
        let per_part = segments.len().div_ceil(parts).max(1);

        // Every entry is written below: the old contents need no clearing.
        locals.truncate(count);
        locals.resize(count, [0; 3]);
        let mut work = Vec::with_capacity(parts);
        let mut rest = locals.as_mut_slice();
        for part in segments.chunks(per_part) {
            let length = part[part.len() - 1].1 - part[0].0;
            let (head, tail) = rest.split_at_mut(length);
            work.push((part, head, I::take(pool, n)));
            rest = tail;
        }
        let partial = &self.partial;
        let results: Vec<(Vec<TriangleSums>, Vec<I>)> = work
            .into_par_iter()
            .map(|(part, out, mut degrees)| {
                let mut sums_of = Vec::with_capacity(part.len());
                let base = part[0].0;
                for &(start, end) in part {
                    // The first segment continues the global chunk in progress.
                    let mut sums = if start == 0 {
                        partial.clone()
                    } else {
                        TriangleSums::default()
                    };
                    let mut pending = PendingTriangles::default();
                    for (tri, local) in view.triangles[start..end]
                        .iter()
                        .zip(&mut out[start - base..end - base])
                    {
                        let (Some(a), Some(b), Some(c)) =
                            (lookup(tri[0]), lookup(tri[1]), lookup(tri[2]))
                        else {
                            sums.invalid += 1;
                            *local = [INVALID; 3];
                            continue;
                        };
                        *local = [a.0, b.0, c.0];
                        for v in *local {
                            let degree = &mut degrees[v as usize];
                            *degree = I::from_usize(degree.to_usize() + 1);
                        }
                        sums.add_triangle(
                            &mut pending,
                            tri,
                            [a.1, b.1, c.1].map(|p| p.map(f64::from)),
                            reference,
                        );
                    }
                    sums.flush(&mut pending);
                    sums_of.push(sums);
                }
                (sums_of, degrees)
            })
            .collect();

        let ranges = segments
            .chunks(per_part)
            .map(|part| part[0].0..part[part.len() - 1].1);
        let mut degrees = Vec::with_capacity(results.len());
        let mut segment = segments.iter();
        for ((sums_of, counts), triangles) in results.into_iter().zip(ranges) {
            for sums in sums_of {
                let end = segment.next().map_or(0, |s| s.1);
                if (offset + end).is_multiple_of(TRIANGLE_CHUNK) {
                    self.completed.add(&sums);
                    self.partial = TriangleSums::default();
                } else {
                    self.partial = sums;
                }
            }
            degrees.push(Part { triangles, counts });
        }
        self.triangles += count;
        (locals, degrees)
    }
}

/// The alive vertices' local numbering: `earlier` ids below the view's first own id (sorted;
/// local `k < earlier` is `ids[k]`), then the own vertices in id order.
struct Alive {
    earlier: usize,
    ids: Vec<u32>,
    positions: Vec<[f32; 3]>,
    /// For each earlier vertex, its index among the previously open ones, or `u32::MAX` when it
    /// was not open (a borrowed id starting a new fan).
    prev_index: Vec<u32>,
    /// The local number of each previously open vertex.
    prev_local: Vec<u32>,
    /// The local number of each borrowed entry below the first own id (the sorted prefix of
    /// `borrowed` this long); later entries are ignored.
    borrowed_local: Vec<u32>,
}

impl Alive {
    /// Merges the previously open ids (all below the view's first id: see `push`) with the
    /// borrowed ids below it.
    fn new(prev: &OpenSet, view: &View) -> Alive {
        let borrowed = &view.borrowed[..view
            .borrowed
            .partition_point(|&(id, _)| u64::from(id) < view.first)];
        let capacity = prev.ids.len() + borrowed.len();
        let mut alive = Alive {
            earlier: 0,
            ids: Vec::with_capacity(capacity),
            positions: Vec::with_capacity(capacity),
            prev_index: Vec::with_capacity(capacity),
            prev_local: Vec::with_capacity(prev.ids.len()),
            borrowed_local: Vec::with_capacity(borrowed.len()),
        };
        let (mut i, mut j) = (0, 0);
        loop {
            let open = prev.ids.get(i).copied();
            let lent = borrowed.get(j).map(|&(id, _)| id);
            let local = alive.ids.len() as u32;
            match (open, lent) {
                (None, None) => break,
                (Some(o), _) if lent.is_none_or(|b| o <= b) => {
                    if lent == Some(o) {
                        alive.borrowed_local.push(local);
                        j += 1;
                    }
                    // An open vertex keeps the position its own chunk gave it.
                    alive.ids.push(o);
                    alive.positions.push(prev.positions[i]);
                    alive.prev_index.push(i as u32);
                    alive.prev_local.push(local);
                    i += 1;
                }
                (_, Some(b)) => {
                    alive.borrowed_local.push(local);
                    alive.ids.push(b);
                    alive.positions.push(borrowed[j].1);
                    alive.prev_index.push(u32::MAX);
                    j += 1;
                }
                // Unreachable: the first arm takes every (Some, None).
                (Some(_), None) => break,
            }
        }
        alive.earlier = alive.ids.len();
        alive
    }

    /// The local number of alive id `id`.
    fn local(&self, id: u32, view: &View) -> Option<usize> {
        let id64 = u64::from(id);
        if id64 >= view.first {
            let k = (id64 - view.first) as usize;
            (k < view.vertices.len()).then_some(self.earlier + k)
        } else {
            self.ids.binary_search(&id).ok()
        }
    }
}

/// The corner counts of one part of the triangle pass: its range of the view's triangles and
/// the corners they put at every alive vertex. [`scatter`] turns the counts into the part's
/// cursors.
struct Part<I> {
    triangles: std::ops::Range<usize>,
    counts: Vec<I>,
}

/// The counting sort's scatter: vertex `v`'s corners are those carried for it (if it was
/// open), then those of each part's triangles, parts in order, each in triangle order. Each
/// part places the corners of its own triangles, in slots no other part writes; where `check`
/// (`Links::scatter`) has each thread own a range of vertices and scan every triangle, here
/// every triangle is read once. Returns the offsets and the corners (links).
fn scatter<I: Counts>(
    prev: &OpenSet,
    alive: &Alive,
    view: &View,
    locals: &[[u32; 3]],
    mut parts: Vec<Part<I>>,
    mut links: Vec<u64>,
    scratch: &mut Scratch,
) -> (Vec<I>, Vec<u64>) {
    let n = alive.earlier + view.vertices.len();
    let carried = |v: usize| -> &[u64] {
        match alive.prev_index.get(v) {
            Some(&i) if i != u32::MAX => {
                let i = i as usize;
                &prev.links[prev.offsets[i]..prev.offsets[i + 1]]
            }
            _ => &[],
        }
    };
    // offsets[v] is where v's corners start; each part's count at v becomes where its first
    // corner at v goes.
    let mut offsets = I::take(&mut scratch.counts, n + 1);
    let mut total = 0;
    for (v, offset) in offsets[..n].iter_mut().enumerate() {
        *offset = I::from_usize(total);
        total += carried(v).len();
        for part in parts.iter_mut() {
            let count = part.counts[v].to_usize();
            part.counts[v] = I::from_usize(total);
            total += count;
        }
    }
    offsets[n] = I::from_usize(total);

    // Every slot is written below: the old contents need no clearing.
    links.truncate(total);
    links.resize(total, 0);
    for (v, offset) in offsets[..alive.earlier].iter().enumerate() {
        let held = carried(v);
        let at = offset.to_usize();
        links[at..at + held.len()].copy_from_slice(held);
    }
    match as_atomic(&mut links) {
        // Relaxed: the parts write disjoint slots, and the end of the parallel loop orders the
        // writes before the fan pass reads them. A plain store on the targets we know.
        Some(slots) => parts.par_iter_mut().for_each(|part| {
            place(locals, view.triangles, part, |at, link| {
                slots[at].store(link, Ordering::Relaxed)
            });
        }),
        // Not aligned for atomics (a platform where u64 is less aligned): one thread.
        None => parts
            .iter_mut()
            .for_each(|part| place(locals, view.triangles, part, |at, link| links[at] = link)),
    }
    for part in parts {
        I::give(&mut scratch.counts, part.counts);
    }
    (offsets, links)
}

/// Places the corners of `part`'s triangles with `store(slot, link)`, advancing its cursors.
/// Generic in `store` so that the store inlines into the loop.
fn place<I: Index>(
    locals: &[[u32; 3]],
    triangles: &[[u32; 3]],
    part: &mut Part<I>,
    mut store: impl FnMut(usize, u64),
) {
    let range = part.triangles.clone();
    for (local, tri) in locals[range.clone()].iter().zip(&triangles[range]) {
        if local[0] == INVALID {
            continue;
        }
        for corner in 0..3 {
            let cursor = &mut part.counts[local[corner] as usize];
            let at = cursor.to_usize();
            store(at, link(tri[NEXT[corner]], tri[PREV[corner]]));
            *cursor = I::from_usize(at + 1);
        }
    }
}

/// `links` as atomics, so the parts of the scatter can fill disjoint slots of it from several
/// threads without `unsafe` writes; `None` where `u64` is less aligned than `AtomicU64`.
fn as_atomic(links: &mut [u64]) -> Option<&[AtomicU64]> {
    if !links.as_ptr().cast::<AtomicU64>().is_aligned() {
        return None;
    }
    // SAFETY: AtomicU64 has the size and bit validity of u64, and the alignment is checked
    // above; the exclusive borrow of `links` is held for as long as the atomics live, so
    // nothing else reads or writes the memory meanwhile (what `AtomicU64::from_mut_slice`,
    // not yet stable, does).
    Some(unsafe { &*(links as *mut [u64] as *const [AtomicU64]) })
}

struct FanPass {
    sums: FanSums,
    referenced: usize,
    bbox_min: [f32; 3],
    bbox_max: [f32; 3],
}

impl FanPass {
    fn empty() -> FanPass {
        FanPass {
            sums: FanSums::default(),
            referenced: 0,
            bbox_min: [f32::INFINITY; 3],
            bbox_max: [f32::NEG_INFINITY; 3],
        }
    }

    fn merge(mut self, other: FanPass) -> FanPass {
        self.sums = self.sums.merge(other.sums);
        self.referenced += other.referenced;
        for a in 0..3 {
            self.bbox_min[a] = self.bbox_min[a].min(other.bbox_min[a]);
            self.bbox_max[a] = self.bbox_max[a].max(other.bbox_max[a]);
        }
        self
    }
}

/// Classifies the fans of the vertices that finish (not `OPEN`), as `check`'s fan pass does,
/// and marks those with corners `REFERENCED`.
fn fan_pass<I: Index>(
    offsets: &[I],
    links: &[u64],
    state: &mut [u8],
    position: &(impl Fn(usize) -> [f32; 3] + Sync),
    id_of: &(impl Fn(usize) -> u32 + Sync),
) -> FanPass {
    state
        .par_chunks_mut(VERTEX_BLOCK)
        .enumerate()
        .map_init(FanScratch::default, |scratch, (block, states)| {
            let mut pass = FanPass::empty();
            for (k, state) in states.iter_mut().enumerate() {
                let v = block * VERTEX_BLOCK + k;
                let fan = &links[offsets[v].to_usize()..offsets[v + 1].to_usize()];
                if *state & OPEN != 0 || fan.is_empty() {
                    continue;
                }
                *state |= REFERENCED;
                pass.referenced += 1;
                for (a, &x) in position(v).iter().enumerate() {
                    pass.bbox_min[a] = pass.bbox_min[a].min(x);
                    pass.bbox_max[a] = pass.bbox_max[a].max(x);
                }
                let vertex = id_of(v);
                if fan.len() > SMALL_FAN
                    || !closed_fan(
                        &links[offsets[v].to_usize()..],
                        fan.len(),
                        vertex,
                        &mut pass.sums,
                    )
                {
                    general_fan(fan, vertex, scratch, &mut pass.sums);
                }
            }
            pass
        })
        .reduce(FanPass::empty, FanPass::merge)
}

/// Groups the alive vertices that matter (open, finishing referenced, or holding a count) by
/// bit-identical position, with radix partitions and small hash tables as `check` does.
/// Returns the duplicates of the classes that finish (no member left open), and the counts
/// the open classes carry: `(local, count)` sorted, on each class's smallest open member.
fn duplicate_classes(
    state: &[u8],
    position: &(impl Fn(usize) -> [f32; 3] + Sync),
    counts: &[(u32, usize)],
) -> (usize, Vec<(u32, usize)>) {
    let n = state.len();
    let bits = (n / PARTITION_SIZE)
        .max(1)
        .next_power_of_two()
        .trailing_zeros()
        .min(16);
    let partitions = 1usize << bits;
    let partition_of = |entry: Entry| (entry.hash() >> (31 - bits)) as usize;

    // Per block of vertices, its entries grouped by partition: partition p is
    // `entries[starts[p]..starts[p + 1]]`.
    let blocks: Vec<(Vec<usize>, Vec<Entry>)> = (0..n.div_ceil(VERTEX_CHUNK))
        .into_par_iter()
        .map(|block| {
            let vertices = block * VERTEX_CHUNK..((block + 1) * VERTEX_CHUNK).min(n);
            let entries: Vec<Entry> = vertices
                .filter(|&v| state[v] != 0)
                .map(|v| Entry::new(v, &position(v)))
                .collect();
            let mut starts = vec![0usize; partitions + 1];
            for &entry in &entries {
                starts[partition_of(entry) + 1] += 1;
            }
            for p in 0..partitions {
                starts[p + 1] += starts[p];
            }
            let mut next = starts.clone();
            let mut grouped = vec![Entry::EMPTY; entries.len()];
            for &entry in &entries {
                let at = &mut next[partition_of(entry)];
                grouped[*at] = entry;
                *at += 1;
            }
            (starts, grouped)
        })
        .collect();

    // Pairs (first member, member) for every member of a class with more than one member or
    // with a count; classes of one uncounted vertex change nothing.
    let mut pairs: Vec<(u32, u32)> = (0..partitions)
        .into_par_iter()
        .map_init(Vec::new, |table: &mut Vec<Entry>, p| {
            let count: usize = blocks
                .iter()
                .map(|(starts, _)| starts[p + 1] - starts[p])
                .sum();
            let table_bits = (count + count / 3 + 1)
                .max(16)
                .next_power_of_two()
                .trailing_zeros();
            table.clear();
            table.resize(1 << table_bits, Entry::EMPTY);
            let mask = table.len() - 1;
            let bits_of = |entry: Entry| position(entry.vertex()).map(f32::to_bits);
            let mut pairs = Vec::new();
            let members = blocks
                .iter()
                .flat_map(|(starts, entries)| &entries[starts[p]..starts[p + 1]]);
            for &entry in members {
                let v = entry.vertex() as u32;
                let mut slot = (u64::from(entry.hash()).wrapping_mul(0x9e37_79b9_7f4a_7c15)
                    >> (64 - table_bits)) as usize;
                loop {
                    let occupant = table[slot];
                    if occupant == Entry::EMPTY {
                        table[slot] = entry;
                        if state[v as usize] & COUNTED != 0 {
                            pairs.push((v, v));
                        }
                        break;
                    }
                    if occupant.hash() == entry.hash() && bits_of(occupant) == bits_of(entry) {
                        let first = occupant.vertex() as u32;
                        pairs.push((first, first));
                        pairs.push((first, v));
                        break;
                    }
                    slot = (slot + 1) & mask;
                }
            }
            pairs
        })
        .flatten_iter()
        .collect();
    pairs.sort_unstable();
    pairs.dedup();

    let count_of = |v: u32| {
        counts
            .binary_search_by_key(&v, |&(c, _)| c)
            .map_or(0, |k| counts[k].1)
    };
    let mut duplicates = 0;
    let mut carried = Vec::new();
    for class in pairs.chunk_by(|a, b| a.0 == b.0) {
        let mut referenced = 0;
        // Members come in increasing order, so the first open one is the smallest.
        let mut keeper = None;
        for &(_, v) in class {
            referenced += count_of(v);
            let s = state[v as usize];
            if s & OPEN != 0 {
                keeper.get_or_insert(v);
            } else if s & REFERENCED != 0 {
                referenced += 1;
            }
        }
        match keeper {
            Some(v) if referenced > 0 => carried.push((v, referenced)),
            Some(_) => {}
            None => duplicates += referenced.saturating_sub(1),
        }
    }
    carried.sort_unstable();
    (duplicates, carried)
}

/// `open` sorted and without repeats (borrowed when it already is).
fn sorted_ids(ids: &[u32]) -> Cow<'_, [u32]> {
    if ids.windows(2).all(|w| w[0] < w[1]) {
        Cow::Borrowed(ids)
    } else {
        let mut ids = ids.to_vec();
        ids.sort_unstable();
        ids.dedup();
        Cow::Owned(ids)
    }
}

/// `borrowed` sorted by id, the first entry of a repeated id kept.
fn sorted_borrowed(borrowed: &[(u32, [f32; 3])]) -> Cow<'_, [(u32, [f32; 3])]> {
    if borrowed.windows(2).all(|w| w[0].0 < w[1].0) {
        Cow::Borrowed(borrowed)
    } else {
        let mut borrowed = borrowed.to_vec();
        borrowed.sort_by_key(|&(id, _)| id);
        borrowed.dedup_by_key(|&mut (id, _)| id);
        Cow::Owned(borrowed)
    }
}

#[cfg(test)]
mod tests;
