//! Gmsh `.msh` 2.2 and 4.1, ASCII and binary (little-endian, data size 8).
//!
//! Invariants:
//! - Sections read: `$MeshFormat`, `$PhysicalNames`, `$Entities` (4.1: entity → first physical
//!   tag, so elements get their physical group), `$Nodes` (4.1 entity blocks, parametric
//!   coordinates skipped; node tags need not be contiguous), `$Elements`, `$NodeData` (views
//!   with one component kept by name). Any other `$Section` is skipped to its `$EndSection`.
//! - Every Gmsh element type up to order 5 is known by dimension and node count, so lower-
//!   dimensional elements are dropped and other 3D/2D types are named in errors.
//! - Binary numbers follow the format: 4.1 headers and tags are `size_t` (8 bytes), entity
//!   ids and types `int` (4 bytes); 2.2 uses `int` throughout; `$NodeData` node tags are `int`.
//!   Errors in binary files give byte offsets, in ASCII files lines.

use std::collections::HashMap;

use super::assemble::{ElementType, RawMesh, RawNodeData};
use super::cursor::{Cursor, show};
use super::{ElementKind, Scaffold, ScaffoldError};

/// (Gmsh type, name, dimension, nodes) of the types a reader may meet.
const GMSH_TYPES: &[(u32, &str, u8, usize)] = &[
    (1, "line2", 1, 2),
    (2, "tri3", 2, 3),
    (3, "quad4", 2, 4),
    (4, "tet4", 3, 4),
    (5, "hex8", 3, 8),
    (6, "prism6", 3, 6),
    (7, "pyramid5", 3, 5),
    (8, "line3", 1, 3),
    (9, "tri6", 2, 6),
    (10, "quad9", 2, 9),
    (11, "tet10", 3, 10),
    (12, "hex27", 3, 27),
    (13, "prism18", 3, 18),
    (14, "pyramid14", 3, 14),
    (15, "point", 0, 1),
    (16, "quad8", 2, 8),
    (17, "hex20", 3, 20),
    (18, "prism15", 3, 15),
    (19, "pyramid13", 3, 13),
    (20, "tri9", 2, 9),
    (21, "tri10", 2, 10),
    (22, "tri12", 2, 12),
    (23, "tri15", 2, 15),
    (24, "tri15i", 2, 15),
    (25, "tri21", 2, 21),
    (26, "line4", 1, 4),
    (27, "line5", 1, 5),
    (28, "line6", 1, 6),
    (29, "tet20", 3, 20),
    (30, "tet35", 3, 35),
    (31, "tet56", 3, 56),
    (36, "quad16", 2, 16),
    (37, "quad25", 2, 25),
    (38, "quad36", 2, 36),
    (92, "hex64", 3, 64),
    (93, "hex125", 3, 125),
];

struct Reader<'a> {
    cur: Cursor<'a>,
    binary: bool,
    raw: RawMesh,
    /// (entity dimension, entity tag) → physical tag (MSH 4.1 `$Entities`).
    entity_physical: HashMap<(i64, i64), i64>,
    /// Gmsh type → (index into raw.types, node count).
    type_cache: HashMap<u32, (u16, usize)>,
}

pub(super) fn read(bytes: &[u8], name: &str) -> Result<Scaffold, ScaffoldError> {
    let mut cur = Cursor::new(bytes, name);
    cur.expect("$MeshFormat")?;
    let (at, version) = cur.token("the MSH version (2.2 or 4.1)")?;
    let v4 = match version {
        b"4.1" => true,
        v if v.starts_with(b"2.") || v == b"2" => false,
        v => {
            return Err(cur.error(
                at,
                format!("unsupported MSH version `{}`: expected 2.2 or 4.1", show(v)),
            ));
        }
    };
    let (at, file_type) = cur.token("the MSH file type (0 ASCII, 1 binary)")?;
    let binary = match file_type {
        b"0" => false,
        b"1" => true,
        t => {
            return Err(cur.error(
                at,
                format!(
                    "expected the MSH file type 0 (ASCII) or 1 (binary), found `{}`",
                    show(t)
                ),
            ));
        }
    };
    let (at, size) = cur.token("the MSH data size")?;
    if size != b"8" {
        return Err(cur.error(
            at,
            format!("unsupported MSH data size `{}`: expected 8", show(size)),
        ));
    }
    if binary {
        cur.loc.binary = true;
        cur.skip_line();
        let at = cur.pos;
        let one = cur.i32("the binary endianness check (the int 1)")?;
        if one != 1 {
            return Err(cur.error(
                at,
                format!("the binary endianness check is {one}: expected 1 (a little-endian file)"),
            ));
        }
    }
    cur.expect("$EndMeshFormat")?;
    let mut r = Reader {
        cur,
        binary,
        raw: RawMesh::default(),
        entity_physical: HashMap::new(),
        type_cache: HashMap::new(),
    };
    while let Some((at, section)) = r.cur.next_token() {
        match section {
            b"$PhysicalNames" => r.physical_names()?,
            b"$Entities" if v4 => r.entities()?,
            b"$Nodes" if v4 => r.nodes4()?,
            b"$Nodes" => r.nodes2()?,
            b"$Elements" if v4 => r.elements4()?,
            b"$Elements" => r.elements2()?,
            b"$NodeData" => r.node_data()?,
            s if s.starts_with(b"$") => r.skip_section(at, &s[1..])?,
            s => {
                return Err(r.cur.error(
                    at,
                    format!("expected a section such as `$Nodes`, found `{}`", show(s)),
                ));
            }
        }
    }
    let loc = r.cur.loc;
    r.raw.finish(loc)
}

