//! PLY: `ascii 1.0`, `binary_little_endian 1.0` or `binary_big_endian 1.0`.
//!
//! The header declares elements in file order, each with a count and properties: scalars of
//! any of the eight PLY types (plus `int64`/`uint64`, which some writers use) or lists with an
//! integer count type and any item type. We need `x`, `y`, `z` of element `vertex` and the list
//! `vertex_indices` (or `vertex_index`) of element `face`; every other element and property is
//! read past and dropped. A file with fewer element instances than its header declares is
//! truncated; bytes after the last declared instance are ignored.
//!
//! ASCII bodies are read as one stream of tokens, so instances need not sit one per line, but
//! errors still name the line.

use super::text::{self, Tokens};
use super::{Format, Location, MeshReadError, TriangleSoup};
use crate::scalar::Scalar;

/// A PLY type name's type.
fn ply_type(name: &[u8]) -> Option<Scalar> {
    Some(match name {
        b"char" | b"int8" => Scalar::I8,
        b"uchar" | b"uint8" => Scalar::U8,
        b"short" | b"int16" => Scalar::I16,
        b"ushort" | b"uint16" => Scalar::U16,
        b"int" | b"int32" => Scalar::I32,
        b"uint" | b"uint32" => Scalar::U32,
        b"int64" => Scalar::I64,
        b"uint64" => Scalar::U64,
        b"float" | b"float32" => Scalar::F32,
        b"double" | b"float64" => Scalar::F64,
        _ => return None,
    })
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

/// What a property is to us.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Role {
    Coordinate(usize),
    /// `nx`, `ny`, `nz` of a vertex: read only for point clouds.
    Normal(usize),
    Indices,
    Ignored,
}

struct Property {
    kind: Kind,
    role: Role,
}

struct Element {
    name: Vec<u8>,
    count: u64,
    properties: Vec<Property>,
}

#[derive(Clone, Copy, PartialEq)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset and line number where the body starts.
    body: usize,
    body_line: usize,
}

fn unexpected(at: Location, expected: impl Into<String>, found: &[u8]) -> MeshReadError {
    MeshReadError::Unexpected {
        format: Format::Ply,
        at,
        expected: expected.into(),
        found: if found.is_empty() {
            "the end of the line".into()
        } else {
            text::show(found)
        },
    }
}

fn header(bytes: &[u8]) -> Result<Header, MeshReadError> {
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut offset = 0;
    for (line_no, line) in text::lines(bytes) {
        offset += line.len() + 1;
        let at = Location::Line(line_no);
        let mut tokens = text::tokens(line);
        let keyword = tokens.next().unwrap_or_default();
        if line_no == 1 {
            if keyword != b"ply" {
                return Err(unexpected(at, "the `ply` magic line", keyword));
            }
            continue;
        }
        match keyword {
            b"format" => {
                let name = tokens.next().unwrap_or_default();
                encoding = Some(match name {
                    b"ascii" => Encoding::Ascii,
                    b"binary_little_endian" => Encoding::Little,
                    b"binary_big_endian" => Encoding::Big,
                    _ => {
                        return Err(unexpected(
                            at,
                            "`ascii`, `binary_little_endian` or `binary_big_endian`",
                            name,
                        ));
                    }
                });
            }
            b"comment" | b"obj_info" | b"" => {}
            b"element" => {
                let name = tokens.next().unwrap_or_default();
                if name.is_empty() {
                    return Err(unexpected(at, "an element name", name));
                }
                let token = tokens.next().unwrap_or_default();
                let count = text::int(token)
                    .and_then(|c| u64::try_from(c).ok())
                    .ok_or_else(|| unexpected(at, "an element count", token))?;
                elements.push(Element {
                    name: name.to_vec(),
                    count,
                    properties: Vec::new(),
                });
            }
            b"property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(unexpected(
                        at,
                        "an `element` line before `property`",
                        keyword,
                    ));
                };
                let ty = tokens.next().unwrap_or_default();
                let scalar = |token: &[u8]| {
                    ply_type(token).ok_or_else(|| unexpected(at, "a PLY type", token))
                };
                let kind = if ty == b"list" {
                    let count = scalar(tokens.next().unwrap_or_default())?;
                    let item_token = tokens.next().unwrap_or_default();
                    let item = scalar(item_token)?;
                    if !count.is_integer() {
                        return Err(unexpected(at, "an integer list count type", b"float"));
                    }
                    Kind::List { count, item }
                } else {
                    Kind::Scalar(scalar(ty)?)
                };
                let name = tokens.next().unwrap_or_default();
                if name.is_empty() {
                    return Err(unexpected(at, "a property name", name));
                }
                let role = match (&element.name[..], name, kind) {
                    (b"vertex", b"x", Kind::Scalar(_)) => Role::Coordinate(0),
                    (b"vertex", b"y", Kind::Scalar(_)) => Role::Coordinate(1),
                    (b"vertex", b"z", Kind::Scalar(_)) => Role::Coordinate(2),
                    (b"vertex", b"nx", Kind::Scalar(_)) => Role::Normal(0),
                    (b"vertex", b"ny", Kind::Scalar(_)) => Role::Normal(1),
                    (b"vertex", b"nz", Kind::Scalar(_)) => Role::Normal(2),
                    (b"face", b"vertex_indices" | b"vertex_index", Kind::List { item, .. })
                        if item.is_integer() =>
                    {
                        Role::Indices
                    }
                    _ => Role::Ignored,
                };
                element.properties.push(Property { kind, role });
            }
            b"end_header" => {
                let encoding = encoding.ok_or_else(|| {
                    unexpected(at, "a `format` line before `end_header`", keyword)
                })?;
                return Ok(Header {
                    encoding,
                    elements,
                    body: offset.min(bytes.len()),
                    body_line: line_no + 1,
                });
            }
            _ => {
                return Err(unexpected(
                    at,
                    "`format`, `element`, `property`, `comment` or `end_header`",
                    keyword,
                ));
            }
        }
    }
    Err(MeshReadError::Truncated {
        format: Format::Ply,
        at: Location::Line(text::lines(bytes).count()),
        expected: "`end_header`".into(),
    })
}

