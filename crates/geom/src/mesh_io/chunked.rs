//! The writers on a mesh held as [`MeshChunk`]s, which never needs the whole mesh in memory.
//!
//! Invariants:
//! - The bytes are exactly those [`super::write_mesh`] writes for the concatenated mesh: every
//!   format is a header followed by sections of per-record bytes, and a section written chunk
//!   by chunk is the same concatenation. Counts in headers come from [`ChunkSource::totals`];
//!   the chunks must add up to them, or the call fails.
//! - Indexed formats (all but STL) read the chunks twice, vertices then triangles
//!   ([`Pass::Vertices`], [`Pass::Triangles`]); STL reads them once ([`Pass::Facets`]), taking
//!   positions from each chunk ([`MeshChunk::position`]).
//! - A chunk is checked before any of its bytes are written — finite coordinates, indices in
//!   range, ids dense — but for STL's corners, which are resolved from the chunk's own and
//!   borrowed vertices while encoding: one that does not resolve fails the call after the
//!   chunk's bytes. Either way a bad chunk fails the call and the caller discards the output.

use super::encode::Workers;
use super::stamp::Stamp;
use super::{
    Encoding, Format, check_finite, check_finite_by, check_indices, obj, off, ply, stl, threemf,
    vtk, vtu,
};
use crate::mesh::MeshChunk;
use std::io::{self, Seek, SeekFrom, Write};
use std::sync::atomic::{AtomicBool, Ordering};

/// Which arrays of each chunk a pass reads. A source may leave the others empty (but always
/// sets `first_vertex`), so a pass over triangles need not read vertices from disk.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// `vertices`.
    Vertices,
    /// `triangles`.
    Triangles,
    /// `vertices`, `triangles` and `borrowed`: what positions every corner.
    Facets,
}

/// A mesh stored as chunks (in memory, or in a cache entry) that can be visited in order as
/// often as a writer needs. `Sync`, so several formats can be written from one source at once.
pub trait ChunkSource: Sync {
    /// The whole mesh's vertex and triangle counts.
    fn totals(&self) -> (u64, u64);

    /// Calls `visit` with every chunk, in order, with at least the arrays `pass` names. An
    /// error of the source (an unreadable or corrupt chunk) or of `visit` ends the walk.
    fn for_each_chunk(
        &self,
        pass: Pass,
        visit: &mut dyn FnMut(&MeshChunk) -> io::Result<()>,
    ) -> io::Result<()>;
}

impl ChunkSource for Vec<MeshChunk> {
    fn totals(&self) -> (u64, u64) {
        self.iter().fold((0, 0), |(v, t), c| {
            (v + c.vertices.len() as u64, t + c.triangles.len() as u64)
        })
    }

    fn for_each_chunk(
        &self,
        _: Pass,
        visit: &mut dyn FnMut(&MeshChunk) -> io::Result<()>,
    ) -> io::Result<()> {
        self.iter().try_for_each(visit)
    }
}

fn invalid(message: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, message)
}

/// Writes the mesh of `source`'s chunks to `out` in `format` (see [`super::write_mesh`]).
pub fn write_chunked(
    source: &dyn ChunkSource,
    format: Format,
    encoding: Encoding,
    out: &mut dyn Write,
) -> io::Result<()> {
    write_chunked_stamped(source, format, encoding, &Stamp::default(), out)
}

