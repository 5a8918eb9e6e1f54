//! Marching cubes over one chunk: a run of cube layers `k0..k1` between planes `k0..=k1`.
//!
//! Ownership of vertices (the seam rule between chunks): a chunk owns the vertices of plane
//! `k0` and of every plane up to `k1 − 1` (crossings on x- and y-edges, inside nodes on the
//! domain boundary), and of every z-edge between its planes. Plane `k1` belongs to the next
//! chunk, except for the last chunk, which owns it too. A chunk refers to the next chunk's
//! vertices by their ordinal in [`PlaneItems`] order with [`FOREIGN`] set: the next chunk
//! creates exactly those items first, in exactly that order, from bit-identical samples, so
//! ordinal `m` there is local vertex `m`. No lookup tables cross chunk boundaries.
//!
//! Only the sign of each sample and the interpolation along crossing edges matter; signs are
//! packed 64 to a word so that empty and full regions are skipped a word at a time.
//!
//! A band (`lo < f < hi`, see [`Band`]) keeps two bits per sample, above `lo` and at or above
//! `hi`, and two kinds of crossing per edge, each level's crossing interpolated in `f` itself;
//! an edge from below to above has both, kept apart by [`EDGE_MARGIN`] (see [`band_crossing`]).
//! The band also tracks the steepest `f` in the cubes its middle level crosses (the wall
//! estimate of [`super::BandMesh`]).

use super::table::{CORNER_SLOT, HI_SLOT, Tables};
use crate::field::{Band, Grid, PlaneSampler};
use crate::mesh::round_inside;

/// Marks a vertex id as an ordinal among the next chunk's first vertices.
pub const FOREIGN: u32 = 1 << 31;

/// Samples per block of rows handed to the sampler: small enough to stay in L1/L2.
const SAMPLE_BLOCK: usize = 4096;

/// Crossing points are kept at least this fraction of an edge away from its ends, so that two
/// vertices never coincide (STL welds by position) even where a sample is exactly zero.
const EDGE_MARGIN: f64 = 1.0 / 256.0;

/// The mesh of one chunk, with vertex ids local to it or [`FOREIGN`] ordinals.
pub struct ChunkMesh {
    pub vertices: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    /// For a band: the largest `|∇f|²` (field per sample step) over the cubes its middle
    /// level crosses; 0 otherwise.
    pub steepest_squared: f64,
}

/// Planes and z-edge ids a worker reuses across the chunks it runs.
pub struct Scratch {
    lower: Plane,
    upper: Plane,
    z_edge: Items,
    /// A band's upper-level crossings on z-edges (unused otherwise).
    z_hi: Items,
    last_sizes: (usize, usize),
}

/// The vertex items of one kind on one plane (or between two): which positions have one, as
/// bits per word of 64 columns, and the id of the first item in each word. The id of the item
/// at bit `b` is the word's base plus the number of items below `b`. Compared with a dense id
/// per sample this keeps everything the cube pass reads within a few hundred kilobytes.
struct Items {
    mask: Vec<u64>,
    base: Vec<u32>,
}

impl Items {
    fn new(words: usize) -> Items {
        Items {
            mask: vec![0; words],
            base: vec![0; words],
        }
    }

    #[inline]
    fn id(&self, word: usize, bit: usize) -> u32 {
        self.base[word] + (self.mask[word] & low_bits_below(bit)).count_ones()
    }
}

/// Samples of one plane with their packed signs and the vertex items on it.
struct Plane {
    values: Vec<f64>,
    /// Bit `i % 64` of word `j * words_per_row + i / 64` is set when sample (i, j) is inside
    /// (for a band: above its lower level).
    inside: Vec<u64>,
    /// For a band, the same bits for samples at or above its upper level (a subset of
    /// `inside`) and for samples above its middle level; all zero otherwise.
    above: Vec<u64>,
    middle: Vec<u64>,
    /// Crossings on x-edges (i, j)–(i + 1, j), y-edges (i, j)–(i, j + 1), for a band those of
    /// its upper level on the same edges, and inside nodes on the domain boundary, in that
    /// order of ids.
    x_edge: Items,
    y_edge: Items,
    x_hi: Items,
    y_hi: Items,
    node: Items,
}

