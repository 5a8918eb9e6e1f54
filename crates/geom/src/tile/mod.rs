//! Tiling a cell into every element of an unstructured scaffold, as one welded mesh.
//!
//! The lattice inside element `e` is `{X_e(ξ) : Φ(ξ) < 0}` for the cell's implicit function
//! `Φ` in reference coordinates (METHOD.md §1 elements, §8 tiling). How it is made exact:
//!
//! 1. **One symmetric reference sampling.** `Φ` is sampled once on the element's reference
//!    lattice ([`lattice`]) — and only at one representative point per orbit of the
//!    element's group, whose value every point of the orbit takes. The samples are therefore
//!    *exactly* (bitwise) symmetric, so the samples on a face are the same whichever element,
//!    in whichever orientation, looks at it. This needs `Φ` to have the element's symmetry
//!    (Oh for hexahedra, Td for tetrahedra); the caller checks the cell's group.
//! 2. **One reference contour.** The lattice is contoured once in reference coordinates
//!    (marching cubes with the face rule for the cube, marching tetrahedra for the
//!    tetrahedron) into a [`local::LocalMesh`] with a cap for each face. Because the face rule
//!    and the face triangulation are symmetric, two elements sharing a face draw the same
//!    segments on it.
//! 3. **Welding by construction.** A vertex on the element's boundary lies on a lattice edge
//!    whose ends are named intrinsically by their `(global corner node, integer weight)` lists
//!    ([`lattice::Weights`]); equal names are the same vertex. Names are hashed to 128 bits and
//!    sorted: no distance tolerance anywhere. The element with the lowest index owning a
//!    shared vertex places it (`X_e` of its own reference point), so the output does not
//!    depend on the thread count.
//! 4. **Caps** are kept on scaffold boundary faces (faces used by one element) only.
//!
//! Invariants: the output is closed, manifold and outward-oriented whenever every element
//! map is orientation-preserving and the scaffold is conforming (each face used by one or two
//! elements); vertex and triangle order depend only on the scaffold, the cell and the
//! resolution.

mod cube;
mod lattice;
mod local;
mod simplex;

use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

use crate::element::Element3;
use crate::field::ScalarField;
use crate::mesh::Mesh;
use lattice::{Lattice, Weights};
use local::{LocalMesh, POINT};

pub use cube::HEX_CORNERS;

/// The isoparametric maps of a scaffold's elements.
pub trait ElementMap: Sync {
    /// `X_e(ξ)`: the model position of reference point `xi` in element `element`.
    fn map(&self, element: usize, xi: [f64; 3]) -> [f64; 3];
}

/// The elements to tile: their shape, and for each element the global node ids of its corners
/// in the reference element's corner order (hex: Gmsh's; tetrahedron: METHOD.md's `p0..p3`).
pub struct Elements<'a> {
    pub shape: Element3,
    pub corners: &'a [u32],
    pub map: &'a dyn ElementMap,
}

impl Elements<'_> {
    fn corner_count(&self) -> usize {
        match self.shape {
            Element3::Cube => 8,
            Element3::Tetrahedron => 4,
        }
    }

    fn count(&self) -> usize {
        self.corners.len() / self.corner_count()
    }

    fn element(&self, e: usize) -> &[u32] {
        let n = self.corner_count();
        &self.corners[e * n..(e + 1) * n]
    }
}

/// What a tiling made, besides its mesh.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TileStats {
    pub elements: usize,
    pub interior_faces: usize,
    pub boundary_faces: usize,
}

#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum TileError {
    #[error("the resolution must be at least 2 samples per element edge, got {0}")]
    Resolution(usize),
    #[error("a resolution of {0} samples per element edge is more than this tiler supports (256)")]
    ResolutionTooHigh(usize),
    #[error("the corner list has {len} entries, not a multiple of {per_element}")]
    Corners { len: usize, per_element: usize },
    #[error(
        "a face (corner nodes {nodes:?}) is shared by {count} elements; a conforming scaffold shares each face between at most two"
    )]
    NonConforming { nodes: Vec<u32>, count: usize },
    #[error("the mesh would have {0} vertices, more than 32-bit indices can address")]
    TooManyVertices(u64),
}

