//! What each fuzz target runs on one input, and where its seeds come from.
//!
//! A target calls a reader's public entry point the way the build does, then what the build
//! runs on its result without geometry, and asserts the invariants the reader's module
//! states about what it returns: a broken invariant panics, so it is found like any other
//! panic. A target returns a short outcome (the error message, or what was read): the driver
//! keeps inputs whose outcome it has not seen before, a cheap stand-in for coverage.
//!
//! Invariant: targets read no file but their input, except `manifest`, whose loader reads the
//! manifest file and checks that the files it names exist (the scratch directory links the
//! examples' `meshes`, `scaffolds` and `crystals` there, so the shipped manifests' references
//! resolve).

use std::path::{Path, PathBuf};

use latticebuild::diagnostics::render;
use latticebuild::graph::Graph;
use latticebuild::manifest;
use latticebuild_geom::mesh_read::{self, Format};
use latticebuild_geom::periodic::{self, ExpandOptions};
use latticebuild_geom::scaffold::{self, Scaffold};
use latticebuild_geom::stack_lang::{
    self, Aabb, IncludeResolver, Included, NoExternalSolids, Program,
};

/// Where a target's inputs may be written and its references resolved.
pub struct Scratch {
    pub dir: PathBuf,
}

pub struct Target {
    pub name: &'static str,
    pub about: &'static str,
    /// Runs one input, returning its outcome; panics are findings.
    pub run: fn(&[u8], &Scratch) -> String,
    /// Extensions of the repository's files that seed it (`sdf` is special: the programs of
    /// the shipped manifests).
    pub extensions: &'static [&'static str],
    /// Not fuzzed unless named: the runner's own self-test.
    pub hidden: bool,
}

pub const TARGETS: &[Target] = &[
    Target {
        name: "manifest",
        about: "manifest::load of a manifest file (lines `#--set K=V` become overrides), then \
                Graph::compile and every cell's node, or the rendered diagnostics",
        run: manifest_target,
        extensions: &["toml"],
        hidden: false,
    },
    Target {
        name: "mesh-stl",
        about: "mesh_read::read as STL (ASCII or binary by content)",
        run: |b, _| mesh(b, Format::Stl),
        extensions: &["stl"],
        hidden: false,
    },
    Target {
        name: "mesh-obj",
        about: "mesh_read::read as OBJ",
        run: |b, _| mesh(b, Format::Obj),
        extensions: &["obj"],
        hidden: false,
    },
    Target {
        name: "mesh-ply",
        about: "mesh_read::read as PLY (ASCII, binary LE/BE)",
        run: |b, _| mesh(b, Format::Ply),
        extensions: &["ply"],
        hidden: false,
    },
    Target {
        name: "mesh-off",
        about: "mesh_read::read as OFF",
        run: |b, _| mesh(b, Format::Off),
        extensions: &["off"],
        hidden: false,
    },
    Target {
        name: "mesh-3mf",
        about: "mesh_read::read as 3MF: the package as given, and (when it is not a zip) the \
                input as the model part of a package made for it, so XML mutations are not \
                all stopped by the CRC",
        run: |b, _| threemf_target(b),
        extensions: &["3mf", "model"],
        hidden: false,
    },
    Target {
        name: "scaffold-msh",
        about: "scaffold::read_scaffold of a .msh (Gmsh 2.2/4.1, ASCII/binary), then check and facets",
        run: |b, _| scaffold_target(b, "msh"),
        extensions: &["msh"],
        hidden: false,
    },
    Target {
        name: "scaffold-vtk",
        about: "scaffold::read_scaffold of a legacy .vtk (ASCII/binary), then check and facets",
        run: |b, _| scaffold_target(b, "vtk"),
        extensions: &["vtk"],
        hidden: false,
    },
    Target {
        name: "scaffold-vtu",
        about: "scaffold::read_scaffold of a .vtu (ASCII, base64, zlib, LZ4, appended), then check and facets",
        run: |b, _| scaffold_target(b, "vtu"),
        extensions: &["vtu"],
        hidden: false,
    },
    Target {
        name: "scaffold-inp",
        about: "scaffold::read_scaffold of an Abaqus .inp, then check and facets",
        run: |b, _| scaffold_target(b, "inp"),
        extensions: &["inp"],
        hidden: false,
    },
    Target {
        name: "scaffold-surface",
        about: "scaffold::read_scaffold of an OBJ or OFF surface scaffold, then check and facets",
        run: |b, _| {
            // The content decides between OBJ and OFF; the hint only when it cannot.
            let hint = if b.trim_ascii_start().starts_with(b"OFF") {
                "off"
            } else {
                "obj"
            };
            scaffold_target(b, hint)
        },
        extensions: &["obj", "off"],
        hidden: false,
    },
    Target {
        name: "crystal-cif",
        about: "periodic::read_crystal of a CIF, then the atoms expanded (with and without images)",
        run: |b, _| crystal(b, "fuzz.cif"),
        extensions: &["cif"],
        hidden: false,
    },
    Target {
        name: "crystal-xyz",
        about: "periodic::read_crystal of an extended XYZ, then the atoms expanded",
        run: |b, _| crystal(b, "fuzz.xyz"),
        extensions: &["xyz", "extxyz"],
        hidden: false,
    },
    Target {
        name: "sdf",
        about: "an SDF program: words, @includes (of itself), Program::parse, canonical text \
                re-parsed, the field compiled and contoured on 6³ with and without pruning",
        run: |b, _| sdf_target(b),
        extensions: &["sdf"],
        hidden: false,
    },
    Target {
        name: "canary",
        about: "self-test: `panic`, `spin`, `alloc`, `abort` or `deep` do what they say",
        run: |b, _| canary(b),
        extensions: &[],
        hidden: true,
    },
];

