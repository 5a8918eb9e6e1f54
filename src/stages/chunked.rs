//! The chunked mesh payload: a tiled mesh stored a [`MeshChunk`] at a time as it is produced,
//! and read back a chunk at a time, so neither the tile stage's cache write nor the write
//! stage holds the whole mesh.
//!
//! Layout (all integers little-endian, arrays raw as in `artifact.rs`):
//!
//! | part      | content                                                             |
//! |-----------|---------------------------------------------------------------------|
//! | magic     | `LBCHUNK1`                                                          |
//! | chunk k   | vertices (3 × f32), triangles (3 × u32), borrowed (u32 id, 3 × f32), open (u32) |
//! | trailer   | JSON [`ChunkedTrailer`]: summary, tiling, totals, one [`ChunkEntry`] per chunk |
//! | check     | blake3 of the trailer JSON (32 bytes)                               |
//! | length    | the trailer JSON's length, u64                                      |
//!
//! Invariants:
//! - The payload is a deterministic function of the chunks and the head: the same mesh cut
//!   the same way gives the same bytes, hence the same content hash downstream.
//! - Nothing is trusted before it is verified: the trailer by its blake3, the chunk table by
//!   its arithmetic (records tile the space between magic and trailer, ids are dense, counts
//!   add up), and every section by its own blake3 as it is read. Any failure is
//!   [`CorruptChunks`] (an `InvalidData` I/O error), which the builder treats as a missing
//!   entry: the tile node runs again.
//! - The trailer's blake3 (the `check`) identifies the payload: the trailer holds every
//!   section's hash, offset and count, so equal checks mean equal bytes. The builder stores the
//!   payload as a self-verifying cache entry under this hash, rather than hashing the
//!   gigabyte again whole; [`ChunkedMesh::open`] checks that a declared hash is the check.

use std::fmt;
use std::io::{self, Write};

use serde::{Deserialize, Serialize};

use latticebuild_geom::mesh::MeshChunk;
use latticebuild_geom::mesh_io::{ChunkSource, Pass};

use super::artifact::{MeshSummary, TilingSummary};
use crate::cache::{ContentHash, EntryReader};

pub const CHUNKED_MAGIC: &[u8; 8] = b"LBCHUNK1";
/// The blake3 and the length after the trailer JSON.
const TAIL_BYTES: u64 = 40;

/// What a chunked mesh is besides its chunks: the summary the report shows and the tiling.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChunkedHead {
    pub summary: MeshSummary,
    pub tiling: Option<TilingSummary>,
    /// For a shell, its wall (see [`super::artifact::MeshArtifact::shell`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shell: Option<super::artifact::ShellSummary>,
    /// See [`super::artifact::MeshArtifact::sizing`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sizing: Option<super::artifact::SizingSummary>,
}

/// Where one chunk's record is and what it holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChunkEntry {
    /// Offset of the record in the payload.
    pub offset: u64,
    pub first_vertex: u32,
    pub vertices: u64,
    pub triangles: u64,
    pub borrowed: u64,
    pub open: u64,
    /// blake3 of each section: vertices, triangles, borrowed, open.
    pub hashes: [ContentHash; 4],
}

const VERTEX_BYTES: u64 = 12;
const TRIANGLE_BYTES: u64 = 12;
const BORROWED_BYTES: u64 = 16;
const OPEN_BYTES: u64 = 4;

impl ChunkEntry {
    /// Byte offsets of the four sections and the record's end, or `None` on overflow.
    fn sections(&self) -> Option<[u64; 5]> {
        let v = self.offset;
        let t = v.checked_add(self.vertices.checked_mul(VERTEX_BYTES)?)?;
        let b = t.checked_add(self.triangles.checked_mul(TRIANGLE_BYTES)?)?;
        let o = b.checked_add(self.borrowed.checked_mul(BORROWED_BYTES)?)?;
        let end = o.checked_add(self.open.checked_mul(OPEN_BYTES)?)?;
        Some([v, t, b, o, end])
    }
}

/// The JSON at the end of the payload.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChunkedTrailer {
    pub head: ChunkedHead,
    pub vertices: u64,
    pub triangles: u64,
    pub chunks: Vec<ChunkEntry>,
}

/// A chunked payload that failed verification.
#[derive(Debug)]
pub struct CorruptChunks(pub String);

impl fmt::Display for CorruptChunks {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "the chunked mesh entry is corrupt: {}", self.0)
    }
}

impl std::error::Error for CorruptChunks {}

fn corrupt(what: impl Into<String>) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, CorruptChunks(what.into()))
}