/// Tiles `field` (the solid's implicit function in reference coordinates, negative inside,
/// with the element's symmetry) into every element, with `resolution` samples per element edge.
pub fn tile(
    elements: &Elements,
    field: &dyn ScalarField,
    resolution: usize,
) -> Result<(Mesh, TileStats), TileError> {
    if resolution < 2 {
        return Err(TileError::Resolution(resolution));
    }
    if resolution > 256 {
        return Err(TileError::ResolutionTooHigh(resolution));
    }
    let per_element = elements.corner_count();
    if !elements.corners.len().is_multiple_of(per_element) {
        return Err(TileError::Corners {
            len: elements.corners.len(),
            per_element,
        });
    }
    let lattice: Box<dyn Lattice> = match elements.shape {
        Element3::Cube => Box::new(cube::CubeLattice::new(resolution)),
        Element3::Tetrahedron => Box::new(simplex::TetLattice::new(resolution)),
    };
    let values = symmetric_samples(lattice.as_ref(), field);
    let local = lattice.contour(&values);
    weld(elements, lattice.as_ref(), &local)
}

/// The field at every lattice point, evaluated at its orbit's representative only.
fn symmetric_samples(lattice: &dyn Lattice, field: &dyn ScalarField) -> Vec<f64> {
    let len = lattice.index_len();
    let reps: Vec<u32> = (0..len as u32)
        .map(|p| {
            if lattice.is_point(p) {
                lattice.representative(p)
            } else {
                u32::MAX
            }
        })
        .collect();
    let mut distinct: Vec<u32> = reps.iter().copied().filter(|&r| r != u32::MAX).collect();
    distinct.sort_unstable();
    distinct.dedup();
    let xi: Vec<[f64; 3]> = distinct.iter().map(|&p| lattice.xi(p)).collect();
    let (xs, ys, zs): (Vec<f64>, Vec<f64>, Vec<f64>) = (
        xi.iter().map(|p| p[0]).collect(),
        xi.iter().map(|p| p[1]).collect(),
        xi.iter().map(|p| p[2]).collect(),
    );
    let mut at_rep = vec![0.0; distinct.len()];
    field.eval_points(&xs, &ys, &zs, &mut at_rep);
    reps.iter()
        .map(|&r| {
            if r == u32::MAX {
                f64::NAN
            } else {
                at_rep[distinct.binary_search(&r).unwrap_or(0)]
            }
        })
        .collect()
}

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
    elements: &Elements,
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

