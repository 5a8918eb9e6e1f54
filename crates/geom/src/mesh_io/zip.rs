//! A zip archive written front to back, for 3MF packages: entries deflated (or stored) as their
//! bytes come, never held whole, to any `io::Write` (no seeking).
//!
//! Written by hand on `miniz_oxide` (already the crate's deflater) rather than through the
//! `zip` crate: a package needs four record kinds, and owning them keeps the bytes a pure
//! function of the content (no clock: every timestamp is 1980-01-01 00:00) and the crate's
//! dependency tree as it was.
//!
//! Invariants:
//! - Each entry's sizes and CRC-32 follow its data in a data descriptor (general-purpose flag
//!   bit 3), and are repeated in the central directory, which readers go by.
//! - Deflate input is cut into [`PIECE`]-byte pieces by position in the entry, whatever the
//!   sizes of the writes, so the same content gives the same bytes however it was written (a
//!   chunked mesh's package equals its whole mesh's).
//! - An entry that may reach 4 GiB is declared ZIP64 before its first byte ([`Zip::begin`]'s
//!   bound): a local ZIP64 extra field, 8-byte sizes in its descriptor, and the archive then
//!   ends with ZIP64 end records. Small packages are plain zip.

use miniz_oxide::deflate::core::{
    CompressorOxide, TDEFLFlush, TDEFLStatus, compress_to_output, create_comp_flags_from_zip_params,
};
use std::io::{self, Write};

/// Bytes of entry content deflated at a time.
const PIECE: usize = 1 << 16;
/// miniz level 1: the XML of a mesh compresses about 4× at about 100 MB/s; higher levels gain
/// little on it for several times the time.
const LEVEL: i32 = 1;
/// Sizes at or above this need ZIP64 fields.
const ZIP32_LIMIT: u64 = 0xFFFF_FFFF;
/// Version needed to extract: 2.0 (deflate), 4.5 (ZIP64).
const VERSION_DEFLATE: u16 = 20;
const VERSION_ZIP64: u16 = 45;
/// DOS date of 1980-01-01 (time 00:00 is 0).
const DOS_DATE: u16 = (1 << 5) | 1;

/// A finished entry, for the central directory.
struct Entry {
    name: String,
    offset: u64,
    crc: u32,
    compressed: u64,
    size: u64,
    deflated: bool,
    zip64: bool,
}

/// The entry being written.
struct Open {
    entry: Entry,
    /// Content not yet deflated (less than a piece).
    pending: Vec<u8>,
    compressor: Option<Box<CompressorOxide>>,
    crc: Crc32,
}

/// An archive being written to `out`.
pub(super) struct Zip<'a> {
    out: &'a mut dyn Write,
    /// Bytes written to `out` so far.
    offset: u64,
    done: Vec<Entry>,
    open: Option<Open>,
    /// Deflated bytes waiting to be written (reused).
    buffer: Vec<u8>,
}

