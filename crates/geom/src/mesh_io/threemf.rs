//! 3MF (3D Manufacturing Format, core specification 1.3): an OPC zip package of
//! `[Content_Types].xml`, `_rels/.rels` and the model part `3D/3dmodel.model`, holding one
//! mesh object and one build item that places it.
//!
//! The model's `unit` is the stamp's ([`super::Stamp`]; `millimeter` when unsaid, as the
//! specification defaults). Metadata: `Title`, `Application` (the generator, with its
//! version), and one `latticebuild:NAME` entry per parameter, in a namespace of our own as the
//! specification asks of names outside its list.
//!
//! The model is a header, a `<vertex>` per vertex, `</vertices><triangles>`, a `<triangle>`
//! per triangle and a footer: sections of per-record bytes like the other indexed formats, so
//! a chunked mesh writes the same XML, and the zip writer ([`super::zip`]) deflates it into the
//! same bytes whatever the chunking. Coordinates are printed as the shortest decimal that
//! parses back to the same `f32`; indices are the mesh's own (every vertex is written).

use super::encode::{Workers, push_f32, push_uint, records_per_block, write_encoded_by};
use super::stamp::{Stamp, Units};
use super::zip::Zip;
use crate::mesh::Mesh;
use std::io::{self, Write};

/// The model part's path in the package.
pub const MODEL_PATH: &str = "3D/3dmodel.model";
/// The core specification's XML namespace.
pub const CORE_NAMESPACE: &str = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02";
/// The namespace of our metadata names.
pub const METADATA_NAMESPACE: &str = "urn:latticebuild:metadata";

/// Longest `<vertex …/>` line: three numbers of at most 16 characters.
const VERTEX_BYTES: u64 = 80;
/// Longest `<triangle …/>` line: three indices of at most 10 digits.
const TRIANGLE_BYTES: u64 = 64;

const CONTENT_TYPES: &str = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
<Types xmlns=\"http://schemas.openxmlformats.org/package/2006/content-types\">\n\
<Default Extension=\"rels\" ContentType=\"application/vnd.openxmlformats-package.relationships+xml\"/>\n\
<Default Extension=\"model\" ContentType=\"application/vnd.ms-package.3dmanufacturing-3dmodel+xml\"/>\n\
</Types>\n";

const RELS: &str = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\">\n\
<Relationship Target=\"/3D/3dmodel.model\" Id=\"rel0\" \
Type=\"http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel\"/>\n\
</Relationships>\n";

const FOOTER: &str = "</triangles>\n</mesh>\n</object>\n</resources>\n\
<build>\n<item objectid=\"1\"/>\n</build>\n</model>\n";

pub(super) fn write(mesh: &Mesh, stamp: &Stamp, out: &mut dyn Write) -> io::Result<()> {
    write_bounded(mesh, stamp, 0, out)
}

/// [`write`], declaring the model `extra` bytes bigger than it can be (to test ZIP64 fields
/// on a small mesh).
pub(crate) fn write_bounded(
    mesh: &Mesh,
    stamp: &Stamp,
    extra: u64,
    out: &mut dyn Write,
) -> io::Result<()> {
    let mut package = Package::begin_with(
        mesh.vertices.len() as u64,
        mesh.triangles.len() as u64,
        stamp,
        extra,
        out,
    )?;
    vertices(&mesh.vertices, &mut package)?;
    package.between()?;
    triangles(&mesh.triangles, &mut package)?;
    package.finish()
}

/// A package whose model part is being written.
pub(super) struct Package<'a> {
    zip: Zip<'a>,
}

impl<'a> Package<'a> {
    /// Writes the package's parts up to the model's first vertex, for `nv` vertices and `nt`
    /// triangles.
    pub(super) fn begin(
        nv: u64,
        nt: u64,
        stamp: &Stamp,
        out: &'a mut dyn Write,
    ) -> io::Result<Package<'a>> {
        Package::begin_with(nv, nt, stamp, 0, out)
    }

    fn begin_with(
        nv: u64,
        nt: u64,
        stamp: &Stamp,
        extra: u64,
        out: &'a mut dyn Write,
    ) -> io::Result<Package<'a>> {
        let mut zip = Zip::new(out);
        zip.begin("[Content_Types].xml", true, CONTENT_TYPES.len() as u64)?;
        zip.write_all(CONTENT_TYPES.as_bytes())?;
        zip.begin("_rels/.rels", true, RELS.len() as u64)?;
        zip.write_all(RELS.as_bytes())?;
        let header = model_header(stamp);
        let bound = header.len() as u64
            + nv.saturating_mul(VERTEX_BYTES)
            + nt.saturating_mul(TRIANGLE_BYTES)
            + FOOTER.len() as u64
            + 64
            + extra;
        zip.begin(MODEL_PATH, true, bound)?;
        zip.write_all(header.as_bytes())?;
        Ok(Package { zip })
    }

    /// Between the vertices and the triangles.
    pub(super) fn between(&mut self) -> io::Result<()> {
        self.zip.write_all(b"</vertices>\n<triangles>\n")
    }

    /// The model's end, and the package's.
    pub(super) fn finish(mut self) -> io::Result<()> {
        self.zip.write_all(FOOTER.as_bytes())?;
        self.zip.finish()
    }
}