pub struct ChunkContext<'a> {
    pub sampler: &'a dyn PlaneSampler,
    pub model: &'a Grid,
    pub tables: &'a Tables,
    /// `None`: the solid is `{g < 0}` of the samples `g`; `Some`: the samples are `f` and the
    /// solid is the band `lo < f < hi`.
    pub band: Option<Band>,
}

/// Hands out vertex ids in creation order: this chunk's own vertices, or ordinals among the
/// next chunk's first vertices.
enum Ids<'v> {
    Own(&'v mut Vec<[f32; 3]>),
    Foreign(u32),
}

impl ChunkContext<'_> {
    fn counts(&self) -> [usize; 3] {
        self.model.counts
    }

    fn words_per_row(&self) -> usize {
        self.counts()[0].div_ceil(64)
    }

    fn new_plane(&self) -> Plane {
        let [nx, ny, _] = self.counts();
        let words = self.words_per_row() * ny;
        Plane {
            values: vec![0.0; nx * ny],
            inside: vec![0; words],
            above: vec![0; words],
            middle: vec![0; words],
            x_edge: Items::new(words),
            y_edge: Items::new(words),
            x_hi: Items::new(words),
            y_hi: Items::new(words),
            node: Items::new(words),
        }
    }

    fn sample(&self, k: usize, plane: &mut Plane) {
        let [nx, ny, _] = self.counts();
        let wpr = self.words_per_row();
        // Pack signs a few rows after sampling them, while they are still in cache.
        let rows_per_block = (SAMPLE_BLOCK / nx).max(1);
        for j0 in (0..ny).step_by(rows_per_block) {
            let j1 = (j0 + rows_per_block).min(ny);
            self.sampler
                .sample_rows(k, j0..j1, &mut plane.values[j0 * nx..j1 * nx]);
            for j in j0..j1 {
                let row = &plane.values[j * nx..(j + 1) * nx];
                let words = j * wpr..(j + 1) * wpr;
                match self.band {
                    None => {
                        for (word, values) in plane.inside[words].iter_mut().zip(row.chunks(64)) {
                            *word = pack_signs(values);
                        }
                    }
                    Some(Band { lo, hi }) => {
                        let middle = lo + 0.5 * (hi - lo);
                        let words = plane.inside[words.clone()]
                            .iter_mut()
                            .zip(&mut plane.above[words.clone()])
                            .zip(&mut plane.middle[words]);
                        for (((inside, above), mid), values) in words.zip(row.chunks(64)) {
                            // NaN compares false everywhere: below the band, outside.
                            [*inside, *above, *mid] =
                                pack_by(values, |v| [v > lo, v >= hi, v > middle]);
                        }
                    }
                }
            }
        }
    }

    /// Position of the crossing on the edge from sample value `v0` to `v1`, as a fraction.
    #[inline]
    fn crossing(v0: f64, v1: f64) -> f64 {
        crossing_fraction(v0, v1)
    }

    /// Position of a crossing on the edge from sample `at` to the next along `axis`, whose
    /// samples are `v0` and `v1`: of the zero level, or for a band of its lower level (`upper`
    /// false) or its upper level. Strictly inside the edge in `f32` ([`round_inside`]), which
    /// `contour` has checked the grid leaves room for; the two levels' crossings on one edge
    /// also differ in `f32` (see [`apart_in_f32`]).
    #[inline]
    fn edge_position(
        &self,
        at: [usize; 3],
        axis: usize,
        v0: f64,
        v1: f64,
        upper: bool,
    ) -> [f32; 3] {
        let g = self.model;
        let mut p = self.position(at[0], at[1], at[2]);
        let i = at[axis];
        let (a, b) = (g.coord(axis, i), g.coord(axis, i + 1));
        let rounded =
            |t: f64| round_inside(g.origin[axis] + (i as f64 + t) * g.spacing[axis], a, b);
        p[axis] = match self.band {
            None => rounded(Self::crossing(v0, v1)),
            Some(band) if spans_band(v0, v1, band) => {
                let t_lo = band_crossing(v0, v1, band, false);
                let t_hi = band_crossing(v0, v1, band, true);
                let (lo, hi) = apart_in_f32(rounded(t_lo), rounded(t_hi), t_hi > t_lo, a, b);
                if upper { hi } else { lo }
            }
            Some(band) => rounded(band_crossing(v0, v1, band, upper)),
        };
        p
    }

    /// Position of sample `(i, j, k)`.
    #[inline]
    fn position(&self, i: usize, j: usize, k: usize) -> [f32; 3] {
        let g = self.model;
        [
            g.coord(0, i) as f32,
            g.coord(1, j) as f32,
            g.coord(2, k) as f32,
        ]
    }

    /// Records the items of one word and gives them ids; owned items become vertices at the
    /// positions `place(column)` gives.
    #[inline]
    fn assign(
        items: &mut Items,
        word: usize,
        mask: u64,
        w: usize,
        ids: &mut Ids,
        place: impl Fn(usize) -> [f32; 3],
    ) {
        items.mask[word] = mask;
        match ids {
            Ids::Own(vertices) => {
                items.base[word] = vertices.len() as u32;
                let mut bits = mask;
                while bits != 0 {
                    let i = w * 64 + bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    vertices.push(place(i));
                }
            }
            Ids::Foreign(next) => {
                items.base[word] = FOREIGN | *next;
                *next += mask.count_ones();
            }
        }
    }

    /// Gives every vertex item of plane `k` an id, in the canonical order: x-edge crossings
    /// row by row, then y-edge crossings, for a band its upper level's x- and y-edge
    /// crossings, then inside nodes on the domain boundary. Owned items become vertices of
    /// this chunk; the next chunk's get [`FOREIGN`] ordinals.
    fn enumerate_items(&self, k: usize, plane: &mut Plane, mut ids: Ids) {
        let Plane {
            values,
            inside,
            above,
            x_edge,
            y_edge,
            x_hi,
            y_hi,
            node,
            ..
        } = plane;
        self.edge_items(k, values, inside, x_edge, y_edge, false, &mut ids);
        if self.band.is_some() {
            self.edge_items(k, values, above, x_hi, y_hi, true, &mut ids);
        }
        let [nx, ny, nz] = self.counts();
        let wpr = self.words_per_row();
        let last_word_mask = low_bits(nx - (wpr - 1) * 64);
        let whole_plane = k == 0 || k == nz - 1;
        for j in 0..ny {
            let boundary_row = whole_plane || j == 0 || j == ny - 1;
            for w in 0..wpr {
                let word_mask = if w + 1 == wpr {
                    last_word_mask
                } else {
                    u64::MAX
                };
                let columns = if boundary_row {
                    word_mask
                } else {
                    column_mask(w, &[0, nx - 1])
                };
                // In a band, `above` is zero outside it: inside nodes are those between.
                let word = j * wpr + w;
                let mask = inside[word] & !above[word] & columns;
                Self::assign(node, word, mask, w, &mut ids, |i| self.position(i, j, k));
            }
        }
    }

    /// Gives ids to the crossings on the x- and y-edges of plane `k` between samples whose
    /// `bits` differ (row by row, x-edges first), placed on the lower (`upper` false) or upper
    /// level.
    #[allow(clippy::too_many_arguments)]
    fn edge_items(
        &self,
        k: usize,
        values: &[f64],
        bits: &[u64],
        x_edge: &mut Items,
        y_edge: &mut Items,
        upper: bool,
        ids: &mut Ids,
    ) {
        let [nx, ny, _] = self.counts();
        let wpr = self.words_per_row();
        let last_word_mask = low_bits(nx - (wpr - 1) * 64);
        let inside = bits;
        for j in 0..ny {
            let row = &inside[j * wpr..(j + 1) * wpr];
            for w in 0..wpr {
                let next_first = if w + 1 < wpr { row[w + 1] & 1 } else { 0 };
                let shifted = (row[w] >> 1) | (next_first << 63);
                let mask = (row[w] ^ shifted) & edge_mask(w, wpr, nx - 1);
                Self::assign(x_edge, j * wpr + w, mask, w, ids, |i| {
                    let (v0, v1) = (values[j * nx + i], values[j * nx + i + 1]);
                    self.edge_position([i, j, k], 0, v0, v1, upper)
                });
            }
        }
        for j in 0..ny {
            for w in 0..wpr {
                let mask = if j + 1 == ny {
                    0
                } else {
                    let word_mask = if w + 1 == wpr {
                        last_word_mask
                    } else {
                        u64::MAX
                    };
                    (inside[j * wpr + w] ^ inside[(j + 1) * wpr + w]) & word_mask
                };
                Self::assign(y_edge, j * wpr + w, mask, w, ids, |i| {
                    let (v0, v1) = (values[j * nx + i], values[(j + 1) * nx + i]);
                    self.edge_position([i, j, k], 1, v0, v1, upper)
                });
            }
        }
    }

    /// Creates the vertices on the z-edges between `lower` (plane k) and `upper` (k + 1):
    /// the crossings, then for a band its upper level's crossings.
    fn z_edges(
        &self,
        k: usize,
        lower: &Plane,
        upper: &Plane,
        z_edge: &mut Items,
        z_hi: &mut Items,
        out: &mut Vec<[f32; 3]>,
    ) {
        let mut ids = Ids::Own(out);
        self.z_edge_items(k, lower, upper, |p| &p.inside, z_edge, false, &mut ids);
        if self.band.is_some() {
            self.z_edge_items(k, lower, upper, |p| &p.above, z_hi, true, &mut ids);
        }
    }

    /// The z-edge crossings between samples whose `bits` differ.
    #[allow(clippy::too_many_arguments)]
    fn z_edge_items(
        &self,
        k: usize,
        lower: &Plane,
        upper: &Plane,
        bits: impl Fn(&Plane) -> &Vec<u64>,
        z_edge: &mut Items,
        upper_level: bool,
        ids: &mut Ids,
    ) {
        let [nx, ny, _] = self.counts();
        let wpr = self.words_per_row();
        let last_word_mask = low_bits(nx - (wpr - 1) * 64);
        let (below, above) = (bits(lower), bits(upper));
        for j in 0..ny {
            for w in 0..wpr {
                let word_mask = if w + 1 == wpr {
                    last_word_mask
                } else {
                    u64::MAX
                };
                let word = j * wpr + w;
                let mask = (below[word] ^ above[word]) & word_mask;
                Self::assign(z_edge, word, mask, w, ids, |i| {
                    let (v0, v1) = (lower.values[j * nx + i], upper.values[j * nx + i]);
                    self.edge_position([i, j, k], 2, v0, v1, upper_level)
                });
            }
        }
    }

    /// Emits the triangles (surface and caps) of cube layer `k`; for a band (`BAND`, which
    /// must be `self.band.is_some()`: one-level solids get a copy without the band's work),
    /// also raises `steepest_squared` to `|∇f|²` of every cube its middle level crosses.
    #[inline(never)]
    fn cubes<const BAND: bool>(
        &self,
        (k, lower, upper, z_edge, z_hi): (usize, &Plane, &Plane, &Items, &Items),
        tris: &mut Vec<[u32; 3]>,
        steepest_squared: &mut f64,
    ) {
        let [nx, ny, nz] = self.counts();
        let wpr = self.words_per_row();
        let layer_on_boundary = k == 0 || k + 2 == nz;
        let boundary_columns = |w: usize| column_mask(w, &[0, nx - 2]);
        let items: [&Items; 12] = [
            &lower.x_edge,
            &upper.x_edge,
            &lower.y_edge,
            &upper.y_edge,
            z_edge,
            &lower.node,
            &upper.node,
            &lower.x_hi,
            &upper.x_hi,
            &lower.y_hi,
            &upper.y_hi,
            z_hi,
        ];
        for j in 0..ny - 1 {
            let row_on_boundary = layer_on_boundary || j == 0 || j + 2 == ny;
            // The cube's four rows of corners: (dy, dz) = (0, 0), (1, 0), (0, 1), (1, 1).
            let (r0, r1) = (j * wpr..(j + 1) * wpr, (j + 1) * wpr..(j + 2) * wpr);
            let rows = [
                &lower.inside[r0.clone()],
                &lower.inside[r1.clone()],
                &upper.inside[r0.clone()],
                &upper.inside[r1.clone()],
            ];
            let above = [
                &lower.above[r0.clone()],
                &lower.above[r1.clone()],
                &upper.above[r0.clone()],
                &upper.above[r1.clone()],
            ];
            let middle = [
                &lower.middle[r0.clone()],
                &lower.middle[r1.clone()],
                &upper.middle[r0],
                &upper.middle[r1],
            ];
            for w in 0..wpr {
                let cubes_in_word = edge_mask(w, wpr, nx - 1);
                let (all, any) = cube_bits(&rows, w, wpr);
                // A cube needs work when the surface passes through it, or when it has an
                // inside corner and a face on the domain boundary (its cap).
                let boundary = if row_on_boundary {
                    u64::MAX
                } else {
                    boundary_columns(w)
                };
                let mut work = (any & !all) | (any & boundary);
                if BAND {
                    let (all_above, any_above) = cube_bits(&above, w, wpr);
                    work |= any_above & !all_above;
                    let (all_mid, any_mid) = cube_bits(&middle, w, wpr);
                    let mut crossed = any_mid & !all_mid & cubes_in_word;
                    while crossed != 0 {
                        let i = w * 64 + crossed.trailing_zeros() as usize;
                        crossed &= crossed - 1;
                        let g2 = gradient_squared(lower, upper, i, j, nx);
                        // `max` ignores NaN: an undefined sample says nothing of the wall.
                        *steepest_squared = steepest_squared.max(g2);
                    }
                }
                work &= cubes_in_word;
                while work != 0 {
                    let i = w * 64 + work.trailing_zeros() as usize;
                    work &= work - 1;
                    let config = cube_config(&rows, i);
                    let config_above = if BAND { cube_config(&above, i) } else { 0 };
                    // Word and bit of the four columns (i + dx, j + dy) the cube touches.
                    let at: [(usize, usize); 4] = std::array::from_fn(|c| {
                        let (col, row) = (i + (c & 1), j + (c >> 1));
                        (row * wpr + col / 64, col % 64)
                    });
                    let id = |s: u8| {
                        let (kind, corner) = SLOT_REFS[s as usize];
                        let (word, bit) = at[corner as usize];
                        items[kind as usize].id(word, bit)
                    };
                    for tri in self.tables.triangles(config) {
                        tris.push([id(tri[0]), id(tri[1]), id(tri[2])]);
                    }
                    // The upper level's surface faces the other way: the band lies below it.
                    if BAND {
                        for tri in self.tables.triangles(config_above) {
                            tris.push([
                                id(HI_SLOT + tri[0]),
                                id(HI_SLOT + tri[2]),
                                id(HI_SLOT + tri[1]),
                            ]);
                        }
                    }
                    if row_on_boundary || i == 0 || i + 2 == nx {
                        let on_face = [
                            i == 0,
                            i + 2 == nx,
                            j == 0,
                            j + 2 == ny,
                            k == 0,
                            k + 2 == nz,
                        ];
                        for face in (0..6).filter(|&f| on_face[f]) {
                            let cap = if BAND {
                                self.tables.band_cap(config, config_above, face)
                            } else {
                                self.tables.cap(config, face)
                            };
                            for tri in cap {
                                tris.push([id(tri[0]), id(tri[1]), id(tri[2])]);
                            }
                        }
                    }
                }
            }
        }
    }

    /// Working memory for chunks, reused from one chunk to the next on a thread.
    pub fn scratch(&self) -> Scratch {
        let words = self.words_per_row() * self.counts()[1];
        Scratch {
            lower: self.new_plane(),
            upper: self.new_plane(),
            z_edge: Items::new(words),
            z_hi: Items::new(words),
            last_sizes: (0, 0),
        }
    }

    /// Runs marching cubes over cube layers `k0..k1`; `progress(1)` is called per layer.
    pub fn run(
        &self,
        k0: usize,
        k1: usize,
        scratch: &mut Scratch,
        progress: &(dyn Fn(usize) + Sync),
    ) -> ChunkMesh {
        let nz = self.counts()[2];
        // Neighbouring chunks cut similar amounts of surface: reserving what the last one
        // needed avoids most regrowth copies.
        let mut vertices = Vec::with_capacity(scratch.last_sizes.0);
        let mut triangles = Vec::with_capacity(scratch.last_sizes.1);
        let mut steepest_squared = 0.0f64;
        let Scratch {
            lower,
            upper,
            z_edge,
            z_hi,
            ..
        } = scratch;
        self.sample(k0, lower);
        self.enumerate_items(k0, lower, Ids::Own(&mut vertices));
        for k in k0..k1 {
            self.sample(k + 1, upper);
            self.z_edges(k, lower, upper, z_edge, z_hi, &mut vertices);
            let ids = if k + 1 < k1 || k1 == nz - 1 {
                Ids::Own(&mut vertices)
            } else {
                Ids::Foreign(0)
            };
            self.enumerate_items(k + 1, upper, ids);
            let args = (k, &*lower, &*upper, &*z_edge, &*z_hi);
            if self.band.is_some() {
                self.cubes::<true>(args, &mut triangles, &mut steepest_squared);
            } else {
                self.cubes::<false>(args, &mut triangles, &mut steepest_squared);
            }
            std::mem::swap(lower, upper);
            progress(1);
        }
        scratch.last_sizes = (
            vertices.len() + vertices.len() / 8,
            triangles.len() + triangles.len() / 8,
        );
        ChunkMesh {
            vertices,
            triangles,
            steepest_squared,
        }
    }
}

