//! 3MF packages (core specification): the mesh every build item places, in the model's unit.
//!
//! The model part is the one `_rels/.rels` names (`3D/3dmodel.model` when it names none). Its
//! XML is scanned here, not by an XML crate: a model is start and end tags with attributes,
//! and the scanner keeps the crate's dependencies as they are and reads a big model without
//! building a tree. What it reads:
//! - `<model unit>` (default `millimeter`); a non-empty `requiredextensions` is refused, naming
//!   the extensions, since their content (beams, slices, displacement) would be lost.
//! - `<object id type>` with a `<mesh>` (`<vertex x y z>`, `<triangle v1 v2 v3>`) or
//!   `<components>` (`<component objectid transform>`); objects of types other than `model`
//!   (supports) are left out.
//! - `<build>`'s `<item objectid transform>`s: each places its object (and its components,
//!   transforms composed) in the soup. A transform `m00 … m32` maps `(x, y, z)` to
//!   `(x, y, z, 1)·M` as the specification defines; a mirroring one (negative determinant)
//!   reverses the triangles so they stay counter-clockwise from outside. What the items place
//!   is counted first: more than [`MAX_INSTANCING`] times what the model defines is refused
//!   before anything is copied.
//! - `<metadata name>` text (our writer's stamp: `latticebuild:…` parameters), as given.
//!
//! Entities, comments, processing instructions and CDATA are skipped where they may stand;
//! numbers must be plain (no entity). Errors name the model's line (counted from 1), or the
//! byte offset in the package for a zip problem.

use super::unzip::{self, ZipError};
use super::{Format, Location, MeshReadError, TriangleSoup};
use std::collections::HashMap;

/// A 3MF package's mesh and its unit.
#[derive(Clone, Debug, PartialEq)]
pub struct ThreeMf {
    /// Every build item's triangles, in the model's unit.
    pub soup: TriangleSoup,
    /// The model's `unit` as written (`millimeter` when absent).
    pub unit: String,
    /// The length of that unit in millimetres.
    pub unit_mm: f64,
    /// The model's `<metadata name>` elements, name (prefix kept) and text (entities of
    /// XML's five replaced), in order.
    pub metadata: Vec<(String, String)>,
}

/// Components nest at most this deep (deeper is taken for a cycle).
const MAX_DEPTH: usize = 32;

/// The build items place at most this many times the vertices and triangles the model
/// defines: copies of a part are common, a fan of components sharing objects level by level
/// is a bomb (a few hundred bytes placing billions of triangles).
const MAX_INSTANCING: u64 = 4096;

fn zip_error(e: ZipError) -> MeshReadError {
    MeshReadError::Unexpected {
        format: Format::ThreeMf,
        at: Location::Byte(e.at),
        expected: "a 3MF package (a zip archive)".into(),
        found: e.what,
    }
}

/// Reads the package `bytes`.
pub fn read(bytes: &[u8]) -> Result<ThreeMf, MeshReadError> {
    let parts = unzip::parts(bytes).map_err(zip_error)?;
    let find = |name: &str| {
        parts
            .iter()
            .find(|p| p.name.trim_start_matches('/').eq_ignore_ascii_case(name))
    };
    let mut model_name = "3D/3dmodel.model".to_string();
    if let Some(rels) = find("_rels/.rels") {
        let rels = unzip::content(bytes, rels).map_err(zip_error)?;
        if let Some(target) = model_target(&rels) {
            model_name = target.trim_start_matches('/').to_string();
        }
    }
    let part = find(&model_name).ok_or_else(|| MeshReadError::Unexpected {
        format: Format::ThreeMf,
        at: Location::Byte(0),
        expected: format!("a model part `{model_name}`"),
        found: "a package without it".into(),
    })?;
    let xml = unzip::content(bytes, part).map_err(zip_error)?;
    parse_model(&xml)
}

/// The target of the package's 3D model relationship.
fn model_target(rels: &[u8]) -> Option<String> {
    let mut scanner = Scanner::new(rels);
    while let Ok(Some(tag)) = scanner.next() {
        if tag.start && tag.name == b"Relationship" {
            let ty = scanner.attr(b"Type").unwrap_or_default();
            if ty.ends_with(b"/3dmodel") {
                let target = scanner.attr(b"Target")?;
                return Some(String::from_utf8_lossy(target).into_owned());
            }
        }
    }
    None
}

