//! Abaqus `.inp`: `*NODE`, `*ELEMENT, TYPE=…` and `*ELSET` (plain or `GENERATE`); every other
//! keyword and its data lines are skipped; `**` lines are comments.
//!
//! Invariants:
//! - Element types map by family and node count: C3D4/C3D10/C3D8/C3D20 (any suffix: R, H, I,
//!   M, …) to tet4/tet10/hex8/hex20, and the plane, axisymmetric, shell and membrane families
//!   (CPS, CPE, CAX, S, STRI, M3D, R3D, SFM3D, …) with 3/4/6/8/9 nodes to tri3/quad4/tri6/
//!   quad8/quad9. Abaqus's C3D10 and C3D20 orders are rewritten into Gmsh's.
//! - Element sets become physical groups numbered from 1 in order of appearance; an element's
//!   group is the first standalone `*ELSET` that lists it, else its `*ELEMENT`'s `ELSET`.
//! - Data lines continue an element over several lines until it has all its nodes.

use std::collections::HashMap;

use super::assemble::{ElementType, RawMesh};
use super::cursor::Locator;
use super::{ElementKind, Scaffold, ScaffoldError};

const C3D20_FROM_ABAQUS: [usize; 20] = [
    0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 16, 9, 17, 10, 18, 19, 12, 15, 13, 14,
];

/// The element type an Abaqus type name stands for, with its node count.
fn abaqus_type(name: &str) -> Option<(ElementType, usize)> {
    let digits = |prefix: &str| -> Option<u32> {
        let rest = name.strip_prefix(prefix)?;
        let d: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
        d.parse().ok()
    };
    let kind3 = |n| match n {
        4 => Some((Some(ElementKind::Tet4), 4)),
        10 => Some((Some(ElementKind::Tet10), 10)),
        8 => Some((Some(ElementKind::Hex8), 8)),
        20 => Some((Some(ElementKind::Hex20), 20)),
        6 | 15 | 5 | 13 | 27 => Some((None, n as usize)),
        _ => None,
    };
    let kind2 = |n| match n {
        3 => Some((ElementKind::Tri3, 3)),
        4 => Some((ElementKind::Quad4, 4)),
        6 | 65 => Some((ElementKind::Tri6, 6)),
        8 => Some((ElementKind::Quad8, 8)),
        9 => Some((ElementKind::Quad9, 9)),
        _ => None,
    };
    for family in ["DC3D", "C3D"] {
        if let Some(n) = digits(family) {
            let (kind, nodes) = kind3(n)?;
            return Some((
                ElementType {
                    name: kind.map_or(format!("Abaqus {name}"), |k| k.name().to_string()),
                    dimension: 3,
                    kind,
                },
                nodes,
            ));
        }
    }
    for family in [
        "SFM3D", "CPEG", "CGAX", "DC2D", "STRI", "M3D", "R3D", "CPS", "CPE", "CAX", "DS", "S",
    ] {
        if let Some(n) = digits(family) {
            let (kind, nodes) = kind2(n)?;
            return Some((ElementType::of(kind), nodes));
        }
    }
    for family in ["T2D", "T3D", "B2", "B3", "CONN"] {
        if let Some(n) = digits(family) {
            let nodes = (n % 10).max(2) as usize;
            return Some((
                ElementType {
                    name: format!("Abaqus {name}"),
                    dimension: 1,
                    kind: None,
                },
                nodes,
            ));
        }
    }
    None
}

/// Gmsh's local node `i` is the Abaqus local node `abaqus_local(kind, i)`.
fn abaqus_local(kind: Option<ElementKind>, i: usize) -> usize {
    match kind {
        Some(ElementKind::Tet10) if i >= 8 => 17 - i,
        Some(ElementKind::Hex20) => C3D20_FROM_ABAQUS[i],
        _ => i,
    }
}

enum State {
    Skip,
    Node,
    Element { t: u16, nodes: usize, set: i64 },
    Elset { set: i64, generate: bool },
}

/// An element still collecting its node tags (possibly over several lines).
struct Pending {
    tag: u64,
    at: usize,
    t: u16,
    nodes: usize,
    set: i64,
    tags: Vec<u64>,
}

