//! Shared machinery of the writers: block-parallel record encoding and text number formatting.
//!
//! Invariant: the bytes written are exactly those a sequential loop over the records would
//! produce; parallelism only changes who encodes a block, never the order blocks are written.

use super::Encoding;
use rayon::prelude::*;
use std::io::{self, Write};

/// Target size of one encoded block. Blocks are written with one `write_all` each, so the
/// writer sees a few large writes instead of one per field.
pub(super) const BLOCK_BYTES: usize = 1 << 20;

/// How many records of about `record_bytes` bytes fill one block.
pub(super) fn records_per_block(record_bytes: usize) -> usize {
    (BLOCK_BYTES / record_bytes.max(1)).max(1)
}

/// Who encodes the records of a writer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Workers {
    /// The rayon pool, while the calling thread writes.
    Pool,
    /// The calling thread alone: for a thread that feeds on work the rayon pool makes, which
    /// would deadlock waiting for pool threads blocked on feeding it.
    Caller,
}

/// Encodes `items` with `encode` and writes the result to `out`, in order, by `workers`.
///
/// With [`Workers::Pool`], items /// Items are cut into blocks of `per_block`; a batch of blocks is encoded in parallel on the
/// rayon pool into reusable buffers while the calling thread writes the previous batch. Two
/// batches of buffers are alive at a time, so memory stays at a few MiB whatever the mesh size,
/// and no allocation happens per record once the buffers have grown to their working size.
pub(super) fn write_encoded_by<T, F>(
    workers: Workers,
    out: &mut dyn Write,
    items: &[T],
    per_block: usize,
    encode: F,
) -> io::Result<()>
where
    T: Sync,
    F: Fn(&mut Vec<u8>, &T) + Sync,
{
    write_blocks_by(workers, out, items, per_block, |buf, block| {
        for item in block {
            encode(buf, item);
        }
    })
}

/// Encodes `items` a block (at most `per_block` items) at a time with `encode_block`, which
/// appends the block's records to the buffer, and writes the result to `out` in order: by the
/// rayon pool while the calling thread writes (`Workers::Pool`, as [`write_encoded_by`]), or by
/// the caller alone. For encoders that gain from seeing many records at once.
pub(super) fn write_blocks_by<T, F>(
    workers: Workers,
    out: &mut dyn Write,
    items: &[T],
    per_block: usize,
    encode_block: F,
) -> io::Result<()>
where
    T: Sync,
    F: Fn(&mut Vec<u8>, &[T]) + Sync,
{
    let per_block = per_block.max(1);
    if workers == Workers::Caller {
        let mut buf = Vec::new();
        for block in items.chunks(per_block) {
            buf.clear();
            encode_block(&mut buf, block);
            out.write_all(&buf)?;
        }
        return Ok(());
    }
    // Two blocks per thread keeps every thread busy even when blocks encode at uneven speed.
    let blocks_per_batch = 2 * rayon::current_num_threads().max(1);
    let mut batches = items.chunks(per_block * blocks_per_batch);
    let Some(first) = batches.next() else {
        return Ok(());
    };

    let encode_batch = |bufs: &mut [Vec<u8>], batch: &[T]| {
        bufs.par_iter_mut()
            .zip(batch.par_chunks(per_block))
            .for_each(|(buf, chunk)| {
                buf.clear();
                encode_block(buf, chunk);
            });
    };
    let blocks_in = |batch: &[T]| batch.len().div_ceil(per_block);

    let mut ready: Vec<Vec<u8>> = (0..blocks_per_batch).map(|_| Vec::new()).collect();
    let mut spare: Vec<Vec<u8>> = (0..blocks_per_batch).map(|_| Vec::new()).collect();
    encode_batch(&mut ready, first);
    let mut ready_blocks = blocks_in(first);

    loop {
        let next = batches.next();
        // `in_place_scope` runs the closure on this thread, so `out` (which need not be `Send`)
        // is only ever touched here, while the spawned job encodes the next batch.
        let written = rayon::in_place_scope(|scope| {
            if let Some(batch) = next {
                let spare = &mut spare;
                let encode_batch = &encode_batch;
                scope.spawn(move |_| encode_batch(spare, batch));
            }
            ready[..ready_blocks]
                .iter()
                .try_for_each(|buf| out.write_all(buf))
        });
        written?;
        match next {
            None => return Ok(()),
            Some(batch) => {
                std::mem::swap(&mut ready, &mut spare);
                ready_blocks = blocks_in(batch);
            }
        }
    }
}