/// Whether `error` (from a write over a [`ChunkedMesh`]) says its entry is corrupt.
pub fn is_corrupt(error: &io::Error) -> bool {
    error
        .get_ref()
        .is_some_and(|inner| inner.is::<CorruptChunks>())
}

/// Writes chunks as records into `out`, then the trailer.
pub struct ChunkedWriter<W: Write> {
    out: W,
    at: u64,
    vertices: u64,
    triangles: u64,
    chunks: Vec<ChunkEntry>,
}

/// Writes and hashes a section. Serial: this runs on the builder's chunk writer, a thread the
/// tiling's rayon workers wait on (see [`ContentHash::of_serial`]).
fn hashed(out: &mut impl Write, bytes: &[u8]) -> io::Result<ContentHash> {
    out.write_all(bytes)?;
    Ok(ContentHash::of_serial(bytes))
}

impl<W: Write> ChunkedWriter<W> {
    pub fn new(mut out: W) -> io::Result<ChunkedWriter<W>> {
        out.write_all(CHUNKED_MAGIC)?;
        Ok(ChunkedWriter {
            out,
            at: CHUNKED_MAGIC.len() as u64,
            vertices: 0,
            triangles: 0,
            chunks: Vec::new(),
        })
    }

    /// Appends `chunk`'s record. Its ids must continue the previous chunk's.
    pub fn push(&mut self, chunk: &MeshChunk) -> io::Result<()> {
        if u64::from(chunk.first_vertex) != self.vertices {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "a chunk starts at vertex {} where {} was expected",
                    chunk.first_vertex, self.vertices
                ),
            ));
        }
        let borrowed: Vec<u8> = chunk
            .borrowed
            .iter()
            .flat_map(|(id, p)| {
                let mut record = [0u8; 16];
                record[..4].copy_from_slice(&id.to_le_bytes());
                for (slot, c) in record[4..].chunks_exact_mut(4).zip(p) {
                    slot.copy_from_slice(&c.to_le_bytes());
                }
                record
            })
            .collect();
        let hashes = [
            hashed(&mut self.out, bytemuck::cast_slice(&chunk.vertices))?,
            hashed(&mut self.out, bytemuck::cast_slice(&chunk.triangles))?,
            hashed(&mut self.out, &borrowed)?,
            hashed(&mut self.out, bytemuck::cast_slice(&chunk.open))?,
        ];
        let entry = ChunkEntry {
            offset: self.at,
            first_vertex: chunk.first_vertex,
            vertices: chunk.vertices.len() as u64,
            triangles: chunk.triangles.len() as u64,
            borrowed: chunk.borrowed.len() as u64,
            open: chunk.open.len() as u64,
            hashes,
        };
        // Written from in-memory slices, so the sections cannot overflow.
        self.at = entry.sections().map_or(u64::MAX, |s| s[4]);
        self.vertices += entry.vertices;
        self.triangles += entry.triangles;
        self.chunks.push(entry);
        Ok(())
    }

    /// Writes the trailer; returns the writer, the trailer and the payload's identifying hash
    /// (the trailer's blake3: see the module docs).
    pub fn finish(mut self, head: ChunkedHead) -> io::Result<(W, ChunkedTrailer, ContentHash)> {
        let trailer = ChunkedTrailer {
            head,
            vertices: self.vertices,
            triangles: self.triangles,
            chunks: self.chunks,
        };
        let json = serde_json::to_vec(&trailer).map_err(io::Error::other)?;
        let check = ContentHash::of_serial(&json);
        self.out.write_all(&json)?;
        self.out.write_all(check.as_bytes())?;
        self.out.write_all(&(json.len() as u64).to_le_bytes())?;
        Ok((self.out, trailer, check))
    }
}

/// Where a chunked payload's bytes come from: a cache entry, or memory in tests.
pub trait ReadAt: Sync + Send {
    fn payload_len(&self) -> u64;
    fn read_at(&self, offset: u64, buf: &mut [u8]) -> io::Result<()>;
    /// The hash the payload's store declared for it without computing it (a self-verifying
    /// cache entry's), which the payload must then prove; `None` when the store verified it.
    fn declared_hash(&self) -> Option<ContentHash> {
        None
    }
}

impl ReadAt for EntryReader {
    fn payload_len(&self) -> u64 {
        self.len()
    }

    fn read_at(&self, offset: u64, buf: &mut [u8]) -> io::Result<()> {
        EntryReader::read_at(self, offset, buf)
    }

    fn declared_hash(&self) -> Option<ContentHash> {
        self.self_verified().then(|| self.hash())
    }
}

impl ReadAt for Vec<u8> {
    fn payload_len(&self) -> u64 {
        self.len() as u64
    }