pub(super) fn read(bytes: &[u8], name: &str) -> Result<Scaffold, ScaffoldError> {
    let loc = Locator {
        bytes,
        name,
        binary: false,
    };
    let mut raw = RawMesh::default();
    let mut state = State::Skip;
    let mut sets: Vec<String> = Vec::new();
    let mut listed: HashMap<u64, i64> = HashMap::new();
    let mut pending: Option<Pending> = None;
    let mut offset = 0;
    let mut top_dimension = 0u32;
    let set_id = |sets: &mut Vec<String>, name: &str| -> i64 {
        match sets.iter().position(|s| s.eq_ignore_ascii_case(name)) {
            Some(i) => i as i64 + 1,
            None => {
                sets.push(name.to_string());
                sets.len() as i64
            }
        }
    };
    for raw_line in bytes.split(|&b| b == b'\n') {
        let at = offset;
        offset += raw_line.len() + 1;
        let line = String::from_utf8_lossy(raw_line);
        let line = line.trim();
        if line.is_empty() || line.starts_with("**") {
            continue;
        }
        if let Some(keyword_line) = line.strip_prefix('*') {
            if let Some(p) = &pending {
                return Err(loc.error(
                    p.at,
                    format!(
                        "element {} has {} of its {} nodes",
                        p.tag,
                        p.tags.len(),
                        p.nodes
                    ),
                ));
            }
            let mut parts = keyword_line.split(',').map(str::trim);
            let keyword = parts.next().unwrap_or("").to_ascii_uppercase();
            let mut params: HashMap<String, String> = HashMap::new();
            for p in parts {
                let (k, v) = p.split_once('=').unwrap_or((p, ""));
                params.insert(k.trim().to_ascii_uppercase(), v.trim().to_string());
            }
            state = match keyword.as_str() {
                "NODE" => State::Node,
                "ELEMENT" => {
                    let Some(type_name) = params.get("TYPE") else {
                        return Err(loc.error(
                            at,
                            "*ELEMENT without TYPE=: expected e.g. *ELEMENT, TYPE=C3D8",
                        ));
                    };
                    let upper = type_name.to_ascii_uppercase();
                    let (ty, nodes) = abaqus_type(&upper).ok_or_else(|| {
                        loc.error(at, format!("unknown Abaqus element type {type_name}"))
                    })?;
                    top_dimension = top_dimension.max(u32::from(ty.dimension));
                    let t = raw.type_index(ty);
                    let set = params.get("ELSET").map_or(0, |s| set_id(&mut sets, s));
                    State::Element { t, nodes, set }
                }
                "ELSET" => {
                    let Some(set_name) = params.get("ELSET") else {
                        return Err(loc.error(
                            at,
                            "*ELSET without ELSET=: expected e.g. *ELSET, ELSET=name",
                        ));
                    };
                    State::Elset {
                        set: set_id(&mut sets, set_name),
                        generate: params.contains_key("GENERATE"),
                    }
                }
                _ => State::Skip,
            };
            continue;
        }
        let fields: Vec<&str> = line
            .split(',')
            .map(str::trim)
            .filter(|f| !f.is_empty())
            .collect();
        let number = |f: &str, what: &str| -> Result<f64, ScaffoldError> {
            let v: f64 = f
                .parse()
                .map_err(|_| loc.error(at, format!("expected {what}, found `{f}`")))?;
            super::cursor::finite(v, what).map_err(|m| loc.error(at, m))
        };
        let tag = |f: &str, what: &str| -> Result<u64, ScaffoldError> {
            f.parse::<u64>().map_err(|_| {
                loc.error(
                    at,
                    format!("expected {what} (a positive integer), found `{f}`"),
                )
            })
        };
        match &state {
            State::Skip => {}
            State::Node => {
                if fields.len() < 3 || fields.len() > 4 {
                    return Err(loc.error(
                        at,
                        format!(
                            "expected a node line `id, x, y[, z]`, found {} fields",
                            fields.len()
                        ),
                    ));
                }
                let id = tag(fields[0], "a node id")?;
                let mut p = [0.0; 3];
                for (c, f) in p.iter_mut().zip(&fields[1..]) {
                    *c = number(f, "a node coordinate")?;
                }
                raw.push_node(id, p, at);
            }
            &State::Element { t, nodes, set } => {
                let mut rest = &fields[..];
                if pending.is_none() {
                    let Some(first) = rest.first() else { continue };
                    pending = Some(Pending {
                        tag: tag(first, "an element id")?,
                        at,
                        t,
                        nodes,
                        set,
                        tags: Vec::with_capacity(nodes),
                    });
                    rest = &rest[1..];
                }
                let Some(p) = pending.as_mut() else { continue };
                for f in rest {
                    if p.tags.len() == p.nodes {
                        return Err(loc.error(
                            at,
                            format!("element {} has more than {} nodes", p.tag, p.nodes),
                        ));
                    }
                    p.tags.push(tag(f, "a node id")?);
                }
                if p.tags.len() == p.nodes {
                    let kind = raw.types[p.t as usize].kind;
                    raw.begin_element(p.t, p.tag, p.set, p.at);
                    for i in 0..p.nodes {
                        raw.element_nodes.push(p.tags[abaqus_local(kind, i)]);
                    }
                    pending = None;
                }
            }
            &State::Elset { set, generate } => {
                let ids: Vec<u64> = fields
                    .iter()
                    .map(|f| tag(f, "an element id"))
                    .collect::<Result<_, _>>()?;
                if generate {
                    if ids.len() < 2 || ids.len() > 3 || ids.get(2) == Some(&0) || ids[1] < ids[0] {
                        return Err(
                            loc.error(at, "expected `first, last[, step]` after *ELSET, GENERATE")
                        );
                    }
                    let step = ids.get(2).copied().unwrap_or(1);
                    if (ids[1] - ids[0]) / step > 100_000_000 {
                        return Err(loc.error(at, "*ELSET, GENERATE range is too large"));
                    }
                    let mut e = ids[0];
                    while e <= ids[1] {
                        listed.entry(e).or_insert(set);
                        e += step;
                    }
                } else {
                    for e in ids {
                        listed.entry(e).or_insert(set);
                    }
                }
            }
        }
    }
    if let Some(p) = &pending {
        return Err(loc.error(
            p.at,
            format!(
                "element {} has {} of its {} nodes (unexpected end of file)",
                p.tag,
                p.tags.len(),
                p.nodes
            ),
        ));
    }
    for (e, physical) in raw.physical.iter_mut().enumerate() {
        if let Some(&set) = listed.get(&raw.element_tags[e]) {
            *physical = set;
        }
    }
    raw.physical_names = sets
        .into_iter()
        .enumerate()
        .map(|(i, s)| (i as i64 + 1, top_dimension, s))
        .collect();
    raw.finish(loc)
}
