//! STL, binary (default) or ASCII.
//!
//! Binary layout (little-endian): an 80-byte header beginning with the stamp's generator
//! (`latticebuild 0.1.0 binary STL, units: mm`; never `solid`, so readers that sniff the first
//! line do not mistake it for ASCII), a `u32` facet count, then per
//! facet the unit normal, the three vertices (12 `f32`) and a `u16` attribute count of 0: 50
//! bytes, so a file of `n` facets is `84 + 50 n` bytes.
//!
//! STL has no vertex sharing: every facet repeats its three positions. The facet normal is
//! computed from the `f32` vertices in `f64` and rounded to `f32`; a degenerate facet (zero
//! area) gets the zero vector, which readers take as "compute it yourself".
//!
//! ASCII names its solid by the stamp: `solid latticebuild 0.1.0, units: mm`, and the same
//! name after `endsolid`.

use super::Encoding;
use super::encode::{
    Workers, push_f32, push_point, records_per_block, write_blocks_by, write_encoded_by,
};
use super::stamp::Stamp;
use crate::mesh::Mesh;
use std::io::{self, Write};

const FACET_BYTES: usize = 50;
/// Facets whose normals are found together: a batch's square roots and divisions then run
/// two to an instruction (they were half of the binary writer's time one facet at a time).
const NORMAL_BATCH: usize = 8;
/// A generous estimate of one ASCII facet, only used to size blocks.
const ASCII_FACET_BYTES: usize = 256;

pub(super) fn write(
    mesh: &Mesh,
    encoding: Encoding,
    stamp: &Stamp,
    out: &mut dyn Write,
) -> io::Result<()> {
    header(mesh.triangles.len() as u64, encoding, stamp, out)?;
    // Indices were range-checked by `write_mesh`.
    facets(
        &mesh.triangles,
        |i| mesh.vertices[i as usize],
        encoding,
        Workers::Pool,
        out,
    )?;
    footer(encoding, stamp, out)
}

