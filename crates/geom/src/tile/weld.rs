//! Welding the elements' local meshes into one mesh, by the intrinsic names of boundary
//! vertices (module docs of [`super`], step 3).
//!
//! Invariants: a boundary vertex's name depends only on global node ids and lattice weights,
//! never on the element's frame; the lowest element using a vertex places and numbers it;
//! ids are assigned element by element in local order, so the mesh does not depend on the
//! thread count.

use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

use super::lattice::{Lattice, Weights};
use super::local::{LocalMesh, LocalVertex, POINT};
use super::{Elements, TileError, TileStats};

/// What the weld needs of a set of elements, of any dimension: their count, each one's
/// global corner nodes (in its lattice's corner order) and where a reference point goes.
pub trait Corners: Sync {
    fn count(&self) -> usize;
    fn element(&self, e: usize) -> &[u32];
    /// The model position of reference point `xi` in element `e`.
    fn place(&self, e: usize, xi: [f64; 3]) -> [f64; 3];
}

impl Corners for Elements<'_> {
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
use crate::mesh::Mesh;

/// A local vertex on the element boundary: the weights of its lattice ends, and the faces
/// whose caps alone use it (0 when surface triangles use it).
struct SharedVertex {
    a: Weights,
    b: Option<Weights>,
    caps: u8,
}

/// What an element does with one of its shared vertices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    /// Only caps on interior faces use it: it is not in the output.
    Unused,
    /// The lowest element using it: it places and numbers it.
    Owner,
    /// Another element owns it.
    Borrower,
}

/// Which faces of each element lie on the scaffold boundary (one bit per face).
fn boundary_faces(
    elements: &dyn Corners,
    face_masks: &[u8],
) -> Result<(Vec<u8>, TileStats), TileError> {
    let n = elements.count();
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
                (nodes, (e * face_masks.len() + f) as u32)
            })
        })
        .collect();
    faces.par_sort_unstable();
    let mut boundary = vec![0u8; n];
    let mut stats = TileStats {
        elements: n,
        ..TileStats::default()
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
                boundary[slot / face_masks.len()] |= 1 << (slot % face_masks.len());
                stats.boundary_faces += 1;
            }
            2 => stats.interior_faces += 1,
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
    Ok((boundary, stats))
}