impl<'a> Reader<'a> {
    fn end(&mut self, section: &str) -> Result<(), ScaffoldError> {
        self.cur.expect(&format!("$End{section}"))
    }

    /// After a section keyword or an ASCII count in a binary file: data starts on the next line.
    fn start_binary_data(&mut self) {
        if self.binary {
            self.cur.skip_line();
        }
    }

    fn size(&mut self, what: &str) -> Result<u64, ScaffoldError> {
        if self.binary {
            self.cur.u64(what)
        } else {
            self.cur.uint(what)
        }
    }

    fn int(&mut self, what: &str) -> Result<i64, ScaffoldError> {
        if self.binary {
            self.cur.i32(what).map(i64::from)
        } else {
            self.cur.int(what)
        }
    }

    fn double(&mut self, what: &str) -> Result<f64, ScaffoldError> {
        if self.binary {
            self.cur.f64(what)
        } else {
            self.cur.float(what)
        }
    }

    /// A count from the file that must fit in what is left at `min_bytes` per item.
    fn count(&mut self, what: &str, min_bytes: usize) -> Result<usize, ScaffoldError> {
        let at = self.cur.mark();
        let v = self.size(what)?;
        self.cur.check_count(at, v, what, min_bytes)
    }

    fn skip_section(&mut self, at: usize, name: &[u8]) -> Result<(), ScaffoldError> {
        let mut end = b"$End".to_vec();
        end.extend_from_slice(name);
        let bytes = self.cur.bytes();
        match bytes[self.cur.pos..]
            .windows(end.len())
            .position(|w| w == end.as_slice())
        {
            Some(k) => {
                self.cur.pos += k + end.len();
                Ok(())
            }
            None => Err(self.cur.error(
                at,
                format!("section `${}` has no `{}`", show(name), show(&end)),
            )),
        }
    }

    fn physical_names(&mut self) -> Result<(), ScaffoldError> {
        let n = self.cur.count("the number of physical names", 6)?;
        for _ in 0..n {
            let dim = self.cur.uint("a physical group's dimension")?;
            let tag = self.cur.int("a physical group's tag")?;
            let name = self.cur.quoted("a physical group's name")?;
            self.raw.physical_names.push((tag, dim as u32, name));
        }
        self.end("PhysicalNames")
    }

    fn entities(&mut self) -> Result<(), ScaffoldError> {
        self.start_binary_data();
        let mut counts = [0usize; 4];
        for (dim, c) in counts.iter_mut().enumerate() {
            *c = self.count(&format!("the number of {dim}D entities"), 4)?;
        }
        for (dim, &count) in counts.iter().enumerate() {
            for _ in 0..count {
                let tag = self.int("an entity tag")?;
                let box_values = if dim == 0 { 3 } else { 6 };
                for _ in 0..box_values {
                    self.double("an entity's coordinates")?;
                }
                let physicals = self.count("an entity's number of physical tags", 4)?;
                for k in 0..physicals {
                    let p = self.int("a physical tag")?;
                    if k == 0 {
                        self.entity_physical.insert((dim as i64, tag), p);
                    }
                }
                if dim > 0 {
                    let bounding = self.count("an entity's number of bounding entities", 4)?;
                    for _ in 0..bounding {
                        self.int("a bounding entity tag")?;
                    }
                }
            }
        }
        self.end("Entities")
    }

    fn node_tag(&mut self, what: &str) -> Result<u64, ScaffoldError> {
        self.size(what)
    }