fn weld(
    elements: &Elements,
    lattice: &dyn Lattice,
    local: &LocalMesh,
) -> Result<(Mesh, TileStats), TileError> {
    let face_masks = lattice.face_masks();
    let (boundary, stats) = boundary_faces(elements, face_masks)?;
    let n = elements.count();

    // Local vertices on the element's boundary: those whose lattice edge (or point) lies in
    // one face, i.e. whose corner support is inside a face's corners.
    let on_face = |mask: u8| face_masks.iter().any(|&f| mask & !f == 0);
    let mut shared: Vec<SharedVertex> = Vec::new();
    // For each local vertex: its index in `shared`, or NONE for interior vertices.
    const NONE: u32 = u32::MAX;
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
    // Vertices only caps use (inside lattice points on faces) exist in an element only where
    // one of those caps is kept. Interior vertices are always on surface triangles.
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
    let interior = local.vertices.len() - shared.len();
    let used = |e: usize, s: &SharedVertex| s.caps == 0 || s.caps & boundary[e] != 0;

    // Name every shared vertex every element uses; equal names are one vertex, owned by the
    // lowest element.
    let mut names: Vec<(u128, u32, u32)> = (0..n)
        .into_par_iter()
        .flat_map_iter(|e| {
            let corners = elements.element(e);
            shared
                .iter()
                .enumerate()
                .filter(move |(_, v)| used(e, v))
                .map(move |(s, v)| (vertex_name(corners, v), e as u32, s as u32))
        })
        .collect();
    names.par_sort_unstable();
    // role/group of element e's shared vertex s, at e * shared.len() + s.
    let per = shared.len();
    let mut group = vec![0u32; n * per];
    let mut role = vec![Role::Unused; n * per];
    let mut groups = 0u32;
    for (r, &(name, e, s)) in names.iter().enumerate() {
        let first = r == 0 || names[r - 1].0 != name;
        if first {
            groups += 1;
        }
        let slot = e as usize * per + s as usize;
        group[slot] = groups - 1;
        role[slot] = if first { Role::Owner } else { Role::Borrower };
    }
    drop(names);
    let total = n as u64 * interior as u64 + u64::from(groups);
    if total > u64::from(u32::MAX) {
        return Err(TileError::TooManyVertices(total));
    }

    // Vertex ids: element by element, its interior vertices and the shared ones it owns, in
    // local order.
    let owned: Vec<u32> = (0..n)
        .map(|e| {
            let roles = &role[e * per..(e + 1) * per];
            interior as u32 + roles.iter().filter(|&&r| r == Role::Owner).count() as u32
        })
        .collect();
    let mut base = Vec::with_capacity(n + 1);
    base.push(0u32);
    for &c in &owned {
        base.push(base.last().copied().unwrap_or(0) + c);
    }
    let group_id: Vec<AtomicU32> = (0..groups).map(|_| AtomicU32::new(0)).collect();
    let xi_of = |v: &local::LocalVertex| {
        let a = lattice.xi(v.a);
        if v.b == POINT {
            a
        } else {
            let b = lattice.xi(v.b);
            std::array::from_fn(|k| a[k] + v.t * (b[k] - a[k]))
        }
    };
    let ref_xi: Vec<[f64; 3]> = local.vertices.iter().map(xi_of).collect();
    let positions: Vec<Vec<[f32; 3]>> = (0..n)
        .into_par_iter()
        .map(|e| {
            let mut next = base[e];
            let mut out = Vec::with_capacity(owned[e] as usize);
            for (i, xi) in ref_xi.iter().enumerate() {
                let s = shared_index[i];
                if s != NONE {
                    let slot = e * per + s as usize;
                    if role[slot] != Role::Owner {
                        continue;
                    }
                    group_id[group[slot] as usize].store(next, Ordering::Relaxed);
                }
                next += 1;
                out.push(elements.map.map(e, *xi).map(|c| c as f32));
            }
            out
        })
        .collect();
    let vertices: Vec<[f32; 3]> = positions.into_iter().flatten().collect();

    let triangles: Vec<Vec<[u32; 3]>> = (0..n)
        .into_par_iter()
        .map(|e| {
            let mut next = base[e];
            let ids: Vec<u32> = (0..local.vertices.len())
                .map(|i| {
                    let s = shared_index[i];
                    if s != NONE {
                        let slot = e * per + s as usize;
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
            let mut out: Vec<[u32; 3]> = local
                .triangles
                .iter()
                .map(|t| t.map(|v| ids[v as usize]))
                .collect();
            for (f, cap) in local.caps.iter().enumerate() {
                if boundary[e] & 1 << f != 0 {
                    out.extend(cap.iter().map(|t| t.map(|v| ids[v as usize])));
                }
            }
            out
        })
        .collect();
    let triangles = triangles.into_iter().flatten().collect();
    Ok((
        Mesh {
            vertices,
            triangles,
        },
        stats,
    ))
}

#[cfg(test)]
mod tests;