/// 128-bit name of a shared vertex in element `corners`: its ends' `(global node, weight)`
/// lists, sorted by node and put in a fixed order. Collisions between distinct names are
/// as likely as for any 128-bit hash of a few million keys (about 2⁻⁸⁰): not a concern.
fn vertex_name(corners: &[u32], v: &SharedVertex) -> u128 {
    let list = |w: &Weights| {
        let mut out = [(u32::MAX, 0u32); 4];
        for (k, &(c, weight)) in w.as_slice().iter().enumerate() {
            out[k] = (corners[c as usize], weight);
        }
        out.sort_unstable();
        out
    };
    let a = list(&v.a);
    let mut h = Hasher128::new(u64::from(v.b.is_some()));
    match &v.b {
        None => a
            .iter()
            .for_each(|&(n, w)| h.add(u64::from(n) << 32 | u64::from(w))),
        Some(b) => {
            let b = list(b);
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            for &(n, w) in lo.iter().chain(hi.iter()) {
                h.add(u64::from(n) << 32 | u64::from(w));
            }
        }
    }
    h.finish()
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

/// The local mesh of each element: one for all (a uniform cell) or one each.
pub enum Locals<'a> {
    Uniform(&'a LocalMesh),
    PerElement(&'a [LocalMesh]),
}

impl Locals<'_> {
    fn get(&self, e: usize) -> &LocalMesh {
        match self {
            Locals::Uniform(local) => local,
            Locals::PerElement(all) => &all[e],
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
                shared.push(SharedVertex { a, b, caps: 0 });
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

/// Welds the elements' local meshes into one mesh (see the module docs, step 3).
pub fn weld(
    elements: &dyn Corners,
    lattice: &dyn Lattice,
    locals: Locals,
) -> Result<(Mesh, TileStats), TileError> {
    let (boundary, stats) = boundary_faces(elements, lattice.face_masks())?;
    let n = elements.count();
    let classified: Vec<Classified> = match &locals {
        Locals::Uniform(local) => vec![Classified::new(lattice, local)],
        Locals::PerElement(all) => all
            .par_iter()
            .map(|l| Classified::new(lattice, l))
            .collect(),
    };
    let class = |e: usize| match &locals {
        Locals::Uniform(_) => &classified[0],
        Locals::PerElement(_) => &classified[e],
    };
    let used = |e: usize, s: &SharedVertex| s.caps == 0 || s.caps & boundary[e] != 0;
    // Slots of element e's shared vertices: slot_base[e]..slot_base[e + 1].
    let mut slot_base = Vec::with_capacity(n + 1);
    slot_base.push(0usize);
    for e in 0..n {
        slot_base.push(slot_base[e] + class(e).shared.len());
    }

    // Name every shared vertex every element uses; equal names are one vertex, owned by the
    // lowest element.
    let mut names: Vec<(u128, u32, u32)> = (0..n)
        .into_par_iter()
        .flat_map_iter(|e| {
            let corners = elements.element(e);
            class(e)
                .shared
                .iter()
                .enumerate()
                .filter(move |(_, v)| used(e, v))
                .map(move |(s, v)| (vertex_name(corners, v), e as u32, s as u32))
        })
        .collect();
    names.par_sort_unstable();
    let slots = slot_base[n];
    let mut group = vec![0u32; slots];
    let mut role = vec![Role::Unused; slots];
    let mut groups = 0u32;
    for (r, &(name, e, s)) in names.iter().enumerate() {
        let first = r == 0 || names[r - 1].0 != name;
        if first {
            groups += 1;
        }
        let slot = slot_base[e as usize] + s as usize;
        group[slot] = groups - 1;
        role[slot] = if first { Role::Owner } else { Role::Borrower };
    }
    drop(names);

    // Vertex ids: element by element, its interior vertices and the shared ones it owns, in
    // local order.
    let owned: Vec<u64> = (0..n)
        .into_par_iter()
        .map(|e| {
            let c = class(e);
            let interior = c.shared_index.len() - c.shared.len();
            let roles = &role[slot_base[e]..slot_base[e + 1]];
            (interior + roles.iter().filter(|&&r| r == Role::Owner).count()) as u64
        })
        .collect();
    let mut base = Vec::with_capacity(n + 1);
    base.push(0u64);
    for &c in &owned {
        base.push(base[base.len() - 1] + c);
    }
    if base[n] > u64::from(u32::MAX) {
        return Err(TileError::TooManyVertices(base[n]));
    }
    let group_id: Vec<AtomicU32> = (0..groups).map(|_| AtomicU32::new(0)).collect();
    // Written in place, element by element in parallel: each element's vertices and
    // triangles have a known range of the output.
    let mut vertices = vec![[0.0f32; 3]; base[n] as usize];
    let vertex_ranges = split_by(&mut vertices, owned.iter().map(|&c| c as usize));
    vertex_ranges
        .into_par_iter()
        .enumerate()
        .for_each(|(e, out)| {
            let c = class(e);
            let mut next = base[e] as u32;
            let mut out = out.iter_mut();
            for (i, xi) in c.xi.iter().enumerate() {
                let s = c.shared_index[i];
                if s != NONE {
                    let slot = slot_base[e] + s as usize;
                    if role[slot] != Role::Owner {
                        continue;
                    }
                    group_id[group[slot] as usize].store(next, Ordering::Relaxed);
                }
                next += 1;
                if let Some(v) = out.next() {
                    *v = elements.place(e, *xi).map(|c| c as f32);
                }
            }
        });

    let triangle_counts: Vec<usize> = (0..n)
        .into_par_iter()
        .map(|e| {
            let local = locals.get(e);
            let caps = local.caps.iter().enumerate();
            local.triangles.len()
                + caps
                    .filter(|(f, _)| boundary[e] & 1 << f != 0)
                    .map(|(_, cap)| cap.len())
                    .sum::<usize>()
        })
        .collect();
    let mut triangles = vec![[0u32; 3]; triangle_counts.iter().sum()];
    let triangle_ranges = split_by(&mut triangles, triangle_counts.iter().copied());
    triangle_ranges
        .into_par_iter()
        .enumerate()
        .for_each(|(e, out)| {
            let (local, c) = (locals.get(e), class(e));
            let mut next = base[e] as u32;
            let ids: Vec<u32> = (0..local.vertices.len())
                .map(|i| {
                    let s = c.shared_index[i];
                    if s != NONE {
                        let slot = slot_base[e] + s as usize;
                        match role[slot] {
                            Role::Owner => {}
                            // Only dropped caps use it: never referenced.
                            Role::Unused => return u32::MAX,
                            Role::Borrower => {
                                return group_id[group[slot] as usize].load(Ordering::Relaxed);
                            }
                        }
                    }
                    next += 1;
                    next - 1
                })
                .collect();
            let caps = local
                .caps
                .iter()
                .enumerate()
                .filter(|(f, _)| boundary[e] & 1 << f != 0)
                .flat_map(|(_, cap)| cap.iter());
            for (slot, t) in out.iter_mut().zip(local.triangles.iter().chain(caps)) {
                *slot = t.map(|v| ids[v as usize]);
            }
        });
    Ok((
        Mesh {
            vertices,
            triangles,
        },
        stats,
    ))
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