/// [`write_chunked`] with the headers and metadata of `stamp` (see
/// [`super::write_mesh_stamped`]).
pub fn write_chunked_stamped(
    source: &dyn ChunkSource,
    format: Format,
    encoding: Encoding,
    stamp: &Stamp,
    out: &mut dyn Write,
) -> io::Result<()> {
    let (nv, nt) = source.totals();
    match format {
        Format::Stl => {
            stl::header(nt, encoding, stamp, out)?;
            facets(source, nt, &mut |chunk, done| {
                stl_facets(chunk, done, encoding, Workers::Pool, out)
            })?;
            stl::footer(encoding, stamp, out)?;
        }
        Format::Ply => {
            ply::header(nv, nt, encoding, stamp, out)?;
            vertices(source, nv, &mut |v| ply::vertices(v, encoding, out))?;
            triangles(source, nv, nt, &mut |t| ply::faces(t, encoding, out))?;
        }
        Format::Obj => {
            obj::header(nv, nt, stamp, out)?;
            vertices(source, nv, &mut |v| obj::vertices(v, out))?;
            triangles(source, nv, nt, &mut |t| obj::faces(t, out))?;
        }
        Format::Off => {
            off::header(nv, nt, out)?;
            vertices(source, nv, &mut |v| off::vertices(v, out))?;
            triangles(source, nv, nt, &mut |t| off::faces(t, out))?;
        }
        Format::Vtk => {
            vtk::header(nv, nt, encoding, stamp, out)?;
            vertices(source, nv, &mut |v| vtk::points(v, encoding, out))?;
            vtk::polygons_header(nt, encoding, out)?;
            triangles(source, nv, nt, &mut |t| vtk::polygons(t, encoding, out))?;
            vtk::end(encoding, out)?;
        }
        Format::Vtu => {
            vtu::header(nv, nt, stamp, out)?;
            vertices(source, nv, &mut |v| vtu::points(v, out))?;
            vtu::connectivity_header(nt, out)?;
            triangles(source, nv, nt, &mut |t| vtu::connectivity(t, out))?;
            vtu::tail(nt, out)?;
        }
        Format::ThreeMf => {
            let mut package = threemf::Package::begin(nv, nt, stamp, out)?;
            vertices(source, nv, &mut |v| threemf::vertices(v, &mut package))?;
            package.between()?;
            triangles(source, nv, nt, &mut |t| threemf::triangles(t, &mut package))?;
            package.finish()?;
        }
    }
    out.flush()
}

/// `chunk`'s STL facets, `done` triangles into the mesh. Corners are resolved once, while
/// encoding (a separate check doubled the cost of the random lookups of borrowed ids); a miss
/// fails the call after this chunk's bytes, which the caller discards with the rest of the
/// partial file.
fn stl_facets(
    chunk: &MeshChunk,
    done: u64,
    encoding: Encoding,
    workers: Workers,
    out: &mut dyn Write,
) -> io::Result<()> {
    let positions = Positions::of(chunk);
    let missing = AtomicBool::new(false);
    stl::facets(
        &chunk.triangles,
        |i| {
            *positions.get(i).unwrap_or_else(|| {
                missing.store(true, Ordering::Relaxed);
                &[0.0; 3]
            })
        },
        encoding,
        workers,
        out,
    )?;
    if missing.load(Ordering::Relaxed) {
        let resolves = |tri: &[u32; 3]| tri.iter().all(|&i| positions.get(i).is_some());
        let t = chunk
            .triangles
            .iter()
            .position(|tri| !resolves(tri))
            .unwrap_or(0);
        return Err(invalid(format!(
            "triangle {} {:?} uses a vertex its chunk neither has nor borrows",
            done + t as u64,
            chunk.triangles.get(t).copied().unwrap_or_default()
        )));
    }
    Ok(())
}

/// An STL file written a chunk at a time while the chunks are still being made, before the
/// facet count is known: the bytes [`write_chunked`] writes for the same chunks. A binary
/// header is written with a count of 0 and patched by [`StlStream::finish`], so the output
/// must seek; ASCII has no count.
#[derive(Debug)]
pub struct StlStream {
    encoding: Encoding,
    stamp: Stamp,
    workers: Workers,
    /// Triangles and vertices written so far.
    triangles: u64,
    vertices: u64,
}

impl StlStream {
    /// Writes the header (with `stamp`'s text); `workers` encode the facets.
    pub fn begin(
        encoding: Encoding,
        stamp: &Stamp,
        workers: Workers,
        out: &mut dyn Write,
    ) -> io::Result<StlStream> {
        stl::header(0, encoding, stamp, out)?;
        Ok(StlStream {
            encoding,
            stamp: stamp.clone(),
            workers,
            triangles: 0,
            vertices: 0,
        })
    }

    /// Appends `chunk`'s facets, checked as [`write_chunked`] checks them.
    pub fn push(&mut self, chunk: &MeshChunk, out: &mut dyn Write) -> io::Result<()> {
        check_facet_chunk(chunk, &mut self.vertices, self.workers)?;
        stl_facets(chunk, self.triangles, self.encoding, self.workers, out)?;
        self.triangles += chunk.triangles.len() as u64;
        Ok(())
    }

    /// Ends the file: the footer, and the binary facet count at its place in the header.
    pub fn finish<W: Write + Seek>(self, out: &mut W) -> io::Result<()> {
        stl::footer(self.encoding, &self.stamp, out)?;
        if self.encoding == Encoding::Binary {
            let end = out.stream_position()?;
            let mut header = Vec::with_capacity(84);
            stl::header(self.triangles, self.encoding, &self.stamp, &mut header)?;
            out.seek(SeekFrom::Start(80))?;
            out.write_all(&header[80..])?;
            out.seek(SeekFrom::Start(end))?;
        }
        out.flush()
    }
}