/// For each slot, which [`Items`] holds its vertex (lower x, upper x, lower y, upper y, z,
/// lower nodes, upper nodes, then a band's upper level's lower x, upper x, lower y, upper y,
/// z) and at which of the cube's four columns (dx + 2 dy).
const SLOT_REFS: [(u8, u8); 32] = {
    let mut refs = [(0u8, 0u8); 32];
    let mut s = 0;
    while s < 32 {
        refs[s] = if s >= CORNER_SLOT as usize && s < HI_SLOT as usize {
            let c = (s - CORNER_SLOT as usize) as u8;
            (5 + ((c >> 2) & 1), c & 3)
        } else {
            let (e, shift) = if s >= HI_SLOT as usize {
                (s - HI_SLOT as usize, 7)
            } else {
                (s, 0)
            };
            let (axis, r) = (e / 4, (e % 4) as u8);
            let (a, b) = (r & 1, r >> 1);
            let (kind, column) = match axis {
                0 => (b, 2 * a),
                1 => (2 + b, a),
                _ => (4, a + 2 * b),
            };
            (kind + shift, column)
        };
        s += 1;
    }
    refs
};

/// Bit `b` set when `values[b] < 0` (NaN compares false: an undefined sample is outside).
#[inline]
fn pack_signs(values: &[f64]) -> u64 {
    if let Ok(full) = <&[f64; 64]>::try_from(values) {
        // A fixed trip count lets the compiler turn this into vector compares and mask moves.
        let mut bits = 0u64;
        for (b, &v) in full.iter().enumerate() {
            bits |= u64::from(v < 0.0) << b;
        }
        return bits;
    }
    values
        .iter()
        .enumerate()
        .fold(0, |bits, (b, &v)| bits | u64::from(v < 0.0) << b)
}

