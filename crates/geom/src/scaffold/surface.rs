//! OBJ and OFF surface meshes as tri3 or quad4 scaffolds (one of the two per file).
//!
//! Invariants:
//! - Faces keep their corner order (no triangulation); faces of other sizes are polygons that
//!   the assembler rejects by name.
//! - OBJ: `v` and `f` records only (`f a/b/c`, negative indices relative to the vertices so
//!   far); node and element tags are 1-based like OBJ's indices. OFF: 0-based tags; extra
//!   values on vertex or face lines (colours) are ignored.

use super::assemble::{ElementType, RawMesh};
use super::cursor::{Cursor, Locator, show};
use super::{ElementKind, Scaffold, ScaffoldError};

fn face_type(raw: &mut RawMesh, corners: usize) -> u16 {
    let ty = match corners {
        3 => ElementType::of(ElementKind::Tri3),
        4 => ElementType::of(ElementKind::Quad4),
        n => ElementType {
            name: format!("polygon{n}"),
            dimension: 2,
            kind: None,
        },
    };
    raw.type_index(ty)
}

pub(super) fn read_obj(bytes: &[u8], name: &str) -> Result<Scaffold, ScaffoldError> {
    let loc = Locator {
        bytes,
        name,
        binary: false,
    };
    let mut raw = RawMesh::default();
    let mut offset = 0;
    for line in bytes.split(|&b| b == b'\n') {
        let at = offset;
        offset += line.len() + 1;
        let mut words = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|w| !w.is_empty());
        match words.next() {
            Some(b"v") => {
                let mut p = [0.0; 3];
                for c in &mut p {
                    let w = words.next().ok_or_else(|| {
                        loc.error(at, "expected three vertex coordinates after `v`")
                    })?;
                    let v: f64 = std::str::from_utf8(w)
                        .ok()
                        .and_then(|s| s.parse().ok())
                        .ok_or_else(|| {
                            loc.error(
                                at,
                                format!("expected a vertex coordinate, found `{}`", show(w)),
                            )
                        })?;
                    *c = super::cursor::finite(v, "a vertex coordinate")
                        .map_err(|m| loc.error(at, m))?;
                }
                let tag = raw.nodes.len() as u64 + 1;
                raw.push_node(tag, p, at);
            }
            Some(b"f") => {
                let count = raw.nodes.len() as i64;
                let mut tags = Vec::new();
                for w in words {
                    let index = w.split(|&b| b == b'/').next().unwrap_or(w);
                    let i: i64 = std::str::from_utf8(index)
                        .ok()
                        .and_then(|s| s.parse().ok())
                        .ok_or_else(|| {
                            loc.error(at, format!("expected a vertex index, found `{}`", show(w)))
                        })?;
                    let resolved = if i < 0 { count + 1 + i } else { i };
                    if resolved < 1 {
                        return Err(loc.error(
                            at,
                            format!("vertex index {i} refers to no vertex ({count} so far)"),
                        ));
                    }
                    tags.push(resolved as u64);
                }
                if tags.len() < 3 {
                    return Err(loc.error(
                        at,
                        format!("a face needs at least 3 vertices, found {}", tags.len()),
                    ));
                }
                let t = face_type(&mut raw, tags.len());
                let tag = raw.element_tags.len() as u64 + 1;
                raw.begin_element(t, tag, 0, at);
                raw.element_nodes.extend_from_slice(&tags);
            }
            _ => {}
        }
    }
    raw.finish(loc)
}

pub(super) fn read_off(bytes: &[u8], name: &str) -> Result<Scaffold, ScaffoldError> {
    let mut cur = Cursor::new(bytes, name);
    let (at, header) = cur.token("OFF")?;
    if !header.ends_with(b"OFF") {
        return Err(cur.error(at, format!("expected `OFF`, found `{}`", show(header))));
    }
    skip_comments(&mut cur);
    let nv = cur.count("the number of vertices", 6)?;
    let nf = cur.count("the number of faces", 4)?;
    cur.uint("the number of edges")?;
    cur.skip_line();
    let mut raw = RawMesh {
        indices_as_tags: true,
        ..RawMesh::default()
    };
    raw.nodes.reserve(nv);
    for i in 0..nv {
        skip_comments(&mut cur);
        let at = cur.mark();
        let mut p = [0.0; 3];
        for c in &mut p {
            *c = cur.float("a vertex coordinate")?;
        }
        cur.skip_line();
        raw.push_node(i as u64, p, at);
    }
    for f in 0..nf {
        skip_comments(&mut cur);
        let at = cur.mark();
        let k = cur.count("a face's vertex count", 2)?;
        if k < 3 {
            return Err(cur.error(
                at,
                format!("face {f} has {k} vertices: a face needs at least 3"),
            ));
        }
        let t = face_type(&mut raw, k);
        raw.begin_element(t, f as u64, 0, at);
        for _ in 0..k {
            let v = cur.uint("a vertex index")?;
            raw.element_nodes.push(v);
        }
        cur.skip_line();
    }
    let loc = cur.loc;
    raw.finish(loc)
}

fn skip_comments(cur: &mut Cursor<'_>) {
    loop {
        cur.skip_whitespace();
        if cur.bytes().get(cur.pos) == Some(&b'#') {
            cur.skip_line();
        } else {
            return;
        }
    }
}