pub fn find(name: &str) -> Option<&'static Target> {
    TARGETS.iter().find(|t| t.name == name)
}

/// `⌊log2 n⌋ + 1` (0 for 0): sizes in outcomes, so that they group instead of all differing.
fn magnitude(n: usize) -> u32 {
    usize::BITS - n.leading_zeros()
}

fn manifest_target(bytes: &[u8], scratch: &Scratch) -> String {
    let path = scratch.dir.join("lattice.toml");
    if let Err(e) = std::fs::write(&path, bytes) {
        panic!("cannot write {}: {e}", path.display());
    }
    let overrides: Vec<String> = String::from_utf8_lossy(bytes)
        .lines()
        .filter_map(|l| l.strip_prefix("#--set "))
        .map(str::to_string)
        .collect();
    match manifest::load(&path, &overrides) {
        Err(diags) => {
            let text = render(&diags);
            assert!(
                !diags.is_empty() && text.starts_with("error"),
                "invariant: a refused manifest has diagnostics, rendered:\n{text}"
            );
            diags
                .iter()
                .map(|d| d.message.as_str())
                .collect::<Vec<_>>()
                .join("; ")
        }
        Ok(m) => match Graph::compile(&m) {
            Err(cycle) => format!("cycle {cycle}"),
            Ok(mut graph) => {
                for name in m.cells.keys() {
                    if let Err(cycle) = graph.compile_cell(&m, name) {
                        return format!("cell cycle {cycle}");
                    }
                }
                let targets: Vec<String> = m.outputs.keys().cloned().collect();
                let needed = graph.needed(&targets).map(|n| n.len()).unwrap_or(0);
                format!(
                    "ok cells {} outputs {} sdf {} tiled {} scaffolds {} needed {}",
                    magnitude(m.cells.len()),
                    magnitude(m.outputs.len()),
                    magnitude(m.program_outputs.len()),
                    magnitude(m.tiled_outputs.len()),
                    magnitude(m.scaffolds.len()),
                    magnitude(needed),
                )
            }
        },
    }
}

fn mesh(bytes: &[u8], format: Format) -> String {
    match mesh_read::read(bytes, format) {
        Err(e) => e.to_string(),
        Ok(soup) => {
            // mesh_read/soup.rs: at least one triangle, every index below the position count,
            // every coordinate finite.
            assert!(
                !soup.triangles.is_empty(),
                "invariant: a soup has triangles"
            );
            let n = soup.positions.len();
            if let Some((t, tri)) = soup
                .triangles
                .iter()
                .enumerate()
                .find(|(_, tri)| tri.iter().any(|&i| i as usize >= n))
            {
                panic!("invariant: triangle {t} {tri:?} indexes past {n} positions");
            }
            if let Some((i, p)) = soup
                .positions
                .iter()
                .enumerate()
                .find(|(_, p)| p.iter().any(|c| !c.is_finite()))
            {
                panic!("invariant: position {i} {p:?} is not finite");
            }
            let _ = soup.bounds();
            format!(
                "ok positions {} triangles {}",
                magnitude(n),
                magnitude(soup.triangles.len())
            )
        }
    }
}

/// A 3MF package as the build reads it; input that is not a zip archive is also read as the
/// model part of a package made round it (stored, CRC right), which reaches the XML scanner.
fn threemf_target(bytes: &[u8]) -> String {
    let package = mesh(bytes, Format::ThreeMf);
    if bytes.starts_with(b"PK") {
        return package;
    }
    let wrapped = stored_zip(&[("3D/3dmodel.model", bytes)]);
    format!("{package} | model {}", mesh(&wrapped, Format::ThreeMf))
}