/// Per test `t`, bit `b` of word `t` set when `tests(values[b])[t]`. Tests are comparisons,
/// false for NaN: an undefined sample is below a band. One pass for all tests (measured:
/// fewer instructions in all than one vectorized pass per test).
#[inline(always)]
fn pack_by<const T: usize>(values: &[f64], tests: impl Fn(f64) -> [bool; T]) -> [u64; T] {
    let mut bits = [0u64; T];
    for (b, &v) in values.iter().enumerate() {
        let hits = tests(v);
        for t in 0..T {
            bits[t] |= u64::from(hits[t]) << b;
        }
    }
    bits
}

/// For the cubes whose lower-left column is each bit of word `w`: bits set when all eight
/// corners are set in `rows` (the cube's four rows of one bit plane), and when any is.
#[inline(always)]
fn cube_bits(rows: &[&[u64]; 4], w: usize, wpr: usize) -> (u64, u64) {
    let (mut all, mut any) = (u64::MAX, 0u64);
    for r in rows {
        let next_first = if w + 1 < wpr { r[w + 1] & 1 } else { 0 };
        let shifted = (r[w] >> 1) | (next_first << 63);
        all &= r[w] & shifted;
        any |= r[w] | shifted;
    }
    (all, any)
}

/// The 8-bit configuration of the cube at column `i` (corner `dx | dy << 1 | dz << 2`): the
/// two bits of columns `i` and `i + 1` of each row, rows in corner order.
#[inline(always)]
fn cube_config(rows: &[&[u64]; 4], i: usize) -> u8 {
    let (word, bit) = (i / 64, i % 64);
    let pair = |r: &[u64]| {
        // Column `i + 1` is in the next word when `i` is a word's last column.
        let next = if bit == 63 { r[word + 1] << 1 } else { 0 };
        (((r[word] >> bit) | next) & 3) as u8
    };
    pair(rows[0]) | pair(rows[1]) << 2 | pair(rows[2]) << 4 | pair(rows[3]) << 6
}