/// What every chunk of the facet pass must be: ids continuing at `next` (advanced past this
/// chunk), own and borrowed positions finite.
fn check_facet_chunk(chunk: &MeshChunk, next: &mut u64, workers: Workers) -> io::Result<()> {
    if u64::from(chunk.first_vertex) != *next {
        return Err(invalid(format!(
            "a chunk starts at vertex {} where {next} was expected",
            chunk.first_vertex
        )));
    }
    *next += chunk.vertices.len() as u64;
    check_finite_by(workers, &chunk.vertices, u64::from(chunk.first_vertex))?;
    // One fold, not a check per entry: a chunk may borrow a million positions.
    let finite = |p: &[f32; 3]| p.iter().all(|c| c.is_finite());
    if let Some(&(id, p)) = chunk.borrowed.iter().find(|(_, p)| !finite(p)) {
        check_finite(&[p], u64::from(id))?;
    }
    Ok(())
}

/// The vertex pass: each chunk's vertices, checked, in id order, adding up to `nv`.
fn vertices(
    source: &dyn ChunkSource,
    nv: u64,
    write: &mut dyn FnMut(&[[f32; 3]]) -> io::Result<()>,
) -> io::Result<()> {
    let mut next = 0u64;
    source.for_each_chunk(Pass::Vertices, &mut |chunk| {
        if u64::from(chunk.first_vertex) != next {
            return Err(invalid(format!(
                "a chunk starts at vertex {} where {next} was expected",
                chunk.first_vertex
            )));
        }
        next += chunk.vertices.len() as u64;
        if next > nv {
            return Err(count_mismatch("vertices", nv, next));
        }
        check_finite(&chunk.vertices, u64::from(chunk.first_vertex))?;
        write(&chunk.vertices)
    })?;
    if next != nv {
        return Err(count_mismatch("vertices", nv, next));
    }
    Ok(())
}

/// The triangle pass: each chunk's triangles, indices below `nv`, adding up to `nt`.
fn triangles(
    source: &dyn ChunkSource,
    nv: u64,
    nt: u64,
    write: &mut dyn FnMut(&[[u32; 3]]) -> io::Result<()>,
) -> io::Result<()> {
    let mut done = 0u64;
    source.for_each_chunk(Pass::Triangles, &mut |chunk| {
        check_indices(&chunk.triangles, nv, done)?;
        done += chunk.triangles.len() as u64;
        if done > nt {
            return Err(count_mismatch("triangles", nt, done));
        }
        write(&chunk.triangles)
    })?;
    if done != nt {
        return Err(count_mismatch("triangles", nt, done));
    }
    Ok(())
}

/// The facet pass: each chunk whole, its own and borrowed positions finite, adding up to `nt`
/// triangles; `write` gets the chunk and the number of triangles before it (and resolves
/// the corners).
fn facets(
    source: &dyn ChunkSource,
    nt: u64,
    write: &mut dyn FnMut(&MeshChunk, u64) -> io::Result<()>,
) -> io::Result<()> {
    let mut done = 0u64;
    let mut next = 0u64;
    source.for_each_chunk(Pass::Facets, &mut |chunk| {
        check_facet_chunk(chunk, &mut next, Workers::Pool)?;
        let before = done;
        done += chunk.triangles.len() as u64;
        if done > nt {
            return Err(count_mismatch("triangles", nt, done));
        }
        write(chunk, before)
    })?;
    if done != nt {
        return Err(count_mismatch("triangles", nt, done));
    }
    Ok(())
}

/// A chunk's positions by id: its own vertices by index, borrowed ones through an
/// open-addressing table over the borrowed list. A binary search there made STL writing 4×
/// slower than from a whole mesh: a tiling's chunk borrows up to a million seam vertices, and
/// a search misses the cache at every step; a table lookup misses about once.
struct Positions<'a> {
    first: u32,
    own: &'a [[f32; 3]],
    borrowed: &'a [(u32, [f32; 3])],
    /// Index + 1 into `borrowed`, 0 for an empty slot; a power of two long, at most half full.
    slots: Vec<u32>,
    shift: u32,
}