    fn nodes4(&mut self) -> Result<(), ScaffoldError> {
        self.start_binary_data();
        let min_node = if self.binary { 32 } else { 8 };
        let blocks = self.count("the number of node blocks", 16)?;
        let total = self.count("the number of nodes", min_node)?;
        self.size("the minimum node tag")?;
        self.size("the maximum node tag")?;
        self.raw.nodes.reserve(total);
        let mut seen = 0usize;
        for _ in 0..blocks {
            let dim = self.int("a node block's entity dimension")?;
            self.int("a node block's entity tag")?;
            let at = self.cur.mark();
            let parametric = self.int("a node block's parametric flag")?;
            if !(0..=1).contains(&parametric) || !(0..=3).contains(&dim) {
                return Err(self.cur.error(
                    at,
                    format!("expected a parametric flag 0 or 1 and an entity dimension 0..3, found {parametric} and {dim}"),
                ));
            }
            let n = self.count("the number of nodes in a block", min_node)?;
            seen += n;
            let first = self.raw.nodes.len();
            for _ in 0..n {
                let at = self.cur.mark();
                let tag = self.node_tag("a node tag")?;
                self.raw.push_node(tag, [0.0; 3], at);
            }
            let extra = (parametric * dim) as usize;
            for i in first..first + n {
                let mut p = [0.0; 3];
                for c in &mut p {
                    *c = self.double("a node coordinate")?;
                }
                for _ in 0..extra {
                    self.double("a parametric node coordinate")?;
                }
                self.raw.nodes[i] = p;
            }
        }
        if seen != total {
            return Err(self.cur.error(
                self.cur.pos,
                format!("the node blocks hold {seen} nodes, but the `$Nodes` header says {total}"),
            ));
        }
        self.end("Nodes")
    }

    fn nodes2(&mut self) -> Result<(), ScaffoldError> {
        let n = self
            .cur
            .count("the number of nodes", if self.binary { 28 } else { 8 })?;
        self.start_binary_data();
        self.raw.nodes.reserve(n);
        for _ in 0..n {
            let at = self.cur.mark();
            let tag = if self.binary {
                self.cur.index32("a node tag")?
            } else {
                self.cur.uint("a node tag")?
            };
            let mut p = [0.0; 3];
            for c in &mut p {
                *c = self.double("a node coordinate")?;
            }
            self.raw.push_node(tag, p, at);
        }
        self.end("Nodes")
    }

    /// The raw type index and node count of a Gmsh element type.
    fn element_type(
        &mut self,
        gmsh: i64,
        at: usize,
        context: &str,
    ) -> Result<(u16, usize), ScaffoldError> {
        let key = u32::try_from(gmsh).unwrap_or(u32::MAX);
        if let Some(&t) = self.type_cache.get(&key) {
            return Ok(t);
        }
        let Some(&(_, name, dimension, nodes)) = GMSH_TYPES.iter().find(|t| t.0 == key) else {
            return Err(self
                .cur
                .error(at, format!("unknown Gmsh element type {gmsh}{context}")));
        };
        let index = self.raw.type_index(ElementType {
            name: name.to_string(),
            dimension,
            kind: ElementKind::from_gmsh_type(key),
        });
        self.type_cache.insert(key, (index, nodes));
        Ok((index, nodes))
    }

    fn elements4(&mut self) -> Result<(), ScaffoldError> {
        self.start_binary_data();
        let blocks = self.count("the number of element blocks", 16)?;
        let total = self.count("the number of elements", 4)?;
        self.size("the minimum element tag")?;
        self.size("the maximum element tag")?;
        let mut seen = 0usize;
        for _ in 0..blocks {
            let dim = self.int("an element block's entity dimension")?;
            let entity = self.int("an element block's entity tag")?;
            let at = self.cur.mark();
            let gmsh = self.int("an element type")?;
            let (t, nodes) = self.element_type(gmsh, at, " in an element block")?;
            let per = if self.binary {
                8 * (nodes + 1)
            } else {
                2 * (nodes + 1)
            };
            let n = self.count("the number of elements in a block", per)?;
            seen += n;
            let physical = self
                .entity_physical
                .get(&(dim, entity))
                .copied()
                .unwrap_or(0);
            for _ in 0..n {
                let at = self.cur.mark();
                let tag = self.size("an element tag")?;
                self.raw.begin_element(t, tag, physical, at);
                for _ in 0..nodes {
                    let node = self.node_tag("an element's node tag")?;
                    self.raw.element_nodes.push(node);
                }
            }
        }
        if seen != total {
            return Err(self.cur.error(
                self.cur.pos,
                format!("the element blocks hold {seen} elements, but the `$Elements` header says {total}"),
            ));
        }
        self.end("Elements")
    }