/// An affine map `(x, y, z, 1)·M`, rows `m[0..3]` linear, `m[3]` the translation.
type Transform = [[f64; 3]; 4];
const IDENTITY: Transform = [[1., 0., 0.], [0., 1., 0.], [0., 0., 1.], [0., 0., 0.]];

fn apply(m: &Transform, p: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|j| p[0] * m[0][j] + p[1] * m[1][j] + p[2] * m[2][j] + m[3][j])
}

/// First `a`, then `b`.
fn compose(a: &Transform, b: &Transform) -> Transform {
    std::array::from_fn(|i| {
        // The translation row is a point (w = 1), the others directions (w = 0).
        let w = if i == 3 { 1.0 } else { 0.0 };
        std::array::from_fn(|j| {
            a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j] + w * b[3][j]
        })
    })
}

fn determinant(m: &Transform) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

#[derive(Default)]
struct Object {
    /// `type="model"` (the default).
    is_model: bool,
    positions: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    components: Vec<(u32, Transform, usize)>,
}

fn parse_model(xml: &[u8]) -> Result<ThreeMf, MeshReadError> {
    let mut scanner = Scanner::new(xml);
    let mut unit = "millimeter".to_string();
    let mut objects: HashMap<u32, Object> = HashMap::new();
    let mut current: Option<(u32, Object)> = None;
    let mut items: Vec<(u32, Transform, usize)> = Vec::new();
    let mut stack: Vec<Vec<u8>> = Vec::new();
    let mut saw_model = false;
    let mut metadata = Vec::new();
    loop {
        let tag = match scanner.next() {
            Ok(Some(tag)) => tag,
            Ok(None) => break,
            Err((at, what)) => return Err(scanner.unexpected(at, "well-formed XML", what)),
        };
        let at = tag.at;
        if !tag.start {
            if tag.name == b"object"
                && let Some((id, object)) = current.take()
            {
                objects.insert(id, object);
            }
            stack.pop();
            continue;
        }
        let parent = stack.last().map(Vec::as_slice).unwrap_or(b"");
        match (parent, tag.name) {
            (b"", b"model") => {
                saw_model = true;
                if let Some(u) = scanner.attr(b"unit") {
                    unit = String::from_utf8_lossy(u).into_owned();
                }
                if let Some(required) = scanner.attr(b"requiredextensions")
                    && !required.iter().all(u8::is_ascii_whitespace)
                {
                    return Err(MeshReadError::Unsupported {
                        format: Format::ThreeMf,
                        at: Location::Line(scanner.line_of(at)),
                        what: format!(
                            "a model that requires the extensions `{}`",
                            String::from_utf8_lossy(required)
                        ),
                    });
                }
            }
            (b"resources", b"object") => {
                let id = scanner.index(b"id", at)?;
                let is_model = scanner.attr(b"type").is_none_or(|t| t == b"model");
                current = Some((
                    id,
                    Object {
                        is_model,
                        ..Object::default()
                    },
                ));
            }
            (b"vertices", b"vertex") => {
                let p = [
                    scanner.number(b"x", at)?,
                    scanner.number(b"y", at)?,
                    scanner.number(b"z", at)?,
                ];
                if let Some((_, object)) = current.as_mut() {
                    object.positions.push(p);
                }
            }
            (b"triangles", b"triangle") => {
                let t = [
                    scanner.index(b"v1", at)?,
                    scanner.index(b"v2", at)?,
                    scanner.index(b"v3", at)?,
                ];
                if let Some((_, object)) = current.as_mut() {
                    // Vertices come first (the schema's order), so every index is known.
                    let count = object.positions.len();
                    if let Some(&index) = t.iter().find(|&&i| i as usize >= count) {
                        return Err(MeshReadError::IndexOutOfRange {
                            format: Format::ThreeMf,
                            at: Location::Line(scanner.line_of(at)),
                            face: object.triangles.len(),
                            index: i64::from(index),
                            count,
                        });
                    }
                    object.triangles.push(t);
                }
            }
            (b"components", b"component") => {
                if scanner.attr(b"path").is_some() {
                    return Err(MeshReadError::Unsupported {
                        format: Format::ThreeMf,
                        at: Location::Line(scanner.line_of(at)),
                        what: "a component in another model part (`p:path`)".into(),
                    });
                }
                let id = scanner.index(b"objectid", at)?;
                let m = scanner.transform(at)?;
                if let Some((_, object)) = current.as_mut() {
                    object.components.push((id, m, at));
                }
            }
            (b"model", b"metadata") => {
                let name = scanner.attr(b"name").unwrap_or_default();
                let name = String::from_utf8_lossy(name).into_owned();
                let text = if tag.empty {
                    String::new()
                } else {
                    scanner.text()
                };
                metadata.push((name, text));
            }
            (b"build", b"item") => {
                let id = scanner.index(b"objectid", at)?;
                items.push((id, scanner.transform(at)?, at));
            }
            _ => {}
        }
        if !tag.empty {
            stack.push(tag.name.to_vec());
        }
    }
    if !saw_model {
        return Err(scanner.unexpected(0, "a `<model>` element", "none".into()));
    }
    let unit_mm = match crate::mesh_io::Units::from_three_mf(&unit) {
        Some(Ok(u)) => u.millimeters(),
        Some(Err(mm)) => mm,
        None => {
            return Err(MeshReadError::Unsupported {
                format: Format::ThreeMf,
                at: Location::Line(1),
                what: format!(
                    "the unit `{unit}` (3MF names micron, millimeter, centimeter, inch, foot, meter)"
                ),
            });
        }
    };
    // Components may share an object many times over (each of 32 levels naming the next
    // twice is 2^32 copies): what the items place is counted before anything is copied.
    let mut placed = HashMap::new();
    let defined: u64 = objects
        .values()
        .map(|o| (o.positions.len() + o.triangles.len()) as u64)
        .sum();
    let mut total = 0u64;
    for &(id, _, at) in &items {
        total = total.saturating_add(size_placed(&objects, id, 0, at, &scanner, &mut placed)?);
    }
    if total > MAX_INSTANCING.saturating_mul(defined.max(1)) {
        return Err(MeshReadError::Unsupported {
            format: Format::ThreeMf,
            at: Location::Line(1),
            what: format!(
                "build items that place {total} vertices and triangles, over {MAX_INSTANCING} \
                 times the {defined} the model defines"
            ),
        });
    }
    let mut soup = TriangleSoup::default();
    for (id, m, at) in items {
        place(&objects, id, &m, 0, at, &scanner, &mut soup)?;
    }
    Ok(ThreeMf {
        soup,
        unit,
        unit_mm,
        metadata,
    })
}