impl<'a> Positions<'a> {
    fn of(chunk: &'a MeshChunk) -> Positions<'a> {
        let borrowed = chunk.borrowed.as_slice();
        let bits = (2 * borrowed.len())
            .max(16)
            .next_power_of_two()
            .trailing_zeros();
        let mut table = Positions {
            first: chunk.first_vertex,
            own: &chunk.vertices,
            borrowed,
            slots: vec![0; 1 << bits],
            shift: 64 - bits,
        };
        let mask = table.slots.len() - 1;
        for (k, &(id, _)) in borrowed.iter().enumerate() {
            let mut h = table.slot(id);
            while table.slots[h] != 0 {
                h = (h + 1) & mask;
            }
            // `borrowed` is a slice of a Vec of at most 2^32 ids (they are u32), so k + 1 fits.
            table.slots[h] = k as u32 + 1;
        }
        table
    }

    #[inline(always)]
    fn slot(&self, id: u32) -> usize {
        ((u64::from(id).wrapping_mul(0x9E37_79B9_7F4A_7C15)) >> self.shift) as usize
    }

    /// A reference rather than a copy: an `Option<[f32; 3]>` went through the stack, and the
    /// encoder's wider loads of it could not be forwarded from the narrower stores (a stall
    /// per corner, a third of the STL encoder's time).
    #[inline(always)]
    fn get(&self, id: u32) -> Option<&'a [f32; 3]> {
        if let Some(k) = id.checked_sub(self.first) {
            return self.own.get(k as usize);
        }
        self.borrowed_position(id)
    }

    /// Out of line, so that [`Positions::get`] is small enough to inline into the encoders:
    /// most corners are own vertices.
    #[cold]
    #[inline(never)]
    fn borrowed_position(&self, id: u32) -> Option<&'a [f32; 3]> {
        let mask = self.slots.len() - 1;
        let mut h = self.slot(id);
        loop {
            let s = self.slots[h] as usize;
            let (at, p) = self.borrowed.get(s.checked_sub(1)?)?;
            if *at == id {
                return Some(p);
            }
            h = (h + 1) & mask;
        }
    }
}

