//! The `sdf` stage: an SDF program (the Cesogen stack language) contoured into a checked
//! mesh, and the parts of it `latticebuild sdf` shares: [`mesh_field`] turns a `file` word's
//! bytes into the mesh's signed distance, and [`contour_field`] finds the box and contours.
//!
//! Invariants:
//! - The stage is a pure function of its program, box, resolution, contouring method and the
//!   bytes of its `file` meshes (its inputs, in the order of [`ProgramStage::files`]), all in
//!   its key. The key holds the program's
//!   canonical text with each path replaced by its input's number and extension, so renaming
//!   or touching a mesh reruns nothing, while editing it does.
//! - A solid with no surface in its box is an error, not an empty file.

use std::sync::Arc;

use latticebuild_geom::contour::Contouring;
use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::mesh_read;
use latticebuild_geom::mesh_sdf::{MeshSdf, SdfOptions};
use latticebuild_geom::stack_lang::{
    self, Aabb, ExternalField, ExternalSolids, Program, ProgramField,
};
use latticebuild_geom::validate::{self, MeshCheck};

use super::StageError;
use super::artifact::{MeshArtifact, MeshSummary};
use crate::cache::{KeyBuilder, Param};
use crate::manifest::{ProgramOutput, ProgramResolution, voxel_samples};
use crate::progress::StageProgress;

/// 2: the summary counts the mesh's connected pieces.
pub const VERSION: u32 = 2;

/// The signed distance of the mesh in `bytes`, read in the format its content shows (the
/// extension of `given` when the content does not tell); errors name `given`.
pub fn mesh_field(given: &str, bytes: &[u8]) -> Result<Arc<dyn ExternalField>, StageError> {
    let extension = std::path::Path::new(given)
        .extension()
        .and_then(|e| e.to_str());
    let soup = mesh_read::read_auto(bytes, extension)
        .map_err(|e| StageError::geometry_of(format!("cannot read `{given}`"), e))?;
    let sdf = MeshSdf::new(&soup, SdfOptions::default())
        .map_err(|e| StageError::geometry_of(format!("`{given}`"), e))?;
    Ok(Arc::new(sdf))
}

/// A contoured program: the mesh, its check, and the box and samples it was contoured with.
pub struct Contoured {
    pub mesh: Mesh,
    pub check: MeshCheck,
    pub domain: Aabb,
    pub samples: [usize; 3],
}

/// Contours `field` by `method` over `bounds` (its own bounds, with the paper's box rule, when
/// `None`) at the samples `samples` gives for that box.
pub fn contour_field(
    field: &ProgramField,
    method: Contouring,
    bounds: Option<Aabb>,
    samples: &dyn Fn(&Aabb) -> Result<[usize; 3], StageError>,
    progress: &dyn StageProgress,
) -> Result<Contoured, StageError> {
    let domain = bounds.unwrap_or_else(|| field.domain());
    let counts = samples(&domain)?;
    progress.phase("contouring");
    let mesh = stack_lang::mesh_by(method, field, &domain, counts, &|n| progress.advance(n))?;
    if mesh.is_empty() {
        return Err(StageError::EmptySolid(format!(
            "the solid has no surface in the box {}",
            box_text(&domain)
        )));
    }
    progress.phase("checking the mesh");
    let check = validate::check(&mesh);
    Ok(Contoured {
        mesh,
        check,
        domain,
        samples: counts,
    })
}

/// `[x0,x1]×[y0,y1]×[z0,z1]`
pub fn box_text(b: &Aabb) -> String {
    (0..3)
        .map(|a| format!("[{},{}]", b.min[a], b.max[a]))
        .collect::<Vec<_>>()
        .join("×")
}

/// `sdf`: an SDF output's program, contoured.
#[derive(Clone, Debug, PartialEq)]
pub struct ProgramStage {
    pub program: Program,
    /// The paths of the `file` words as written, once each: input `i` holds the bytes of
    /// `files[i]`.
    pub files: Vec<String>,
    pub bounds: Option<[[f64; 3]; 2]>,
    pub resolution: ProgramResolution,
    pub contouring: Contouring,
}

