//! Tiling a cell into every element of an unstructured scaffold, as one welded mesh.
//!
//! The lattice inside element `e` is `{X_e(ξ) : Φ(ξ) < 0}` for the cell's implicit function
//! `Φ` in reference coordinates (docs/method.md §Reference elements, §Tiling and continuity). How
//! it is made exact:
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
//! 5. **Streaming.** Elements are taken in a Morton order of their centroids (`scaffold.rs`)
//!    and welded a chunk at a time ([`stream_scaffold`], `weld::Welder`): memory holds one
//!    chunk's local meshes and output, the chunk before it (being taken by the sink, on the
//!    pool, while this one is made) and the vertices later chunks may still use. The chunks
//!    of any size concatenate to the one-chunk mesh bit for bit.
//!
//! 2D scaffolds (tri, quad) are tiled by the same steps into a planar or surface region, see
//! `planar.rs` ([`tile_surface_scaffold`]); choose by `ElementKind::dimension()`.
//!
//! Invariants: the output is closed, manifold and outward-oriented whenever every element
//! map is orientation-preserving and the scaffold is conforming (each face used by one or two
//! elements); vertex and triangle order depend only on the scaffold, the cell and the
//! resolution. A resolution whose vertex margin (1/256 of a lattice edge) is below the `f32`
//! step where the scaffold lies is refused before tiling (`scaffold::check_f32_room`): the
//! written `f32` positions could not keep vertices apart.

mod cube;
mod face_plan;
mod lattice;
mod local;
mod planar;
mod scaffold;
mod shape;
mod simplex;
mod skin;
mod square;
mod triangle;
mod weld;

use rayon::prelude::*;

use crate::contour2d::Element2;
use crate::element::Element3;
use crate::field::{ScalarField, Solid};
use crate::mesh::{Mesh, MeshChunk, SpareArrays};
use lattice::{Lattice, Weights};
use local::Samples;
use shape::{Order, Shape};
use weld::{Corners, Locals, Welder};

pub use cube::HEX_CORNERS;
pub use planar::{
    Elements2, RegionError, TiledRegion, TiledShell, extrude, region_svg, surface_element,
    thickness_normal, tile_planar, tile_surface_scaffold,
};
pub use scaffold::{reference_element, tile_scaffold};
pub use shape::Nodes;
pub use skin::{Skin, stream_scaffold, tile_scaffold_with_skin};

/// The isoparametric maps of a scaffold's elements.
pub trait ElementMap: Sync {
    /// `X_e(ξ)`: the model position of reference point `xi` in element `element`.
    fn map(&self, element: usize, xi: [f64; 3]) -> [f64; 3];
}

/// The elements to tile: their shape, and for each element the global node ids of its corners
/// in the reference element's corner order (hex: Gmsh's; tetrahedron: `p0..p3` of
/// docs/method.md §Reference elements; 2D ([`Elements2`]): Gmsh's, reference points
/// `[ξ₁, ξ₂, 0]`).
pub struct Elements<'a, S = Element3> {
    pub shape: S,
    pub corners: &'a [u32],
    /// Every node of each element (its corners first, as in `corners`): nodal values are
    /// interpolated by the shape functions of `nodes.kind` through all of them.
    pub nodes: Nodes<'a>,
    pub map: &'a dyn ElementMap,
}

/// A reference element's shape, as [`Elements`] need it.
pub trait ElementShape: Copy + Sync {
    fn corner_count(self) -> usize;
}

impl ElementShape for Element3 {
    fn corner_count(self) -> usize {
        match self {
            Element3::Cube => 8,
            Element3::Tetrahedron => 4,
        }
    }
}

impl ElementShape for Element2 {
    fn corner_count(self) -> usize {
        match self {
            Element2::Square => 4,
            Element2::Triangle => 3,
        }
    }
}