/// `|∇f|²` of the cube at column `i`, row `j` between two planes (see
/// [`corner_gradient_squared`]).
#[inline]
fn gradient_squared(lower: &Plane, upper: &Plane, i: usize, j: usize, nx: usize) -> f64 {
    let (a, b) = (j * nx + i, (j + 1) * nx + i);
    let (l, u) = (&lower.values, &upper.values);
    corner_gradient_squared(&[
        l[a],
        l[a + 1],
        l[b],
        l[b + 1],
        u[a],
        u[a + 1],
        u[b],
        u[b + 1],
    ])
}

/// `|∇f|²` in field units per sample step from a cube's corner values `v` (corner
/// `dx | dy << 1 | dz << 2`): its forward differences averaged over its four edges along each
/// axis (second-order accurate at the cube's centre).
#[inline]
pub(super) fn corner_gradient_squared(v: &[f64; 8]) -> f64 {
    let gx = 0.25 * ((v[1] - v[0]) + (v[3] - v[2]) + (v[5] - v[4]) + (v[7] - v[6]));
    let gy = 0.25 * ((v[2] - v[0]) + (v[3] - v[1]) + (v[6] - v[4]) + (v[7] - v[5]));
    let gz = 0.25 * ((v[4] - v[0]) + (v[5] - v[1]) + (v[6] - v[2]) + (v[7] - v[3]));
    gx * gx + gy * gy + gz * gz
}

