//! The parts of a zip archive (a 3MF package), found through its central directory and
//! inflated on demand.
//!
//! Invariants: no input panics; every offset and size read from the archive is checked against
//! the bytes before use; an inflated part is at most [`MAX_RATIO`] times its compressed size
//! (deflate's own limit is 1032) and must have exactly the size and CRC-32 its directory
//! record declares, or the archive is refused as corrupt.

use miniz_oxide::inflate::decompress_to_vec_with_limit;

/// Deflate cannot expand more than 1032:1.
const MAX_RATIO: u64 = 1032;

/// A part of the archive, as its central directory record gives it.
#[derive(Clone, Debug)]
pub(super) struct Part {
    pub name: String,
    method: u16,
    crc: u32,
    compressed: u64,
    size: u64,
    local_offset: u64,
}

/// Why an archive cannot be read, with the byte offset of the problem.
#[derive(Clone, Debug)]
pub(super) struct ZipError {
    pub at: usize,
    pub what: String,
}

fn err(at: usize, what: impl Into<String>) -> ZipError {
    ZipError {
        at,
        what: what.into(),
    }
}

// `at` may be anything a corrupt archive says: the ends are added with overflow checked.
fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(
        b.get(at..at.checked_add(2)?)?.try_into().ok()?,
    ))
}
fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(
        b.get(at..at.checked_add(4)?)?.try_into().ok()?,
    ))
}
fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(
        b.get(at..at.checked_add(8)?)?.try_into().ok()?,
    ))
}

/// The parts of the archive `bytes`, in directory order.
pub(super) fn parts(bytes: &[u8]) -> Result<Vec<Part>, ZipError> {
    // The end record: 22 bytes plus a comment of at most 65535, searched from the end.
    let lowest = bytes.len().saturating_sub(22 + 0xFFFF);
    let end = (lowest..=bytes.len().saturating_sub(22))
        .rev()
        .find(|&i| u32_at(bytes, i) == Some(0x0605_4b50))
        .ok_or_else(|| {
            err(
                bytes.len(),
                "no end of central directory: not a zip archive",
            )
        })?;
    let mut count = u64::from(u16_at(bytes, end + 10).unwrap_or(0));
    let mut dir_size = u64::from(u32_at(bytes, end + 12).unwrap_or(0));
    let mut dir_start = u64::from(u32_at(bytes, end + 16).unwrap_or(0));
    // A ZIP64 locator sits right before the end record.
    if end >= 20 && u32_at(bytes, end - 20) == Some(0x0706_4b50) {
        let record = u64_at(bytes, end - 12).unwrap_or(u64::MAX);
        let record = usize::try_from(record).unwrap_or(usize::MAX);
        if u32_at(bytes, record) != Some(0x0606_4b50) {
            return Err(err(
                end - 20,
                "the ZIP64 locator points at no ZIP64 end record",
            ));
        }
        let field = |offset| u64_at(bytes, record + offset).ok_or_else(|| err(record, "cut"));
        count = field(32)?;
        dir_size = field(40)?;
        dir_start = field(48)?;
    }
    let start = usize::try_from(dir_start).unwrap_or(usize::MAX);
    let stop = start.saturating_add(usize::try_from(dir_size).unwrap_or(usize::MAX));
    if stop > bytes.len() {
        return Err(err(
            end,
            "the central directory lies past the end of the file",
        ));
    }
    let mut parts = Vec::new();
    let mut at = start;
    for _ in 0..count {
        if u32_at(bytes, at) != Some(0x0201_4b50) {
            return Err(err(at, "expected a central directory record"));
        }
        let cut = || err(at, "a central directory record is cut short");
        let method = u16_at(bytes, at + 10).ok_or_else(cut)?;
        let crc = u32_at(bytes, at + 16).ok_or_else(cut)?;
        let mut compressed = u64::from(u32_at(bytes, at + 20).ok_or_else(cut)?);
        let mut size = u64::from(u32_at(bytes, at + 24).ok_or_else(cut)?);
        let name_len = usize::from(u16_at(bytes, at + 28).ok_or_else(cut)?);
        let extra_len = usize::from(u16_at(bytes, at + 30).ok_or_else(cut)?);
        let comment_len = usize::from(u16_at(bytes, at + 32).ok_or_else(cut)?);
        let mut local_offset = u64::from(u32_at(bytes, at + 42).ok_or_else(cut)?);
        let name = bytes.get(at + 46..at + 46 + name_len).ok_or_else(cut)?;
        let name = String::from_utf8_lossy(name).into_owned();
        let extra_start = at + 46 + name_len;
        let extra = bytes
            .get(extra_start..extra_start + extra_len)
            .ok_or_else(cut)?;
        // ZIP64 extra field: the values marked 0xFFFFFFFF, in order.
        let mut e = 0;
        while e + 4 <= extra.len() {
            let tag = u16_at(extra, e).unwrap_or(0);
            let len = usize::from(u16_at(extra, e + 2).unwrap_or(0));
            if tag == 1 {
                let mut k = e + 4;
                for value in [&mut size, &mut compressed, &mut local_offset] {
                    if *value == 0xFFFF_FFFF {
                        *value = u64_at(extra, k).ok_or_else(cut)?;
                        k += 8;
                    }
                }
            }
            e += 4 + len;
        }
        parts.push(Part {
            name,
            method,
            crc,
            compressed,
            size,
            local_offset,
        });
        at = extra_start + extra_len + comment_len;
    }
    Ok(parts)
}

/// The content of `part`, inflated and checked.
pub(super) fn content(bytes: &[u8], part: &Part) -> Result<Vec<u8>, ZipError> {
    let local = usize::try_from(part.local_offset).unwrap_or(usize::MAX);
    if u32_at(bytes, local) != Some(0x0403_4b50) {
        return Err(err(
            local,
            format!("no local header for part {}", part.name),
        ));
    }
    let cut = || err(local, format!("part {} is cut short", part.name));
    let name_len = usize::from(u16_at(bytes, local + 26).ok_or_else(cut)?);
    let extra_len = usize::from(u16_at(bytes, local + 28).ok_or_else(cut)?);
    let data_start = local + 30 + name_len + extra_len;
    let data_len = usize::try_from(part.compressed).map_err(|_| cut())?;
    let data = bytes
        .get(data_start..data_start.saturating_add(data_len))
        .ok_or_else(cut)?;
    let content = match part.method {
        0 => data.to_vec(),
        8 => {
            let limit = part.size.min(MAX_RATIO.saturating_mul(part.compressed));
            let limit = usize::try_from(limit).map_err(|_| cut())?;
            decompress_to_vec_with_limit(data, limit).map_err(|e| {
                err(
                    data_start,
                    format!("part {} does not inflate ({:?})", part.name, e.status),
                )
            })?
        }
        m => {
            return Err(err(
                local,
                format!(
                    "part {} is compressed by method {m}, not deflate",
                    part.name
                ),
            ));
        }
    };
    if content.len() as u64 != part.size || crate::mesh_io::crc32(&content) != part.crc {
        return Err(err(
            data_start,
            format!("part {} is corrupt (size or CRC-32 differ)", part.name),
        ));
    }
    Ok(content)
}
