//! From what a reader found (nodes and elements by file tag) to a [`Scaffold`]: keep the
//! highest dimension, insist on one kind, resolve node tags, attach node data.
//!
//! Invariants: the result satisfies every invariant of `Scaffold` (mod.rs); each error names
//! where the offending node or element was written (through the reader's `Locator`). Every
//! reader ends here, so the checks on all nodes (coordinates within single precision) and
//! elements are made once for every format.

use std::collections::HashMap;

use super::cursor::Locator;
use super::{ElementKind, NodeData, Scaffold, ScaffoldError};

/// Why a node position cannot be tiled, if it cannot: a coordinate that is not finite, or
/// beyond single precision, the precision of tiled meshes (their cache entries and files),
/// where it would turn infinite. Shared by every reader (through [`RawMesh::finish`]) and by
/// the grid generator.
pub(super) fn coordinate_problem(p: [f64; 3]) -> Option<String> {
    let axis = p
        .iter()
        .position(|v| !v.is_finite() || v.abs() > f64::from(f32::MAX))?;
    let name = ["x", "y", "z"][axis];
    let v = p[axis];
    Some(if v.is_finite() {
        format!(
            "coordinate {name} = {v:e} is beyond ±{:e}, the largest a mesh vertex (single \
             precision) holds",
            f32::MAX
        )
    } else {
        format!("coordinate {name} is {v}, not a finite number")
    })
}

/// An element type as a file names it, with what is needed to drop or reject it.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct ElementType {
    /// e.g. "tet4", "prism6", "line2".
    pub name: String,
    pub dimension: u8,
    pub kind: Option<ElementKind>,
}

impl ElementType {
    pub fn of(kind: ElementKind) -> ElementType {
        ElementType {
            name: kind.name().to_string(),
            dimension: kind.dimension() as u8,
            kind: Some(kind),
        }
    }
}

/// A node data view as read: (node tag, value, where) triples.
pub(super) struct RawNodeData {
    pub name: String,
    pub at: usize,
    pub values: Vec<(u64, f64, usize)>,
}

/// What a reader collects; `finish` turns it into a scaffold.
#[derive(Default)]
pub(super) struct RawMesh {
    pub nodes: Vec<[f64; 3]>,
    pub node_tags: Vec<u64>,
    /// Byte offset where each node was written.
    pub node_at: Vec<usize>,
    pub types: Vec<ElementType>,
    /// Per element: index into `types`, tag, physical group, byte offset, first entry in
    /// `element_nodes`.
    pub element_type: Vec<u16>,
    pub element_tags: Vec<u64>,
    pub physical: Vec<i64>,
    pub element_at: Vec<usize>,
    pub element_start: Vec<usize>,
    /// Node tags of all elements, concatenated; already in Gmsh local order.
    pub element_nodes: Vec<u64>,
    pub physical_names: Vec<(i64, u32, String)>,
    pub node_data: Vec<RawNodeData>,
    /// Node tags are 0-based indices (VTK, OFF): messages say "point".
    pub indices_as_tags: bool,
}

impl RawMesh {
    pub fn type_index(&mut self, t: ElementType) -> u16 {
        match self.types.iter().position(|x| *x == t) {
            Some(i) => i as u16,
            None => {
                self.types.push(t);
                (self.types.len() - 1) as u16
            }
        }
    }

    pub fn push_node(&mut self, tag: u64, p: [f64; 3], at: usize) {
        self.nodes.push(p);
        self.node_tags.push(tag);
        self.node_at.push(at);
    }

    /// Starts an element; its node tags follow through `element_nodes.push`.
    pub fn begin_element(&mut self, type_index: u16, tag: u64, physical: i64, at: usize) {
        self.element_type.push(type_index);
        self.element_tags.push(tag);
        self.physical.push(physical);
        self.element_at.push(at);
        self.element_start.push(self.element_nodes.len());
    }

    fn element_end(&self, e: usize) -> usize {
        self.element_start
            .get(e + 1)
            .copied()
            .unwrap_or(self.element_nodes.len())
    }