impl<S: ElementShape> Elements<'_, S> {
    fn corner_count(&self) -> usize {
        self.shape.corner_count()
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
    #[error("{what} values are given for {given} nodes, but the scaffold has {nodes}")]
    NodalValues {
        what: &'static str,
        given: usize,
        nodes: usize,
    },
    #[error("{0} scaffolds are surfaces: tile them with tile_surface_scaffold")]
    NotVolume(&'static str),
    #[error("the mesh would have {0} vertices, more than 32-bit indices can address")]
    TooManyVertices(u64),
    /// The tiler's margin between vertices and lattice points is below one `f32` step where
    /// the scaffold lies (see [`scaffold::check_f32_room`]).
    #[error(
        "at resolution {resolution} the lattice is too fine for 32-bit positions (what mesh files store) this far from the origin: vertices are kept {} from lattice points (1/256 of the shortest lattice edge, {}), less than the 32-bit step {} at {}, as far as the scaffold reaches; place the scaffold nearer the origin or use a resolution of at most {max_resolution}",
        f64::from_bits(*margin_bits),
        f64::from_bits(*edge_bits),
        f64::from_bits(*step_bits),
        f64::from_bits(*reach_bits)
    )]
    BeyondF32 {
        resolution: usize,
        /// The shortest lattice edge, the margin (1/256 of it), the `f32` step at `reach` and
        /// the largest coordinate magnitude, as bits (keeping the error `Eq`).
        edge_bits: u64,
        margin_bits: u64,
        step_bits: u64,
        reach_bits: u64,
        /// The highest resolution whose margin is at least the step (below 2: none).
        max_resolution: usize,
    },
    #[error("skin: {0}")]
    Skin(String),
    /// What the receiver of a streamed tiling's chunks reported.
    #[error("{0}")]
    Sink(String),
    #[error("the element nodes do not fit the elements: {0}")]
    Nodes(String),
    #[error(
        "the graded thickness must be greater than 0, but it interpolates to {} inside element {element}: its shape functions overshoot between nodal values that vary sharply across it; smooth the thickness or refine the scaffold there",
        f64::from_bits(*.value_bits)
    )]
    Thickness {
        /// The element's tag when tiled from a [`crate::scaffold::Scaffold`], else its index.
        element: u64,
        /// The lowest interpolated value in it, as bits (keeping the error `Eq`).
        value_bits: u64,
    },
}

impl TileError {
    /// The error with element indices replaced by the scaffold's element tags.
    pub(crate) fn tagged(self, tags: &[u64]) -> TileError {
        match self {
            TileError::Thickness {
                element,
                value_bits,
            } => TileError::Thickness {
                element: usize::try_from(element)
                    .ok()
                    .and_then(|e| tags.get(e))
                    .copied()
                    .unwrap_or(element),
                value_bits,
            },
            other => other,
        }
    }
}

/// What is tiled into every element: a cell (or a transition between two), in reference
/// coordinates and with the element's symmetry, seen through a solid whose thickness or offset
/// may be graded. Nodal arrays are indexed by global node id (the ids in [`Elements::nodes`])
/// and interpolated by the element's own shape functions through all its nodes (quadratic for
/// tet10, hex20, hex27, tri6, quad8, quad9), which on a face involve only that face's nodes:
/// graded values are continuous across faces, and bitwise equal on them ([`shape`]).
///
/// A quadratic interpolant may leave the range of its nodal values. Transition weights are
/// therefore clamped to [0, 1] at every lattice point, after interpolation; a graded thickness
/// that interpolates to ≤ 0 at a lattice point is an error naming the element
/// ([`TileError::Thickness`]): a shell that silently vanishes, or is clamped to a sliver, where
/// the user asked for a positive thickness is a defect they would only find in the print.
pub struct TiledSolid<'a> {
    /// The cell field, and a second one for a transition.
    pub cell: &'a dyn ScalarField,
    pub transition: Option<Transition<'a>>,
    pub solid: Solid,
    /// Per node: the shell thickness (replacing the solid's own; shells only).
    pub thickness: Option<&'a [f64]>,
    /// Per node: the offset (replacing the solid's own; every solid but a plain shell).
    pub offset: Option<&'a [f64]>,
}

/// `Φ = (1 − w) Φ_cell + w Φ_to`, with `w` the weight of `to` given at each node, interpolated
/// and then clamped to [0, 1] (so nodal weights outside [0, 1] are the clamp of their
/// interpolant, not an interpolant of clamped values).
pub struct Transition<'a> {
    pub to: &'a dyn ScalarField,
    pub weight: &'a [f64],
}

impl TiledSolid<'_> {
    /// The plain solid of one cell.
    pub fn of(cell: &dyn ScalarField, solid: Solid) -> TiledSolid<'_> {
        TiledSolid {
            cell,
            transition: None,
            solid,
            thickness: None,
            offset: None,
        }
    }

    fn is_uniform(&self) -> bool {
        self.transition.is_none() && self.thickness.is_none() && self.offset.is_none()
    }

    fn nodal(&self) -> impl Iterator<Item = (&'static str, &[f64])> {
        [
            (
                "transition weight",
                self.transition.as_ref().map(|t| t.weight),
            ),
            ("thickness", self.thickness),
            ("offset", self.offset),
        ]
        .into_iter()
        .filter_map(|(what, v)| v.map(|v| (what, v)))
    }
}

