//! An output's mesh for display: read from the file the build wrote, welded into an indexed
//! mesh, decimated above a triangle budget by vertex clustering, and encoded compactly.
//!
//! Invariants:
//! - A binary STL is streamed (three blocks of facets in memory at a time: read by a thread of
//!   its own, handed over in the file's order), so a tiling of tens of millions of triangles
//!   is never held whole; only the clustered result is. Other formats (PLY, OBJ, OFF, ASCII
//!   STL) are read whole through the geometry crate's readers.
//! - Below the budget nothing is lost: corners are welded by their exact `f32` position (the
//!   writers never give two vertices one position), so the triangles are the file's own.
//! - Above it, corners are welded per cell of a grid whose spacing is chosen from the
//!   report's area so that about `budget` triangles remain; each cell's vertex is the mean of
//!   its corners; triangles that collapse or repeat are dropped. Deterministic: the same file
//!   gives the same bytes (vertices are numbered in the order their first corner comes, and
//!   each sums its corners in the file's order, whatever shortcut found it — tested against
//!   one lookup per corner). If the estimate still leaves too many, the result is clustered
//!   again on a coarser grid, so the budget always holds.
//! - The encoding ([`encode`]) quantizes positions to `u16` over the bounding box (an error of
//!   at most 1/131070 of the box, invisible on screen), indices stay `u32`.

use latticebuild_geom::floor::floor_i64;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hash, Hasher};
use std::io::{self, Read};
use std::path::Path;
use std::sync::mpsc;

/// Triangles shown per output before decimation starts.
pub const DEFAULT_BUDGET: usize = 2_000_000;

/// The encoding's first bytes (`LBM1`: latticebuild mesh, version 1).
pub const MAGIC: &[u8; 4] = b"LBM1";

/// An indexed mesh ready to encode.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct DisplayMesh {
    pub positions: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    /// Triangles in the file.
    pub source_triangles: u64,
    /// Whether clustering coarsened the mesh.
    pub decimated: bool,
}

/// A multiply-shift hash: the keys are positions or grid cells, never chosen by a remote
/// party, and SipHash made welding 40 M triangles several times slower.
#[derive(Default)]
pub struct FastHasher(u64);

impl Hasher for FastHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u32(&mut self, n: u32) {
        self.write_u64(u64::from(n));
    }
    fn write_u64(&mut self, n: u64) {
        self.0 = (self.0.rotate_left(23) ^ n).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
    fn write_usize(&mut self, n: usize) {
        self.write_u64(n as u64);
    }
}

type Fast = BuildHasherDefault<FastHasher>;

/// What welds corners into one vertex: a position's `f32` bits, or a grid cell's indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Key([u32; 3]);

impl Hash for Key {
    /// Two words. `[u32; 3]`'s own `Hash` feeds a length and then twelve single bytes, each a
    /// multiply of [`FastHasher`]: that made hashing a fifth of the whole load.
    fn hash<H: Hasher>(&self, state: &mut H) {
        let [x, y, z] = self.0;
        state.write_u64(u64::from(x) | (u64::from(y) << 32));
        state.write_u32(z);
    }
}

/// Entries of [`Recent`]: 16 × 16 × 16, indexed by the low 4 bits of each of a key's words.
const RECENT_BITS: u32 = 4;

/// A direct-mapped cache of the last vertex seen per slot, in front of the map of all of
/// them. A tiling is written element after element along a Morton curve, so the corners of
/// consecutive triangles lie in a few neighbouring cells; any 16 × 16 × 16 block of cells
/// takes distinct slots, and most lookups end here (64 KiB, in L1/L2) instead of in a map of
/// hundreds of thousands of entries scattered over memory. It only remembers ids the map
/// gave, so it changes no id.
struct Recent {
    slots: Vec<(Key, u32)>,
}

impl Recent {
    /// Marks an empty slot. Were a vertex to get this id (the 4 294 967 295th), its slot
    /// would just always miss: slower, never wrong.
    const EMPTY: u32 = u32::MAX;

    fn new() -> Recent {
        Recent {
            slots: vec![(Key([0; 3]), Recent::EMPTY); 1 << (3 * RECENT_BITS)],
        }
    }

    fn slot(key: Key) -> usize {
        let low = |w: u32| (w & ((1 << RECENT_BITS) - 1)) as usize;
        let [x, y, z] = key.0;
        low(x) | (low(y) << RECENT_BITS) | (low(z) << (2 * RECENT_BITS))
    }
}