/// The vertices and triangles placing object `id` adds (saturating), memoised by object; an
/// unknown object or nesting past [`MAX_DEPTH`] is the error [`place`] would give.
fn size_placed(
    objects: &HashMap<u32, Object>,
    id: u32,
    depth: usize,
    at: usize,
    scanner: &Scanner,
    memo: &mut HashMap<u32, u64>,
) -> Result<u64, MeshReadError> {
    if let Some(&size) = memo.get(&id) {
        return Ok(size);
    }
    let object = object_at(objects, id, depth, at, scanner)?;
    if !object.is_model {
        return Ok(0);
    }
    let mut size = (object.positions.len() + object.triangles.len()) as u64;
    for &(child, _, cat) in &object.components {
        let child = size_placed(objects, child, depth + 1, cat, scanner, memo)?;
        size = size.saturating_add(child);
    }
    memo.insert(id, size);
    Ok(size)
}

/// Object `id`, met `depth` components deep at byte `at`: an error when it is not defined or
/// the nesting is deeper than [`MAX_DEPTH`].
fn object_at<'a>(
    objects: &'a HashMap<u32, Object>,
    id: u32,
    depth: usize,
    at: usize,
    scanner: &Scanner,
) -> Result<&'a Object, MeshReadError> {
    let object = objects.get(&id).ok_or_else(|| {
        scanner.unexpected(at, "an object id defined in the resources", format!("{id}"))
    })?;
    if depth > MAX_DEPTH {
        return Err(MeshReadError::Unsupported {
            format: Format::ThreeMf,
            at: Location::Line(scanner.line_of(at)),
            what: format!("components nested over {MAX_DEPTH} deep (a cycle?)"),
        });
    }
    Ok(object)
}