impl<'a> Zip<'a> {
    pub(super) fn new(out: &'a mut dyn Write) -> Zip<'a> {
        Zip {
            out,
            offset: 0,
            done: Vec::new(),
            open: None,
            buffer: Vec::new(),
        }
    }

    fn emit(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.out.write_all(bytes)?;
        self.offset += bytes.len() as u64;
        Ok(())
    }

    /// Starts entry `name` (ending the open one), deflated or stored; `bound` is at least its
    /// size (what decides ZIP64).
    pub(super) fn begin(&mut self, name: &str, deflate: bool, bound: u64) -> io::Result<()> {
        self.end()?;
        // Deflate can grow incompressible input by a few bytes per 64 KiB block.
        let zip64 =
            bound.saturating_add(bound / 1024 + 1024) >= ZIP32_LIMIT || self.offset >= ZIP32_LIMIT;
        let mut header = Vec::with_capacity(64);
        header.extend_from_slice(&0x0403_4b50u32.to_le_bytes());
        header.extend_from_slice(&version(zip64).to_le_bytes());
        header.extend_from_slice(&(1u16 << 3).to_le_bytes()); // sizes in a data descriptor
        header.extend_from_slice(&method(deflate).to_le_bytes());
        header.extend_from_slice(&0u16.to_le_bytes()); // time
        header.extend_from_slice(&DOS_DATE.to_le_bytes());
        header.extend_from_slice(&[0; 12]); // CRC and sizes: in the descriptor
        header.extend_from_slice(&(name.len() as u16).to_le_bytes());
        let extra: &[u8] = if zip64 { &ZIP64_LOCAL_EXTRA } else { &[] };
        header.extend_from_slice(&(extra.len() as u16).to_le_bytes());
        header.extend_from_slice(name.as_bytes());
        header.extend_from_slice(extra);
        let offset = self.offset;
        self.emit(&header)?;
        let flags = create_comp_flags_from_zip_params(LEVEL, -15, 0);
        self.open = Some(Open {
            entry: Entry {
                name: name.to_string(),
                offset,
                crc: 0,
                compressed: 0,
                size: 0,
                deflated: deflate,
                zip64,
            },
            pending: Vec::with_capacity(if deflate { PIECE } else { 0 }),
            compressor: deflate.then(|| Box::new(CompressorOxide::new(flags))),
            crc: Crc32::new(),
        });
        Ok(())
    }

    /// Deflates the pending content (all of it) into the buffer, then writes the buffer.
    fn deflate(&mut self, flush: TDEFLFlush) -> io::Result<()> {
        let Some(open) = self.open.as_mut() else {
            return Ok(());
        };
        let Some(compressor) = open.compressor.as_mut() else {
            return Ok(());
        };
        let buffer = &mut self.buffer;
        buffer.clear();
        let input: &[u8] = &open.pending;
        let mut consumed = 0;
        loop {
            let (status, used) =
                compress_to_output(compressor, &input[consumed..], flush, |bytes| {
                    buffer.extend_from_slice(bytes);
                    true
                });
            consumed += used;
            match status {
                TDEFLStatus::Okay if consumed == input.len() => break,
                TDEFLStatus::Okay => continue,
                TDEFLStatus::Done => break,
                _ => return Err(io::Error::other("the deflate compressor failed")),
            }
        }
        open.pending.clear();
        open.entry.compressed += self.buffer.len() as u64;
        let buffer = std::mem::take(&mut self.buffer);
        let written = self.emit(&buffer);
        self.buffer = buffer;
        written
    }

    /// Ends the open entry, if any: the last deflate piece and the data descriptor.
    fn end(&mut self) -> io::Result<()> {
        let deflated = match &self.open {
            None => return Ok(()),
            Some(open) => open.compressor.is_some(),
        };
        if deflated {
            self.deflate(TDEFLFlush::Finish)?;
        }
        let Some(open) = self.open.take() else {
            return Ok(());
        };
        let mut entry = open.entry;
        entry.crc = open.crc.value();
        if !entry.deflated {
            entry.compressed = entry.size;
        }
        let mut descriptor = Vec::with_capacity(24);
        descriptor.extend_from_slice(&0x0807_4b50u32.to_le_bytes());
        descriptor.extend_from_slice(&entry.crc.to_le_bytes());
        if entry.zip64 {
            descriptor.extend_from_slice(&entry.compressed.to_le_bytes());
            descriptor.extend_from_slice(&entry.size.to_le_bytes());
        } else {
            descriptor.extend_from_slice(&(entry.compressed as u32).to_le_bytes());
            descriptor.extend_from_slice(&(entry.size as u32).to_le_bytes());
        }
        self.emit(&descriptor)?;
        if !entry.zip64 && (entry.compressed >= ZIP32_LIMIT || entry.size >= ZIP32_LIMIT) {
            return Err(io::Error::other(format!(
                "zip entry {} outgrew the size it was declared with",
                entry.name
            )));
        }
        self.done.push(entry);
        Ok(())
    }

    /// Ends the last entry and writes the central directory and end records.
    pub(super) fn finish(mut self) -> io::Result<()> {
        self.end()?;
        let start = self.offset;
        let entries = std::mem::take(&mut self.done);
        let any64 = entries.iter().any(|e| e.zip64);
        for entry in &entries {
            let record = central_record(entry);
            self.emit(&record)?;
        }
        let size = self.offset - start;
        let count = entries.len() as u64;
        let mut end = Vec::with_capacity(120);
        if any64 || start >= ZIP32_LIMIT {
            let zip64_end = self.offset;
            end.extend_from_slice(&0x0606_4b50u32.to_le_bytes());
            end.extend_from_slice(&44u64.to_le_bytes()); // size of the rest of this record
            end.extend_from_slice(&VERSION_ZIP64.to_le_bytes()); // made by
            end.extend_from_slice(&VERSION_ZIP64.to_le_bytes()); // needed
            end.extend_from_slice(&[0; 8]); // disk numbers
            end.extend_from_slice(&count.to_le_bytes());
            end.extend_from_slice(&count.to_le_bytes());
            end.extend_from_slice(&size.to_le_bytes());
            end.extend_from_slice(&start.to_le_bytes());
            // The locator.
            end.extend_from_slice(&0x0706_4b50u32.to_le_bytes());
            end.extend_from_slice(&0u32.to_le_bytes());
            end.extend_from_slice(&zip64_end.to_le_bytes());
            end.extend_from_slice(&1u32.to_le_bytes());
        }
        end.extend_from_slice(&0x0605_4b50u32.to_le_bytes());
        end.extend_from_slice(&[0; 4]); // disk numbers
        end.extend_from_slice(&(count as u16).to_le_bytes());
        end.extend_from_slice(&(count as u16).to_le_bytes());
        end.extend_from_slice(&clamp32(size).to_le_bytes());
        end.extend_from_slice(&clamp32(start).to_le_bytes());
        end.extend_from_slice(&0u16.to_le_bytes()); // comment length
        self.emit(&end)?;
        self.out.flush()
    }
}

impl Write for Zip<'_> {
    fn write(&mut self, bytes: &[u8]) -> io::Result<usize> {
        self.write_all(bytes)?;
        Ok(bytes.len())
    }

