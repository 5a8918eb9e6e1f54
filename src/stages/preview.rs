//! The `preview` stage: `NAME.png`, a picture of an output's mesh with its caption
//! ([`latticebuild_geom::render`]: an isometric view beside the section through the middle of
//! the output's box; a planar region seen from above).
//!
//! It reads the mesh (whole, or a tiling's chunks streamed from the cache entry: never whole
//! in memory; or takes the picture drawn while the tiling ran, [`crate::early`], or while
//! the write ran, [`PreviewStage::draw_whole`], when it was drawn to the same spec), the
//! write stage's record (for the caption's triangle count, volume fraction and warnings) and
//! the payloads of the cell stages whose warnings the report repeats, so its key holds
//! everything its picture shows. A change of formats reruns the write and this
//! stage, nothing before them. Like the write stage it reaches its file only through the
//! [`OutputSink`], and a chunked input found corrupt while read is
//! [`WriteError::CorruptInput`] (the builder reruns the node that made it).

use latticebuild_geom::mesh_io::Pass;
use latticebuild_geom::render::{Line, Preview, Spec};

use super::StageError;
use super::artifact::{MeshArtifact, MeshSummary, TilingSummary, WrittenFile, WrittenOutput};
use super::chunked::is_corrupt;
use super::warnings;
use super::write::{MeshInput, OutputSink, WriteError};
use crate::cache::{KeyBuilder, Param};

/// 1: the first. 2: a caption band of one height; a 3D tiling fitted to its scaffold's box.
/// 3: projected and shaded in `f32` (a pixel's colour may move by a level, an edge by a pixel).
pub const VERSION: u32 = 3;

/// The default image size (`[build] preview_size`).
pub const DEFAULT_SIZE: [u32; 2] = [1024, 768];

#[derive(Clone, Debug, PartialEq)]
pub struct PreviewStage {
    /// The output's name, for the caption.
    pub output: String,
    /// The PNG's path, without `.png`, relative to the output directory.
    pub stem: String,
    /// Width and height in pixels.
    pub size: [u32; 2],
    /// The box the output was made in, when the manifest gives it (a cell's domain): its
    /// volume is the fraction's reference, its middle the section's plane.
    pub domain: Option<[[f64; 3]; 2]>,
    /// The solid fills a part (`within`): its fraction is not compared with the one asked.
    pub within: bool,
    /// The node names of the cell stages read after the mesh and the write record (inputs 2…),
    /// for their warnings.
    pub carriers: Vec<String>,
}

impl PreviewStage {
    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        let domain = Param::List(
            self.domain
                .iter()
                .flatten()
                .flatten()
                .map(|&c| Param::F64(c))
                .collect(),
        );
        let size = Param::List(self.size.iter().map(|&v| Param::U64(v.into())).collect());
        key.param("output", self.output.as_str())
            .param("path", self.stem.as_str())
            .param("size", size)
            .param("domain", domain)
            .param("within", self.within)
    }

    pub fn path(&self) -> String {
        format!("{}.png", self.stem)
    }

    /// The caption: `NAME: N triangles, volume fraction F`, then the report's warnings.
    pub fn caption(&self, written: &WrittenOutput, cell_warnings: &[String]) -> Vec<Line> {
        let fraction = warnings::volume_fraction(written, self.domain);
        let what = match written.planar_element_area {
            Some(_) => "area fraction",
            None => "volume fraction",
        };
        let mut lines = vec![Line {
            text: format!(
                "{}: {} triangles, {what} {fraction:.4}",
                self.output,
                thousands(written.summary.triangles)
            ),
            warning: false,
        }];
        let found = warnings::mesh_warnings(written, fraction, self.within);
        lines.extend(
            found
                .into_iter()
                .chain(cell_warnings.iter().cloned())
                .map(|w| Line {
                    text: format!("warning: {w}"),
                    warning: true,
                }),
        );
        lines
    }

    /// What the picture is fitted to: a 3D tiling's scaffold box (known before its first
    /// triangle, so the picture can be drawn while it tiles), the output's box (its own,
    /// found by an SDF program, or the manifest's), else the mesh's bounding box; the section
    /// cuts its middle.
    fn spec(&self, written: &WrittenOutput) -> Spec {
        let planar = written.planar_element_area.is_some();
        self.spec_from(
            written.tiling.as_ref(),
            written.domain,
            &written.summary,
            planar,
        )
    }

    /// The spec of the picture of a whole mesh, known before it is written: the same as
    /// [`PreviewStage::spec`] of its write record, which copies these fields from it.
    pub fn spec_of(&self, mesh: &MeshArtifact) -> Spec {
        let planar = mesh.planar.is_some();
        self.spec_from(mesh.tiling.as_ref(), mesh.domain, &mesh.summary, planar)
    }

    /// The picture of a whole mesh, drawn before its write record exists (to
    /// [`PreviewStage::spec_of`]); `None` for a mesh with a corner out of range, which the
    /// stage reports when it runs.
    pub fn draw_whole(&self, mesh: &MeshArtifact) -> Option<Preview> {
        draw(self.spec_of(mesh), MeshInput::Whole(mesh)).ok()
    }

    fn spec_from(
        &self,
        tiling: Option<&TilingSummary>,
        domain: Option<[[f64; 3]; 2]>,
        summary: &MeshSummary,
        planar: bool,
    ) -> Spec {
        if let Some(bbox) = tiling.and_then(|t| t.scaffold_bbox) {
            return self.tiling_spec(bbox);
        }
        let bbox = domain
            .or(self.domain)
            .filter(|_| tiling.is_none())
            .unwrap_or([summary.bbox_min, summary.bbox_max]);
        self.fitted(bbox, planar)
    }

    /// The picture of a 3D tiling of a scaffold of box `bbox`.
    pub fn tiling_spec(&self, bbox: [[f64; 3]; 2]) -> Spec {
        self.fitted(bbox, false)
    }

    fn fitted(&self, bbox: [[f64; 3]; 2], planar: bool) -> Spec {
        let finite = bbox.iter().flatten().all(|c| c.is_finite());
        let bbox = if finite { bbox } else { [[0.0; 3], [1.0; 3]] };
        Spec {
            size: (self.size[0] as usize, self.size[1] as usize),
            bbox,
            cut: (!planar).then_some((bbox[0][2] + bbox[1][2]) / 2.0),
        }
    }

    /// Draws the mesh and writes the PNG through `sink`. `early`: the mesh's picture drawn
    /// while it was made ([`crate::early`]), used when drawn to this output's spec.
    pub fn run(
        &self,
        input: MeshInput,
        written: &WrittenOutput,
        cell_warnings: &[String],
        sink: &dyn OutputSink,
        early: Option<Preview>,
    ) -> Result<WrittenFile, WriteError> {
        let spec = self.spec(written);
        let preview = match early {
            Some(picture) if *picture.spec() == spec => picture,
            _ => draw(spec, input)?,
        };
        let image = preview.finish(&self.caption(written, cell_warnings));
        let path = self.path();
        let (bytes, modified_ns) = sink
            .write_file(&path, &mut |w| image.write_png(w))
            .map_err(|e| {
                WriteError::Failed(StageError::Output {
                    path: path.clone(),
                    source: e,
                })
            })?;
        Ok(WrittenFile {
            path,
            format: "png".into(),
            bytes,
            modified_ns,
        })
    }
}