/// Where a corner welds, as a [`Key`]: a pure function of the corner, so the STL's reader
/// thread computes it ahead of the [`Clusterer`].
#[derive(Clone, Copy, Debug)]
struct Keying {
    /// The grid's cells per unit of length (the reciprocal of the spacing: a multiply, not a
    /// division, nine times per triangle), or `None` to weld by exact position.
    cells_per_unit: Option<f64>,
    origin: [f64; 3],
}

impl Keying {
    /// Grid cells `cell` wide counted from `origin`, or exact positions.
    fn new(cell: Option<f64>, origin: [f64; 3]) -> Keying {
        Keying {
            cells_per_unit: cell.map(|h| 1.0 / h),
            origin,
        }
    }

    fn key(&self, p: [f32; 3]) -> Key {
        Key(match self.cells_per_unit {
            None => p.map(f32::to_bits),
            // Cells are counted from the box's corner, so indices are small and non-negative
            // (a wrapped `i64 as u32` would still be a distinct key within any real box).
            Some(scale) => std::array::from_fn(|a| {
                floor_i64((f64::from(p[a]) - self.origin[a]) * scale) as u32
            }),
        })
    }

    fn keys(&self, corners: [[f32; 3]; 3]) -> [Key; 3] {
        corners.map(|p| self.key(p))
    }
}

/// Welds corners into vertices by their keys.
///
/// Vertex ids are given in the order corners are first seen, and each vertex sums its
/// corners in the order they come (three per triangle, first to last), so the result is a
/// function of the file's bytes alone.
struct Clusterer {
    keying: Keying,
    ids: HashMap<Key, u32, Fast>,
    recent: Recent,
    sums: Vec<[f64; 3]>,
    counts: Vec<u32>,
    triangles: Vec<[u32; 3]>,
}

impl Clusterer {
    fn new(keying: Keying) -> Clusterer {
        Clusterer {
            keying,
            ids: HashMap::default(),
            recent: Recent::new(),
            sums: Vec::new(),
            counts: Vec::new(),
            triangles: Vec::new(),
        }
    }

    /// Whether corners weld by grid cell (decimating), not by exact position.
    fn by_cell(&self) -> bool {
        self.keying.cells_per_unit.is_some()
    }

    /// The vertex of `key`, a new one (summing nothing yet) if it is the first.
    fn id(&mut self, key: Key) -> u32 {
        let slot = &mut self.recent.slots[Recent::slot(key)];
        if slot.1 != Recent::EMPTY && slot.0 == key {
            return slot.1;
        }
        let next = self.sums.len() as u32;
        let id = *self.ids.entry(key).or_insert(next);
        if id == next {
            self.sums.push([0.0; 3]);
            self.counts.push(0);
        }
        *slot = (key, id);
        id
    }

    fn add(&mut self, id: u32, p: [f32; 3]) {
        for (sum, c) in self.sums[id as usize].iter_mut().zip(p) {
            *sum += f64::from(c);
        }
        self.counts[id as usize] += 1;
    }

    /// Adds a triangle, its corners' keys computed by `self.keying`.
    fn triangle(&mut self, corners: [[f32; 3]; 3], keys: [Key; 3]) {
        if self.by_cell() && keys[0] == keys[1] && keys[1] == keys[2] {
            // Wholly inside one cell, as most are when decimating hard: the triangle
            // collapses, and its corners go to the cell with one lookup instead of three
            // (added one by one, so the sum is the one per-corner welding gives).
            let id = self.id(keys[0]);
            for p in corners {
                self.add(id, p);
            }
            return;
        }
        let mut t = [0; 3];
        for ((id, key), p) in t.iter_mut().zip(keys).zip(corners) {
            *id = self.id(key);
            self.add(*id, p);
        }
        if !self.by_cell() {
            self.triangles.push(t);
            return;
        }
        if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
            // Repeats are dropped in `finish`.
            self.triangles.push(t);
        }
    }

    fn finish(self, source_triangles: u64) -> DisplayMesh {
        // The mean of a cell's corners; with exact welding every corner of a vertex has the
        // one position, and n equal `f32` values sum and divide exactly in `f64`.
        let positions = self
            .sums
            .iter()
            .zip(&self.counts)
            .map(|(s, &n)| s.map(|c| (c / f64::from(n)) as f32))
            .collect();
        let decimated = self.by_cell();
        let mut triangles = self.triangles;
        if decimated {
            drop_repeats(&mut triangles);
        }
        DisplayMesh {
            positions,
            triangles,
            source_triangles,
            decimated,
        }
    }
}

