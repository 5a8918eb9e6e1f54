//! The schema of triangle-mesh inputs: cells made from a mesh (`mesh`, `placement`, `sample`)
//! and outputs filling a part (`within`, `skin`).
//!
//! A child of `schema.rs` (it extends its `Checker`). Invariants:
//! - No IO: file names are resolved against the manifest's directory, and their extension is
//!   checked against the formats the readers know; whether the file exists is checked by
//!   [`super::super::check_input_files`] when a manifest is loaded from disk.
//! - Keys that only make sense with a mesh (`placement`, `sample`, `skin`) are errors without
//!   one, naming the key that is missing.

use std::collections::BTreeMap;

use latticebuild_geom::spelling;

use super::super::model::{Cell, CellSource, InputFile, MeshCell, MeshSampling, Output};
use super::{Checker, Fields, Value, list};

/// File extensions of the mesh readers, lower case.
pub(super) const MESH_EXTENSIONS: [&str; 5] = ["stl", "obj", "ply", "off", "3mf"];
/// SDF programs read meshes as written, and a 3MF's coordinates have a unit: not read there.
const PROGRAM_MESH_EXTENSIONS: [&str; 4] = ["stl", "obj", "ply", "off"];

/// A kind of input file: the extensions its readers know, its noun in messages, and a help
/// line for a file they don't.
pub(super) struct FileKind {
    pub extensions: &'static [&'static str],
    pub noun: &'static str,
    pub help: &'static str,
}

pub(super) const MESH_FILES: FileKind = FileKind {
    extensions: &MESH_EXTENSIONS,
    noun: "mesh",
    help: "convert the mesh to STL, OBJ, PLY, OFF or 3MF",
};

pub(super) const PROGRAM_MESH_FILES: FileKind = FileKind {
    extensions: &PROGRAM_MESH_EXTENSIONS,
    noun: "mesh",
    help: "convert the mesh to STL, OBJ, PLY or OFF",
};
const PLACEMENTS: [&str; 2] = ["reference", "fit"];
const SAMPLINGS: [&str; 2] = ["sdf", "containment"];

