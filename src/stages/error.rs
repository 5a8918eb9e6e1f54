//! [`StageError`]: why running a node failed, as the build reports it (`stage `NODE` failed:
//! …`); and [`GeomError`], the geometry crate's errors a stage passes on.
//!
//! Invariant: each error's text is the message users see, word for word: the variants type
//! what failed, they do not reword it.

use std::io;
use std::path::PathBuf;

use latticebuild_geom::contour::ContourError;
use latticebuild_geom::contour2d::PlanarError;
use latticebuild_geom::density::TableError;
use latticebuild_geom::expr::ParseError;
use latticebuild_geom::islands::IslandError;
use latticebuild_geom::mesh_read::MeshReadError;
use latticebuild_geom::mesh_sdf::MeshSdfError;
use latticebuild_geom::periodic::CrystalError;
use latticebuild_geom::periodic::reconstruct::ReconstructError;
use latticebuild_geom::point_cloud::PointCloudError;
use latticebuild_geom::scaffold::ScaffoldError;
use latticebuild_geom::stack_lang::ProgramError;
use latticebuild_geom::symmetric::{FitError, GroupError};
use latticebuild_geom::tile::RegionError;
use latticebuild_geom::tile::TileError;
use latticebuild_geom::voxels::VoxelError;

use crate::cache::{CacheError, KeyError};