/// Tiles `solid` into every element, with `resolution` samples per element edge.
pub fn tile(
    elements: &Elements,
    solid: &TiledSolid,
    resolution: usize,
) -> Result<(Mesh, TileStats), TileError> {
    tile_with(elements, solid, None, resolution)
}

/// [`tile`], with a skin along the scaffold's boundary when given (`skin.rs`).
fn tile_with(
    elements: &Elements,
    solid: &TiledSolid,
    skin: Option<&Skin>,
    resolution: usize,
) -> Result<(Mesh, TileStats), TileError> {
    let lattice = checked_lattice(elements, solid, resolution)?;
    tile_on(elements, elements.nodes, lattice.as_ref(), solid, skin)
}

/// [`tile_with`], handing the mesh to `sink` a chunk of `chunk_elements` elements at a time.
fn stream_with(
    elements: &Elements,
    solid: &TiledSolid,
    skin: Option<&Skin>,
    resolution: usize,
    chunk_elements: usize,
    spare: &SpareArrays,
    sink: &mut ChunkSink,
) -> Result<TileStats, TileError> {
    let lattice = checked_lattice(elements, solid, resolution)?;
    let nodes = elements.nodes;
    stream_on(
        elements,
        nodes,
        lattice.as_ref(),
        solid,
        skin,
        Chunking {
            elements: chunk_elements,
            spare,
        },
        sink,
    )
}

/// The elements' node lists against their shape, which for their node kind is `reference`,
/// then [`check_input`].
fn check_elements<S: ElementShape + PartialEq + std::fmt::Debug>(
    elements: &Elements<S>,
    reference: Option<S>,
    solid: &TiledSolid,
    resolution: usize,
) -> Result<(), TileError> {
    if reference != Some(elements.shape) {
        return Err(TileError::Nodes(format!(
            "{} nodes on {:?} elements",
            elements.nodes.kind.name(),
            elements.shape
        )));
    }
    check_input(
        elements.corners,
        elements.corner_count(),
        &elements.nodes,
        solid,
        resolution,
    )
}

/// The 3D elements checked ([`check_elements`]), and their lattice at `resolution`.
fn checked_lattice(
    elements: &Elements,
    solid: &TiledSolid,
    resolution: usize,
) -> Result<Box<dyn Lattice>, TileError> {
    let reference = reference_element(elements.nodes.kind);
    check_elements(elements, reference, solid, resolution)?;
    Ok(lattice_of(elements.shape, resolution))
}

fn lattice_of(shape: Element3, resolution: usize) -> Box<dyn Lattice> {
    match shape {
        Element3::Cube => Box::new(cube::CubeLattice::new(resolution)),
        Element3::Tetrahedron => Box::new(simplex::TetLattice::new(resolution)),
    }
}

/// The checks every tiling makes before it starts: the resolution, the corner list's length,
/// the node lists against it, and nodal arrays long enough for every node they name.
fn check_input(
    corners: &[u32],
    per_element: usize,
    nodes: &Nodes,
    solid: &TiledSolid,
    resolution: usize,
) -> Result<(), TileError> {
    if resolution < 2 {
        return Err(TileError::Resolution(resolution));
    }
    if resolution > 256 {
        return Err(TileError::ResolutionTooHigh(resolution));
    }
    if !corners.len().is_multiple_of(per_element) {
        return Err(TileError::Corners {
            len: corners.len(),
            per_element,
        });
    }
    shape::check_nodes(corners, per_element, nodes).map_err(TileError::Nodes)?;
    let nodes = nodes.ids.iter().map(|&c| c as usize + 1).max().unwrap_or(0);
    for (what, values) in solid.nodal() {
        if values.len() < nodes {
            return Err(TileError::NodalValues {
                what,
                given: values.len(),
                nodes,
            });
        }
    }
    Ok(())
}