fn count_mismatch(what: &str, declared: u64, found: u64) -> io::Error {
    invalid(format!(
        "the chunked mesh declares {declared} {what} but its chunks hold {found} or more"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use crate::mesh_io::write_mesh_stamped;

    /// A closed mesh of many tetrahedra, some vertices shared far apart in triangle order
    /// (so chunks borrow), plus an unreferenced vertex, with awkward coordinates.
    fn mesh() -> Mesh {
        let mut mesh = Mesh::default();
        for k in 0..300u32 {
            let o = [
                k as f32 * 0.37,
                (k % 7) as f32 * -1.3e-6,
                (k % 11) as f32 * 3.1e7,
            ];
            let base = mesh.vertices.len() as u32;
            for d in [
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.1],
                [0.2, 0.3, 1.0],
            ] {
                mesh.vertices
                    .push([o[0] + d[0], o[1] + d[1] / 3.0, o[2] + d[2]]);
            }
            let [a, b, c, d] = [base, base + 1, base + 2, base + 3];
            mesh.triangles
                .extend([[a, c, b], [a, b, d], [b, c, d], [a, d, c]]);
        }
        mesh.vertices.push([9.0, 9.0, 9.0]);
        mesh.vertices.push([-1.0, 0.5, 2.0]); // never referenced
        // Reuse early vertices late, as a tiling's welded seams do.
        mesh.triangles.push([0, 5, 1200]);
        mesh.triangles.push([3, 1199, 7]);
        mesh
    }

    fn stamp() -> Stamp {
        Stamp {
            generator: "latticebuild 9.8.7".into(),
            units: Some(crate::mesh_io::Units::Inch),
            title: "part <1> & \"2\"".into(),
            parameters: vec![("cell".into(), "gyroid".into())],
        }
    }

    /// Also with a stamp, and for 3MF, whose zip deflates the XML as it comes.
    #[test]
    fn every_format_and_encoding_is_byte_identical_to_the_whole_mesh() {
        let mesh = mesh();
        for per in [1, 5, 97, 10_000] {
            let chunks = MeshChunk::split(&mesh, per);
            assert!(per > 1000 || chunks.iter().any(|c| !c.borrowed.is_empty()));
            for format in Format::ALL {
                for (encoding, stamp) in [
                    (Encoding::Binary, Stamp::default()),
                    (Encoding::Ascii, Stamp::default()),
                    (Encoding::Binary, stamp()),
                    (Encoding::Ascii, stamp()),
                ] {
                    let mut whole = Vec::new();
                    write_mesh_stamped(&mesh, format, encoding, &stamp, &mut whole).expect("whole");
                    let mut chunked = Vec::new();
                    write_chunked_stamped(&chunks, format, encoding, &stamp, &mut chunked)
                        .expect("chunked");
                    assert!(
                        whole == chunked,
                        "{format:?} {encoding:?}, {per} per chunk: {} vs {} bytes",
                        whole.len(),
                        chunked.len()
                    );
                }
            }
        }
    }

    #[test]
    fn bad_chunks_are_errors_not_files() {
        let mesh = mesh();
        let good = MeshChunk::split(&mesh, 50);
        let mut nan = good.clone();
        nan[3].vertices[0][1] = f32::NAN;
        let mut missing = good.clone();
        let borrows = good
            .iter()
            .position(|c| !c.borrowed.is_empty())
            .expect("a chunk borrows");
        missing[borrows].borrowed.clear();
        let mut short = good.clone();
        short.pop();
        // `totals` comes from the chunks, so a short list is a consistent, smaller mesh; a
        // source whose totals disagree with its chunks is caught here.
        struct Lying<'a>(&'a Vec<MeshChunk>);
        impl ChunkSource for Lying<'_> {
            fn totals(&self) -> (u64, u64) {
                let (v, t) = self.0.totals();
                (v + 1, t)
            }
            fn for_each_chunk(
                &self,
                pass: Pass,
                visit: &mut dyn FnMut(&MeshChunk) -> io::Result<()>,
            ) -> io::Result<()> {
                self.0.for_each_chunk(pass, visit)
            }
        }
        let write = |source: &dyn ChunkSource, format| {
            write_chunked(source, format, Encoding::Binary, &mut Vec::new())
        };
        assert!(write(&nan, Format::Ply).is_err());
        assert!(write(&nan, Format::Stl).is_err());
        assert!(write(&missing, Format::Stl).is_err());
        assert!(write(&Lying(&good), Format::Off).is_err());
        assert!(write(&good, Format::Stl).is_ok());
    }

    /// An STL streamed while its chunks are made, before its facet count is known, is the
    /// file `write_chunked` (and `write_mesh`) writes, in both encodings and for any chunking.
    #[test]
    fn streamed_stl_is_the_chunked_file() {
        let mesh = mesh();
        for encoding in [Encoding::Binary, Encoding::Ascii] {
            let mut whole = Vec::new();
            write_mesh_stamped(&mesh, Format::Stl, encoding, &stamp(), &mut whole).expect("whole");
            for (per, workers) in [
                (1, Workers::Caller),
                (7, Workers::Pool),
                (50, Workers::Caller),
                (10_000, Workers::Pool),
                (10_000, Workers::Caller),
            ] {
                let chunks = MeshChunk::split(&mesh, per);
                let mut out = io::Cursor::new(Vec::new());
                let mut stream =
                    StlStream::begin(encoding, &stamp(), workers, &mut out).expect("begin");
                for chunk in &chunks {
                    stream.push(chunk, &mut out).expect("push");
                }
                stream.finish(&mut out).expect("finish");
                assert!(
                    out.into_inner() == whole,
                    "{encoding:?}, {per} a chunk, {workers:?}"
                );
            }
        }
    }

    /// A streamed chunk that does not continue the ids, or whose corner does not resolve,
    /// fails its push.
    #[test]
    fn streamed_stl_refuses_bad_chunks() {
        let chunks = MeshChunk::split(&mesh(), 50);
        let mut out = io::Cursor::new(Vec::new());
        let mut stream = StlStream::begin(
            Encoding::Binary,
            &Stamp::default(),
            Workers::Caller,
            &mut out,
        )
        .expect("begin");
        assert!(
            stream.push(&chunks[1], &mut out).is_err(),
            "skipped chunk 0"
        );
        let mut stream = StlStream::begin(
            Encoding::Binary,
            &Stamp::default(),
            Workers::Caller,
            &mut out,
        )
        .expect("begin");
        let borrows = chunks
            .iter()
            .position(|c| !c.borrowed.is_empty())
            .expect("a chunk borrows");
        for chunk in &chunks[..borrows] {
            stream.push(chunk, &mut out).expect("push");
        }
        let mut missing = chunks[borrows].clone();
        missing.borrowed.clear();
        assert!(stream.push(&missing, &mut out).is_err());
    }
}