/// Appends object `id` under `m` to `soup`.
fn place(
    objects: &HashMap<u32, Object>,
    id: u32,
    m: &Transform,
    depth: usize,
    at: usize,
    scanner: &Scanner,
    soup: &mut TriangleSoup,
) -> Result<(), MeshReadError> {
    let object = object_at(objects, id, depth, at, scanner)?;
    if !object.is_model {
        return Ok(());
    }
    let first = u32::try_from(soup.positions.len()).map_err(|_| MeshReadError::Unsupported {
        format: Format::ThreeMf,
        at: Location::Line(scanner.line_of(at)),
        what: "more than 2^32 vertices".into(),
    })?;
    soup.positions
        .extend(object.positions.iter().map(|&p| apply(m, p)));
    // Finite numbers composed can overflow (`-1e308` times 2): a soup's coordinates are finite.
    if let Some(i) = soup.positions[first as usize..]
        .iter()
        .position(|p| p.iter().any(|c| !c.is_finite()))
    {
        return Err(MeshReadError::Unsupported {
            format: Format::ThreeMf,
            at: Location::Line(scanner.line_of(at)),
            what: format!(
                "a transform placing vertex {i} of object {id} beyond the finite numbers"
            ),
        });
    }
    let mirrored = determinant(m) < 0.0;
    soup.triangles.extend(object.triangles.iter().map(|t| {
        let t = t.map(|i| i + first);
        if mirrored { [t[0], t[2], t[1]] } else { t }
    }));
    for (child, cm, cat) in &object.components {
        place(
            objects,
            *child,
            &compose(cm, m),
            depth + 1,
            *cat,
            scanner,
            soup,
        )?;
    }
    Ok(())
}

/// A start or end tag.
struct Tag<'a> {
    /// Local name (prefix dropped).
    name: &'a [u8],
    start: bool,
    /// `<… />`.
    empty: bool,
    /// Byte offset of its `<`.
    at: usize,
}

/// Tags of an XML text, one at a time, with the last start tag's attributes.
struct Scanner<'a> {
    xml: &'a [u8],
    pos: usize,
    attrs: Vec<(&'a [u8], &'a [u8])>,
}