/// The picture of `input` to `spec`, read from the cache entry a chunk at a time when chunked.
fn draw(spec: Spec, input: MeshInput) -> Result<Preview, WriteError> {
    let mut preview = Preview::new(spec);
    let bad = |i: usize| {
        WriteError::Failed(StageError::Internal(format!(
            "triangle {i} of the mesh has a corner out of range"
        )))
    };
    match input {
        MeshInput::Whole(artifact) => preview.add_mesh(&artifact.mesh).map_err(bad)?,
        MeshInput::Chunked { chunks, .. } => {
            let mut failed = None;
            let walk = chunks.for_each_chunk(Pass::Facets, &mut |chunk| {
                preview.add_chunk(chunk).map_err(|i| {
                    failed = Some(i);
                    std::io::Error::other("a corner out of range")
                })
            });
            if let Err(e) = walk {
                return Err(match failed {
                    Some(i) => bad(i),
                    None if is_corrupt(&e) => WriteError::CorruptInput(e.to_string()),
                    None => WriteError::Failed(StageError::Internal(format!(
                        "cannot read the mesh: {e}"
                    ))),
                });
            }
        }
    }
    Ok(preview)
}

/// `1234567` as `1,234,567`.
fn thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::files::OutputDir;
    use crate::stages::artifact::Planar;
    use crate::stages::measure::ReportLevel;
    use crate::stages::write::{WriteStage, stamp};
    use latticebuild_geom::mesh::Mesh;
    use latticebuild_geom::mesh_io::{Encoding, Format};

    #[test]
    fn the_spec_of_a_whole_mesh_before_its_write_is_the_one_of_its_write_record() {
        // A picture drawn while the write runs is used only if drawn to the spec the preview
        // stage then finds from the write's record: with the output's box given, with the
        // mesh's own box, with the manifest's domain, for a planar region.
        let mesh = Mesh {
            vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        };
        let dir = tempfile::tempdir().expect("temp dir");
        let sink = OutputDir::new(dir.path().to_path_buf());
        let write = WriteStage {
            formats: vec![Format::Stl],
            encoding: Encoding::Binary,
            stem: "t".into(),
            report: ReportLevel::Basic,
            pore_box: None,
            stamp: stamp("t", "mm", Vec::new()),
        };
        let mut checked = 0;
        for (domain, planar) in [
            (None, false),
            (Some([[-1.0; 3], [4.0; 3]]), false),
            (None, true),
        ] {
            let artifact = MeshArtifact {
                summary: MeshSummary::of_mesh(&mesh, planar),
                mesh: mesh.clone(),
                planar: planar.then(|| Planar {
                    boundary: Vec::new(),
                    element: Vec::new(),
                    element_area: 1.0,
                    svg: None,
                }),
                domain,
                tiling: None,
                shell: None,
                sizing: None,
            };
            let written = write
                .run(MeshInput::Whole(&artifact), &sink, Vec::new())
                .expect("written");
            for manifest_domain in [None, Some([[-2.0; 3], [5.0; 3]])] {
                let preview = PreviewStage {
                    output: "t".into(),
                    stem: "t".into(),
                    size: DEFAULT_SIZE,
                    domain: manifest_domain,
                    within: false,
                    carriers: Vec::new(),
                };
                let spec = preview.spec(&written);
                assert_eq!(preview.spec_of(&artifact), spec, "{domain:?} {planar}");
                assert_eq!(spec.cut.is_none(), planar);
                checked += 1;
            }
        }
        assert_eq!(checked, 6);
    }

    #[test]
    fn thousands_are_separated() {
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(999), "999");
        assert_eq!(thousands(1000), "1,000");
        assert_eq!(thousands(44_123_456), "44,123,456");
    }
}