/// Position of a band level's crossing on the edge from `v0` to `v1` (samples of `f`), as a
/// fraction: [`band_fraction`] of the levels' functions `lo − f` and `f − hi`.
#[inline]
pub(crate) fn band_crossing(v0: f64, v1: f64, band: Band, upper: bool) -> f64 {
    let Band { lo, hi } = band;
    band_fraction([lo - v0, lo - v1], [v0 - hi, v1 - hi], upper)
}

/// Position of a band level's crossing on an edge, as a fraction from its first end, from
/// the two levels' functions at its ends, each negative on the band's side: `lower` (as
/// `lo − f`, at or above 0 below the band, NaN too) and `upper` (as `f − hi`, at or above 0
/// above it); the levels may vary along the edge. Alone on its edge a level's crossing is
/// its linear one kept [`EDGE_MARGIN`] from the ends, as for one level. An edge from below
/// the band to above it holds both levels' crossings: measured from the end below, the lower
/// one is kept in `[m, 1 − 2m]` and the upper one in `[lower + m, 1 − m]` (`m` the margin),
/// so that the two never meet, however thin the band (a band thinner than `m` of an edge is
/// widened to it). Both are computed from the same four values wherever the edge's owner
/// computes them. (With `lower = lo − f` the quotients are exact negations of those in `f −
/// lo`, so the box contourer's crossings are the same bits either way.)
#[inline]
pub(crate) fn band_fraction(lower: [f64; 2], upper: [f64; 2], upper_level: bool) -> f64 {
    let below = |k: usize| lower[k].partial_cmp(&0.0) != Some(std::cmp::Ordering::Less);
    let above = |k: usize| upper[k] >= 0.0;
    let from_first = below(0) && above(1);
    if !(from_first || (below(1) && above(0))) {
        let v = if upper_level { upper } else { lower };
        return crossing_fraction(v[0], v[1]);
    }
    let (from, to) = if from_first { (0, 1) } else { (1, 0) };
    let raw = |v: [f64; 2]| v[from] / (v[from] - v[to]);
    let m = EDGE_MARGIN;
    let t_lo = raw(lower);
    let t_lo = if t_lo.is_finite() {
        t_lo.clamp(m, 1.0 - 2.0 * m)
    } else {
        1.0 / 3.0
    };
    let t = if upper_level {
        let t_hi = raw(upper);
        if t_hi.is_finite() {
            t_hi.clamp(t_lo + m, 1.0 - m)
        } else {
            (2.0f64 / 3.0).max(t_lo + m)
        }
    } else {
        t_lo
    };
    if from_first { t } else { 1.0 - t }
}

