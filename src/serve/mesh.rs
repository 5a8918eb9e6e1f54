//! An output's mesh for display: read from the file the build wrote, welded into an indexed
//! mesh, decimated above a triangle budget by vertex clustering, and encoded compactly.
//!
//! Invariants:
//! - A binary STL is streamed (one block of facets in memory at a time), so a tiling of tens
//!   of millions of triangles is never held whole; only the clustered result is. Other
//!   formats (PLY, OBJ, OFF, ASCII STL) are read whole through the geometry crate's readers.
//! - Below the budget nothing is lost: corners are welded by their exact `f32` position (the
//!   writers never give two vertices one position), so the triangles are the file's own.
//! - Above it, corners are welded per cell of a grid whose spacing is chosen from the
//!   report's area so that about `budget` triangles remain; each cell's vertex is the mean of
//!   its corners; triangles that collapse or repeat are dropped. Deterministic: the same file
//!   gives the same bytes. If the estimate still leaves too many, the result is clustered
//!   again on a coarser grid, so the budget always holds.
//! - The encoding ([`encode`]) quantizes positions to `u16` over the bounding box (an error of
//!   at most 1/131070 of the box, invisible on screen), indices stay `u32`.

use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};
use std::io::{self, Read};
use std::path::Path;

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

/// Welds corners into vertices: by exact position (`cell == None`) or by grid cell.
struct Clusterer {
    cell: Option<f64>,
    origin: [f64; 3],
    ids: HashMap<[u32; 3], u32, Fast>,
    sums: Vec<[f64; 3]>,
    counts: Vec<u32>,
    triangles: Vec<[u32; 3]>,
    seen: HashSet<[u32; 3], Fast>,
}

impl Clusterer {
    fn new(cell: Option<f64>, origin: [f64; 3]) -> Clusterer {
        Clusterer {
            cell,
            origin,
            ids: HashMap::default(),
            sums: Vec::new(),
            counts: Vec::new(),
            triangles: Vec::new(),
            seen: HashSet::default(),
        }
    }

    fn vertex(&mut self, p: [f32; 3]) -> u32 {
        let key = match self.cell {
            None => p.map(f32::to_bits),
            // Cells are counted from the box's corner, so indices are small and non-negative
            // (a wrapped `i64 as u32` would still be a distinct key within any real box).
            Some(h) => std::array::from_fn(|a| {
                ((f64::from(p[a]) - self.origin[a]) / h).floor() as i64 as u32
            }),
        };
        let next = self.sums.len() as u32;
        let id = *self.ids.entry(key).or_insert(next);
        if id == next {
            self.sums.push([0.0; 3]);
            self.counts.push(0);
        }
        for (sum, c) in self.sums[id as usize].iter_mut().zip(p) {
            *sum += f64::from(c);
        }
        self.counts[id as usize] += 1;
        id
    }

    fn triangle(&mut self, corners: [[f32; 3]; 3]) {
        let t = corners.map(|p| self.vertex(p));
        if self.cell.is_none() {
            self.triangles.push(t);
            return;
        }
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return;
        }
        // The same triangle from several source triangles: keep one (rotated so the smallest
        // index leads, which keeps the winding).
        let lead = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
        let key = [t[lead], t[(lead + 1) % 3], t[(lead + 2) % 3]];
        if self.seen.insert(key) {
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
        DisplayMesh {
            positions,
            triangles: self.triangles,
            source_triangles,
            decimated: self.cell.is_some(),
        }
    }
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

/// Clusters the triangles of `feed` (which calls its argument once per triangle).
fn cluster(
    hint: &Hint,
    budget: usize,
    feed: impl FnOnce(&mut dyn FnMut([[f32; 3]; 3])) -> io::Result<u64>,
) -> io::Result<DisplayMesh> {
    let cell = (hint.triangles as usize > budget && hint.area > 0.0)
        .then(|| spacing(hint.area, budget))
        .filter(|h| h.is_finite() && *h > 0.0);
    let mut clusterer = Clusterer::new(cell, hint.bbox_min);
    let read = feed(&mut |t| clusterer.triangle(t))?;
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
    let mut clusterer = Clusterer::new(Some(h), origin);
    for t in &mesh.triangles {
        clusterer.triangle(t.map(|i| mesh.positions[i as usize]));
    }
    clusterer.finish(mesh.source_triangles)
}

/// Streams a binary STL's facets (after its 84-byte header) into `emit`.
fn stream_binary_stl(
    reader: &mut dyn Read,
    facets: u64,
    emit: &mut dyn FnMut([[f32; 3]; 3]),
) -> io::Result<u64> {
    const BLOCK: usize = 8192;
    let mut buffer = vec![0u8; 50 * BLOCK];
    let mut left = facets;
    while left > 0 {
        let n = left.min(BLOCK as u64) as usize;
        let bytes = &mut buffer[..50 * n];
        reader.read_exact(bytes)?;
        for facet in bytes.chunks_exact(50) {
            let f = |i: usize| {
                let at = 12 + 4 * i;
                f32::from_le_bytes([facet[at], facet[at + 1], facet[at + 2], facet[at + 3]])
            };
            let corners = [[f(0), f(1), f(2)], [f(3), f(4), f(5)], [f(6), f(7), f(8)]];
            if corners.iter().flatten().all(|c| c.is_finite()) {
                emit(corners);
            }
        }
        left -= n as u64;
    }
    Ok(facets)
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
            return cluster(hint, budget, |emit| {
                stream_binary_stl(&mut reader, facets, emit)
            });
        }
    }
    drop(reader);
    let bytes = crate::files::read_input(path)?;
    let extension = path.extension().and_then(|e| e.to_str());
    let soup = latticebuild_geom::mesh_read::read_auto(&bytes, extension)
        .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e.to_string()))?;
    drop(bytes);
    cluster(hint, budget, |emit| {
        for t in &soup.triangles {
            emit(t.map(|i| soup.positions[i as usize].map(|c| c as f32)));
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