/// Appends `v` in decimal.
#[inline]
pub(super) fn push_uint(buf: &mut Vec<u8>, mut v: u64) {
    let mut digits = [0u8; 20];
    let mut start = digits.len();
    loop {
        start -= 1;
        digits[start] = b'0' + (v % 10) as u8;
        v /= 10;
        if v == 0 {
            break;
        }
    }
    buf.extend_from_slice(&digits[start..]);
}

/// Appends `v` with the shortest decimal that parses back to the same `f32`.
///
/// Plain notation in the usual range, exponent notation for very small or very large
/// magnitudes (where plain notation would spell out dozens of zeros). Both are the shortest
/// round-trip digits, so a text file holds exactly the values of the binary one.
#[inline]
pub(super) fn push_f32(buf: &mut Vec<u8>, v: f32) {
    let magnitude = v.abs();
    // Writing into a Vec cannot fail, so the fmt::Result carries no information.
    let _ = if magnitude == 0.0 || (1e-5..1e16).contains(&magnitude) {
        write!(buf, "{v}")
    } else {
        write!(buf, "{v:e}")
    };
}

/// Appends `x y z` (no line end).
#[inline]
pub(super) fn push_point(buf: &mut Vec<u8>, p: &[f32; 3]) {
    push_f32(buf, p[0]);
    buf.push(b' ');
    push_f32(buf, p[1]);
    buf.push(b' ');
    push_f32(buf, p[2]);
}

/// Appends `a b c` (no line end), each index plus `base`.
#[inline]
pub(super) fn push_indices(buf: &mut Vec<u8>, tri: &[u32; 3], base: u64) {
    push_uint(buf, u64::from(tri[0]) + base);
    buf.push(b' ');
    push_uint(buf, u64::from(tri[1]) + base);
    buf.push(b' ');
    push_uint(buf, u64::from(tri[2]) + base);
}

/// Byte order of a binary format's numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum ByteOrder {
    Little,
    Big,
}

impl ByteOrder {
    #[inline]
    fn f32(self, v: f32) -> [u8; 4] {
        match self {
            ByteOrder::Little => v.to_le_bytes(),
            ByteOrder::Big => v.to_be_bytes(),
        }
    }

    #[inline]
    fn u32(self, v: u32) -> [u8; 4] {
        match self {
            ByteOrder::Little => v.to_le_bytes(),
            ByteOrder::Big => v.to_be_bytes(),
        }
    }
}

/// Vertices, in order: binary, one record of three `f32` in `order` each; text, one line
/// `x y z` each.
pub(super) fn write_points(
    out: &mut dyn Write,
    vertices: &[[f32; 3]],
    encoding: Encoding,
    order: ByteOrder,
) -> io::Result<()> {
    const POINT_BYTES: usize = 12;
    match encoding {
        Encoding::Binary => {
            let per_block = records_per_block(POINT_BYTES);
            write_encoded_by(Workers::Pool, out, vertices, per_block, |buf, p| {
                let mut record = [0u8; POINT_BYTES];
                for (slot, &value) in record.chunks_exact_mut(4).zip(p) {
                    slot.copy_from_slice(&order.f32(value));
                }
                buf.extend_from_slice(&record);
            })
        }
        Encoding::Ascii => write_text_points(out, vertices, b""),
    }
}