/// Keeps the first of triangles that repeat (the same vertices in the same cyclic order: the
/// same triangle from several source triangles), in order.
///
/// By sorting: a hash set of the triangles kept took a fifth of the whole load, nearly all of
/// it waiting for memory (each insert lands at random in tens of megabytes); a sort streams.
fn drop_repeats(triangles: &mut Vec<[u32; 3]>) {
    // The triangle rotated so its smallest index leads (which keeps the winding), then its
    // place: equal triangles sort together, the first of them first.
    let mut keyed: Vec<u128> = triangles
        .iter()
        .zip(0u32..)
        .map(|(t, place)| {
            let lead = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
            [t[lead], t[(lead + 1) % 3], t[(lead + 2) % 3], place]
                .iter()
                .fold(0u128, |key, &word| (key << 32) | u128::from(word))
        })
        .collect();
    keyed.sort_unstable();
    let mut keep = vec![false; triangles.len()];
    let mut last = None;
    for key in keyed {
        let triangle = key >> 32;
        if last != Some(triangle) {
            keep[(key as u32) as usize] = true;
            last = Some(triangle);
        }
    }
    let mut kept = keep.iter();
    triangles.retain(|_| kept.next().copied().unwrap_or(false));
}

/// What is known of the mesh before reading it (from its report).
#[derive(Clone, Copy, Debug)]
pub struct Hint {
    pub triangles: u64,
    pub area: f64,
    pub bbox_min: [f64; 3],
    pub bbox_max: [f64; 3],
}

/// The grid spacing that leaves about `budget` triangles of a surface of `area`: a surface
/// crosses on average 1.5 cells per h² of its area (the mean of |nx|+|ny|+|nz|), each cell
/// gives a vertex, and a closed surface has about two triangles per vertex. Aim at 80 %.
fn spacing(area: f64, budget: usize) -> f64 {
    (3.0 * area / (0.8 * budget as f64)).sqrt()
}

/// Clusters the triangles of `feed`, which calls its second argument once per triangle with
/// its corners and their keys by the first.
fn cluster(
    hint: &Hint,
    budget: usize,
    feed: impl FnOnce(Keying, &mut dyn FnMut([[f32; 3]; 3], [Key; 3])) -> io::Result<u64>,
) -> io::Result<DisplayMesh> {
    let cell = (hint.triangles as usize > budget && hint.area > 0.0)
        .then(|| spacing(hint.area, budget))
        .filter(|h| h.is_finite() && *h > 0.0);
    let keying = Keying::new(cell, hint.bbox_min);
    let mut clusterer = Clusterer::new(keying);
    let read = feed(keying, &mut |t, keys| clusterer.triangle(t, keys))?;
    let mut mesh = clusterer.finish(read);
    // The estimate was off (or the report's count was): coarsen until the budget holds.
    let mut h = cell.unwrap_or_else(|| spacing(hint.area.max(1e-300), budget));
    let mut rounds = 0;
    while mesh.triangles.len() > budget && rounds < 20 {
        h *= 1.25 * (mesh.triangles.len() as f64 / budget as f64).sqrt();
        mesh = recluster(&mesh, h, hint.bbox_min);
        rounds += 1;
    }
    Ok(mesh)
}

fn recluster(mesh: &DisplayMesh, h: f64, origin: [f64; 3]) -> DisplayMesh {
    let keying = Keying::new(Some(h), origin);
    let mut clusterer = Clusterer::new(keying);
    for t in &mesh.triangles {
        let corners = t.map(|i| mesh.positions[i as usize]);
        clusterer.triangle(corners, keying.keys(corners));
    }
    clusterer.finish(mesh.source_triangles)
}