    fn elements2(&mut self) -> Result<(), ScaffoldError> {
        let total = self
            .cur
            .count("the number of elements", if self.binary { 12 } else { 8 })?;
        self.start_binary_data();
        if self.binary {
            let mut seen = 0usize;
            while seen < total {
                let at = self.cur.mark();
                let gmsh = i64::from(self.cur.i32("an element type")?);
                let (t, nodes) = self.element_type(gmsh, at, " in an element block header")?;
                let n = self.cur.index32("the number of elements in a block")?;
                let tags = self.cur.index32("the number of element tags")? as usize;
                let n = self.cur.check_count(
                    at,
                    n,
                    "the number of elements in a block",
                    4 * (1 + tags + nodes),
                )?;
                if seen + n > total {
                    return Err(self.cur.error(
                        at,
                        format!(
                            "element blocks hold more than the {total} elements the header declares"
                        ),
                    ));
                }
                seen += n;
                for _ in 0..n {
                    let at = self.cur.mark();
                    let tag = self.cur.index32("an element tag")?;
                    let mut physical = 0;
                    for k in 0..tags {
                        let v = self.cur.i32("an element's tag")?;
                        if k == 0 {
                            physical = i64::from(v);
                        }
                    }
                    self.raw.begin_element(t, tag, physical, at);
                    for _ in 0..nodes {
                        let node = self.cur.index32("an element's node tag")?;
                        self.raw.element_nodes.push(node);
                    }
                }
            }
        } else {
            for _ in 0..total {
                let at = self.cur.mark();
                let tag = self.cur.uint("an element tag")?;
                let type_at = self.cur.mark();
                let gmsh = self.cur.int("an element type")?;
                let (t, nodes) = self.element_type(gmsh, type_at, &format!(" (element {tag})"))?;
                let tags = self.cur.count("the number of element tags", 2)?;
                let mut physical = 0;
                for k in 0..tags {
                    let v = self.cur.int("an element's tag")?;
                    if k == 0 {
                        physical = v;
                    }
                }
                self.raw.begin_element(t, tag, physical, at);
                for _ in 0..nodes {
                    let node = self.cur.uint("an element's node tag")?;
                    self.raw.element_nodes.push(node);
                }
            }
        }
        self.end("Elements")
    }

    fn node_data(&mut self) -> Result<(), ScaffoldError> {
        let at = self.cur.mark();
        let strings = self.cur.count("the number of string tags", 2)?;
        let mut name = String::new();
        for k in 0..strings {
            let s = self.cur.quoted("a string tag")?;
            if k == 0 {
                name = s;
            }
        }
        let reals = self.cur.count("the number of real tags", 2)?;
        for _ in 0..reals {
            self.cur.float("a real tag")?;
        }
        let ints = self.cur.count("the number of integer tags", 2)?;
        let mut int_tags = Vec::with_capacity(ints);
        for _ in 0..ints {
            int_tags.push(self.cur.int("an integer tag")?);
        }
        if int_tags.len() < 3 {
            return Err(self.cur.error(
                at,
                "expected at least 3 integer tags in `$NodeData` (time step, components, node count)",
            ));
        }
        let components = usize::try_from(int_tags[1])
            .ok()
            .filter(|&c| (1..=9).contains(&c))
            .ok_or_else(|| {
                self.cur.error(
                    at,
                    format!(
                        "expected 1 to 9 components in `$NodeData`, found {}",
                        int_tags[1]
                    ),
                )
            })?;
        let n = u64::try_from(int_tags[2]).map_err(|_| {
            self.cur.error(
                at,
                format!(
                    "expected a node count in `$NodeData`, found {}",
                    int_tags[2]
                ),
            )
        })?;
        let per = if self.binary {
            4 + 8 * components
        } else {
            2 * (1 + components)
        };
        let n = self
            .cur
            .check_count(at, n, "the number of `$NodeData` values", per)?;
        self.start_binary_data();
        let mut values = Vec::with_capacity(if components == 1 { n } else { 0 });
        for _ in 0..n {
            let value_at = self.cur.mark();
            let tag = if self.binary {
                self.cur.index32("a node tag")?
            } else {
                self.cur.uint("a node tag")?
            };
            for c in 0..components {
                let v = self.double("a node value")?;
                if components == 1 && c == 0 {
                    values.push((tag, v, value_at));
                }
            }
        }
        if components == 1 {
            self.raw.node_data.push(RawNodeData { name, at, values });
        }
        self.end("NodeData")
    }
}
