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

use super::table::{CORNER_SLOT, Tables};
use crate::field::{Grid, PlaneSampler};
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
}

/// Planes and z-edge ids a worker reuses across the chunks it runs.
pub struct Scratch {
    lower: Plane,
    upper: Plane,
    z_edge: Items,
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
    /// Bit `i % 64` of word `j * words_per_row + i / 64` is set when sample (i, j) is inside.
    inside: Vec<u64>,
    /// Crossings on x-edges (i, j)–(i + 1, j), y-edges (i, j)–(i, j + 1), and inside nodes on
    /// the domain boundary, in that order of ids.
    x_edge: Items,
    y_edge: Items,
    node: Items,
}

pub struct ChunkContext<'a> {
    pub sampler: &'a dyn PlaneSampler,
    pub model: &'a Grid,
    pub tables: &'a Tables,
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
            x_edge: Items::new(words),
            y_edge: Items::new(words),
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
                let words = &mut plane.inside[j * wpr..(j + 1) * wpr];
                for (word, values) in words.iter_mut().zip(row.chunks(64)) {
                    *word = pack_signs(values);
                }
            }
        }
    }

    /// Position of the crossing on the edge from sample value `v0` to `v1`, as a fraction.
    #[inline]
    fn crossing(v0: f64, v1: f64) -> f64 {
        let t = v0 / (v0 - v1);
        if t.is_finite() {
            t.clamp(EDGE_MARGIN, 1.0 - EDGE_MARGIN)
        } else {
            0.5
        }
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

    /// Position of the crossing a fraction `t` along the edge from sample `at` to the next
    /// sample along `axis`: strictly inside the edge in `f32` too ([`round_inside`]), which
    /// `contour` has checked the grid leaves room for.
    #[inline]
    fn crossing_position(&self, at: [usize; 3], axis: usize, t: f64) -> [f32; 3] {
        let g = self.model;
        let mut p = self.position(at[0], at[1], at[2]);
        let i = at[axis];
        p[axis] = round_inside(
            g.origin[axis] + (i as f64 + t) * g.spacing[axis],
            g.coord(axis, i),
            g.coord(axis, i + 1),
        );
        p
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
    /// row by row, then y-edge crossings, then inside nodes on the domain boundary. Owned
    /// items become vertices of this chunk; the next chunk's get [`FOREIGN`] ordinals.
    fn enumerate_items(&self, k: usize, plane: &mut Plane, mut ids: Ids) {
        let [nx, ny, nz] = self.counts();
        let wpr = self.words_per_row();
        let last_word_mask = low_bits(nx - (wpr - 1) * 64);
        let Plane {
            values,
            inside,
            x_edge,
            y_edge,
            node,
        } = plane;
        for j in 0..ny {
            let row = &inside[j * wpr..(j + 1) * wpr];
            for w in 0..wpr {
                let next_first = if w + 1 < wpr { row[w + 1] & 1 } else { 0 };
                let shifted = (row[w] >> 1) | (next_first << 63);
                let mask = (row[w] ^ shifted) & edge_mask(w, wpr, nx - 1);
                Self::assign(x_edge, j * wpr + w, mask, w, &mut ids, |i| {
                    let t = Self::crossing(values[j * nx + i], values[j * nx + i + 1]);
                    self.crossing_position([i, j, k], 0, t)
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
                Self::assign(y_edge, j * wpr + w, mask, w, &mut ids, |i| {
                    let t = Self::crossing(values[j * nx + i], values[(j + 1) * nx + i]);
                    self.crossing_position([i, j, k], 1, t)
                });
            }
        }
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
                let mask = inside[j * wpr + w] & columns;
                Self::assign(node, j * wpr + w, mask, w, &mut ids, |i| {
                    self.position(i, j, k)
                });
            }
        }
    }

    /// Creates the vertices on the z-edges between `lower` (plane k) and `upper` (k + 1).
    fn z_edges(
        &self,
        k: usize,
        lower: &Plane,
        upper: &Plane,
        z_edge: &mut Items,
        out: &mut Vec<[f32; 3]>,
    ) {
        let [nx, ny, _] = self.counts();
        let wpr = self.words_per_row();
        let last_word_mask = low_bits(nx - (wpr - 1) * 64);
        let mut ids = Ids::Own(out);
        for j in 0..ny {
            for w in 0..wpr {
                let word_mask = if w + 1 == wpr {
                    last_word_mask
                } else {
                    u64::MAX
                };
                let word = j * wpr + w;
                let mask = (lower.inside[word] ^ upper.inside[word]) & word_mask;
                Self::assign(z_edge, word, mask, w, &mut ids, |i| {
                    let t = Self::crossing(lower.values[j * nx + i], upper.values[j * nx + i]);
                    self.crossing_position([i, j, k], 2, t)
                });
            }
        }
    }

    /// Emits the triangles (surface and caps) of cube layer `k`.
    #[inline(never)]
    fn cubes(
        &self,
        k: usize,
        lower: &Plane,
        upper: &Plane,
        z_edge: &Items,
        tris: &mut Vec<[u32; 3]>,
    ) {
        let [nx, ny, nz] = self.counts();
        let wpr = self.words_per_row();
        let layer_on_boundary = k == 0 || k + 2 == nz;
        let boundary_columns = |w: usize| column_mask(w, &[0, nx - 2]);
        let items: [&Items; 7] = [
            &lower.x_edge,
            &upper.x_edge,
            &lower.y_edge,
            &upper.y_edge,
            z_edge,
            &lower.node,
            &upper.node,
        ];
        for j in 0..ny - 1 {
            let row_on_boundary = layer_on_boundary || j == 0 || j + 2 == ny;
            let rows = [
                &lower.inside[j * wpr..(j + 1) * wpr],
                &lower.inside[(j + 1) * wpr..(j + 2) * wpr],
                &upper.inside[j * wpr..(j + 1) * wpr],
                &upper.inside[(j + 1) * wpr..(j + 2) * wpr],
            ];
            for w in 0..wpr {
                let (mut all, mut any) = (u64::MAX, 0u64);
                for r in rows {
                    let next_first = if w + 1 < wpr { r[w + 1] & 1 } else { 0 };
                    let pair_all = r[w] & ((r[w] >> 1) | (next_first << 63));
                    let pair_any = r[w] | ((r[w] >> 1) | (next_first << 63));
                    all &= pair_all;
                    any |= pair_any;
                }
                let cubes_in_word = edge_mask(w, wpr, nx - 1);
                // A cube needs work when the surface passes through it, or when it has an
                // inside corner and a face on the domain boundary (its cap).
                let boundary = if row_on_boundary {
                    u64::MAX
                } else {
                    boundary_columns(w)
                };
                let mut work = ((any & !all) | (any & boundary)) & cubes_in_word;
                while work != 0 {
                    let i = w * 64 + work.trailing_zeros() as usize;
                    work &= work - 1;
                    let bit = |r: &[u64], i: usize| ((r[i / 64] >> (i % 64)) & 1) as u8;
                    let config = bit(rows[0], i)
                        | bit(rows[0], i + 1) << 1
                        | bit(rows[1], i) << 2
                        | bit(rows[1], i + 1) << 3
                        | bit(rows[2], i) << 4
                        | bit(rows[2], i + 1) << 5
                        | bit(rows[3], i) << 6
                        | bit(rows[3], i + 1) << 7;
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
                            for tri in self.tables.cap(config, face) {
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
        let Scratch {
            lower,
            upper,
            z_edge,
            ..
        } = scratch;
        self.sample(k0, lower);
        self.enumerate_items(k0, lower, Ids::Own(&mut vertices));
        for k in k0..k1 {
            self.sample(k + 1, upper);
            self.z_edges(k, lower, upper, z_edge, &mut vertices);
            let ids = if k + 1 < k1 || k1 == nz - 1 {
                Ids::Own(&mut vertices)
            } else {
                Ids::Foreign(0)
            };
            self.enumerate_items(k + 1, upper, ids);
            self.cubes(k, lower, upper, z_edge, &mut triangles);
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
        }
    }
}

/// For each slot, which [`Items`] holds its vertex (lower x, upper x, lower y, upper y, z,
/// lower nodes, upper nodes) and at which of the cube's four columns (dx + 2 dy).
const SLOT_REFS: [(u8, u8); 20] = {
    let mut refs = [(0u8, 0u8); 20];
    let mut s = 0;
    while s < 20 {
        refs[s] = if s >= CORNER_SLOT as usize {
            let c = (s - CORNER_SLOT as usize) as u8;
            (5 + ((c >> 2) & 1), c & 3)
        } else {
            let (axis, r) = (s / 4, (s % 4) as u8);
            let (a, b) = (r & 1, r >> 1);
            match axis {
                0 => (b, 2 * a),
                1 => (2 + b, a),
                _ => (4, a + 2 * b),
            }
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
