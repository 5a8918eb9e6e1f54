//! The binary data of one `.vtu` array: VTK's header (UInt32 or UInt64, the file's byte
//! order) and its bytes, raw or in compressed blocks (zlib, LZ4).
//!
//! Layout (VTK's vtkXMLWriter): uncompressed, one header number (the byte count) and the
//! bytes; compressed, `[blocks, block size, last block size, compressed size × blocks]` and
//! the blocks, each compressed on its own (zlib streams; LZ4 raw blocks without a frame).
//!
//! Invariants: no panic on any input; the declared sizes must add up to exactly the bytes the
//! caller expects, so no block is decompressed past its declared size and nothing is
//! allocated beyond what the array needs; errors are messages about the array, which the
//! caller places.

use crate::scaffold::cursor::Cursor;

/// A `.vtu` file's compressor attribute.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Compressor {
    None,
    Zlib,
    Lz4,
}

impl Compressor {
    /// The compressor a VTKFile's `compressor` attribute names, or `Err(message)`.
    pub(super) fn from_attribute(name: Option<&[u8]>) -> Result<Compressor, String> {
        match name {
            None | Some(b"") => Ok(Compressor::None),
            Some(b"vtkZLibDataCompressor") => Ok(Compressor::Zlib),
            Some(b"vtkLZ4DataCompressor") => Ok(Compressor::Lz4),
            Some(other) => Err(format!(
                "unsupported compressor \"{}\": expected vtkZLibDataCompressor, \
                 vtkLZ4DataCompressor or none{}",
                crate::scaffold::cursor::show(other),
                if other == b"vtkLZMADataCompressor" {
                    " (save the file with zlib or LZ4 compression)"
                } else {
                    ""
                }
            )),
        }
    }
}

/// How a file's binary arrays are written.
#[derive(Clone, Copy, Debug)]
pub(super) struct Encoding {
    pub big_endian: bool,
    /// Header numbers are UInt64 (else UInt32).
    pub header64: bool,
    pub compressor: Compressor,
}

impl Encoding {
    /// The array's bytes from its header and data at the start of `data`: at least
    /// `expected` bytes (exactly that many when compressed).
    pub(super) fn unpack(
        &self,
        name: &str,
        data: &[u8],
        expected: usize,
    ) -> Result<Vec<u8>, String> {
        let mut cur = Cursor::new(data, name);
        cur.big_endian = self.big_endian;
        if self.compressor == Compressor::None {
            let n = self.header(&mut cur, "header")?;
            let n = usize::try_from(n).map_err(|_| "truncated data".to_string())?;
            return Ok(cur
                .take(n, "data")
                .map_err(|_| "truncated data".to_string())?
                .to_vec());
        }
        self.decompress(&mut cur, expected)
    }

    /// One header number (UInt32 or UInt64).
    fn header(&self, cur: &mut Cursor<'_>, what: &str) -> Result<u64, String> {
        let read = if self.header64 {
            cur.u64("a header")
        } else {
            cur.i32("a header").map(|v| v as u32 as u64)
        };
        read.map_err(|_| format!("truncated {what}"))
    }

    /// The compressed blocks (block list at `cur`), decompressed: `expected` bytes.
    fn decompress(&self, cur: &mut Cursor<'_>, expected: usize) -> Result<Vec<u8>, String> {
        let h = if self.header64 { 8 } else { 4 };
        let blocks = self.header(cur, "block list")?;
        let block_size = self.header(cur, "block list")?;
        let last_size = self.header(cur, "block list")?;
        let blocks = cur
            .check_count(0, blocks, "the number of compressed blocks", h)
            .map_err(|_| "truncated block list".to_string())?;
        let mut sizes = Vec::with_capacity(blocks);
        for _ in 0..blocks {
            sizes.push(self.header(cur, "block list")?);
        }
        // The last block's size is 0 when it is a whole block (VTK's convention).
        let last_size = if last_size == 0 {
            block_size
        } else {
            last_size
        };
        let total = match blocks {
            0 => 0,
            _ => block_size
                .saturating_mul(blocks as u64 - 1)
                .saturating_add(last_size),
        };
        if blocks > 0 && total != expected as u64 {
            return Err(format!(
                "compressed blocks hold {total} bytes, expected {expected}"
            ));
        }
        let mut out = Vec::with_capacity(expected.min(cur.remaining().saturating_mul(1100)));
        for (b, &size) in sizes.iter().enumerate() {
            let size = usize::try_from(size).map_err(|_| "truncated block".to_string())?;
            let block = cur
                .take(size, "a compressed block")
                .map_err(|_| "truncated compressed block".to_string())?;
            let limit = if b + 1 == blocks {
                last_size
            } else {
                block_size
            } as usize;
            let bytes = match self.compressor {
                Compressor::Zlib => {
                    miniz_oxide::inflate::decompress_to_vec_zlib_with_limit(block, limit)
                        .map_err(|e| format!("bad zlib data in block {b} ({:?})", e.status))?
                }
                // LZ4 expands at most 255:1, and its output is allocated whole up front.
                Compressor::Lz4 if limit > block.len().saturating_mul(255).saturating_add(16) => {
                    return Err(format!(
                        "LZ4 block {b} of {} bytes cannot hold {limit} bytes",
                        block.len()
                    ));
                }
                Compressor::Lz4 => lz4_flex::block::decompress(block, limit)
                    .map_err(|e| format!("bad LZ4 data in block {b} ({e})"))?,
                Compressor::None => block.to_vec(),
            };
            if bytes.len() != limit {
                return Err(format!(
                    "block {b} decompresses to {} bytes, expected {limit}",
                    bytes.len()
                ));
            }
            out.extend_from_slice(&bytes);
        }
        Ok(out)
    }
}