/// Why a node's stage failed.
#[derive(Debug, thiserror::Error)]
pub enum StageError {
    /// A `file` node's file could not be read.
    #[error("cannot read `{}`: {source}", path.display())]
    Unreadable {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    /// The stage's parameters do not form a cache key (a bug in the stage).
    #[error("cannot form its cache key: {0}")]
    Key(#[source] KeyError),
    /// A step of the geometry crate failed.
    #[error(transparent)]
    Geometry(Box<GeomError>),
    /// A step of the geometry crate failed on `what` (a file, the scaffold, a tiling…).
    #[error("{what}: {source}")]
    GeometryOf {
        what: String,
        #[source]
        source: Box<GeomError>,
    },
    /// A mesh input's name has no mesh extension, so its format is unknown.
    #[error("`{given}` has no mesh file extension")]
    NoMeshExtension { given: String },
    /// An earlier stage's payload (read back from the cache) does not decode.
    #[error("malformed {payload} payload{}", detail.as_ref().map(|d| format!(": {d}")).unwrap_or_default())]
    Malformed {
        payload: &'static str,
        detail: Option<String>,
    },
    /// The solid (or region, or surface) the manifest's values describe is empty: the cell has
    /// no solid part at this offset or thickness, or the program no surface in the box.
    #[error("{0}")]
    EmptySolid(String),
    /// A manifest value is out of its range somewhere, found only when the stage evaluated it:
    /// a graded thickness at a node, a volume fraction out of reach, too fine a voxel size.
    /// The message names the key and where.
    #[error("{0}")]
    ValueOutOfRange(String),
    /// A key or cell does not fit the input it applies to: a cell's group and the scaffold's
    /// elements, `skin` or `extrude` on the wrong kind of scaffold, a node-data view the
    /// scaffold lacks, a species the crystal lacks, `keep` on a planar region.
    #[error("{0}")]
    DoesNotFit(String),
    /// A crystal's surface reconstruction stayed above its tolerance.
    #[error("{0}")]
    NotConverged(String),
    /// A stage was handed an input of a kind it does not take, or made an output of a shape
    /// the builder does not expect: a bug in how the graph was built, never the user's.
    #[error("{0}")]
    Internal(String),
    /// An output file could not be written.
    #[error("cannot write `{path}`: {source}")]
    Output {
        path: String,
        #[source]
        source: io::Error,
    },
    /// The mesh could not be read back to measure it while its files were written.
    #[error("cannot measure the mesh: {0}")]
    Measure(#[source] io::Error),
    /// A chunked mesh input could not be read (not corruption: that reruns its node).
    #[error("cannot read the tiled mesh: {0}")]
    ReadChunked(#[source] io::Error),
    /// A chunk of a streamed mesh could not be written to its cache entry.
    #[error("cannot write the cache entry: {0}")]
    CacheWrite(#[source] io::Error),
    /// A streamed cache entry could not be begun.
    #[error(transparent)]
    CacheBegin(io::Error),
    #[error(transparent)]
    Cache(#[from] CacheError),
    /// The thread writing a streamed mesh to the cache stopped taking chunks (its own error,
    /// when it has one, is reported instead).
    #[error("the cache writer stopped")]
    CacheWriterStopped,
    /// A helper thread (named) panicked.
    #[error("{0} panicked")]
    Panicked(&'static str),
    /// The entry a stage just streamed into the cache does not open as a chunked mesh.
    #[error("the cache entry just written cannot be read back")]
    EntryUnreadable,
    /// The node's input was rebuilt after it was found corrupt, and was corrupt again.
    #[error("its input was corrupt again after a rebuild: {0}")]
    InputCorruptAgain(String),
    /// A node rebuilt after its entry was found corrupt made other bytes than before.
    #[error(
        "rebuilt after its cache entry was corrupt, it made different bytes (the stage is not \
         deterministic)"
    )]
    NotDeterministic,
}

impl StageError {
    /// A geometry error on `what`: `WHAT: ERROR`.
    pub fn geometry_of(what: impl Into<String>, source: impl Into<GeomError>) -> StageError {
        StageError::GeometryOf {
            what: what.into(),
            source: Box::new(source.into()),
        }
    }

    /// A payload that does not decode, without or with (`detail`) what is wrong with it.
    pub fn malformed(payload: &'static str) -> StageError {
        StageError::Malformed {
            payload,
            detail: None,
        }
    }
}

/// An error of the geometry crate, as a stage passes it on (its text unchanged).
#[derive(Debug, thiserror::Error)]
pub enum GeomError {
    #[error(transparent)]
    MeshRead(#[from] MeshReadError),
    #[error(transparent)]
    Voxel(#[from] VoxelError),
    #[error(transparent)]
    PointCloud(#[from] PointCloudError),
    #[error(transparent)]
    MeshSdf(#[from] MeshSdfError),
    #[error(transparent)]
    Sdf(#[from] ProgramError),
    #[error(transparent)]
    Group(#[from] GroupError),
    #[error(transparent)]
    Fit(#[from] FitError),
    #[error(transparent)]
    Crystal(#[from] CrystalError),
    #[error(transparent)]
    Reconstruct(#[from] ReconstructError),
    #[error(transparent)]
    Contour(#[from] ContourError),
    #[error(transparent)]
    Planar(#[from] PlanarError),
    #[error(transparent)]
    Tile(#[from] TileError),
    #[error(transparent)]
    Region(#[from] RegionError),
    #[error(transparent)]
    Scaffold(#[from] ScaffoldError),
    #[error(transparent)]
    Table(#[from] TableError),
    #[error(transparent)]
    Island(#[from] IslandError),
    /// An expression that does not compile: its message alone (the span is not shown).
    #[error("{}", .0.message)]
    Expr(ParseError),
}

impl From<ParseError> for GeomError {
    fn from(e: ParseError) -> GeomError {
        GeomError::Expr(e)
    }
}

/// `?` on a geometry crate's result in a stage: the error as it is.
macro_rules! geometry_errors {
    ($($error:ty),*) => {$(
        impl From<$error> for StageError {
            fn from(e: $error) -> StageError {
                StageError::Geometry(Box::new(e.into()))
            }
        }
    )*};
}

geometry_errors!(
    MeshReadError,
    MeshSdfError,
    ProgramError,
    GroupError,
    FitError,
    CrystalError,
    ReconstructError,
    ContourError,
    PlanarError,
    TileError,
    RegionError,
    ScaffoldError,
    TableError,
    IslandError,
    ParseError
);

#[cfg(test)]
mod tests {
    use super::*;

    /// The texts users saw when these were strings, built as they were.
    #[test]
    fn the_texts_are_the_messages_they_replace() {
        let io = || io::Error::new(io::ErrorKind::NotFound, "No such file or directory");
        let cases = [
            (
                StageError::Unreadable {
                    path: PathBuf::from("parts/a.stl"),
                    source: io(),
                },
                format!("cannot read `parts/a.stl`: {}", io()),
            ),
            (
                StageError::malformed("density table"),
                "malformed density table payload".to_string(),
            ),
            (
                StageError::Malformed {
                    payload: "mesh",
                    detail: Some("wrong magic".into()),
                },
                "malformed mesh payload: wrong magic".to_string(),
            ),
            (
                StageError::geometry_of("the cell's mesh", TileError::Resolution(1)),
                format!("the cell's mesh: {}", TileError::Resolution(1)),
            ),
            (
                StageError::from(TileError::Resolution(1)),
                TileError::Resolution(1).to_string(),
            ),
            (
                StageError::Output {
                    path: "out/a.stl".into(),
                    source: io(),
                },
                format!("cannot write `out/a.stl`: {}", io()),
            ),
            (
                StageError::Panicked("the cache writer"),
                "the cache writer panicked".to_string(),
            ),
        ];
        for (error, text) in cases {
            assert_eq!(error.to_string(), text);
        }
        let parse = latticebuild_geom::expr::compile("x +").expect_err("does not compile");
        let message = parse.message.clone();
        assert_eq!(
            StageError::geometry_of("cell formula does not compile", parse).to_string(),
            format!("cell formula does not compile: {message}")
        );
    }
}