/// The values of a body, whatever its encoding.
enum Body<'a> {
    Ascii(Tokens<'a>),
    Binary {
        bytes: &'a [u8],
        pos: usize,
        big: bool,
    },
}

impl Body<'_> {
    fn at(&mut self) -> Location {
        match self {
            Body::Ascii(tokens) => Location::Line(tokens.line()),
            Body::Binary { pos, .. } => Location::Byte(*pos),
        }
    }

    /// The next value of type `ty`; `what` names it for errors.
    fn value(&mut self, ty: Scalar, what: &dyn Fn() -> String) -> Result<f64, MeshReadError> {
        match self {
            Body::Ascii(tokens) => {
                let line = tokens.line();
                let (token, line) =
                    tokens
                        .next_token()
                        .ok_or_else(|| MeshReadError::Truncated {
                            format: Format::Ply,
                            at: Location::Line(line),
                            expected: what(),
                        })?;
                let value = match ty {
                    // A declared `float` holds what a binary file would: the nearest f32.
                    Scalar::F32 => text::float(token).map(|v| f64::from(v as f32)),
                    Scalar::F64 => text::float(token),
                    _ => text::int(token).map(|v| v as f64),
                };
                value.ok_or_else(|| {
                    unexpected(Location::Line(line), format!("{} ({ty:?})", what()), token)
                })
            }
            Body::Binary { bytes, pos, big } => {
                let size = ty.size();
                let Some(raw) = bytes.get(*pos..*pos + size) else {
                    return Err(MeshReadError::Truncated {
                        format: Format::Ply,
                        at: Location::Byte(bytes.len()),
                        expected: what(),
                    });
                };
                *pos += size;
                Ok(ty.decode(raw, *big))
            }
        }
    }

    /// Bytes left, an upper bound on the values still to come.
    fn remaining(&self) -> usize {
        match self {
            Body::Ascii(tokens) => tokens.remaining_bytes(),
            Body::Binary { bytes, pos, .. } => bytes.len().saturating_sub(*pos),
        }
    }
}

pub(super) fn read(bytes: &[u8]) -> Result<TriangleSoup, MeshReadError> {
    read_with_normals(bytes).map(|(soup, _)| soup)
}

/// The vertices and, when every vertex has `nx`, `ny`, `nz`, their normals (else empty);
/// faces are read as for a mesh.
pub(super) fn read_with_normals(
    bytes: &[u8],
) -> Result<(TriangleSoup, Vec<[f64; 3]>), MeshReadError> {
    let header = header(bytes)?;
    let mut body = match header.encoding {
        Encoding::Ascii => Body::Ascii(Tokens::new(&bytes[header.body..], header.body_line)),
        // Binary positions stay offsets into the whole file, as errors report them.
        Encoding::Little | Encoding::Big => Body::Binary {
            bytes,
            pos: header.body,
            big: header.encoding == Encoding::Big,
        },
    };
    read_body(&header, &mut body)
}