impl Write for Package<'_> {
    fn write(&mut self, bytes: &[u8]) -> io::Result<usize> {
        self.zip.write(bytes)
    }
    fn write_all(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.zip.write_all(bytes)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.zip.flush()
    }
}

/// Everything of the model before its first `<vertex>`.
fn model_header(stamp: &Stamp) -> String {
    let unit = stamp.units.unwrap_or(Units::Millimeter).three_mf();
    let mut xml = format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
         <model unit=\"{unit}\" xml:lang=\"en-US\" xmlns=\"{CORE_NAMESPACE}\" \
         xmlns:latticebuild=\"{METADATA_NAMESPACE}\">\n"
    );
    let mut metadata = |name: &str, value: &str| {
        xml.push_str("<metadata name=\"");
        xml.push_str(name);
        xml.push_str("\">");
        escape_into(&mut xml, value);
        xml.push_str("</metadata>\n");
    };
    if !stamp.title.is_empty() {
        metadata("Title", &stamp.title);
    }
    metadata("Application", &stamp.generator());
    for (name, value) in &stamp.parameters {
        let name: String = name
            .chars()
            .map(|c| match c.is_ascii_alphanumeric() || c == '.' {
                true => c,
                false => '_',
            })
            .collect();
        metadata(&format!("latticebuild:{name}"), value);
    }
    xml.push_str("<resources>\n<object id=\"1\" type=\"model\"");
    if !stamp.title.is_empty() {
        xml.push_str(" name=\"");
        escape_into(&mut xml, &stamp.title);
        xml.push('"');
    }
    xml.push_str(">\n<mesh>\n<vertices>\n");
    xml
}

/// `text` with XML's special characters escaped (fit for attributes and content) and control
/// characters, which XML 1.0 cannot hold, as spaces.
fn escape_into(xml: &mut String, text: &str) {
    for c in text.chars() {
        match c {
            '&' => xml.push_str("&amp;"),
            '<' => xml.push_str("&lt;"),
            '>' => xml.push_str("&gt;"),
            '"' => xml.push_str("&quot;"),
            '\'' => xml.push_str("&apos;"),
            c if c.is_control() => xml.push(' '),
            c => xml.push(c),
        }
    }
}

/// `<vertex>` records, in order.
pub(super) fn vertices(vertices: &[[f32; 3]], out: &mut dyn Write) -> io::Result<()> {
    let per_block = records_per_block(VERTEX_BYTES as usize);
    write_encoded_by(Workers::Pool, out, vertices, per_block, |buf, p| {
        buf.extend_from_slice(b"<vertex x=\"");
        push_f32(buf, p[0]);
        buf.extend_from_slice(b"\" y=\"");
        push_f32(buf, p[1]);
        buf.extend_from_slice(b"\" z=\"");
        push_f32(buf, p[2]);
        buf.extend_from_slice(b"\"/>\n");
    })
}

/// `<triangle>` records, in order.
pub(super) fn triangles(triangles: &[[u32; 3]], out: &mut dyn Write) -> io::Result<()> {
    let per_block = records_per_block(TRIANGLE_BYTES as usize);
    write_encoded_by(Workers::Pool, out, triangles, per_block, |buf, t| {
        buf.extend_from_slice(b"<triangle v1=\"");
        push_uint(buf, u64::from(t[0]));
        buf.extend_from_slice(b"\" v2=\"");
        push_uint(buf, u64::from(t[1]));
        buf.extend_from_slice(b"\" v3=\"");
        push_uint(buf, u64::from(t[2]));
        buf.extend_from_slice(b"\"/>\n");
    })
}
