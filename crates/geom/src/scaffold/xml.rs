//! Just enough XML for VTK files: start/end tags with attributes, the text up to the next tag,
//! comments and declarations skipped; base64 decoding.
//!
//! Invariants: no panics on any input; positions are byte offsets into the input.

/// One start, end or empty-element tag.
pub(super) struct Tag<'a> {
    pub name: &'a [u8],
    pub attributes: Vec<(&'a [u8], &'a [u8])>,
    /// Offset of `<`.
    pub start: usize,
    /// Offset just after `>`.
    pub end: usize,
    pub closing: bool,
    pub empty: bool,
}

impl<'a> Tag<'a> {
    pub fn attribute(&self, name: &str) -> Option<&'a [u8]> {
        self.attributes
            .iter()
            .find(|(k, _)| *k == name.as_bytes())
            .map(|&(_, v)| v)
    }

    pub fn attribute_str(&self, name: &str) -> Option<String> {
        self.attribute(name)
            .map(|v| String::from_utf8_lossy(v).into_owned())
    }
}

/// The next tag at or after `from`, or `Err(offset)` for a `<` that never closes.
pub(super) fn next_tag(bytes: &[u8], from: usize) -> Option<Result<Tag<'_>, usize>> {
    let mut pos = from;
    loop {
        let lt = pos + bytes.get(pos..)?.iter().position(|&b| b == b'<')?;
        let rest = &bytes[lt..];
        if rest.starts_with(b"<!--") {
            match find(bytes, b"-->", lt) {
                Some(k) => pos = k + 3,
                None => return Some(Err(lt)),
            }
            continue;
        }
        let gt = match bytes[lt..].iter().position(|&b| b == b'>') {
            Some(k) => lt + k,
            None => return Some(Err(lt)),
        };
        if rest.starts_with(b"<?") || rest.starts_with(b"<!") {
            pos = gt + 1;
            continue;
        }
        let mut inner = &bytes[lt + 1..gt];
        let closing = inner.first() == Some(&b'/');
        if closing {
            inner = &inner[1..];
        }
        let empty = inner.last() == Some(&b'/');
        if empty {
            inner = &inner[..inner.len() - 1];
        }
        let name_len = inner
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .unwrap_or(inner.len());
        let name = &inner[..name_len];
        let mut attributes = Vec::new();
        let mut i = name_len;
        while i < inner.len() {
            while i < inner.len() && inner[i].is_ascii_whitespace() {
                i += 1;
            }
            let key_start = i;
            while i < inner.len() && inner[i] != b'=' && !inner[i].is_ascii_whitespace() {
                i += 1;
            }
            let key = &inner[key_start..i];
            while i < inner.len() && inner[i].is_ascii_whitespace() {
                i += 1;
            }
            if i >= inner.len() || inner[i] != b'=' {
                break;
            }
            i += 1;
            while i < inner.len() && inner[i].is_ascii_whitespace() {
                i += 1;
            }
            let Some(&quote) = inner.get(i) else { break };
            if quote != b'"' && quote != b'\'' {
                break;
            }
            let value_start = i + 1;
            let Some(len) = inner[value_start..].iter().position(|&b| b == quote) else {
                break;
            };
            attributes.push((key, &inner[value_start..value_start + len]));
            i = value_start + len + 1;
        }
        return Some(Ok(Tag {
            name,
            attributes,
            start: lt,
            end: gt + 1,
            closing,
            empty,
        }));
    }
}

pub(super) fn find(bytes: &[u8], pattern: &[u8], from: usize) -> Option<usize> {
    bytes
        .get(from..)?
        .windows(pattern.len())
        .position(|w| w == pattern)
        .map(|k| from + k)
}

fn base64_value(c: u8) -> Option<u32> {
    Some(match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => return None,
    } as u32)
}

/// Decodes base64, ignoring whitespace. Padding may also end a group in the middle, so that
/// separately encoded pieces written one after the other (VTK's header, then its data) decode
/// to the pieces one after the other. `Err(offset)` gives the first invalid character.
pub(super) fn base64_decode(text: &[u8], offset: usize) -> Result<Vec<u8>, usize> {
    let mut out = Vec::with_capacity(text.len() / 4 * 3);
    let mut group = [0u32; 4];
    let mut n = 0;
    let mut pads = 0;
    for (i, &c) in text.iter().enumerate() {
        if c.is_ascii_whitespace() {
            continue;
        }
        if c == b'=' {
            if n < 2 {
                return Err(offset + i);
            }
            pads += 1;
            group[n] = 0;
            n += 1;
        } else {
            if pads > 0 {
                return Err(offset + i);
            }
            group[n] = base64_value(c).ok_or(offset + i)?;
            n += 1;
        }
        if n == 4 {
            let v = group[0] << 18 | group[1] << 12 | group[2] << 6 | group[3];
            let bytes = [(v >> 16) as u8, (v >> 8) as u8, v as u8];
            out.extend_from_slice(&bytes[..3 - pads]);
            n = 0;
            pads = 0;
        }
    }
    if n != 0 {
        return Err(offset + text.len());
    }
    Ok(out)
}
