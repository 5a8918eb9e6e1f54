//! Wavefront OBJ: `v x y z [w | r g b]` and `f a b c …` records; everything else (`vt`, `vn`,
//! groups, materials, lines, comments) is skipped.
//!
//! Face corners are `v`, `v/vt`, `v//vn` or `v/vt/vn`; only `v` matters. Positive indices count
//! from 1; negative ones count back from the last vertex defined so far (`-1` is the latest).
//! Positive indices may point forward to vertices defined later in the file (some exporters
//! write faces first), so their range is checked once the whole file is read.

use super::text;
use super::{Format, Location, MeshReadError, TriangleSoup};

/// The first positive index found out of range, kept for the error message.
struct Forward {
    index: i64,
    line: usize,
    face: usize,
}

pub(super) fn read(bytes: &[u8]) -> Result<TriangleSoup, MeshReadError> {
    let mut soup = TriangleSoup::default();
    let mut corners: Vec<u32> = Vec::new();
    let mut faces = 0usize;
    // The largest positive index seen (1-based) and where, checked against the final count.
    let mut largest: Option<Forward> = None;
    for (line_no, line) in text::lines(bytes) {
        let mut tokens = text::tokens(text::strip_comment(line));
        match tokens.next() {
            Some(b"v") => {
                let mut p = [0.0; 3];
                for c in &mut p {
                    let token = tokens.next().unwrap_or_default();
                    *c = text::float(token).ok_or_else(|| MeshReadError::Unexpected {
                        format: Format::Obj,
                        at: Location::Line(line_no),
                        expected: "three vertex coordinates".into(),
                        found: if token.is_empty() {
                            "the end of the line".into()
                        } else {
                            text::show(token)
                        },
                    })?;
                    if !c.is_finite() {
                        return Err(MeshReadError::NonFinite {
                            format: Format::Obj,
                            at: Location::Line(line_no),
                            vertex: soup.positions.len(),
                            value: *c,
                        });
                    }
                }
                soup.positions.push(p);
            }
            Some(b"f") => {
                corners.clear();
                for token in tokens {
                    let vertex = token.split(|&b| b == b'/').next().unwrap_or_default();
                    let index = text::int(vertex).filter(|&i| i != 0).ok_or_else(|| {
                        MeshReadError::Unexpected {
                            format: Format::Obj,
                            at: Location::Line(line_no),
                            expected: "a nonzero vertex index (`v`, `v/vt`, `v//vn` or `v/vt/vn`)"
                                .into(),
                            found: text::show(token),
                        }
                    })?;
                    let count = soup.positions.len();
                    let resolved = if index < 0 {
                        // Relative to the vertices defined so far.
                        let back = index.unsigned_abs();
                        if back > count as u64 {
                            return Err(MeshReadError::IndexOutOfRange {
                                format: Format::Obj,
                                at: Location::Line(line_no),
                                face: faces,
                                index,
                                count,
                            });
                        }
                        (count as u64 - back) as i64
                    } else {
                        if index > u32::MAX as i64 {
                            return Err(MeshReadError::IndexOutOfRange {
                                format: Format::Obj,
                                at: Location::Line(line_no),
                                face: faces,
                                index,
                                count,
                            });
                        }
                        if largest.as_ref().is_none_or(|l| index > l.index) {
                            largest = Some(Forward {
                                index,
                                line: line_no,
                                face: faces,
                            });
                        }
                        index - 1
                    };
                    corners.push(resolved as u32);
                }
                if corners.len() < 3 {
                    return Err(MeshReadError::Unexpected {
                        format: Format::Obj,
                        at: Location::Line(line_no),
                        expected: "a face of at least three vertices".into(),
                        found: format!("{} vertices", corners.len()),
                    });
                }
                for i in 1..corners.len() - 1 {
                    soup.triangles
                        .push([corners[0], corners[i], corners[i + 1]]);
                }
                faces += 1;
            }
            _ => {}
        }
    }
    if let Some(l) = largest
        && l.index as u64 > soup.positions.len() as u64
    {
        return Err(MeshReadError::IndexOutOfRange {
            format: Format::Obj,
            at: Location::Line(l.line),
            face: l.face,
            index: l.index,
            count: soup.positions.len(),
        });
    }
    Ok(soup)
}