    pub fn finish(self, loc: Locator<'_>) -> Result<Scaffold, ScaffoldError> {
        let node_word = if self.indices_as_tags {
            "point"
        } else {
            "node"
        };
        let Some(top) = self
            .element_type
            .iter()
            .map(|&t| self.types[t as usize].dimension)
            .max()
        else {
            return Err(
                loc.file_error("no elements: expected at least one tri, quad, tet or hex element")
            );
        };
        let mut counts: Vec<(u16, usize)> = Vec::new();
        for &t in &self.element_type {
            if self.types[t as usize].dimension != top {
                continue;
            }
            match counts.iter_mut().find(|(u, _)| *u == t) {
                Some(c) => c.1 += 1,
                None => counts.push((t, 1)),
            }
        }
        if counts.len() > 1 {
            counts.sort_by_key(|c| std::cmp::Reverse(c.1));
            let list: Vec<String> = counts
                .iter()
                .map(|&(t, n)| format!("{} ({n})", self.types[t as usize].name))
                .collect();
            return Err(loc.file_error(format!(
                "mixed element types: {}; a scaffold has one element type",
                list.join(", ")
            )));
        }
        let chosen = counts[0].0;
        let Some(kind) = self.types[chosen as usize].kind else {
            let names: Vec<&str> = ElementKind::ALL.iter().map(|k| k.name()).collect();
            return Err(loc.file_error(format!(
                "element type {} is not a scaffold element type (expected one of {})",
                self.types[chosen as usize].name,
                names.join(", ")
            )));
        };

        for (i, p) in self.nodes.iter().enumerate() {
            if let Some(problem) = coordinate_problem(*p) {
                return Err(loc.error(
                    self.node_at[i],
                    format!("{node_word} {}: {problem}", self.node_tags[i]),
                ));
            }
        }
        let index = NodeIndex::new(&self, node_word, loc)?;
        let n = kind.node_count();
        let kept = counts[0].1;
        let mut connectivity = Vec::with_capacity(kept * n);
        let mut element_tags = Vec::with_capacity(kept);
        let mut physical = Vec::with_capacity(kept);
        for e in 0..self.element_type.len() {
            if self.element_type[e] != chosen {
                continue;
            }
            let tags = &self.element_nodes[self.element_start[e]..self.element_end(e)];
            if tags.len() != n {
                return Err(loc.error(
                    self.element_at[e],
                    format!(
                        "element {} has {} nodes, expected {n} for {kind}",
                        self.element_tags[e],
                        tags.len()
                    ),
                ));
            }
            for &t in tags {
                let i = index.get(t).ok_or_else(|| {
                    loc.error(
                        self.element_at[e],
                        format!(
                            "element {} refers to {node_word} {t}, which is not in the file",
                            self.element_tags[e]
                        ),
                    )
                })?;
                connectivity.push(i);
            }
            element_tags.push(self.element_tags[e]);
            physical.push(self.physical[e]);
        }

        let mut node_data = Vec::with_capacity(self.node_data.len());
        for view in &self.node_data {
            let mut values = vec![f64::NAN; self.nodes.len()];
            for &(tag, v, at) in &view.values {
                let i = index.get(tag).ok_or_else(|| {
                    loc.error(
                        at,
                        format!(
                            "node data \"{}\" gives a value for {node_word} {tag}, which is not in the file",
                            view.name
                        ),
                    )
                })?;
                values[i as usize] = v;
            }
            if let Some(missing) = values.iter().position(|v| v.is_nan()) {
                return Err(loc.error(
                    view.at,
                    format!(
                        "node data \"{}\" has no value for {node_word} {} (expected one value per node)",
                        view.name, self.node_tags[missing]
                    ),
                ));
            }
            node_data.push(NodeData {
                name: view.name.clone(),
                values,
            });
        }

        Ok(Scaffold {
            kind,
            nodes: self.nodes,
            connectivity,
            node_tags: self.node_tags,
            element_tags,
            physical,
            physical_names: self.physical_names,
            node_data,
            source: loc.name.to_string(),
            smooth: None,
        })
    }
}

/// Node tag → node index: a table when tags are dense, a hash map otherwise.
enum NodeIndex {
    Dense { min: u64, table: Vec<u32> },
    Sparse(HashMap<u64, u32>),
}

impl NodeIndex {
    fn new(raw: &RawMesh, node_word: &str, loc: Locator<'_>) -> Result<NodeIndex, ScaffoldError> {
        if raw.nodes.len() >= u32::MAX as usize {
            return Err(loc.file_error("too many nodes (at most 2³² - 1)"));
        }
        let duplicate = |i: usize| {
            loc.error(
                raw.node_at[i],
                format!("{node_word} {} is listed twice", raw.node_tags[i]),
            )
        };
        let min = raw.node_tags.iter().copied().min().unwrap_or(0);
        let max = raw.node_tags.iter().copied().max().unwrap_or(0);
        if max - min < 2 * raw.nodes.len() as u64 + 1024 {
            let mut table = vec![u32::MAX; (max - min + 1) as usize];
            for (i, &t) in raw.node_tags.iter().enumerate() {
                let slot = &mut table[(t - min) as usize];
                if *slot != u32::MAX {
                    return Err(duplicate(i));
                }
                *slot = i as u32;
            }
            Ok(NodeIndex::Dense { min, table })
        } else {
            let mut map = HashMap::with_capacity(raw.nodes.len());
            for (i, &t) in raw.node_tags.iter().enumerate() {
                if map.insert(t, i as u32).is_some() {
                    return Err(duplicate(i));
                }
            }
            Ok(NodeIndex::Sparse(map))
        }
    }

    fn get(&self, tag: u64) -> Option<u32> {
        match self {
            NodeIndex::Dense { min, table } => tag
                .checked_sub(*min)
                .and_then(|k| table.get(k as usize))
                .copied()
                .filter(|&i| i != u32::MAX),
            NodeIndex::Sparse(map) => map.get(&tag).copied(),
        }
    }
}