impl<'a> Scanner<'a> {
    fn new(xml: &'a [u8]) -> Scanner<'a> {
        Scanner {
            xml,
            pos: 0,
            attrs: Vec::new(),
        }
    }

    fn line_of(&self, at: usize) -> usize {
        1 + self.xml[..at.min(self.xml.len())]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
    }

    fn unexpected(&self, at: usize, expected: &str, found: String) -> MeshReadError {
        MeshReadError::Unexpected {
            format: Format::ThreeMf,
            at: Location::Line(self.line_of(at)),
            expected: expected.to_string(),
            found,
        }
    }

    fn find(&self, from: usize, pattern: &[u8]) -> Option<usize> {
        self.xml
            .get(from..)?
            .windows(pattern.len())
            .position(|w| w == pattern)
            .map(|i| from + i)
    }

    /// The next tag, `None` at the end.
    fn next(&mut self) -> Result<Option<Tag<'a>>, (usize, String)> {
        let xml = self.xml;
        loop {
            let Some(lt) = xml[self.pos..].iter().position(|&b| b == b'<') else {
                self.pos = xml.len();
                return Ok(None);
            };
            let at = self.pos + lt;
            let rest = &xml[at..];
            let skip_to = |s: &Self, end: &[u8]| {
                s.find(at, end).map(|i| i + end.len()).ok_or((
                    at,
                    "an unterminated comment, CDATA or declaration".to_string(),
                ))
            };
            if rest.starts_with(b"<!--") {
                self.pos = skip_to(self, b"-->")?;
                continue;
            }
            if rest.starts_with(b"<![CDATA[") {
                self.pos = skip_to(self, b"]]>")?;
                continue;
            }
            if rest.starts_with(b"<?") {
                self.pos = skip_to(self, b"?>")?;
                continue;
            }
            if rest.starts_with(b"<!") {
                return Err((at, "a DOCTYPE (not allowed in 3MF)".into()));
            }
            let end = self.tag_end(at)?;
            self.pos = end + 1;
            let inner = &xml[at + 1..end];
            if let Some(name) = inner.strip_prefix(b"/") {
                let name = name.trim_ascii();
                return Ok(Some(Tag {
                    name: local(name),
                    start: false,
                    empty: false,
                    at,
                }));
            }
            let (inner, empty) = match inner.strip_suffix(b"/") {
                Some(inner) => (inner, true),
                None => (inner, false),
            };
            let name_len = inner
                .iter()
                .position(|b| b.is_ascii_whitespace())
                .unwrap_or(inner.len());
            if name_len == 0 {
                return Err((at, "a tag without a name".into()));
            }
            self.attrs.clear();
            let mut a = &inner[name_len..];
            loop {
                a = a.trim_ascii_start();
                if a.is_empty() {
                    break;
                }
                let eq = a
                    .iter()
                    .position(|&b| b == b'=')
                    .ok_or((at, "an attribute without `=`".to_string()))?;
                let key = a[..eq].trim_ascii();
                let after = a[eq + 1..].trim_ascii_start();
                let quote = *after
                    .first()
                    .filter(|q| **q == b'"' || **q == b'\'')
                    .ok_or((at, "an attribute value without quotes".to_string()))?;
                let close = after[1..]
                    .iter()
                    .position(|&b| b == quote)
                    .ok_or((at, "an unterminated attribute value".to_string()))?;
                self.attrs.push((local(key), &after[1..1 + close]));
                a = &after[close + 2..];
            }
            return Ok(Some(Tag {
                name: local(&inner[..name_len]),
                start: true,
                empty,
                at,
            }));
        }
    }

    /// The text from here to the next tag, with XML's five entities replaced (others kept
    /// as written: 3MF metadata is plain text).
    fn text(&self) -> String {
        let rest = &self.xml[self.pos.min(self.xml.len())..];
        let end = rest.iter().position(|&b| b == b'<').unwrap_or(rest.len());
        let raw = String::from_utf8_lossy(&rest[..end]);
        raw.replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&quot;", "\"")
            .replace("&apos;", "'")
            .replace("&amp;", "&")
    }

    /// The `>` ending the tag at `at`, outside quoted values.
    fn tag_end(&self, at: usize) -> Result<usize, (usize, String)> {
        let mut quote = None;
        for (i, &b) in self.xml[at..].iter().enumerate() {
            match (quote, b) {
                (None, b'"' | b'\'') => quote = Some(b),
                (Some(q), _) if b == q => quote = None,
                (None, b'>') => return Ok(at + i),
                _ => {}
            }
        }
        Err((at, "a tag cut short at the end of the file".into()))
    }

    fn attr(&self, key: &[u8]) -> Option<&'a [u8]> {
        self.attrs.iter().find(|(k, _)| *k == key).map(|&(_, v)| v)
    }

    fn required(&self, key: &[u8], at: usize) -> Result<&'a [u8], MeshReadError> {
        self.attr(key).ok_or_else(|| {
            self.unexpected(
                at,
                &format!("attribute `{}`", String::from_utf8_lossy(key)),
                "none".into(),
            )
        })
    }

    fn number(&self, key: &[u8], at: usize) -> Result<f64, MeshReadError> {
        let text = self.required(key, at)?;
        let value = std::str::from_utf8(text)
            .ok()
            .and_then(|t| t.trim().parse::<f64>().ok());
        match value {
            Some(v) if v.is_finite() => Ok(v),
            _ => Err(self.unexpected(
                at,
                &format!("a finite number for `{}`", String::from_utf8_lossy(key)),
                format!("`{}`", String::from_utf8_lossy(text)),
            )),
        }
    }

    fn index(&self, key: &[u8], at: usize) -> Result<u32, MeshReadError> {
        let text = self.required(key, at)?;
        std::str::from_utf8(text)
            .ok()
            .and_then(|t| t.trim().parse::<u32>().ok())
            .ok_or_else(|| {
                self.unexpected(
                    at,
                    &format!("an index for `{}`", String::from_utf8_lossy(key)),
                    format!("`{}`", String::from_utf8_lossy(text)),
                )
            })
    }

    /// The tag's `transform`, or the identity.
    fn transform(&self, at: usize) -> Result<Transform, MeshReadError> {
        let Some(text) = self.attr(b"transform") else {
            return Ok(IDENTITY);
        };
        let numbers: Option<Vec<f64>> = std::str::from_utf8(text).ok().and_then(|t| {
            t.split_ascii_whitespace()
                .map(|n| n.parse::<f64>().ok().filter(|v| v.is_finite()))
                .collect()
        });
        match numbers.as_deref() {
            Some(&[a, b, c, d, e, f, g, h, i, j, k, l]) => {
                Ok([[a, b, c], [d, e, f], [g, h, i], [j, k, l]])
            }
            _ => Err(self.unexpected(
                at,
                "a transform of 12 finite numbers",
                format!("`{}`", String::from_utf8_lossy(text)),
            )),
        }
    }
}

