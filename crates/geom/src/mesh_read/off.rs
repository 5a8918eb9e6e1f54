//! Object File Format: a keyword line (`OFF`, or `COFF`/`NOFF`/`CNOFF`/`STOFF`… for the
//! variants that add colours, normals or texture coordinates after each position), the counts
//! `V F [E]` (possibly on the keyword line), `V` vertex lines `x y z …`, then `F` face lines
//! `n i1 … in …` with 0-based indices. Values after the ones we need on a line (colours,
//! normals) are ignored. Blank lines and `#` comments may appear anywhere.
//!
//! Not supported: `OFF BINARY` and the `4OFF`/`nOFF` dimension variants.

use super::text;
use super::{Format, Location, MeshReadError, TriangleSoup};

/// `OFF` with any of the optional prefixes `ST`, `C`, `N`, `4`, `n`.
pub(super) fn is_keyword(token: &[u8]) -> bool {
    token.ends_with(b"OFF")
        && token[..token.len() - 3]
            .iter()
            .all(|b| b"STCN4n".contains(b))
}

fn unexpected(line: usize, expected: impl Into<String>, found: &[u8]) -> MeshReadError {
    MeshReadError::Unexpected {
        format: Format::Off,
        at: Location::Line(line),
        expected: expected.into(),
        found: if found.is_empty() {
            "the end of the line".into()
        } else {
            text::show(found)
        },
    }
}

pub(super) fn read(bytes: &[u8]) -> Result<TriangleSoup, MeshReadError> {
    let mut lines = text::lines(bytes)
        .map(|(n, line)| (n, text::strip_comment(line)))
        .filter(|(_, line)| text::tokens(line).next().is_some());
    let mut last_line = 1;
    let mut next_line = |expected: &str| {
        lines
            .next()
            .inspect(|(n, _)| last_line = *n)
            .ok_or_else(|| MeshReadError::Truncated {
                format: Format::Off,
                at: Location::Line(last_line),
                expected: expected.to_string(),
            })
    };

    let (line_no, line) = next_line("the `OFF` keyword")?;
    let mut tokens = text::tokens(line);
    let keyword = tokens.next().unwrap_or_default();
    if !is_keyword(keyword) {
        return Err(unexpected(line_no, "the `OFF` keyword", keyword));
    }
    if keyword.contains(&b'4') || keyword.contains(&b'n') {
        return Err(MeshReadError::Unsupported {
            format: Format::Off,
            at: Location::Line(line_no),
            what: format!("the dimension variant {}", text::show(keyword)),
        });
    }
    let mut rest: Vec<&[u8]> = tokens.collect();
    if rest.first() == Some(&&b"BINARY"[..]) {
        return Err(MeshReadError::Unsupported {
            format: Format::Off,
            at: Location::Line(line_no),
            what: "binary OFF".into(),
        });
    }
    let mut counts_line = line_no;
    if rest.is_empty() {
        let (n, line) = next_line("the counts line `vertices faces edges`")?;
        counts_line = n;
        rest = text::tokens(line).collect();
    }
    let count = |i: usize, what: &str| {
        let token = rest.get(i).copied().unwrap_or_default();
        text::int(token)
            .and_then(|v| usize::try_from(v).ok())
            .ok_or_else(|| unexpected(counts_line, format!("the {what} count"), token))
    };
    let (nv, nf) = (count(0, "vertex")?, count(1, "face")?);

    // Each vertex and face takes at least one line, so the input bounds what we reserve.
    let lines_left = bytes.len() / 2 + 1;
    let mut soup = TriangleSoup {
        positions: Vec::with_capacity(nv.min(lines_left)),
        triangles: Vec::with_capacity(nf.min(lines_left)),
    };
    for v in 0..nv {
        let (n, line) = next_line(&format!("vertex {v} of the {nv} declared"))?;
        let mut tokens = text::tokens(line);
        let mut p = [0.0; 3];
        for c in &mut p {
            let token = tokens.next().unwrap_or_default();
            *c = text::float(token)
                .ok_or_else(|| unexpected(n, "three vertex coordinates", token))?;
            if !c.is_finite() {
                return Err(MeshReadError::NonFinite {
                    format: Format::Off,
                    at: Location::Line(n),
                    vertex: v,
                    value: *c,
                });
            }
        }
        soup.positions.push(p);
    }
    let mut corners = Vec::new();
    for face in 0..nf {
        let (n, line) = next_line(&format!("face {face} of the {nf} declared"))?;
        let mut tokens = text::tokens(line);
        let token = tokens.next().unwrap_or_default();
        let size = text::int(token)
            .filter(|&k| k >= 3)
            .ok_or_else(|| unexpected(n, "a corner count of at least 3", token))?;
        corners.clear();
        for _ in 0..size {
            let token = tokens.next().unwrap_or_default();
            let index = text::int(token)
                .ok_or_else(|| unexpected(n, format!("{size} vertex indices"), token))?;
            if index < 0 || index >= nv as i64 {
                return Err(MeshReadError::IndexOutOfRange {
                    format: Format::Off,
                    at: Location::Line(n),
                    face,
                    index,
                    count: nv,
                });
            }
            corners.push(index as u32);
        }
        for i in 1..corners.len() - 1 {
            soup.triangles
                .push([corners[0], corners[i], corners[i + 1]]);
        }
    }
    Ok(soup)
}