/// `(b − a) × (c − a)`, computed in `f64` from the `f32` corners.
#[inline]
fn facet_cross(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> [f64; 3] {
    let u = [
        f64::from(b[0]) - f64::from(a[0]),
        f64::from(b[1]) - f64::from(a[1]),
        f64::from(b[2]) - f64::from(a[2]),
    ];
    let v = [
        f64::from(c[0]) - f64::from(a[0]),
        f64::from(c[1]) - f64::from(a[1]),
        f64::from(c[2]) - f64::from(a[2]),
    ];
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

/// The right-hand unit normal of triangle `abc`, or zero when its area is zero.
#[inline]
pub(super) fn facet_normal(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> [f32; 3] {
    let n = facet_cross(a, b, c);
    let inv = inverse_length(&n);
    n.map(|x| scaled(x, inv))
}

/// `x · inv` in `f32`, zero when `inv` is (so non-finite components give zero too).
#[inline]
fn scaled(x: f64, inv: f64) -> f32 {
    if inv > 0.0 { (x * inv) as f32 } else { 0.0 }
}

/// `1 / |n|`, or zero when `n` is zero or not finite (a degenerate facet's normal is zero).
/// One division and three products instead of three divisions: the normal's `f32` can differ
/// from the quotients' by an ulp, and the binary and text writers agree bit for bit.
#[inline]
fn inverse_length(n: &[f64; 3]) -> f64 {
    let square = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if square > 0.0 && square.is_finite() {
        1.0 / square.sqrt()
    } else {
        0.0
    }
}

/// Appends the binary records of `batch` (at most [`NORMAL_BATCH`] facets), with corner
/// positions from `corners`; the normals are [`facet_normal`]'s.
#[inline]
fn binary_facets(
    buf: &mut Vec<u8>,
    batch: &[[u32; 3]],
    corners: &impl Fn(&[u32; 3]) -> [[f32; 3]; 3],
) {
    let mut normals = [[0f64; 3]; NORMAL_BATCH];
    let mut inverse = [0f64; NORMAL_BATCH];
    for (tri, n) in batch.iter().zip(&mut normals) {
        let [a, b, c] = corners(tri);
        *n = facet_cross(a, b, c);
    }
    // A loop of its own, so that it vectorizes.
    for (n, inv) in normals.iter().zip(&mut inverse) {
        *inv = inverse_length(n);
    }
    // Records are encoded in place: built on the stack and appended, each was read back
    // in 16-byte loads from twelve 4-byte stores, which cannot be forwarded.
    let start = buf.len();
    // Zeroed: the last two bytes of a record, the attribute byte count, stay 0.
    buf.resize(start + batch.len() * FACET_BYTES, 0);
    let records = buf[start..].chunks_exact_mut(FACET_BYTES);
    for (((record, tri), n), &inv) in records.zip(batch).zip(&normals).zip(&inverse) {
        // The corners again (in L1 now) rather than kept: copying them through the stack cost
        // a failed store-to-load forwarding per facet.
        let [a, b, c] = corners(tri);
        let values = [
            scaled(n[0], inv),
            scaled(n[1], inv),
            scaled(n[2], inv),
            a[0],
            a[1],
            a[2],
            b[0],
            b[1],
            b[2],
            c[0],
            c[1],
            c[2],
        ];
        // A flat array, not chained iterators: the loop then unrolls into twelve stores.
        for (slot, value) in record.chunks_exact_mut(4).zip(values) {
            slot.copy_from_slice(&value.to_le_bytes());
        }
    }
}

/// The binary header's text: the stamp's generator, `binary STL` and the unit, cut to 80 bytes
/// (at a character boundary).
fn header_text(stamp: &Stamp) -> String {
    let mut text = format!("{} binary STL", stamp.generator());
    if let Some(units) = stamp.units {
        text.push_str(", units: ");
        text.push_str(units.name());
    }
    while text.len() > 80 {
        text.pop();
    }
    text
}

/// The 84-byte binary header with the facet count, or the ASCII `solid` line.
pub(super) fn header(
    nt: u64,
    encoding: Encoding,
    stamp: &Stamp,
    out: &mut dyn Write,
) -> io::Result<()> {
    match encoding {
        Encoding::Binary => {
            let count = u32::try_from(nt).map_err(|_| {
                io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!(
                        "binary STL holds at most {} facets, mesh has {nt}",
                        u32::MAX
                    ),
                )
            })?;
            let mut header = [0u8; 84];
            let text = header_text(stamp);
            header[..text.len()].copy_from_slice(text.as_bytes());
            header[80..].copy_from_slice(&count.to_le_bytes());
            out.write_all(&header)
        }
        Encoding::Ascii => writeln!(out, "solid {}", stamp.summary()),
    }
}

/// The facets of `triangles`, in order, with corner positions from `position`, which the
/// caller has made total on these triangles' indices.
pub(super) fn facets<P: Fn(u32) -> [f32; 3] + Sync>(
    triangles: &[[u32; 3]],
    position: P,
    encoding: Encoding,
    workers: Workers,
    out: &mut dyn Write,
) -> io::Result<()> {
    // Spelled out rather than `tri.map(&position)`, which left a call per corner un-inlined
    // (4× the time of the whole-mesh writer).
    let corners = |tri: &[u32; 3]| [position(tri[0]), position(tri[1]), position(tri[2])];
    match encoding {
        Encoding::Binary => write_blocks_by(
            workers,
            out,
            triangles,
            records_per_block(FACET_BYTES),
            |buf, block| {
                for batch in block.chunks(NORMAL_BATCH) {
                    binary_facets(buf, batch, &corners);
                }
            },
        ),
        Encoding::Ascii => write_encoded_by(
            workers,
            out,
            triangles,
            records_per_block(ASCII_FACET_BYTES),
            |buf, tri| {
                let [a, b, c] = corners(tri);
                let n = facet_normal(a, b, c);
                buf.extend_from_slice(b"facet normal ");
                push_f32(buf, n[0]);
                buf.push(b' ');
                push_f32(buf, n[1]);
                buf.push(b' ');
                push_f32(buf, n[2]);
                buf.extend_from_slice(b"\n  outer loop\n");
                for p in [&a, &b, &c] {
                    buf.extend_from_slice(b"    vertex ");
                    push_point(buf, p);
                    buf.push(b'\n');
                }
                buf.extend_from_slice(b"  endloop\nendfacet\n");
            },
        ),
    }
}

/// What follows the facets: nothing in binary, the `endsolid` line in ASCII.
pub(super) fn footer(encoding: Encoding, stamp: &Stamp, out: &mut dyn Write) -> io::Result<()> {
    match encoding {
        Encoding::Binary => Ok(()),
        Encoding::Ascii => writeln!(out, "endsolid {}", stamp.summary()),
    }
}