/// `name` without its namespace prefix.
fn local(name: &[u8]) -> &[u8] {
    match name.iter().position(|&b| b == b':') {
        Some(i) => &name[i + 1..],
        None => name,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MODEL: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<!-- a comment with <tags> -->
<model unit="inch" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">
<metadata name="Title">a &amp; b</metadata>
<resources>
<object id="3" type="model"><mesh><vertices>
<vertex x="0" y="0" z="0"/><vertex x="1" y="0" z="0"/><vertex x='0' y='1' z='0'/>
<vertex x="0" y="0" z="1"/>
</vertices><triangles>
<triangle v1="0" v2="2" v3="1"/><triangle v1="0" v2="1" v3="3" pid="1"/>
<triangle v1="0" v2="3" v3="2"/><triangle v1="1" v2="2" v3="3"/>
</triangles></mesh></object>
<object id="4"><components><component objectid="3" transform="1 0 0 0 1 0 0 0 1 10 0 0"/></components></object>
</resources>
<build><item objectid="3"/><item objectid="4" transform="-1 0 0 0 1 0 0 0 1 0 0 5"/></build>
</model>
"#;

    #[test]
    fn items_components_and_transforms_are_placed() {
        let model = parse_model(MODEL.as_bytes()).expect("parses");
        assert_eq!(model.unit, "inch");
        assert_eq!(model.unit_mm, 25.4);
        assert_eq!(model.soup.positions.len(), 8);
        assert_eq!(model.soup.triangles.len(), 8);
        // The second copy: translated by 10 in x, then mirrored in x and lifted by 5.
        assert_eq!(model.soup.positions[5], [-11.0, 0.0, 5.0]);
        // Mirrored, so its triangles are reversed.
        assert_eq!(model.soup.triangles[4], [4, 5, 6]);
        assert_eq!(model.soup.triangles[0], [0, 2, 1]);
        assert_eq!(model.metadata, [("Title".to_string(), "a & b".to_string())]);
    }

    /// A chain of objects each naming the next twice places 2^depth copies: refused before
    /// any is made, while a plain copy of a part many times over still reads.
    #[test]
    fn fanned_out_components_are_refused_before_copying() {
        let tet = r#"<object id="0"><mesh><vertices><vertex x="0" y="0" z="0"/>
<vertex x="1" y="0" z="0"/><vertex x="0" y="1" z="0"/><vertex x="0" y="0" z="1"/></vertices>
<triangles><triangle v1="0" v2="2" v3="1"/><triangle v1="0" v2="1" v3="3"/>
<triangle v1="0" v2="3" v3="2"/><triangle v1="1" v2="2" v3="3"/></triangles></mesh></object>"#;
        let model = |levels: u32, copies: u32| {
            let mut xml = format!("<model><resources>{tet}");
            for level in 1..=levels {
                xml.push_str(&format!("<object id=\"{level}\"><components>"));
                for _ in 0..copies {
                    xml.push_str(&format!("<component objectid=\"{}\"/>", level - 1));
                }
                xml.push_str("</components></object>");
            }
            xml.push_str(&format!(
                "</resources><build><item objectid=\"{levels}\"/></build></model>"
            ));
            xml
        };
        let started = std::time::Instant::now();
        let e = parse_model(model(32, 2).as_bytes()).expect_err("a bomb");
        assert!(e.to_string().contains("over 4096 times"), "{e}");
        assert!(started.elapsed().as_secs() < 5, "refused without copying");
        // 2^12 = 4096 copies of 8 (4 vertices, 4 triangles) is the limit itself.
        let copies = parse_model(model(12, 2).as_bytes()).expect("4096 copies");
        assert_eq!(copies.soup.triangles.len(), 4 * 4096);
        let e = parse_model(model(13, 2).as_bytes()).expect_err("8192 copies");
        assert!(e.to_string().contains("place 65536"), "{e}");
    }

    /// Packages of our writer read back as the same floats and triangles, in each unit, with
    /// plain zip and with ZIP64 fields.
    #[test]
    fn our_packages_read_back_exactly() {
        use crate::mesh::Mesh;
        use crate::mesh_io::{Stamp, Units, threemf};
        let mesh = Mesh {
            vertices: vec![
                [0.1, 0.0, -0.0],
                [1.0, 1e-7, 0.0],
                [0.0, 1.0, 3.4e38],
                [0.0, 0.0, 1.0],
            ],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        };
        for units in Units::ALL {
            for extra in [0, 5 << 30] {
                let stamp = Stamp {
                    units: Some(units),
                    title: "a \"b\" <c>".into(),
                    parameters: vec![
                        ("d e".into(), "&".into()),
                        ("cell.name".into(), "<g>".into()),
                    ],
                    ..Stamp::default()
                };
                let mut bytes = Vec::new();
                threemf::write_bounded(&mesh, &stamp, extra, &mut bytes).expect("write");
                let zip64 = bytes.windows(4).any(|w| w == 0x0606_4b50u32.to_le_bytes());
                assert_eq!(zip64, extra > 0);
                let model = read(&bytes).expect("read");
                assert_eq!(model.unit, units.three_mf());
                assert_eq!(model.unit_mm, units.millimeters());
                // Shortest round-trip decimals of f32, read as f64, round back to them.
                let back: Vec<[f32; 3]> = (model.soup.positions.iter())
                    .map(|p| p.map(|c| c as f32))
                    .collect();
                assert_eq!(back, mesh.vertices);
                assert_eq!(model.soup.triangles, mesh.triangles);
                let text = |v: &str| v.to_string();
                assert_eq!(
                    model.metadata[2..],
                    [
                        (text("latticebuild:d_e"), text("&")),
                        (text("latticebuild:cell.name"), text("<g>"))
                    ]
                );
                assert_eq!(model.metadata[0], (text("Title"), text("a \"b\" <c>")));
            }
        }
    }

    #[test]
    fn bad_models_are_errors_naming_their_line() {
        let cases = [
            (
                MODEL.replace("v3=\"1\"", "v3=\"9\""),
                "line 10",
                "face 0 refers to vertex 9",
            ),
            (MODEL.replace("x=\"1\"", "x=\"one\""), "line 7", "`one`"),
            (
                MODEL.replace("unit=\"inch\"", "unit=\"furlong\""),
                "",
                "furlong",
            ),
            (
                MODEL.replace("unit=\"inch\"", "requiredextensions=\"b\""),
                "line 3",
                "extensions `b`",
            ),
            (
                MODEL.replace("objectid=\"4\"", "objectid=\"7\""),
                "line 15",
                "found 7",
            ),
            (
                // Object 3 moved to x >= 10 by the component, then scaled by -1e308.
                MODEL.replace("transform=\"-1 0 0", "transform=\"-1e308 0 0"),
                "line 13",
                "vertex 0 of object 3 beyond the finite",
            ),
            (
                MODEL.replace("</build>\n</model>\n", "</build"),
                "",
                "cut short",
            ),
        ];
        for (xml, line, what) in cases {
            let e = parse_model(xml.as_bytes()).expect_err(what).to_string();
            assert!(e.contains(line) && e.contains(what), "{e}");
        }
    }
}