/// Samples, contours and welds `solid` over `elements` on `lattice` (steps 1–4 of the module
/// docs), whatever the element's dimension, as one mesh.
fn tile_on(
    elements: &dyn Corners,
    nodes: Nodes,
    lattice: &dyn Lattice,
    solid: &TiledSolid,
    skin: Option<&Skin>,
) -> Result<(Mesh, TileStats), TileError> {
    let mut mesh = Mesh::default();
    let stats = stream_on(
        elements,
        nodes,
        lattice,
        solid,
        skin,
        Chunking {
            elements: usize::MAX,
            spare: &SpareArrays::default(),
        },
        &mut |chunk| {
            // One chunk holds every element: its arrays are the mesh.
            mesh.vertices = chunk.vertices;
            mesh.triangles = chunk.triangles;
            Ok(())
        },
    )?;
    Ok((mesh, stats))
}

/// How a streamed tiling cuts its mesh: chunks of `elements` elements, their arrays taken
/// from `spare`.
struct Chunking<'a> {
    elements: usize,
    spare: &'a SpareArrays,
}

/// Where a streamed tiling's chunks go, in order; an error stops the tiling. It runs on a
/// rayon thread while the next chunk is made, so it may use the pool (its parallel work
/// shares the threads with the tiling's), and should not block for long.
pub type ChunkSink<'s> = dyn FnMut(MeshChunk) -> Result<(), String> + Send + 's;

/// [`tile_on`], handing the mesh to `sink` a chunk of `chunk_elements` elements at a time (at
/// least one chunk, even for no elements): memory holds one chunk's local meshes and output,
/// the chunk before it (in the sink), and the vertices open between chunks.
///
/// Chunk `k + 1` is made while the sink takes chunk `k` (`rayon::join`), so a sink that
/// checks or encodes in parallel keeps both halves of the pool busy without a thread of its
/// own competing with them.
fn stream_on(
    elements: &dyn Corners,
    nodes: Nodes,
    lattice: &dyn Lattice,
    solid: &TiledSolid,
    skin: Option<&Skin>,
    chunking: Chunking<'_>,
    sink: &mut ChunkSink,
) -> Result<TileStats, TileError> {
    let Chunking {
        elements: chunk_elements,
        spare,
    } = chunking;
    let count = elements.count();
    let per_chunk = chunk_elements.clamp(1, count.max(1));
    let chunks = count.div_ceil(per_chunk).max(1);
    let mut welder = Welder::new(elements, lattice, chunks > 1, spare)?;
    let cell = symmetric_samples(lattice, solid.cell);
    let band = lattice.takes_bands() && solid.solid.band().is_some();
    if solid.is_uniform() && skin.is_none() {
        let mut values = vec![f64::NAN; lattice.index_len() * if band { 2 } else { 1 }];
        for (p, &v) in cell.iter().enumerate() {
            set_sample(&mut values, p, solid.solid, v, band, |v| v);
        }
        let local = lattice.contour(samples_in(&values, band));
        pipeline(
            chunks,
            |_| welder.chunk(per_chunk, Locals::Uniform(&local)),
            sink,
        )?;
        return Ok(welder.stats());
    }
    let samples = ElementSamples::new(lattice, solid, cell, nodes)?.with_skin(skin);
    pipeline(
        chunks,
        |k| {
            let range = k * per_chunk..((k + 1) * per_chunk).min(count);
            let locals: Vec<local::LocalMesh> = range
                .into_par_iter()
                .map_init(
                    || vec![f64::NAN; lattice.index_len() * if band { 2 } else { 1 }],
                    |values, e| {
                        samples.fill(e, values, band);
                        lattice.contour(samples_in(values, band))
                    },
                )
                .collect();
            welder.chunk(per_chunk, Locals::PerElement(&locals))
        },
        sink,
    )?;
    Ok(welder.stats())
}

/// Makes chunks `0..chunks` in order with `make`, handing each to `sink` while the next one
/// is made (`rayon::join`); the first error stops both.
fn pipeline(
    chunks: usize,
    mut make: impl FnMut(usize) -> Result<MeshChunk, TileError> + Send,
    sink: &mut ChunkSink,
) -> Result<(), TileError> {
    let mut emit = |made: Option<MeshChunk>| match made {
        Some(chunk) => sink(chunk).map_err(TileError::Sink),
        None => Ok(()),
    };
    let mut made = None;
    for k in 0..chunks {
        let previous = made.take();
        let (chunk, emitted) = rayon::join(|| make(k), || emit(previous));
        emitted?;
        made = Some(chunk?);
    }
    emit(made)
}