    fn read_at(&self, offset: u64, buf: &mut [u8]) -> io::Result<()> {
        let start = usize::try_from(offset).map_err(|_| corrupt("offset"))?;
        let bytes = start
            .checked_add(buf.len())
            .and_then(|end| self.get(start..end))
            .ok_or_else(|| corrupt("read past the payload"))?;
        buf.copy_from_slice(bytes);
        Ok(())
    }
}

/// Whether a payload starts as a chunked one (otherwise it is a whole mesh's).
pub fn is_chunked(source: &dyn ReadAt) -> io::Result<bool> {
    if source.payload_len() < CHUNKED_MAGIC.len() as u64 {
        return Ok(false);
    }
    let mut magic = [0u8; 8];
    source.read_at(0, &mut magic)?;
    Ok(&magic == CHUNKED_MAGIC)
}

/// A chunked payload opened for reading: its verified trailer, and its source.
pub struct ChunkedMesh<R: ReadAt> {
    source: R,
    pub trailer: ChunkedTrailer,
}

impl<R: ReadAt> fmt::Debug for ChunkedMesh<R> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ChunkedMesh")
            .field("vertices", &self.trailer.vertices)
            .field("triangles", &self.trailer.triangles)
            .field("chunks", &self.trailer.chunks.len())
            .finish()
    }
}

impl<R: ReadAt> ChunkedMesh<R> {
    /// Where the payload is read from.
    pub fn source(&self) -> &R {
        &self.source
    }

    /// Reads and verifies the trailer and the chunk table; no chunk is read.
    pub fn open(source: R) -> io::Result<ChunkedMesh<R>> {
        let len = source.payload_len();
        let magic_len = CHUNKED_MAGIC.len() as u64;
        if len < magic_len + TAIL_BYTES
            || !is_chunked(&source).map_err(|e| corrupt(format!("reading the magic: {e}")))?
        {
            return Err(corrupt("no chunked mesh magic"));
        }
        let read = |at: u64, buf: &mut [u8]| {
            source
                .read_at(at, buf)
                .map_err(|e| corrupt(format!("reading the trailer: {e}")))
        };
        let mut tail = [0u8; TAIL_BYTES as usize];
        read(len - TAIL_BYTES, &mut tail)?;
        let (hash, json_len) = tail.split_at(32);
        let json_len = u64::from_le_bytes(json_len.try_into().map_err(|_| corrupt("tail"))?);
        let trailer_at = (len - TAIL_BYTES)
            .checked_sub(json_len)
            .filter(|&at| at >= magic_len)
            .ok_or_else(|| corrupt("trailer length"))?;
        let mut json = vec![0u8; json_len as usize];
        read(trailer_at, &mut json)?;
        let check = ContentHash::of(&json);
        if check.as_bytes() != hash {
            return Err(corrupt("trailer does not match its hash"));
        }
        if source
            .declared_hash()
            .is_some_and(|declared| declared != check)
        {
            return Err(corrupt("the entry's declared hash is not its trailer's"));
        }
        let trailer: ChunkedTrailer =
            serde_json::from_slice(&json).map_err(|e| corrupt(format!("trailer: {e}")))?;
        // The records must tile the space between the magic and the trailer, in order, with
        // dense ids and counts that add up.
        let (mut at, mut vertices, mut triangles) = (magic_len, 0u64, 0u64);
        for (k, chunk) in trailer.chunks.iter().enumerate() {
            let sections = chunk
                .sections()
                .filter(|_| chunk.offset == at && u64::from(chunk.first_vertex) == vertices)
                .ok_or_else(|| corrupt(format!("chunk {k} is out of place")))?;
            at = sections[4];
            vertices = vertices.saturating_add(chunk.vertices);
            triangles = triangles.saturating_add(chunk.triangles);
        }
        if at != trailer_at || vertices != trailer.vertices || triangles != trailer.triangles {
            return Err(corrupt("the chunk table does not add up"));
        }
        if vertices > u64::from(u32::MAX) + 1 {
            return Err(corrupt("more vertices than 32-bit ids"));
        }
        Ok(ChunkedMesh { source, trailer })
    }