/// Streams a binary STL's facets (after its 84-byte header) into `emit`, with their corners'
/// keys by `keying`.
///
/// Reading, parsing and keying (half the load's CPU time, a third of that the kernel copying
/// out of the page cache) run on a thread of their own, up to two blocks ahead of `emit`. Blocks arrive
/// in the file's order and a key depends on its corner alone, so what `emit` sees does not
/// depend on timing.
fn stream_binary_stl(
    reader: &mut (dyn Read + Send),
    facets: u64,
    keying: Keying,
    emit: &mut dyn FnMut([[f32; 3]; 3], [Key; 3]),
) -> io::Result<u64> {
    const BLOCK: usize = 8192;
    type Block = Vec<([[f32; 3]; 3], [Key; 3])>;
    std::thread::scope(|scope| {
        // Full blocks go to this thread; emptied ones go back to the reader. Both channels end
        // when this closure returns (an error included), which ends the reader; a panic of
        // the reader `scope` resumes here.
        let (full_sender, full_blocks) = mpsc::sync_channel::<io::Result<Block>>(2);
        let (empty_sender, empty_blocks) = mpsc::channel::<Block>();
        for _ in 0..3 {
            let _ = empty_sender.send(Vec::with_capacity(BLOCK));
        }
        scope.spawn(move || {
            let mut bytes = vec![0u8; 50 * BLOCK];
            let mut left = facets;
            while left > 0 {
                let Ok(mut block) = empty_blocks.recv() else {
                    return;
                };
                let n = left.min(BLOCK as u64) as usize;
                let read = reader.read_exact(&mut bytes[..50 * n]).map(|()| {
                    block.clear();
                    for facet in bytes[..50 * n].chunks_exact(50) {
                        // After the normal, nine little-endian `f32`s.
                        let words: [u32; 9] = bytemuck::pod_read_unaligned(&facet[12..48]);
                        let c = words.map(|w| f32::from_bits(u32::from_le(w)));
                        let corners = [[c[0], c[1], c[2]], [c[3], c[4], c[5]], [c[6], c[7], c[8]]];
                        if corners.iter().flatten().all(|c| c.is_finite()) {
                            block.push((corners, keying.keys(corners)));
                        }
                    }
                    block
                });
                let failed = read.is_err();
                if full_sender.send(read).is_err() || failed {
                    return;
                }
                left -= n as u64;
            }
        });
        for block in full_blocks {
            let block = block?;
            for &(corners, keys) in &block {
                emit(corners, keys);
            }
            let _ = empty_sender.send(block);
        }
        Ok(facets)
    })
}

/// The display mesh of the file at `path` (an output this build wrote; its report gives the
/// `hint`), within `budget` triangles.
pub fn load(path: &Path, hint: &Hint, budget: usize) -> io::Result<DisplayMesh> {
    let (mut reader, len) = crate::files::open_regular(path)?;
    let mut head = [0u8; 84];
    let is_stl = path.extension().is_some_and(|e| e == "stl");
    if is_stl && len >= 84 {
        reader.read_exact(&mut head)?;
        let facets = u64::from(u32::from_le_bytes([head[80], head[81], head[82], head[83]]));
        if !head.starts_with(b"solid") && 84 + 50 * facets == len {
            return cluster(hint, budget, |keying, emit| {
                stream_binary_stl(&mut reader, facets, keying, emit)
            });
        }
    }
    drop(reader);
    let bytes = crate::files::read_input(path)?;
    let extension = path.extension().and_then(|e| e.to_str());
    let soup = latticebuild_geom::mesh_read::read_auto(&bytes, extension)
        .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e.to_string()))?;
    drop(bytes);
    cluster(hint, budget, |keying, emit| {
        for t in &soup.triangles {
            let corners = t.map(|i| soup.positions[i as usize].map(|c| c as f32));
            emit(corners, keying.keys(corners));
        }
        Ok(soup.triangles.len() as u64)
    })
}