    fn write_all(&mut self, mut bytes: &[u8]) -> io::Result<()> {
        let Some(open) = self.open.as_mut() else {
            return Err(io::Error::other("zip: bytes written outside an entry"));
        };
        open.crc.update(bytes);
        open.entry.size += bytes.len() as u64;
        if open.compressor.is_none() {
            return self.emit(bytes);
        }
        while !bytes.is_empty() {
            let Some(open) = self.open.as_mut() else {
                break;
            };
            let take = (PIECE - open.pending.len()).min(bytes.len());
            open.pending.extend_from_slice(&bytes[..take]);
            bytes = &bytes[take..];
            if open.pending.len() == PIECE {
                self.deflate(TDEFLFlush::None)?;
            }
        }
        Ok(())
    }

    /// Entry bytes are only final at [`Zip::finish`]; this flushes what `out` holds.
    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}

/// The local header's ZIP64 extra field: tag, size, then zero sizes (they follow the data).
const ZIP64_LOCAL_EXTRA: [u8; 20] = [1, 0, 16, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];

fn version(zip64: bool) -> u16 {
    if zip64 {
        VERSION_ZIP64
    } else {
        VERSION_DEFLATE
    }
}

fn method(deflate: bool) -> u16 {
    if deflate { 8 } else { 0 }
}

fn clamp32(v: u64) -> u32 {
    v.min(ZIP32_LIMIT) as u32
}

/// An entry's central directory record (ZIP64 fields for what does not fit 32 bits).
fn central_record(e: &Entry) -> Vec<u8> {
    let big = |v: u64| v >= ZIP32_LIMIT;
    // A ZIP64 entry's sizes are marked 0xFFFFFFFF here and given in the ZIP64 extra field,
    // which holds, in this order, exactly the values marked: sizes, then a far offset.
    let (size, compressed) = if e.zip64 {
        (ZIP32_LIMIT as u32, ZIP32_LIMIT as u32)
    } else {
        (e.size as u32, e.compressed as u32)
    };
    let mut extra = Vec::new();
    if e.zip64 {
        extra.extend_from_slice(&e.size.to_le_bytes());
        extra.extend_from_slice(&e.compressed.to_le_bytes());
    }
    if big(e.offset) {
        extra.extend_from_slice(&e.offset.to_le_bytes());
    }
    let offset = clamp32(e.offset);
    let mut r = Vec::with_capacity(46 + e.name.len() + 4 + extra.len());
    r.extend_from_slice(&0x0201_4b50u32.to_le_bytes());
    let needed = version(e.zip64 || big(e.offset));
    r.extend_from_slice(&needed.to_le_bytes()); // made by (MS-DOS attributes)
    r.extend_from_slice(&needed.to_le_bytes());
    r.extend_from_slice(&(1u16 << 3).to_le_bytes());
    r.extend_from_slice(&method(e.deflated).to_le_bytes());
    r.extend_from_slice(&0u16.to_le_bytes());
    r.extend_from_slice(&DOS_DATE.to_le_bytes());
    r.extend_from_slice(&e.crc.to_le_bytes());
    r.extend_from_slice(&compressed.to_le_bytes());
    r.extend_from_slice(&size.to_le_bytes());
    r.extend_from_slice(&(e.name.len() as u16).to_le_bytes());
    let extra_len = if extra.is_empty() { 0 } else { 4 + extra.len() };
    r.extend_from_slice(&(extra_len as u16).to_le_bytes());
    r.extend_from_slice(&[0; 6]); // comment length, disk, internal attributes
    r.extend_from_slice(&0u32.to_le_bytes()); // external attributes
    r.extend_from_slice(&offset.to_le_bytes());
    r.extend_from_slice(e.name.as_bytes());
    if !extra.is_empty() {
        r.extend_from_slice(&1u16.to_le_bytes());
        r.extend_from_slice(&(extra.len() as u16).to_le_bytes());
        r.extend_from_slice(&extra);
    }
    r
}