    /// Reads section `s` of chunk `entry` into `out` (resized), checking its hash.
    fn section<T: bytemuck::Pod + bytemuck::Zeroable>(
        &self,
        k: usize,
        entry: &ChunkEntry,
        s: usize,
        out: &mut Vec<T>,
    ) -> io::Result<()> {
        let bounds = entry.sections().ok_or_else(|| corrupt("sections"))?;
        let bytes = usize::try_from(bounds[s + 1] - bounds[s]).map_err(|_| corrupt("size"))?;
        let size = std::mem::size_of::<T>();
        out.clear();
        out.resize(bytes / size, T::zeroed());
        let buf: &mut [u8] = bytemuck::cast_slice_mut(out.as_mut_slice());
        self.source
            .read_at(bounds[s], buf)
            .map_err(|e| corrupt(format!("reading chunk {k}: {e}")))?;
        if ContentHash::of(buf) != entry.hashes[s] {
            return Err(corrupt(format!(
                "section {s} of chunk {k} does not match its hash"
            )));
        }
        Ok(())
    }
}

impl<R: ReadAt> ChunkSource for ChunkedMesh<R> {
    fn totals(&self) -> (u64, u64) {
        (self.trailer.vertices, self.trailer.triangles)
    }

    fn for_each_chunk(
        &self,
        pass: Pass,
        visit: &mut dyn FnMut(&MeshChunk) -> io::Result<()>,
    ) -> io::Result<()> {
        let sections = match pass {
            Pass::Vertices => (true, false, false, false),
            Pass::Triangles => (false, true, false, false),
            Pass::Facets => (true, true, true, false),
        };
        self.visit_chunks(sections, visit)
    }
}

impl<R: ReadAt> ChunkedMesh<R> {
    /// Calls `visit` with every chunk whole — vertices, triangles, borrowed and open — in
    /// order (what a pass that relabels the mesh needs), each section verified as it is read.
    pub fn for_each_whole_chunk(
        &self,
        visit: &mut dyn FnMut(&MeshChunk) -> io::Result<()>,
    ) -> io::Result<()> {
        self.visit_chunks((true, true, true, true), visit)
    }