/// Elements per chunk for about `triangles` output triangles per chunk at `resolution`
/// samples per element edge (a lattice surface crosses an element in about `2 r²` triangles).
pub fn chunk_elements_for(resolution: usize, triangles: usize) -> usize {
    let per_element = 2 * resolution.max(2).pow(2);
    (triangles / per_element).max(64)
}

/// The samples of a graded or transition solid in one element, from the symmetric reference
/// samples of its cells and the nodal values at all the element's nodes.
struct ElementSamples<'s> {
    solid: &'s TiledSolid<'s>,
    skin: Option<&'s Skin>,
    cell: Vec<f64>,
    to: Option<Vec<f64>>,
    nodes: Nodes<'s>,
    shape: Shape,
    /// The lattice points, in index order.
    points: Vec<SamplePoint>,
    /// How far below its nodal values an interpolant can reach ([`Shape::undershoot`]).
    undershoot: f64,
}

/// A lattice point: its index, corner weights (naming it, and placing the skin term) and
/// integer coordinates (for the shape-function numerators).
struct SamplePoint {
    index: u32,
    weights: Weights,
    at: shape::Point,
}

impl<'s> ElementSamples<'s> {
    /// The samples over `nodes`; an error if a graded thickness interpolates to ≤ 0 anywhere.
    fn new(
        lattice: &dyn Lattice,
        solid: &'s TiledSolid<'s>,
        cell: Vec<f64>,
        nodes: Nodes<'s>,
    ) -> Result<Self, TileError> {
        let weights: Vec<(u32, Weights)> = (0..lattice.index_len() as u32)
            .filter(|&p| lattice.is_point(p))
            .map(|p| (p, lattice.weights(p)))
            .collect();
        let shape = match weights.first() {
            Some((_, w)) => Shape::from_weights(nodes.kind, w),
            None => Shape::new(nodes.kind, 1),
        };
        let points: Vec<SamplePoint> = weights
            .into_iter()
            .map(|(index, weights)| SamplePoint {
                index,
                weights,
                at: shape.point(&weights),
            })
            .collect();
        let undershoot = shape.undershoot(points.iter().map(|p| p.at));
        let samples = ElementSamples {
            solid,
            skin: None,
            cell,
            to: solid
                .transition
                .as_ref()
                .map(|t| symmetric_samples(lattice, t.to)),
            nodes,
            shape,
            points,
            undershoot,
        };
        samples.check_thickness()?;
        Ok(samples)
    }

    /// The same samples, with the skin term.
    fn with_skin(self, skin: Option<&'s Skin>) -> Self {
        ElementSamples { skin, ..self }
    }

    /// Calls `visit(point, numerators)` for every lattice point, with the numerators of
    /// element `e`'s nodes in the order of `order`.
    fn for_each_point(&self, order: &Order, mut visit: impl FnMut(&SamplePoint, &[i64])) {
        let mut local = [0i64; shape::MAX_NODES];
        for point in &self.points {
            self.shape.numerators(&point.at, &mut local);
            let sorted = order.arrange(&local);
            visit(point, &sorted[..order.len()]);
        }
    }

    /// A graded thickness must stay > 0 at every sample (what [`TiledSolid`] promises):
    /// the lowest element where it does not is the error.
    fn check_thickness(&self) -> Result<(), TileError> {
        let Some(thickness) = self.solid.thickness else {
            return Ok(());
        };
        if !matches!(
            self.solid.solid,
            Solid::Shell { .. } | Solid::EccentricShell { .. }
        ) {
            return Ok(());
        }
        let denominator = self.shape.denominator();
        let lowest = |e: usize| {
            let nodes = self.nodes.element(e);
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for &n in nodes {
                // NaN compares false, so leaves `lo` NaN and fails the bound below.
                let t = thickness[n as usize];
                lo = if t < lo || t.is_nan() { t } else { lo };
                hi = hi.max(t);
            }
            // Every interpolant is ≥ lo − (hi − lo)·undershoot: most elements need no sample
            // pass. The margin dwarfs the sums' rounding (~1e-15 relative).
            if lo > 0.0 && lo - (hi - lo) * self.undershoot > 1e-9 * hi {
                return lo;
            }
            let order = Order::of(nodes);
            let values = order.gather(nodes, thickness);
            let mut lowest = f64::INFINITY;
            self.for_each_point(&order, |_, n| {
                let t = shape::interpolate(n, &values, denominator);
                // A NaN is no thickness either, and stays the answer once found.
                if !lowest.is_nan() && (t.is_nan() || t < lowest) {
                    lowest = t;
                }
            });
            lowest
        };
        let bad = (0..self.nodes.count())
            .into_par_iter()
            .map(|e| (e, lowest(e)))
            // NaN fails too.
            .find_first(|&(_, t)| t.is_nan() || t <= 0.0);
        match bad {
            Some((e, t)) => Err(TileError::Thickness {
                element: e as u64,
                value_bits: t.to_bits(),
            }),
            None => Ok(()),
        }
    }

