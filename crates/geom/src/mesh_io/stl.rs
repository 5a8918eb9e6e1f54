//! STL, binary (default) or ASCII.
//!
//! Binary layout (little-endian): an 80-byte header beginning `latticebuild` (never `solid`, so
//! readers that sniff the first line do not mistake it for ASCII), a `u32` facet count, then per
//! facet the unit normal, the three vertices (12 `f32`) and a `u16` attribute count of 0: 50
//! bytes, so a file of `n` facets is `84 + 50 n` bytes.
//!
//! STL has no vertex sharing: every facet repeats its three positions. The facet normal is
//! computed from the `f32` vertices in `f64` and rounded to `f32`; a degenerate facet (zero
//! area) gets the zero vector, which readers take as "compute it yourself".

use super::Encoding;
use super::encode::{Workers, push_f32, push_point, records_per_block, write_encoded_by};
use crate::mesh::Mesh;
use std::io::{self, Write};

const HEADER_TEXT: &[u8] = b"latticebuild binary STL";
const FACET_BYTES: usize = 50;
/// A generous estimate of one ASCII facet, only used to size blocks.
const ASCII_FACET_BYTES: usize = 256;

pub(super) fn write(mesh: &Mesh, encoding: Encoding, out: &mut dyn Write) -> io::Result<()> {
    header(mesh.triangles.len() as u64, encoding, out)?;
    // Indices were range-checked by `write_mesh`.
    facets(
        &mesh.triangles,
        |i| mesh.vertices[i as usize],
        encoding,
        Workers::Pool,
        out,
    )?;
    footer(encoding, out)
}

/// The right-hand unit normal of triangle `abc`, or zero when its area is zero.
#[inline]
pub(super) fn facet_normal(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> [f32; 3] {
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
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len > 0.0 && len.is_finite() {
        [
            (n[0] / len) as f32,
            (n[1] / len) as f32,
            (n[2] / len) as f32,
        ]
    } else {
        [0.0; 3]
    }
}

/// The 84-byte binary header with the facet count, or the ASCII `solid` line.
pub(super) fn header(nt: u64, encoding: Encoding, out: &mut dyn Write) -> io::Result<()> {
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
            header[..HEADER_TEXT.len()].copy_from_slice(HEADER_TEXT);
            header[80..].copy_from_slice(&count.to_le_bytes());
            out.write_all(&header)
        }
        Encoding::Ascii => out.write_all(b"solid latticebuild\n"),
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
        Encoding::Binary => write_encoded_by(
            workers,
            out,
            triangles,
            records_per_block(FACET_BYTES),
            |buf, tri| {
                let [a, b, c] = corners(tri);
                let n = facet_normal(a, b, c);
                let values = [
                    n[0], n[1], n[2], a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2],
                ];
                let mut record = [0u8; FACET_BYTES];
                // A flat array, not chained iterators: the loop then unrolls into twelve stores.
                for (slot, value) in record.chunks_exact_mut(4).zip(values) {
                    slot.copy_from_slice(&value.to_le_bytes());
                }
                // The last two bytes stay 0: the attribute byte count.
                buf.extend_from_slice(&record);
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
pub(super) fn footer(encoding: Encoding, out: &mut dyn Write) -> io::Result<()> {
    match encoding {
        Encoding::Binary => Ok(()),
        Encoding::Ascii => out.write_all(b"endsolid latticebuild\n"),
    }
}
