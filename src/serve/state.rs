//! What the page is told: after each build, every output's report and display mesh, the
//! stage graph with what was cached and what rebuilt, and the last error (a broken manifest's
//! diagnostics, with their file:line:column).
//!
//! Invariants:
//! - A failed build keeps the last good outputs on the page and adds its error; the next good
//!   build clears the error.
//! - A mesh is read again only when its file changed (path, size and modification time, as
//!   the build recognises written files) or its report did; otherwise the last encoding is
//!   reused, so a rebuild that changes one output re-reads one file.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::Serialize;

use super::mesh::{self, Hint};
use crate::report::Report;

/// One node of the stage graph as the page draws it.
#[derive(Clone, Debug, Serialize)]
pub struct DagNode {
    pub node: String,
    pub stage: String,
    pub inputs: Vec<String>,
    /// `"cached"`, `"rebuilt"`, or `"not built"` (the build stopped before it).
    pub status: &'static str,
}

/// An output's mesh as sent.
#[derive(Clone, Debug, Serialize)]
pub struct MeshInfo {
    /// Changes whenever the bytes do (the page fetches `/api/mesh/NAME?v=VERSION`).
    pub version: String,
    pub triangles: usize,
    pub source_triangles: u64,
    pub decimated: bool,
    pub bytes: usize,
    /// Seconds spent reading and decimating it.
    pub seconds: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct OutputView {
    pub name: String,
    pub report: serde_json::Value,
    pub mesh: Option<MeshInfo>,
    /// Why the mesh cannot be shown (no readable mesh file, unreadable file).
    pub mesh_error: Option<String>,
}

/// The whole state after a build (or while one runs).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Published {
    pub generation: u64,
    pub manifest: String,
    pub building: bool,
    pub error: Option<String>,
    pub outputs: Vec<OutputView>,
    pub dag: Vec<DagNode>,
    #[serde(skip)]
    pub meshes: BTreeMap<String, Arc<Vec<u8>>>,
}

impl Published {
    /// The JSON of `/api/state`.
    pub fn json(&self) -> Vec<u8> {
        serde_json::to_vec(self).unwrap_or_else(|e| format!("{{\"error\":\"{e}\"}}").into_bytes())
    }

    /// The same state, marked as building (the page greys its figures).
    pub fn building(&self) -> Published {
        Published {
            building: true,
            ..self.clone()
        }
    }

    /// The same outputs and graph with `error` as the last error.
    pub fn failed(&self, error: String) -> Published {
        Published {
            building: false,
            error: Some(error),
            ..self.clone()
        }
    }
}

/// The encoded meshes of the last build, by output name, for reuse.
#[derive(Default)]
pub struct MeshCache {
    entries: BTreeMap<String, (MeshKey, Arc<Vec<u8>>, MeshInfo)>,
}

/// What identifies a mesh file's contents without reading it.
#[derive(Clone, Debug, PartialEq)]
struct MeshKey {
    path: PathBuf,
    len: Option<u64>,
    modified_ns: Option<u64>,
    report: String,
}

/// The file to show of an output's written files: a binary STL streams; any other mesh format
/// the geometry crate reads will do.
fn mesh_file(files: &[String]) -> Option<&str> {
    let by_extension = |ext: &str| {
        files
            .iter()
            .map(String::as_str)
            .find(|f| Path::new(f).extension().is_some_and(|e| e == ext))
    };
    ["stl", "ply", "obj", "off"]
        .into_iter()
        .find_map(by_extension)
}

impl MeshCache {
    /// The display mesh of `report`'s output, from the cache when its file is unchanged.
    fn get(
        &mut self,
        report: &Report,
        report_json: &str,
        budget: usize,
    ) -> Result<(Arc<Vec<u8>>, MeshInfo), String> {
        let Some(file) = mesh_file(&report.files) else {
            return Err("no STL, PLY, OBJ or OFF file among the output's formats".into());
        };
        let path = PathBuf::from(file);
        let key = MeshKey {
            len: crate::files::file_len(&path),
            modified_ns: crate::files::modified_ns(&path),
            path: path.clone(),
            report: report_json.to_string(),
        };
        if let Some((old, bytes, info)) = self.entries.get(&report.name)
            && *old == key
        {
            return Ok((Arc::clone(bytes), info.clone()));
        }
        let hint = Hint {
            triangles: report.triangles,
            area: report.area,
            bbox_min: report.bbox.min,
            bbox_max: report.bbox.max,
        };
        let start = std::time::Instant::now();
        let shown = mesh::load(&path, &hint, budget)
            .map_err(|e| format!("cannot read `{}` for display: {e}", path.display()))?;
        let bytes = Arc::new(mesh::encode(&shown));
        let info = MeshInfo {
            version: blake3::hash(&bytes).to_hex()[..16].to_string(),
            triangles: shown.triangles.len(),
            source_triangles: shown.source_triangles,
            decimated: shown.decimated,
            bytes: bytes.len(),
            seconds: start.elapsed().as_secs_f64(),
        };
        self.entries
            .insert(report.name.clone(), (key, Arc::clone(&bytes), info.clone()));
        Ok((bytes, info))
    }

    /// The state after a successful build of `reports` over the stage graph `dag`.
    pub fn published(
        &mut self,
        manifest: &str,
        reports: &[Report],
        dag: Vec<DagNode>,
        budget: usize,
    ) -> Published {
        let mut outputs = Vec::new();
        let mut meshes = BTreeMap::new();
        for report in reports {
            let value = serde_json::to_value(report).unwrap_or(serde_json::Value::Null);
            let text = value.to_string();
            let (mesh, mesh_error) = match self.get(report, &text, budget) {
                Ok((bytes, info)) => {
                    meshes.insert(report.name.clone(), bytes);
                    (Some(info), None)
                }
                Err(e) => (None, Some(e)),
            };
            outputs.push(OutputView {
                name: report.name.clone(),
                report: value,
                mesh,
                mesh_error,
            });
        }
        // Forget outputs no longer built.
        self.entries.retain(|name, _| meshes.contains_key(name));
        Published {
            generation: 0,
            manifest: manifest.to_string(),
            building: false,
            error: None,
            outputs,
            dag,
            meshes,
        }
    }
}