    /// The samples of element `e` into `values` (both levels', for a `band`: see
    /// [`samples_in`]).
    fn fill(&self, e: usize, values: &mut [f64], band: bool) {
        let solid = self.solid;
        let nodes = self.nodes.element(e);
        let corners = &nodes[..self.shape.corner_count()];
        let skin = self.skin.filter(|s| !s.is_far(corners));
        let order = Order::of(nodes);
        // Missing arrays are interpolated as zeros and not used.
        let gather = |nodal: Option<&[f64]>| {
            nodal.map_or([0.0; shape::MAX_NODES], |v| order.gather(nodes, v))
        };
        let arrays = [
            gather(solid.transition.as_ref().map(|t| t.weight)),
            gather(solid.thickness),
            gather(solid.offset),
        ];
        let arrays = [&arrays[0][..], &arrays[1][..], &arrays[2][..]];
        let denominator = self.shape.denominator();
        self.for_each_point(&order, |point, n| {
            let p = point.index as usize;
            // Σ nᵢ vᵢ / D in increasing global node order: the same bits from every element
            // sharing the point.
            let [weight, thickness, offset] = shape::interpolate_each(n, &arrays, denominator);
            let mut phi = self.cell[p];
            if let Some(to) = &self.to {
                // The quadratic interpolant may leave [0, 1] between nodal weights.
                let w = weight.clamp(0.0, 1.0);
                phi = (1.0 - w) * phi + w * to[p];
            }
            let graded = graded_solid(
                solid.solid,
                solid.thickness.map(|_| thickness),
                solid.offset.map(|_| offset),
            );
            set_sample(values, p, graded, phi, band, |v| match skin {
                Some(skin) => skin.apply(v, corners, &point.weights),
                None => v,
            });
        });
    }
}

/// Sets point `p`'s samples of `solid` for cell value `phi`, each passed through `skin` (the
/// skin is a union, `min(·, s)`, which distributes over a band's two levels). One level: the
/// solid's implicit function at `values[p]`. A band (a shell on a 3D lattice): `lo − phi` at
/// `values[p]` and `phi − hi` in the second half ([`Samples`]).
#[inline]
fn set_sample(
    values: &mut [f64],
    p: usize,
    solid: Solid,
    phi: f64,
    band: bool,
    skin: impl Fn(f64) -> f64,
) {
    match solid.band().filter(|_| band) {
        Some(levels) => {
            let half = values.len() / 2;
            values[p] = skin(levels.lo - phi);
            values[half + p] = skin(phi - levels.hi);
        }
        None => values[p] = skin(solid.apply(phi)),
    }
}

/// The samples in `values`: one level, or (`band`) the lower level's in the first half and
/// the upper level's in the second.
fn samples_in(values: &[f64], band: bool) -> Samples<'_> {
    if band {
        let (lower, upper) = values.split_at(values.len() / 2);
        Samples {
            lower,
            upper: Some(upper),
        }
    } else {
        Samples::one(values)
    }
}

/// The solid with its thickness or offset replaced by graded values where given.
fn graded_solid(solid: Solid, thickness: Option<f64>, offset: Option<f64>) -> Solid {
    match solid {
        Solid::Inside { offset: o } => Solid::Inside {
            offset: offset.unwrap_or(o),
        },
        Solid::Outside { offset: o } => Solid::Outside {
            offset: offset.unwrap_or(o),
        },
        Solid::Shell { thickness: t } => Solid::Shell {
            thickness: thickness.unwrap_or(t),
        },
        Solid::EccentricShell {
            offset: o,
            thickness: t,
        } => Solid::EccentricShell {
            offset: offset.unwrap_or(o),
            thickness: thickness.unwrap_or(t),
        },
    }
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

#[cfg(test)]
mod tests;

#[cfg(test)]
mod stream_tests;