/// The `file` words' meshes, from their inputs' bytes.
struct InputMeshes<'a> {
    files: &'a [String],
    bytes: &'a [&'a [u8]],
}

impl ExternalSolids for InputMeshes<'_> {
    fn resolve(&self, path: &str, _from: Option<&str>) -> Result<Arc<dyn ExternalField>, String> {
        let i = self
            .files
            .iter()
            .position(|f| f == path)
            .ok_or_else(|| format!("`{path}` is not an input of the stage"))?;
        let bytes = self.bytes.get(i).ok_or("missing input")?;
        mesh_field(path, bytes).map_err(|e| e.to_string())
    }
}

impl ProgramStage {
    pub fn new(output: &ProgramOutput) -> ProgramStage {
        ProgramStage {
            program: output.program.clone(),
            files: output.files.iter().map(|f| f.given.clone()).collect(),
            bounds: output.bounds,
            resolution: output.resolution,
            contouring: output.contouring,
        }
    }

    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        // A path becomes its input's number (the content's hash is that input's) and its
        // extension (which may pick the reader).
        let file_key = |path: &str| {
            let i = self.files.iter().position(|f| f == path).unwrap_or(0);
            let extension = std::path::Path::new(path)
                .extension()
                .map_or(String::new(), |e| e.to_string_lossy().to_lowercase());
            format!("#{}.{extension}", i + 1)
        };
        let bounds = match self.bounds {
            Some([min, max]) => Param::List(min.iter().chain(&max).map(|&v| v.into()).collect()),
            None => Param::Str("auto".into()),
        };
        let (samples, voxel) = match self.resolution {
            ProgramResolution::Counts(c) => {
                (c.iter().map(|&n| Param::U64(n as u64)).collect(), 0.0)
            }
            ProgramResolution::Voxel(h) => (Vec::new(), h),
        };
        key.param("program", self.program.canonical_with(&file_key))
            .param("bounds", bounds)
            .param("samples", Param::List(samples))
            .param("voxel", voxel)
            .param("contour", self.contouring.name())
    }

    /// Progress steps of [`ProgramStage::run`] (cube layers), when known before it runs.
    pub fn steps(&self) -> u64 {
        match (self.resolution, self.bounds) {
            (ProgramResolution::Counts(c), _) => c[2] as u64 - 1,
            (ProgramResolution::Voxel(h), Some([min, max])) => {
                voxel_samples(min, max, h).map_or(0, |c| c[2] as u64 - 1)
            }
            (ProgramResolution::Voxel(_), None) => 0,
        }
    }

    /// Contours the program with the meshes of its `file` words in `files` (their bytes).
    pub fn run(
        &self,
        files: &[&[u8]],
        progress: &dyn StageProgress,
    ) -> Result<MeshArtifact, StageError> {
        progress.phase("compiling the program");
        let meshes = InputMeshes {
            files: &self.files,
            bytes: files,
        };
        let field = self.program.field(&meshes)?;
        let bounds = self.bounds.map(|[min, max]| Aabb { min, max });
        let samples = |domain: &Aabb| match self.resolution {
            ProgramResolution::Counts(c) => Ok(c),
            ProgramResolution::Voxel(h) => voxel_samples(domain.min, domain.max, h).map_err(|_| {
                StageError::ValueOutOfRange(format!(
                    "`voxel = {h}` gives too many samples for the box {}",
                    box_text(domain)
                ))
            }),
        };
        let contoured = contour_field(&field, self.contouring, bounds, &samples, progress)?;
        Ok(MeshArtifact {
            summary: MeshSummary::from_check(&contoured.check)
                .with_pieces(&validate::pieces(&contoured.mesh), false),
            mesh: contoured.mesh,
            planar: None,
            domain: Some([contoured.domain.min, contoured.domain.max]),
            tiling: None,
            shell: None,
            sizing: None,
        })
    }
}