fn read_body(
    header: &Header,
    body: &mut Body<'_>,
) -> Result<(TriangleSoup, Vec<[f64; 3]>), MeshReadError> {
    let vertex = header.elements.iter().find(|e| e.name == b"vertex");
    let Some(vertex) = vertex else {
        return Err(MeshReadError::Unsupported {
            format: Format::Ply,
            at: Location::Line(1),
            what: "a file without a `vertex` element".into(),
        });
    };
    for axis in 0..3 {
        if !vertex
            .properties
            .iter()
            .any(|p| p.role == Role::Coordinate(axis))
        {
            return Err(MeshReadError::Unsupported {
                format: Format::Ply,
                at: Location::Line(1),
                what: format!(
                    "a `vertex` element without property `{}`",
                    ["x", "y", "z"][axis]
                ),
            });
        }
    }
    let has_normals = (0..3).all(|axis| {
        vertex
            .properties
            .iter()
            .any(|p| p.role == Role::Normal(axis))
    });
    let mut normals = Vec::new();
    let vertex_count = usize::try_from(vertex.count).unwrap_or(usize::MAX);
    let mut soup = TriangleSoup {
        positions: Vec::with_capacity(vertex_count.min(body.remaining() / 3)),
        triangles: Vec::new(),
    };
    let mut corners: Vec<u32> = Vec::new();
    let mut faces = 0usize;
    for element in &header.elements {
        if element.properties.is_empty() {
            // Instances without properties hold no bytes, so the file cannot bound their
            // count: there is nothing to read, however many are declared.
            if element.name == b"face" {
                faces = faces.saturating_add(usize::try_from(element.count).unwrap_or(usize::MAX));
            }
            continue;
        }
        let name = String::from_utf8_lossy(&element.name).into_owned();
        for instance in 0..element.count {
            let what = || format!("{name} {instance} of the {} declared", element.count);
            let mut p = [0.0; 3];
            let mut normal = [0.0; 3];
            let at = body.at();
            for property in &element.properties {
                match property.kind {
                    Kind::Scalar(ty) => {
                        let v = body.value(ty, &what)?;
                        match property.role {
                            Role::Coordinate(axis) => p[axis] = v,
                            Role::Normal(axis) => normal[axis] = v,
                            _ => {}
                        }
                    }
                    Kind::List { count, item } => {
                        let n = body.value(count, &what)?;
                        if n < 0.0 {
                            return Err(unexpected(at, "a list length of at least 0", b"negative"));
                        }
                        let n = n as u64;
                        if property.role == Role::Indices {
                            if n < 3 {
                                return Err(MeshReadError::Unexpected {
                                    format: Format::Ply,
                                    at,
                                    expected: "a face of at least three vertices".into(),
                                    found: format!("{n} vertices"),
                                });
                            }
                            corners.clear();
                            for _ in 0..n {
                                let index = body.value(item, &what)? as i64;
                                if index < 0 || index as u64 >= vertex.count {
                                    return Err(MeshReadError::IndexOutOfRange {
                                        format: Format::Ply,
                                        at,
                                        face: faces,
                                        index,
                                        count: vertex_count,
                                    });
                                }
                                corners.push(index as u32);
                            }
                            for i in 1..corners.len() - 1 {
                                soup.triangles
                                    .push([corners[0], corners[i], corners[i + 1]]);
                            }
                        } else {
                            for _ in 0..n {
                                body.value(item, &what)?;
                            }
                        }
                    }
                }
            }
            if element.name == b"vertex" {
                if has_normals {
                    normals.push(normal);
                }
                if let Some(&c) = p.iter().find(|c| !c.is_finite()) {
                    return Err(MeshReadError::NonFinite {
                        format: Format::Ply,
                        at,
                        vertex: instance as usize,
                        value: c,
                    });
                }
                soup.positions.push(p);
            }
            if element.name == b"face" {
                faces += 1;
            }
        }
    }
    if faces > 0 && soup.triangles.is_empty() {
        return Err(MeshReadError::Unsupported {
            format: Format::Ply,
            at: Location::Line(1),
            what: "a `face` element without a `vertex_indices` list".into(),
        });
    }
    Ok((soup, normals))
}
