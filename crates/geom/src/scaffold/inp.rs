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

#[derive(Clone, Copy)]
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
    let mut reader = InpReader {
        loc: Locator {
            bytes,
            name,
            binary: false,
        },
        raw: RawMesh::default(),
        state: State::Skip,
        sets: Vec::new(),
        listed: HashMap::new(),
        pending: None,
        top_dimension: 0,
    };
    let mut offset = 0;
    for raw_line in bytes.split(|&b| b == b'\n') {
        let at = offset;
        offset += raw_line.len() + 1;
        let line = String::from_utf8_lossy(raw_line);
        let line = line.trim();
        if line.is_empty() || line.starts_with("**") {
            continue;
        }
        match line.strip_prefix('*') {
            Some(keyword_line) => reader.keyword(keyword_line, at)?,
            None => reader.data_line(line, at)?,
        }
    }
    reader.finish()
}

/// An `.inp` file read so far.
struct InpReader<'a> {
    loc: Locator<'a>,
    raw: RawMesh,
    /// What the data lines under the last keyword are.
    state: State,
    /// The element sets' names, in order of appearance (physical group `i + 1`).
    sets: Vec<String>,
    /// The set of each element a standalone `*ELSET` lists (the first one that does).
    listed: HashMap<u64, i64>,
    pending: Option<Pending>,
    top_dimension: u32,
}

