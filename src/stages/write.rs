//! The `write` stage: writes a mesh in each requested format through an [`OutputSink`].
//!
//! Its input is a whole mesh, or a chunked one read from its cache entry a chunk at a time
//! ([`MeshInput::Chunked`]), so writing a tiled mesh of any size holds one chunk per format.
//! A chunked input found corrupt while being read is [`WriteError::CorruptInput`]: the files
//! being written are discarded (the sink renames only whole files) and the builder reruns the
//! node that made the mesh.
//!
//! Every file carries the stage's [`Stamp`]: the tool's version and the model's unit in its
//! header (STL, PLY, OBJ, VTK, VTU), the output's name and parameters too in a 3MF, and an SVG
//! drawing gets its physical `width` and `height` in that unit. The stamp is in the key.
//!
//! With no formats (`formats = []`) nothing is written, but the mesh is measured all the
//! same: the report is the one the files would have had, less their names.

use std::io::{self, Seek, Write};

use rayon::prelude::*;

use latticebuild_geom::contour2d::PlanarRegion;
use latticebuild_geom::mesh_io::{self, ChunkSource, Encoding, Format, Stamp, Units};

use super::StageError;
use super::artifact::{MeshArtifact, WrittenFile, WrittenOutput};
use super::chunked::{ChunkedHead, is_corrupt};
use super::measure::{self, Measures, ReportLevel};
use crate::cache::{KeyBuilder, Param};
use crate::manifest::Output;

/// 2: the payload holds the output's [`Measures`]. 3: files carry a [`Stamp`].
pub const VERSION: u32 = 3;

/// Where the write stage's files go. The CLI's implementation writes each file to a temporary
/// name and renames it into place, so a file is whole or absent.
pub trait OutputSink: Sync {
    /// Creates `relative` (to the output directory) from what `fill` writes, and returns its
    /// size and modification time (ns since the epoch).
    fn write_file(
        &self,
        relative: &str,
        fill: &mut dyn FnMut(&mut dyn Write) -> io::Result<()>,
    ) -> io::Result<(u64, u64)>;

    /// Whether `file` is still on disk as it was written (same size and modification time).
    fn holds(&self, file: &WrittenFile) -> bool;

    /// Starts `relative` as a pending file, written (and sought in) through the handle while
    /// the mesh is still being made: renamed into place by [`PendingFile::commit`], removed
    /// if dropped uncommitted.
    fn begin_file(&self, relative: &str) -> io::Result<Box<dyn PendingFile>>;
}

/// A file of the sink being written, not yet in place.
pub trait PendingFile: Write + Seek + Send {
    /// Puts the file in place; its size and modification time (ns since the epoch).
    fn commit(self: Box<Self>) -> io::Result<(u64, u64)>;
}

/// A file written while its mesh was made (see `Builder`), for the write stage to put in place
/// instead of writing it again: the same bytes, since it was written from the same chunks.
pub struct Prewritten {
    pub format: Format,
    pub file: Box<dyn PendingFile>,
}

/// The mesh the write stage writes.
#[derive(Clone, Copy)]
pub enum MeshInput<'a> {
    Whole(&'a MeshArtifact),
    Chunked {
        chunks: &'a dyn ChunkSource,
        head: &'a ChunkedHead,
    },
}

/// Why the write stage failed.
#[derive(Debug)]
pub enum WriteError {
    /// The chunked input's entry failed verification while being read.
    CorruptInput(String),
    Failed(StageError),
}

#[derive(Clone, Debug, PartialEq)]
pub struct WriteStage {
    pub formats: Vec<Format>,
    pub encoding: Encoding,
    pub stem: String,
    /// How much of the mesh to measure ([`measure`]), while the files are written.
    pub report: ReportLevel,
    /// The box whose void is the output's pores: a block's domain; `None` where the void
    /// round the part is not a pore (a tiled part, a fill within a mesh, an element, an SDF
    /// program's solid).
    pub pore_box: Option<[[f64; 3]; 2]>,
    /// What the files say about themselves ([`stamp`]).
    pub stamp: Stamp,
}

/// The stamp of output `name` of a manifest whose lengths are in `units` (its `units` key,
/// which the manifest has checked), made with `parameters`.
pub fn stamp(name: &str, units: &str, parameters: Vec<(String, String)>) -> Stamp {
    Stamp {
        generator: format!("latticebuild {}", env!("CARGO_PKG_VERSION")),
        units: Some(Units::from_name(units).expect("the manifest checks `units`")),
        title: name.to_string(),
        parameters,
    }
}