impl Checker<'_, '_, '_> {
    /// `mesh = "file"`: a cell source; placement and sampling are filled in by
    /// [`Checker::mesh_options`].
    pub(super) fn mesh_source(&mut self, cell: &str, value: &Value<'_>) -> Option<CellSource> {
        let file = self.mesh_file(&format!("cells.{cell}.mesh"), value)?;
        Some(CellSource::Mesh(MeshCell {
            file,
            fit_placement: false,
            sampling: MeshSampling::SignedDistance,
        }))
    }

    /// `placement` and `sample` of a cell: `(fit placement, sampling)` for a mesh cell, and an
    /// error for each of them given to another cell.
    pub(super) fn mesh_options(
        &mut self,
        cell: &str,
        fields: &Fields<'_, '_>,
        is_mesh: bool,
    ) -> Option<(bool, MeshSampling)> {
        let path = |k: &str| format!("cells.{cell}.{k}");
        if !is_mesh {
            for k in ["placement", "sample"] {
                if let Some((key, _)) = fields.get(k) {
                    self.error(
                        key.span(),
                        &format!("`{}` applies only to mesh cells", path(k)),
                        &format!("cell `{cell}` has no `mesh`"),
                        Some(&format!(
                            "remove `{k}`, or give the cell a `mesh = \"part.stl\"`"
                        )),
                    );
                }
            }
            return None;
        }
        let placement = match fields.get("placement") {
            None => Some("reference"),
            Some((_, v)) => self.choice(&path("placement"), v, &PLACEMENTS, "placement"),
        };
        let sampling = match fields.get("sample") {
            None => Some("sdf"),
            Some((_, v)) => self.choice(&path("sample"), v, &SAMPLINGS, "way of sampling"),
        };
        let sampling = match sampling? {
            "containment" => MeshSampling::Containment,
            _ => MeshSampling::SignedDistance,
        };
        Some((placement? == "fit", sampling))
    }

    /// `within` and `skin` of an output; `(None, None)` when anything was reported.
    #[allow(clippy::type_complexity)]
    pub(super) fn within(
        &mut self,
        output: &str,
        fields: &Fields<'_, '_>,
        over_element: bool,
        planar: bool,
    ) -> (Option<Option<InputFile>>, Option<Option<f64>>) {
        let path = |k: &str| format!("outputs.{output}.{k}");
        let within = match fields.get("within") {
            None => Some(None),
            Some((key, v)) => {
                let conflict = if over_element {
                    Some((
                        "the output is one cell over its element (`over = \"element\"`)",
                        "remove `over`, and give the `domain` to fill",
                    ))
                } else if planar {
                    Some((
                        "the domain is planar, and a part is a 3D solid",
                        "give the `domain` corners as [x, y, z]",
                    ))
                } else {
                    None
                };
                match conflict {
                    Some((why, help)) => {
                        self.error(
                            key.span(),
                            &format!("`{}` does not apply here", path("within")),
                            why,
                            Some(help),
                        );
                        None
                    }
                    None => self.mesh_file(&path("within"), v).map(Some),
                }
            }
        };
        let skin = match fields.get("skin") {
            None => Some(None),
            Some((key, v)) => {
                if fields.contains_key("within") || fields.misspelled("within") {
                    self.positive_number(&path("skin"), v, "a number").map(Some)
                } else {
                    self.error(
                        key.span(),
                        &format!("`{}` applies only with `within`", path("skin")),
                        "there is no part to put a skin on",
                        Some("add `within = \"part.stl\"`, or remove `skin`"),
                    );
                    None
                }
            }
        };
        (within, skin)
    }

    /// A mesh file name: a non-empty string with a known extension, resolved against the
    /// manifest's directory.
    fn mesh_file(&mut self, key: &str, value: &Value<'_>) -> Option<InputFile> {
        let given = self.string(key, value)?;
        self.input_file(&format!("`{key}`"), given, value.span(), &MESH_FILES)
    }

    /// `given`, named at `span` and described as `what` in messages, as an input file of
    /// `kind` resolved against the manifest's directory; an error when its extension is not
    /// one the readers know.
    pub(super) fn input_file(
        &mut self,
        what: &str,
        given: &str,
        span: std::ops::Range<usize>,
        kind: &FileKind,
    ) -> Option<InputFile> {
        let extension = std::path::Path::new(given)
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        if extension
            .as_deref()
            .is_none_or(|e| !kind.extensions.contains(&e))
        {
            let shown = extension.map_or("no extension".to_string(), |e| format!("`.{e}`"));
            self.error(
                span,
                &format!("{what} is not a {} file the readers know", kind.noun),
                &format!("{shown}; expected {}", list(kind.extensions)),
                Some(kind.help),
            );
            return None;
        }
        Some(InputFile {
            given: given.to_string(),
            path: self.root.join(given),
            span,
        })
    }

    /// One of `options`, with a suggestion for a near miss. `what` names the kind of value.
    pub(super) fn choice(
        &mut self,
        key: &str,
        value: &Value<'_>,
        options: &[&'static str],
        what: &str,
    ) -> Option<&'static str> {
        let text = self.string(key, value)?;
        if let Some(found) = options.iter().find(|o| **o == text) {
            return Some(found);
        }
        let help = match spelling::closest(text, options.iter().copied()) {
            Some(close) => format!("did you mean `{close}`?"),
            None => format!("expected one of {}", list(options)),
        };
        self.error(
            value.span(),
            &format!("unknown {what} `{text}` in `{key}`"),
            &format!("expected one of {}", list(options)),
            Some(&help),
        );
        None
    }
}

/// Every mesh, voxel or crystal file the manifest reads, once each, in name order (for `watch` and the load-time
/// existence check).
pub(super) fn input_files(
    cells: &BTreeMap<String, Cell>,
    outputs: &BTreeMap<String, Output>,
) -> Vec<std::path::PathBuf> {
    let mut files: Vec<std::path::PathBuf> = cells
        .values()
        .filter_map(|c| match &c.source {
            CellSource::Mesh(m) => Some(m.file.path.clone()),
            CellSource::Voxels(v) => Some(v.file.path.clone()),
            CellSource::Points(file) => Some(file.path.clone()),
            CellSource::Crystal(c) => Some(c.file.path.clone()),
            _ => None,
        })
        .chain(
            outputs
                .values()
                .filter_map(|o| o.within.as_ref().map(|f| f.path.clone())),
        )
        .collect();
    files.sort();
    files.dedup();
    files
}