/// The bytes sent to the page (little-endian throughout):
///
/// ```text
/// "LBM1"  u32 flags (bit 0: decimated)  u32 vertices  u32 triangles  u32 source triangles
/// f32 origin[3]  f32 step[3]            (position = origin + q · step)
/// u16 q[3 · vertices], zero-padded to a multiple of 4 bytes
/// u32 indices[3 · triangles]
/// ```
pub fn encode(mesh: &DisplayMesh) -> Vec<u8> {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in &mesh.positions {
        lo = std::array::from_fn(|a| lo[a].min(p[a]));
        hi = std::array::from_fn(|a| hi[a].max(p[a]));
    }
    if mesh.positions.is_empty() {
        lo = [0.0; 3];
        hi = [0.0; 3];
    }
    let step: [f32; 3] = std::array::from_fn(|a| {
        let extent = f64::from(hi[a]) - f64::from(lo[a]);
        if extent > 0.0 {
            (extent / 65535.0) as f32
        } else {
            1.0
        }
    });
    let mut out = Vec::with_capacity(44 + 6 * mesh.positions.len() + 4 + 12 * mesh.triangles.len());
    out.extend_from_slice(MAGIC);
    let counts = [
        u32::from(mesh.decimated),
        mesh.positions.len() as u32,
        mesh.triangles.len() as u32,
        mesh.source_triangles.min(u64::from(u32::MAX)) as u32,
    ];
    for c in counts {
        out.extend_from_slice(&c.to_le_bytes());
    }
    for v in lo.iter().chain(&step) {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for p in &mesh.positions {
        for ((&c, &lo), &step) in p.iter().zip(&lo).zip(&step) {
            let q = ((f64::from(c) - f64::from(lo)) / f64::from(step)).round();
            out.extend_from_slice(&(q.clamp(0.0, 65535.0) as u16).to_le_bytes());
        }
    }
    while out.len() % 4 != 0 {
        out.push(0);
    }
    for i in mesh.triangles.iter().flatten() {
        out.extend_from_slice(&i.to_le_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use latticebuild_geom::mesh::Mesh;

    /// A UV sphere of radius 1 with `n` rings: closed, about 2n² triangles.
    fn sphere(n: usize) -> Mesh {
        let mut vertices = vec![[0.0, 0.0, 1.0f32]];
        for i in 1..n {
            let theta = std::f64::consts::PI * i as f64 / n as f64;
            for j in 0..2 * n {
                let phi = std::f64::consts::PI * j as f64 / n as f64;
                vertices.push([
                    (theta.sin() * phi.cos()) as f32,
                    (theta.sin() * phi.sin()) as f32,
                    theta.cos() as f32,
                ]);
            }
        }
        vertices.push([0.0, 0.0, -1.0]);
        let ring = |i: usize, j: usize| (1 + (i - 1) * 2 * n + j % (2 * n)) as u32;
        let south = vertices.len() as u32 - 1;
        let mut triangles = Vec::new();
        for j in 0..2 * n {
            triangles.push([0, ring(1, j), ring(1, j + 1)]);
            triangles.push([south, ring(n - 1, j + 1), ring(n - 1, j)]);
        }
        for i in 1..n - 1 {
            for j in 0..2 * n {
                triangles.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
                triangles.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
            }
        }
        Mesh {
            vertices,
            triangles,
        }
    }

    fn stl_file(mesh: &Mesh) -> tempfile::NamedTempFile {
        let mut file = tempfile::Builder::new()
            .suffix(".stl")
            .tempfile()
            .expect("temp");
        latticebuild_geom::mesh_io::write_mesh(
            mesh,
            latticebuild_geom::mesh_io::Format::Stl,
            latticebuild_geom::mesh_io::Encoding::Binary,
            file.as_file_mut(),
        )
        .expect("write");
        file
    }

    fn hint(mesh: &Mesh) -> Hint {
        Hint {
            triangles: mesh.triangles.len() as u64,
            area: 4.0 * std::f64::consts::PI,
            bbox_min: [-1.0; 3],
            bbox_max: [1.0; 3],
        }
    }

    /// The signed volume of a closed, outward mesh (divergence theorem).
    fn volume(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> f64 {
        triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| positions[i as usize].map(f64::from));
                (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0]))
                    / 6.0
            })
            .sum()
    }

    #[test]
    fn below_the_budget_the_stl_welds_back_to_the_mesh_itself() {
        let mesh = sphere(20);
        let file = stl_file(&mesh);
        let shown = load(file.path(), &hint(&mesh), 1_000_000).expect("load");
        assert!(!shown.decimated);
        assert_eq!(shown.positions.len(), mesh.vertices.len());
        assert_eq!(shown.triangles.len(), mesh.triangles.len());
        // Same triangles, same positions, same winding (vertex order is first-seen order).
        for (t, u) in shown.triangles.iter().zip(&mesh.triangles) {
            assert_eq!(
                t.map(|i| shown.positions[i as usize]),
                u.map(|i| mesh.vertices[i as usize])
            );
        }
    }

    #[test]
    fn above_the_budget_clustering_keeps_the_budget_and_the_shape() {
        let mesh = sphere(120); // 28 800 triangles
        let file = stl_file(&mesh);
        let budget = 3000;
        let shown = load(file.path(), &hint(&mesh), budget).expect("load");
        assert!(shown.decimated);
        assert_eq!(shown.source_triangles, mesh.triangles.len() as u64);
        assert!(shown.triangles.len() <= budget, "{}", shown.triangles.len());
        assert!(
            shown.triangles.len() > budget / 4,
            "the spacing estimate wasted most of the budget: {}",
            shown.triangles.len()
        );
        // Still the sphere: every vertex near radius 1, volume near 4π/3, outward.
        for p in &shown.positions {
            let r = p.iter().map(|c| f64::from(*c).powi(2)).sum::<f64>().sqrt();
            assert!((r - 1.0).abs() < 0.08, "vertex at radius {r}");
        }
        let v = volume(&shown.positions, &shown.triangles);
        let exact = 4.0 * std::f64::consts::PI / 3.0;
        assert!((v - exact).abs() < 0.08 * exact, "volume {v} vs {exact}");
        // Deterministic.
        let again = load(file.path(), &hint(&mesh), budget).expect("load");
        assert_eq!(encode(&shown), encode(&again));
    }

    #[test]
    fn a_wrong_hint_still_keeps_the_budget() {
        let mesh = sphere(60);
        let file = stl_file(&mesh);
        let lying = Hint {
            area: 1e-6,
            ..hint(&mesh)
        };
        let shown = load(file.path(), &lying, 500).expect("load");
        assert!(shown.triangles.len() <= 500 && !shown.triangles.is_empty());
    }

    /// Welding as it was written first, one map lookup per corner and a set of the triangles
    /// kept: what the fast path, the cache of recent vertices and the sort must reproduce.
    fn weld_per_corner(
        corners: &[[[f32; 3]; 3]],
        cell: Option<f64>,
        origin: [f64; 3],
    ) -> DisplayMesh {
        let keying = Keying::new(cell, origin);
        let mut ids = HashMap::new();
        let mut sums: Vec<[f64; 3]> = Vec::new();
        let mut counts: Vec<u32> = Vec::new();
        let mut triangles = Vec::new();
        let mut seen = std::collections::HashSet::new();
        for triangle in corners {
            let t = triangle.map(|p| {
                let next = sums.len() as u32;
                let id = *ids.entry(keying.key(p).0).or_insert(next);
                if id == next {
                    sums.push([0.0; 3]);
                    counts.push(0);
                }
                for (sum, c) in sums[id as usize].iter_mut().zip(p) {
                    *sum += f64::from(c);
                }
                counts[id as usize] += 1;
                id
            });
            if cell.is_none() {
                triangles.push(t);
                continue;
            }
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                continue;
            }
            let lead = (0..3).min_by_key(|&i| t[i]).unwrap();
            if seen.insert([t[lead], t[(lead + 1) % 3], t[(lead + 2) % 3]]) {
                triangles.push(t);
            }
        }
        DisplayMesh {
            positions: sums
                .iter()
                .zip(&counts)
                .map(|(s, &n)| s.map(|c| (c / f64::from(n)) as f32))
                .collect(),
            triangles,
            source_triangles: corners.len() as u64,
            decimated: cell.is_some(),
        }
    }

    fn corners(mesh: &Mesh) -> Vec<[[f32; 3]; 3]> {
        mesh.triangles
            .iter()
            .map(|t| t.map(|i| mesh.vertices[i as usize]))
            .collect()
    }

    fn weld(corners: &[[[f32; 3]; 3]], cell: Option<f64>, origin: [f64; 3]) -> DisplayMesh {
        let keying = Keying::new(cell, origin);
        let mut clusterer = Clusterer::new(keying);
        for &t in corners {
            clusterer.triangle(t, keying.keys(t));
        }
        clusterer.finish(corners.len() as u64)
    }

    #[test]
    fn welding_gives_the_same_mesh_as_one_lookup_per_corner() {
        // 180 000 triangles over 1000 to 3 cells a side: from nearly every triangle spanning
        // cells to nearly every one inside a cell; more than 16 cells a side share the cache's
        // slots. Same positions to the bit: a cell sums its corners in the same order.
        let mesh = sphere(300);
        let mut corners = corners(&mesh);
        for cell in [None, Some(0.002), Some(0.03), Some(0.2), Some(0.7)] {
            assert_eq!(
                weld(&corners, cell, [-1.0; 3]),
                weld_per_corner(&corners, cell, [-1.0; 3]),
                "cell {cell:?}"
            );
        }
        // Out of spatial order (the cache then mostly misses), and with repeats.
        corners.reverse();
        let half = corners.len() / 2;
        corners.extend_from_within(..half);
        for cell in [Some(0.03), Some(0.2)] {
            assert_eq!(
                weld(&corners, cell, [-1.0; 3]),
                weld_per_corner(&corners, cell, [-1.0; 3])
            );
        }
    }

    #[test]
    fn a_streamed_stl_gives_the_same_mesh_as_one_lookup_per_corner() {
        // Keys computed on the reader thread, blocks handed over: the mesh of the corners in
        // the file's order all the same, above the budget and below it.
        let mesh = sphere(120);
        let file = stl_file(&mesh);
        let budget = 3000;
        let cell = spacing(4.0 * std::f64::consts::PI, budget);
        assert_eq!(
            load(file.path(), &hint(&mesh), budget).expect("load"),
            weld_per_corner(&corners(&mesh), Some(cell), [-1.0; 3])
        );
        assert_eq!(
            load(file.path(), &hint(&mesh), 1_000_000).expect("load"),
            weld_per_corner(&corners(&mesh), None, [-1.0; 3])
        );
    }

    #[test]
    fn repeats_are_dropped_in_order_keeping_the_first() {
        let mut triangles = vec![
            [5, 1, 2],
            [0, 1, 2],
            [1, 2, 5], // [5, 1, 2] rotated: a repeat
            [0, 2, 1], // [0, 1, 2] wound the other way: another triangle
            [2, 0, 1], // [0, 1, 2] rotated: a repeat
            [7, 8, 9],
            [5, 1, 2],
        ];
        drop_repeats(&mut triangles);
        assert_eq!(triangles, [[5, 1, 2], [0, 1, 2], [0, 2, 1], [7, 8, 9]]);
        let mut none = Vec::new();
        drop_repeats(&mut none);
        assert!(none.is_empty());
    }

    #[test]
    fn a_failing_read_ends_the_stream_with_its_error() {
        // Three blocks' worth of facets announced, one and a half there: the reader thread
        // stops at the short read and the error comes back, nothing waits forever.
        let facets = 3 * 8192;
        let bytes = vec![0u8; 50 * 8192 * 3 / 2];
        let mut emitted = 0;
        let keying = Keying::new(Some(0.1), [0.0; 3]);
        let error = stream_binary_stl(&mut bytes.as_slice(), facets, keying, &mut |_, _| {
            emitted += 1
        })
        .expect_err("short file");
        assert_eq!(error.kind(), io::ErrorKind::UnexpectedEof);
        assert_eq!(emitted, 8192);
    }

    #[test]
    fn the_encoding_round_trips_within_its_quantum() {
        let mesh = sphere(8);
        let file = stl_file(&mesh);
        let shown = load(file.path(), &hint(&mesh), 1_000_000).expect("load");
        let bytes = encode(&shown);
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4"));
        let float = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().expect("4"));
        assert_eq!(&bytes[..4], MAGIC);
        let (nv, nt) = (word(8) as usize, word(12) as usize);
        assert_eq!((nv, nt), (shown.positions.len(), shown.triangles.len()));
        assert_eq!(word(16) as usize, mesh.triangles.len());
        let indices_at = (44 + 6 * nv).div_ceil(4) * 4;
        assert_eq!(bytes.len(), indices_at + 12 * nt);
        for (v, p) in shown.positions.iter().enumerate() {
            for (a, &c) in p.iter().enumerate() {
                let at = 44 + 6 * v + 2 * a;
                let q = u16::from_le_bytes([bytes[at], bytes[at + 1]]);
                let back = float(20 + 4 * a) + f32::from(q) * float(32 + 4 * a);
                assert!((back - c).abs() <= 2.0 / 65535.0 + 1e-6);
            }
        }
        for (t, tri) in shown.triangles.iter().enumerate() {
            for (c, &index) in tri.iter().enumerate() {
                assert_eq!(word(indices_at + 12 * t + 4 * c), index);
            }
        }
    }
}
