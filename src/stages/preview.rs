//! The `preview` stage: `NAME.png`, a picture of an output's mesh with its caption
//! ([`latticebuild_geom::render`]: an isometric view beside the section through the middle of
//! the output's box; a planar region seen from above).
//!
//! It reads the mesh (whole, or a tiling's chunks streamed from the cache entry: never whole
//! in memory; or takes the picture drawn while the tiling ran, [`crate::early`], when it was
//! drawn to the same spec), the write stage's record (for the caption's triangle count, volume fraction
//! and warnings) and the payloads of the cell stages whose warnings the report repeats, so
//! its key holds everything its picture shows. A change of formats reruns the write and this
//! stage, nothing before them. Like the write stage it reaches its file only through the
//! [`OutputSink`], and a chunked input found corrupt while read is
//! [`WriteError::CorruptInput`] (the builder reruns the node that made it).

use latticebuild_geom::mesh_io::Pass;
use latticebuild_geom::render::{Line, Preview, Spec};

use super::StageError;
use super::artifact::{WrittenFile, WrittenOutput};
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
        if let Some(bbox) = written.tiling.as_ref().and_then(|t| t.scaffold_bbox) {
            return self.tiling_spec(bbox);
        }
        let s = &written.summary;
        let bbox = written
            .domain
            .or(self.domain)
            .filter(|_| written.tiling.is_none())
            .unwrap_or([s.bbox_min, s.bbox_max]);
        self.fitted(bbox, written.planar_element_area.is_some())
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
    use super::thousands;

    #[test]
    fn thousands_are_separated() {
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(999), "999");
        assert_eq!(thousands(1000), "1,000");
        assert_eq!(thousands(44_123_456), "44,123,456");
    }
}