/// Position of the zero crossing on the edge from sample value `v0` to `v1`, as a fraction,
/// kept [`EDGE_MARGIN`] from the ends (the middle when the samples do not place it).
#[inline]
pub(crate) fn crossing_fraction(v0: f64, v1: f64) -> f64 {
    let t = v0 / (v0 - v1);
    if t.is_finite() {
        t.clamp(EDGE_MARGIN, 1.0 - EDGE_MARGIN)
    } else {
        0.5
    }
}

/// Not above the band's lower level, NaN included (as the sample bits have it).
#[inline]
fn below_band(v: f64, band: Band) -> bool {
    v.partial_cmp(&band.lo) != Some(std::cmp::Ordering::Greater)
}

/// Whether an edge with samples `v0`, `v1` runs from below the band to above it, and so
/// holds both levels' crossings.
#[inline]
pub(crate) fn spans_band(v0: f64, v1: f64, band: Band) -> bool {
    (below_band(v0, band) && v1 >= band.hi) || (below_band(v1, band) && v0 >= band.hi)
}

/// The `f32` positions of the lower and upper levels' crossings on one edge, whose ends round
/// to `a` and `b`, made different: both are strictly inside the edge and `hi` lies beyond
/// `lo` in the direction `increasing` says. Rounding keeps their order but can merge them far
/// from the origin, where an edge spans few `f32` steps; then the upper one moves one step on,
/// or, at the edge's end, the lower one a step back. Needs two `f32` strictly inside the edge,
/// which `contour` checks for a band.
#[inline]
pub(crate) fn apart_in_f32(lo: f32, hi: f32, increasing: bool, a: f64, b: f64) -> (f32, f32) {
    if lo != hi {
        return (lo, hi);
    }
    let (first, last) = (a as f32, b as f32);
    let (first, last) = if first <= last {
        (first, last)
    } else {
        (last, first)
    };
    if increasing {
        if hi.next_up() < last {
            (lo, hi.next_up())
        } else {
            (lo.next_down(), hi)
        }
    } else if hi.next_down() > first {
        (lo, hi.next_down())
    } else {
        (lo.next_up(), hi)
    }
}

/// Bits strictly below `bit` (`bit` in 0..64).
#[inline]
fn low_bits_below(bit: usize) -> u64 {
    (1u64 << bit) - 1
}

/// The lowest `n` bits set (`n` in 1..=64).
#[inline]
fn low_bits(n: usize) -> u64 {
    if n >= 64 { u64::MAX } else { (1u64 << n) - 1 }
}

/// Bits of word `w` whose column index is below `limit`.
#[inline]
fn edge_mask(w: usize, wpr: usize, limit: usize) -> u64 {
    let start = w * 64;
    if start >= limit {
        0
    } else if w + 1 < wpr && start + 64 <= limit {
        u64::MAX
    } else {
        low_bits(limit - start)
    }
}

/// Bits of word `w` for the given column indices.
#[inline]
fn column_mask(w: usize, columns: &[usize]) -> u64 {
    columns
        .iter()
        .filter(|&&c| c / 64 == w)
        .fold(0, |m, &c| m | 1u64 << (c % 64))
}