/// A zip archive of `parts`, stored (method 0), with the CRC-32s right.
fn stored_zip(parts: &[(&str, &[u8])]) -> Vec<u8> {
    fn crc32(bytes: &[u8]) -> u32 {
        let mut crc = 0xFFFF_FFFFu32;
        for &b in bytes {
            crc ^= u32::from(b);
            for _ in 0..8 {
                crc = if crc & 1 == 1 {
                    (crc >> 1) ^ 0xEDB8_8320
                } else {
                    crc >> 1
                };
            }
        }
        !crc
    }
    // Fuzz inputs are small (far below 4 GiB), so 32-bit sizes and offsets hold them.
    let le16 = |v: usize| (v as u16).to_le_bytes();
    let le32 = |v: usize| (v as u32).to_le_bytes();
    let mut out = Vec::new();
    let mut directory = Vec::new();
    for (name, data) in parts {
        let crc = crc32(data).to_le_bytes();
        let offset = out.len();
        out.extend(0x0403_4b50u32.to_le_bytes());
        out.extend([20, 0, 0, 0, 0, 0, 0, 0, 0, 0]); // version, flags, method 0, time, date
        out.extend(crc);
        out.extend(le32(data.len()));
        out.extend(le32(data.len()));
        out.extend(le16(name.len()));
        out.extend(le16(0));
        out.extend(name.as_bytes());
        out.extend(*data);
        directory.extend(0x0201_4b50u32.to_le_bytes());
        directory.extend([20, 0, 20, 0, 0, 0, 0, 0, 0, 0, 0, 0]); // made by, needed, flags, method, time, date
        directory.extend(crc);
        directory.extend(le32(data.len()));
        directory.extend(le32(data.len()));
        directory.extend(le16(name.len()));
        directory.extend([0; 12]); // extra, comment, disk, internal and external attributes
        directory.extend(le32(offset));
        directory.extend(name.as_bytes());
    }
    let start = out.len();
    out.extend(&directory);
    out.extend(0x0605_4b50u32.to_le_bytes());
    out.extend([0; 4]); // disk numbers
    out.extend(le16(parts.len()));
    out.extend(le16(parts.len()));
    out.extend(le32(directory.len()));
    out.extend(le32(start));
    out.extend(le16(0));
    out
}

/// scaffold/mod.rs: a returned scaffold has one kind, valid indices, finite coordinates, and
/// node data parallel to its nodes; errors name the file.
fn scaffold_invariants(s: &Scaffold) {
    let n = s.nodes.len();
    let per = s.kind.node_count();
    let elements = s.element_count();
    assert!(elements > 0, "invariant: a scaffold has elements");
    assert_eq!(
        s.connectivity.len(),
        elements * per,
        "invariant: {elements} {} elements have {per} nodes each",
        s.kind.name()
    );
    if let Some(i) = s.connectivity.iter().position(|&c| c as usize >= n) {
        panic!(
            "invariant: element {} uses node index {} of {n}",
            i / per,
            s.connectivity[i]
        );
    }
    if let Some(i) = s
        .nodes
        .iter()
        .position(|p| p.iter().any(|c| !c.is_finite()))
    {
        panic!("invariant: node {i} {:?} is not finite", s.nodes[i]);
    }
    assert_eq!(s.node_tags.len(), n, "invariant: a tag per node");
    assert_eq!(s.physical.len(), elements, "invariant: a group per element");
    for d in &s.node_data {
        assert_eq!(
            d.values.len(),
            n,
            "invariant: node data `{}` is parallel to the nodes",
            d.name
        );
    }
}

fn scaffold_target(bytes: &[u8], extension: &str) -> String {
    let name = format!("fuzz.{extension}");
    match scaffold::read_scaffold(bytes, &name, Some(extension)) {
        Err(e) => {
            assert_eq!(e.file, name, "invariant: errors name the file");
            e.to_string()
        }
        Ok(s) => {
            scaffold_invariants(&s);
            let check = match scaffold::check(&s) {
                Ok(()) => "ok".to_string(),
                Err(e) => e.message,
            };
            let facets = s.facets();
            format!(
                "ok {} nodes {} elements {} data {} boundary {} overused {} | check {check}",
                s.kind.name(),
                magnitude(s.nodes.len()),
                magnitude(s.element_count()),
                s.node_data.len(),
                magnitude(facets.boundary.len()),
                magnitude(facets.overused.len()),
            )
        }
    }
}