/// CRC-32 (IEEE, reflected, as zip uses), eight bytes a step through eight tables.
pub(super) struct Crc32(u32);

static CRC_TABLES: std::sync::OnceLock<[[u32; 256]; 8]> = std::sync::OnceLock::new();

fn crc_tables() -> &'static [[u32; 256]; 8] {
    CRC_TABLES.get_or_init(|| {
        let mut t = [[0u32; 256]; 8];
        for (i, entry) in t[0].iter_mut().enumerate() {
            let mut c = i as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
            *entry = c;
        }
        // Table k advances a byte through k more zero bytes.
        for k in 1..8 {
            let (done, rest) = t.split_at_mut(k);
            for (entry, &prev) in rest[0].iter_mut().zip(&done[k - 1]) {
                *entry = (prev >> 8) ^ done[0][(prev & 0xFF) as usize];
            }
        }
        t
    })
}

impl Crc32 {
    pub(super) fn new() -> Crc32 {
        Crc32(0xFFFF_FFFF)
    }

    pub(super) fn update(&mut self, bytes: &[u8]) {
        let t = crc_tables();
        let mut c = self.0;
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            let lo = c ^ u32::from_le_bytes([w[0], w[1], w[2], w[3]]);
            let hi = u32::from_le_bytes([w[4], w[5], w[6], w[7]]);
            c = t[7][(lo & 0xFF) as usize]
                ^ t[6][((lo >> 8) & 0xFF) as usize]
                ^ t[5][((lo >> 16) & 0xFF) as usize]
                ^ t[4][(lo >> 24) as usize]
                ^ t[3][(hi & 0xFF) as usize]
                ^ t[2][((hi >> 8) & 0xFF) as usize]
                ^ t[1][((hi >> 16) & 0xFF) as usize]
                ^ t[0][(hi >> 24) as usize];
        }
        for &b in words.remainder() {
            c = (c >> 8) ^ t[0][((c ^ u32::from(b)) & 0xFF) as usize];
        }
        self.0 = c;
    }

    pub(super) fn value(&self) -> u32 {
        !self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bit-at-a-time definition.
    fn crc_slow(bytes: &[u8]) -> u32 {
        let mut c = 0xFFFF_FFFFu32;
        for &b in bytes {
            c ^= u32::from(b);
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }

    #[test]
    fn crc_is_the_standard_one() {
        // The check value of CRC-32/ISO-HDLC.
        let mut crc = Crc32::new();
        crc.update(b"123456789");
        assert_eq!(crc.value(), 0xCBF4_3926);
        let data: Vec<u8> = (0..10_007u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
            .collect();
        let mut crc = Crc32::new();
        crc.update(&data[..13]);
        crc.update(&data[13..]);
        assert_eq!(crc.value(), crc_slow(&data));
    }

    /// An archive's bytes do not depend on how its entries' content was cut into writes, and
    /// its deflated entry inflates back to the content.
    #[test]
    fn entries_inflate_back_and_writes_do_not_matter() {
        let content: Vec<u8> = (0..300_000u32)
            .flat_map(|i| format!("<vertex x=\"{}\"/>\n", i % 977).into_bytes())
            .collect();
        let write = |cut: usize| {
            let mut out = Vec::new();
            let mut zip = Zip::new(&mut out);
            zip.begin("a.txt", false, 3).expect("begin");
            zip.write_all(b"abc").expect("stored");
            zip.begin("b.xml", true, content.len() as u64)
                .expect("begin");
            for piece in content.chunks(cut) {
                zip.write_all(piece).expect("write");
            }
            zip.finish().expect("finish");
            out
        };
        let one = write(1 << 20);
        assert_eq!(one, write(7));
        assert_eq!(one, write(PIECE));
        // The deflated data sits after the second local header (30 bytes + name).
        let second = 30 + 5 + 3 + 16;
        assert_eq!(&one[second..second + 4], &0x0403_4b50u32.to_le_bytes());
        let data = &one[second + 30 + 5..];
        let inflated = miniz_oxide::inflate::decompress_to_vec(data).expect("inflates");
        assert_eq!(inflated, content);
    }
}