impl InpReader<'_> {
    /// A keyword line (after its `*`) at `at`: what the data lines after it are.
    fn keyword(&mut self, keyword_line: &str, at: usize) -> Result<(), ScaffoldError> {
        let loc = self.loc;
        if let Some(p) = &self.pending {
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
        self.state = match keyword.as_str() {
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
                self.top_dimension = self.top_dimension.max(u32::from(ty.dimension));
                let t = self.raw.type_index(ty);
                let set = params.get("ELSET").map_or(0, |s| self.set_id(s));
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
                    set: self.set_id(set_name),
                    generate: params.contains_key("GENERATE"),
                }
            }
            _ => State::Skip,
        };
        Ok(())
    }

    /// The physical group of element set `name`, numbered on first sight.
    fn set_id(&mut self, name: &str) -> i64 {
        match self.sets.iter().position(|s| s.eq_ignore_ascii_case(name)) {
            Some(i) => i as i64 + 1,
            None => {
                self.sets.push(name.to_string());
                self.sets.len() as i64
            }
        }
    }

    /// A data line at `at`, read as the last keyword says.
    fn data_line(&mut self, line: &str, at: usize) -> Result<(), ScaffoldError> {
        let fields: Vec<&str> = line
            .split(',')
            .map(str::trim)
            .filter(|f| !f.is_empty())
            .collect();
        let line = Line {
            loc: self.loc,
            at,
            fields,
        };
        match self.state {
            State::Skip => Ok(()),
            State::Node => self.node(&line),
            State::Element { t, nodes, set } => self.element(&line, t, nodes, set),
            State::Elset { set, generate } => self.elset(&line, set, generate),
        }
    }

    /// A `*NODE` line: `id, x, y[, z]`.
    fn node(&mut self, line: &Line) -> Result<(), ScaffoldError> {
        let fields = &line.fields;
        if fields.len() < 3 || fields.len() > 4 {
            return Err(line.error(format!(
                "expected a node line `id, x, y[, z]`, found {} fields",
                fields.len()
            )));
        }
        let id = line.tag(fields[0], "a node id")?;
        let mut p = [0.0; 3];
        for (c, f) in p.iter_mut().zip(&fields[1..]) {
            *c = line.number(f, "a node coordinate")?;
        }
        self.raw.push_node(id, p, line.at);
        Ok(())
    }

    /// An `*ELEMENT` line of type `t` (`nodes` nodes, set `set`): an element's id and nodes,
    /// or more nodes of the pending one.
    fn element(
        &mut self,
        line: &Line,
        t: u16,
        nodes: usize,
        set: i64,
    ) -> Result<(), ScaffoldError> {
        let mut rest = &line.fields[..];
        if self.pending.is_none() {
            let Some(first) = rest.first() else {
                return Ok(());
            };
            self.pending = Some(Pending {
                tag: line.tag(first, "an element id")?,
                at: line.at,
                t,
                nodes,
                set,
                tags: Vec::with_capacity(nodes),
            });
            rest = &rest[1..];
        }
        let Some(p) = self.pending.as_mut() else {
            return Ok(());
        };
        for f in rest {
            if p.tags.len() == p.nodes {
                return Err(
                    line.error(format!("element {} has more than {} nodes", p.tag, p.nodes))
                );
            }
            p.tags.push(line.tag(f, "a node id")?);
        }
        if p.tags.len() == p.nodes {
            let kind = self.raw.types[p.t as usize].kind;
            self.raw.begin_element(p.t, p.tag, p.set, p.at);
            for i in 0..p.nodes {
                self.raw.element_nodes.push(p.tags[abaqus_local(kind, i)]);
            }
            self.pending = None;
        }
        Ok(())
    }

    /// An `*ELSET` line of set `set`: element ids, or `first, last[, step]` (`generate`).
    fn elset(&mut self, line: &Line, set: i64, generate: bool) -> Result<(), ScaffoldError> {
        let ids: Vec<u64> = line
            .fields
            .iter()
            .map(|f| line.tag(f, "an element id"))
            .collect::<Result<_, _>>()?;
        if !generate {
            for e in ids {
                self.listed.entry(e).or_insert(set);
            }
            return Ok(());
        }
        if ids.len() < 2 || ids.len() > 3 || ids.get(2) == Some(&0) || ids[1] < ids[0] {
            return Err(line.error("expected `first, last[, step]` after *ELSET, GENERATE"));
        }
        let step = ids.get(2).copied().unwrap_or(1);
        if (ids[1] - ids[0]) / step > 100_000_000 {
            return Err(line.error("*ELSET, GENERATE range is too large"));
        }
        let mut e = ids[0];
        while e <= ids[1] {
            self.listed.entry(e).or_insert(set);
            e += step;
        }
        Ok(())
    }

    /// The scaffold, at the end of the file.
    fn finish(mut self) -> Result<Scaffold, ScaffoldError> {
        let loc = self.loc;
        if let Some(p) = &self.pending {
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
        let raw = &mut self.raw;
        for (e, physical) in raw.physical.iter_mut().enumerate() {
            if let Some(&set) = self.listed.get(&raw.element_tags[e]) {
                *physical = set;
            }
        }
        let top_dimension = self.top_dimension;
        raw.physical_names = self
            .sets
            .into_iter()
            .enumerate()
            .map(|(i, s)| (i as i64 + 1, top_dimension, s))
            .collect();
        self.raw.finish(loc)
    }
}

/// A data line's comma-separated fields, and where it starts.
struct Line<'l> {
    loc: Locator<'l>,
    at: usize,
    fields: Vec<&'l str>,
}

impl Line<'_> {
    fn error(&self, message: impl Into<String>) -> ScaffoldError {
        self.loc.error(self.at, message)
    }

    /// Field `f` as a finite number (`what`, for messages).
    fn number(&self, f: &str, what: &str) -> Result<f64, ScaffoldError> {
        let v: f64 = f
            .parse()
            .map_err(|_| self.error(format!("expected {what}, found `{f}`")))?;
        super::cursor::finite(v, what).map_err(|m| self.error(m))
    }

    /// Field `f` as a tag (`what`, for messages).
    fn tag(&self, f: &str, what: &str) -> Result<u64, ScaffoldError> {
        f.parse::<u64>()
            .map_err(|_| self.error(format!("expected {what} (a positive integer), found `{f}`")))
    }
}