fn crystal(bytes: &[u8], name: &str) -> String {
    match periodic::read_crystal(name, bytes) {
        Err(e) => {
            assert_eq!(e.file, name, "invariant: errors name the file");
            e.message
        }
        Ok(c) => {
            let atoms = c.atoms(&ExpandOptions::default());
            // periodic/mod.rs: an expanded atom's fractional coordinates are in [0, 1).
            if let Some(a) = atoms
                .iter()
                .find(|a| a.fract.iter().any(|f| !(0.0..1.0).contains(f)))
            {
                panic!(
                    "invariant: atom `{}` at {:?} is outside [0, 1)",
                    a.label, a.fract
                );
            }
            let images = c.atoms(&ExpandOptions {
                include_images: true,
                ..ExpandOptions::default()
            });
            let species = c.species();
            let points = periodic::positions_of(&images, species.first().map(String::as_str));
            format!(
                "ok sites {} operations {} atoms {} images {} species {} points {}",
                magnitude(c.sites.len()),
                magnitude(c.operations.len()),
                magnitude(atoms.len()),
                magnitude(images.len()),
                magnitude(species.len()),
                magnitude(points.len()),
            )
        }
    }
}

/// Every `@NAME` includes the input itself under the id NAME, so includes nest until a name
/// repeats (a cycle) or the depth limit.
struct SelfInclude<'a>(&'a str);

impl IncludeResolver for SelfInclude<'_> {
    fn read(&self, name: &str, _from: Option<&str>) -> Result<Included, String> {
        if name.is_empty() {
            return Err("no such file".into());
        }
        Ok(Included {
            id: name.to_string(),
            text: self.0.to_string(),
        })
    }
}

fn finite_box(b: &Aabb) -> bool {
    (0..3).all(|a| b.min[a].is_finite() && b.max[a].is_finite() && b.min[a] < b.max[a])
}

fn sdf_target(bytes: &[u8]) -> String {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return "not UTF-8".into();
    };
    let words = match stack_lang::split_words(text) {
        Ok(w) => w,
        Err(_) => return "unclosed quote".into(),
    };
    let words = match stack_lang::expand(&words, &SelfInclude(text)) {
        Ok(w) => w,
        Err(e) => return e.to_string(),
    };
    let program = match Program::parse(&words) {
        Ok(p) => p,
        Err(e) => return e.to_string(),
    };
    // sdf/tree.rs: the canonical text parses back to a tree with the same canonical text.
    let canonical = program.canonical();
    match Program::parse_str(&canonical) {
        Ok(again) => assert_eq!(
            again.canonical(),
            canonical,
            "invariant: canonical text is a fixed point"
        ),
        Err(e) => panic!("invariant: canonical text `{canonical}` does not parse: {e}"),
    }
    let _ = program.files();
    let mut field = match program.field(&NoExternalSolids) {
        Ok(f) => f,
        Err(e) => return format!("field: {e}"),
    };
    let domain = field.domain();
    for p in [[0.0, 0.0, 0.0], [0.3, -0.7, 1.1], domain.min, domain.max] {
        let _ = field.eval(p);
    }
    let (leaves, ops) = field.plan_size();
    let contoured = if finite_box(&domain) {
        // sdf/mod.rs and sampler.rs: pruning never changes the mesh.
        let pruned = stack_lang::mesh(&field, &domain, [6, 6, 6]);
        field.set_pruning(false);
        let plain = stack_lang::mesh(&field, &domain, [6, 6, 6]);
        match (pruned, plain) {
            (Ok(a), Ok(b)) => {
                assert!(
                    a == b,
                    "invariant: pruning changed the mesh of `{canonical}` on {domain:?}"
                );
                format!("triangles {}", magnitude(a.triangles.len()))
            }
            (Err(a), Err(b)) => {
                assert_eq!(a.to_string(), b.to_string());
                format!("| contour error {a}")
            }
            (a, b) => panic!(
                "invariant: pruning changed whether `{canonical}` contours: {:?} vs {:?}",
                a.map(|m| m.triangles.len()),
                b.map(|m| m.triangles.len())
            ),
        }
    } else {
        "unbounded".into()
    };
    format!(
        "ok leaves {} ops {} {contoured}",
        magnitude(leaves),
        magnitude(ops)
    )
}

fn canary(bytes: &[u8]) -> String {
    match bytes.trim_ascii() {
        b"panic" => panic!("canary panic"),
        b"spin" => {
            let mut x = 0u64;
            loop {
                x = std::hint::black_box(x.wrapping_add(1));
            }
        }
        b"alloc" => {
            let v: Vec<u8> = Vec::with_capacity(1 << 40);
            format!("{}", v.capacity())
        }
        b"abort" => std::process::abort(),
        b"deep" => {
            fn down(n: u64) -> u64 {
                let pad = std::hint::black_box([n; 64]);
                if n == 0 { 0 } else { down(n - 1) + pad[7] }
            }
            down(std::hint::black_box(u64::MAX)).to_string()
        }
        other => format!("fine {}", other.len()),
    }
}

/// The extension of `path`, lower case.
pub fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}