impl WriteStage {
    pub fn new(output: &Output, report: ReportLevel, stamp: Stamp) -> WriteStage {
        let boxed = !output.over_element && !output.planar_domain && output.within.is_none();
        WriteStage {
            formats: output.formats.clone(),
            encoding: output.encoding,
            stem: output.stem.clone(),
            report,
            pore_box: boxed.then_some([output.domain_min, output.domain_max]),
            stamp,
        }
    }

    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        // The pore box's six numbers, or none.
        let pores = Param::List(
            self.pore_box
                .iter()
                .flatten()
                .flatten()
                .map(|&c| Param::F64(c))
                .collect(),
        );
        let formats = self
            .formats
            .iter()
            .map(|f| Param::Str(f.name().to_string()))
            .collect();
        let stamp = &self.stamp;
        // Only a 3MF carries the parameters: keyed without one, an edit that leaves the mesh
        // as it was (another spelling of the cell, a renamed scaffold file) reruns no write.
        let carried = self.formats.contains(&Format::ThreeMf);
        let parameters = stamp
            .parameters
            .iter()
            .filter(|_| carried)
            .map(|(k, v)| Param::Str(format!("{k}={v}")))
            .collect();
        key.param("formats", Param::List(formats))
            .param("generator", stamp.generator.as_str())
            .param("units", stamp.units.map_or("", Units::name))
            .param("title", stamp.title.as_str())
            .param("parameters", Param::List(parameters))
            .param("ascii", self.encoding == Encoding::Ascii)
            .param("path", self.stem.as_str())
            .param("report", self.report.name())
            .param("pores", pores)
    }

    /// The relative path of the file for `format`.
    pub fn path(&self, format: Format) -> String {
        format!("{}.{}", self.stem, format.name())
    }

    /// Writes (or puts in place) each format's file, in parallel.
    fn write_files(
        &self,
        input: MeshInput,
        sink: &dyn OutputSink,
        jobs: Vec<(Format, Option<Box<dyn PendingFile>>)>,
    ) -> Result<Vec<WrittenFile>, WriteError> {
        jobs.into_par_iter()
            .map(|(format, ready)| {
                let path = self.path(format);
                let written = match ready {
                    Some(file) => file.commit(),
                    None => sink.write_file(&path, &mut |w| match input {
                        MeshInput::Whole(artifact) => mesh_io::write_mesh_stamped(
                            &artifact.mesh,
                            format,
                            self.encoding,
                            &self.stamp,
                            w,
                        ),
                        MeshInput::Chunked { chunks, .. } => mesh_io::write_chunked_stamped(
                            chunks,
                            format,
                            self.encoding,
                            &self.stamp,
                            w,
                        ),
                    }),
                };
                let (bytes, modified_ns) = written.map_err(|e| {
                    if is_corrupt(&e) {
                        WriteError::CorruptInput(e.to_string())
                    } else {
                        WriteError::Failed(StageError::Output {
                            path: path.clone(),
                            source: e,
                        })
                    }
                })?;
                Ok(WrittenFile {
                    path,
                    format: format.name().to_string(),
                    bytes,
                    modified_ns,
                })
            })
            .collect()
    }

    /// Writes every format (in parallel: each writer streams on its own); a format in
    /// `prewritten` is only put in place.
    pub fn run(
        &self,
        input: MeshInput,
        sink: &dyn OutputSink,
        prewritten: Vec<Prewritten>,
    ) -> Result<WrittenOutput, WriteError> {
        let mut prewritten = prewritten;
        let jobs: Vec<(Format, Option<Box<dyn PendingFile>>)> = self
            .formats
            .iter()
            .map(|&format| {
                let ready = prewritten
                    .iter()
                    .position(|p| p.format == format)
                    .map(|i| prewritten.swap_remove(i).file);
                (format, ready)
            })
            .collect();
        let measure = || -> Result<Option<Measures>, WriteError> {
            Ok(Some(match input {
                MeshInput::Whole(artifact) if artifact.planar.is_some() => return Ok(None),
                MeshInput::Whole(artifact) => {
                    measure::measure(&artifact.mesh, self.report, self.pore_box)
                }
                MeshInput::Chunked { chunks, .. } => {
                    measure::measure_chunked(chunks, self.report, None).map_err(|e| {
                        if is_corrupt(&e) {
                            WriteError::CorruptInput(e.to_string())
                        } else {
                            WriteError::Failed(StageError::Measure(e))
                        }
                    })?
                }
            }))
        };
        let (files, measures) = rayon::join(|| self.write_files(input, sink, jobs), measure);
        let (files, measures) = (files?, measures?);

        let artifact = match input {
            MeshInput::Whole(artifact) => artifact,
            MeshInput::Chunked { head, .. } => {
                return Ok(WrittenOutput {
                    files,
                    summary: head.summary.clone(),
                    planar_element_area: None,
                    domain: None,
                    tiling: head.tiling.clone(),
                    shell: head.shell.clone(),
                    sizing: head.sizing.clone(),
                    measures,
                });
            }
        };
        let mut files = files;
        // `formats = []` writes no file at all, the drawing included (the report only).
        let drawn = artifact
            .planar
            .as_ref()
            .filter(|p| p.svg.is_some() || !p.element.is_empty())
            .filter(|_| !self.formats.is_empty());
        if let Some(planar) = drawn {
            // A planar region also gets an SVG drawing: a 2D cell's is drawn here, a tiled
            // region's came drawn (with its scaffold) from the tile stage.
            let path = format!("{}.svg", self.stem);
            let region = PlanarRegion {
                mesh: Default::default(),
                positions: Vec::new(),
                boundary: planar.boundary.clone(),
            };
            let (bytes, modified_ns) = sink
                .write_file(&path, &mut |w| {
                    let svg = match &planar.svg {
                        Some(svg) => svg.clone(),
                        None => {
                            let mut svg = Vec::new();
                            mesh_io::write_svg(&region, &planar.element, &mut svg)?;
                            String::from_utf8_lossy(&svg).into_owned()
                        }
                    };
                    let svg = match self.stamp.units {
                        Some(units) => mesh_io::with_physical_size(&svg, units),
                        None => svg,
                    };
                    w.write_all(svg.as_bytes())
                })
                .map_err(|e| {
                    WriteError::Failed(StageError::Output {
                        path: path.clone(),
                        source: e,
                    })
                })?;
            files.push(WrittenFile {
                path,
                format: "svg".into(),
                bytes,
                modified_ns,
            });
        }
        Ok(WrittenOutput {
            files,
            summary: artifact.summary.clone(),
            planar_element_area: artifact.planar.as_ref().map(|p| p.element_area),
            domain: artifact.domain,
            tiling: artifact.tiling.clone(),
            shell: artifact.shell.clone(),
            sizing: artifact.sizing.clone(),
            measures,
        })
    }
}