/// Triangles as polygons of three corners, in order: binary, one record each of `count` (the
/// number 3 as the format spells it, at most 4 bytes) and the three indices as 32-bit integers
/// in `order` (the writer has checked that they fit its signed ones, so the bits are equal);
/// text, one line `3 a b c` each.
pub(super) fn write_polygons(
    out: &mut dyn Write,
    triangles: &[[u32; 3]],
    encoding: Encoding,
    count: &[u8],
    order: ByteOrder,
) -> io::Result<()> {
    match encoding {
        Encoding::Binary => {
            let head = count.len();
            let per_block = records_per_block(head + 12);
            write_encoded_by(Workers::Pool, out, triangles, per_block, |buf, tri| {
                let mut record = [0u8; 16];
                record[..head].copy_from_slice(count);
                for (slot, &index) in record[head..head + 12].chunks_exact_mut(4).zip(tri) {
                    slot.copy_from_slice(&order.u32(index));
                }
                buf.extend_from_slice(&record[..head + 12]);
            })
        }
        Encoding::Ascii => write_text_faces(out, triangles, b"3 ", 0),
    }
}

/// Bytes of one text point line, for sizing blocks: three shortest-form f32 and separators.
const TEXT_POINT_BYTES: usize = 48;
/// Bytes of one text face line.
const TEXT_FACE_BYTES: usize = 36;

/// One line `PREFIX x y z` per vertex, in order (the text formats differ only in the prefix).
pub(super) fn write_text_points(
    out: &mut dyn Write,
    vertices: &[[f32; 3]],
    prefix: &[u8],
) -> io::Result<()> {
    let per_block = records_per_block(TEXT_POINT_BYTES + prefix.len());
    write_encoded_by(Workers::Pool, out, vertices, per_block, |buf, p| {
        buf.extend_from_slice(prefix);
        push_point(buf, p);
        buf.push(b'\n');
    })
}

/// One line `PREFIX a b c` per triangle, indices counted from `base`.
pub(super) fn write_text_faces(
    out: &mut dyn Write,
    triangles: &[[u32; 3]],
    prefix: &[u8],
    base: u64,
) -> io::Result<()> {
    let per_block = records_per_block(TEXT_FACE_BYTES + prefix.len());
    write_encoded_by(Workers::Pool, out, triangles, per_block, |buf, tri| {
        buf.extend_from_slice(prefix);
        push_indices(buf, tri, base);
        buf.push(b'\n');
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uint_digits() {
        for v in [0u64, 7, 10, 99, 100, 4_294_967_295, u64::MAX] {
            let mut buf = Vec::new();
            push_uint(&mut buf, v);
            assert_eq!(buf, v.to_string().into_bytes());
        }
    }

    #[test]
    fn f32_text_round_trips_bit_exactly() {
        let samples = [
            0.0f32,
            -0.0,
            1.0,
            -1.5,
            0.1,
            1.0 / 3.0,
            1e-5,
            9.99e-6,
            1.2e-38,
            f32::MIN_POSITIVE / 8.0,
            1e16,
            3.4e38,
            f32::MAX,
            -f32::MAX,
            123456.79,
        ];
        for v in samples {
            let mut buf = Vec::new();
            push_f32(&mut buf, v);
            let text = String::from_utf8(buf).expect("ascii");
            let back: f32 = text.parse().expect("parses");
            assert_eq!(back.to_bits(), v.to_bits(), "{v} printed as {text}");
            assert!(text.len() <= 16, "{v} printed as {text}");
        }
    }

    #[test]
    fn blocks_are_written_in_order() {
        let items: Vec<u32> = (0..100_003).collect();
        let mut out = Vec::new();
        write_encoded_by(Workers::Pool, &mut out, &items, 7, |buf, &v| {
            buf.extend_from_slice(&v.to_le_bytes())
        })
        .expect("vec write");
        let expected: Vec<u8> = items.iter().flat_map(|v| v.to_le_bytes()).collect();
        assert_eq!(out, expected);
    }
}