    /// Visits every chunk with the sections named (vertices, triangles, borrowed, open).
    fn visit_chunks(
        &self,
        (vertices, triangles, borrows, open): (bool, bool, bool, bool),
        visit: &mut dyn FnMut(&MeshChunk) -> io::Result<()>,
    ) -> io::Result<()> {
        // One chunk's buffers, reused: memory is the largest chunk, whatever the mesh.
        let mut chunk = MeshChunk::default();
        let mut borrowed: Vec<[u32; 4]> = Vec::new();
        for (k, entry) in self.trailer.chunks.iter().enumerate() {
            chunk.first_vertex = entry.first_vertex;
            if vertices {
                self.section(k, entry, 0, &mut chunk.vertices)?;
            }
            if triangles {
                self.section(k, entry, 1, &mut chunk.triangles)?;
            }
            if borrows {
                self.section(k, entry, 2, &mut borrowed)?;
                chunk.borrowed.clear();
                chunk.borrowed.extend(
                    borrowed
                        .iter()
                        .map(|r| (r[0], [r[1], r[2], r[3]].map(f32::from_bits))),
                );
            }
            if open {
                self.section(k, entry, 3, &mut chunk.open)?;
            }
            visit(&chunk)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use latticebuild_geom::mesh::Mesh;
    use latticebuild_geom::mesh_io::{Encoding, Format, write_chunked, write_mesh};

    fn summary() -> MeshSummary {
        MeshSummary {
            triangles: 0,
            vertices: 0,
            watertight: true,
            manifold: true,
            euler_characteristic: 2,
            volume: 1.5,
            area: 2.5,
            bbox_min: [0.0; 3],
            bbox_max: [1.0; 3],
            boundary_edges: 0,
            nonmanifold_edges: 0,
            misoriented_edges: 0,
            nonmanifold_vertices: 0,
            degenerate_triangles: 0,
            duplicate_positions: 0,
            components: 1,
            largest_component_fraction: 1.0,
            removed: None,
        }
    }

    fn mesh() -> Mesh {
        let mut mesh = Mesh::default();
        for i in 0..200u32 {
            let x = i as f32 * 0.25;
            mesh.vertices
                .extend([[x, 0.0, 0.0], [x, 1.0, -0.5], [x, 0.5, 1.0 / 3.0]]);
        }
        for i in 0..199u32 {
            let (a, b) = (3 * i, 3 * i + 3);
            mesh.triangles
                .extend([[a, b, a + 1], [b + 1, a + 2, b + 2]]);
        }
        mesh.triangles.push([0, 598, 1]);
        mesh
    }

    fn payload(chunks: &[MeshChunk]) -> Vec<u8> {
        let mut writer = ChunkedWriter::new(Vec::new()).expect("memory");
        for chunk in chunks {
            writer.push(chunk).expect("memory");
        }
        let head = ChunkedHead {
            summary: summary(),
            tiling: None,
            shell: None,
            sizing: None,
        };
        writer.finish(head).expect("memory").0
    }

    #[test]
    fn chunks_read_back_bit_for_bit_and_write_the_whole_meshs_files() {
        let mesh = mesh();
        let chunks = MeshChunk::split(&mesh, 37);
        let bytes = payload(&chunks);
        assert_eq!(bytes, payload(&chunks), "deterministic");
        let read = ChunkedMesh::open(bytes).expect("opens");
        assert_eq!(read.trailer.head.summary, summary());
        let mut back = Vec::new();
        read.for_each_chunk(Pass::Facets, &mut |c| {
            back.push(c.clone());
            Ok(())
        })
        .expect("reads");
        for (a, b) in back.iter().zip(&chunks) {
            assert_eq!(
                (&a.vertices, &a.triangles, &a.borrowed),
                (&b.vertices, &b.triangles, &b.borrowed)
            );
        }
        assert_eq!(back.len(), chunks.len());
        for format in Format::ALL {
            let mut whole = Vec::new();
            write_mesh(&mesh, format, Encoding::Binary, &mut whole).expect("whole");
            let mut streamed = Vec::new();
            write_chunked(&read, format, Encoding::Binary, &mut streamed).expect("chunked");
            assert!(whole == streamed, "{format:?}");
        }
    }

    /// A payload whose store declares a hash for it, as a self-verifying cache entry does.
    struct Declared(Vec<u8>, ContentHash);

    impl ReadAt for Declared {
        fn payload_len(&self) -> u64 {
            self.0.payload_len()
        }
        fn read_at(&self, offset: u64, buf: &mut [u8]) -> io::Result<()> {
            self.0.read_at(offset, buf)
        }
        fn declared_hash(&self) -> Option<ContentHash> {
            Some(self.1)
        }
    }

    #[test]
    fn the_identifying_hash_is_the_trailers_and_a_wrong_declared_one_is_corrupt() {
        let mesh = mesh();
        let chunks = MeshChunk::split(&mesh, 37);
        let mut writer = ChunkedWriter::new(Vec::new()).expect("memory");
        for chunk in &chunks {
            writer.push(chunk).expect("memory");
        }
        let head = ChunkedHead {
            summary: summary(),
            tiling: None,
            shell: None,
            sizing: None,
        };
        let (bytes, trailer, check) = writer.finish(head).expect("memory");
        let json = serde_json::to_vec(&trailer).expect("json");
        assert_eq!(check, ContentHash::of_serial(&json));
        assert_eq!(&bytes[bytes.len() - 40..bytes.len() - 8], check.as_bytes());

        let opened = ChunkedMesh::open(Declared(bytes.clone(), check)).expect("declared right");
        assert_eq!(opened.trailer, trailer);
        let wrong = ContentHash::of(&bytes);
        let e = ChunkedMesh::open(Declared(bytes, wrong)).expect_err("declared wrong");
        assert!(is_corrupt(&e), "{e}");
    }

    #[test]
    fn any_flipped_or_missing_byte_is_corrupt_never_a_different_mesh() {
        let mesh = mesh();
        let chunks = MeshChunk::split(&mesh, 50);
        let bytes = payload(&chunks);
        let mut expected = Vec::new();
        write_mesh(&mesh, Format::Stl, Encoding::Binary, &mut expected).expect("whole");
        // Every byte position, one bit each (a step keeps the test fast but covers every
        // region: magic, each section of each chunk, trailer, hash and length). A flip in a
        // section STL does not read (`open`) may go unseen, but then the file is right.
        let mut caught = 0;
        for at in (0..bytes.len()).step_by(7).chain([bytes.len() - 1]) {
            let mut bad = bytes.clone();
            bad[at] ^= 1 << (at % 8);
            let outcome = ChunkedMesh::open(bad).and_then(|m| {
                let mut out = Vec::new();
                write_chunked(&m, Format::Stl, Encoding::Binary, &mut out).map(|()| out)
            });
            match outcome {
                Err(e) => {
                    assert!(is_corrupt(&e), "byte {at}: {e}");
                    caught += 1;
                }
                Ok(out) => assert!(out == expected, "byte {at} flipped wrote a different file"),
            }
        }
        assert!(caught > bytes.len() / 8, "{caught} flips caught");
        for cut in [
            0,
            5,
            8,
            100,
            bytes.len() / 2,
            bytes.len() - 41,
            bytes.len() - 1,
        ] {
            let e = ChunkedMesh::open(bytes[..cut].to_vec()).expect_err("truncated");
            assert!(is_corrupt(&e), "cut at {cut}: {e}");
        }
    }
}
