//! What an engineer checks of an output, measured on the mesh that is written: wall thickness
//! and pore size as local thickness, the genus of each solid piece, and cavities.
//!
//! Invariants:
//! - `[build] report = "full"` (the default) measures everything; `"basic"` only the topology
//!   (one pass over the mesh), for optimisation loops that call the tool thousands of times.
//! - Local thickness ([`latticebuild_geom::measure`]) is measured on voxels of the mesh's own
//!   sample spacing (recovered from its mean triangle area, see [`measure::sample_spacing`]), coarser
//!   only to keep a part within [`MEASURE_VOXELS`] voxels; each figure carries the voxel it
//!   was measured with, so a wall of few voxels reads as what it is.
//! - Pores are measured only inside a block's box domain, which the lattice fills by
//!   construction: elsewhere (a tiled part, a fill within a mesh, an SDF program's solid) the
//!   void round the part is not a pore, and `pore_size` is absent.
//! - A streamed (chunked) mesh is gathered whole to be measured when it has at most
//!   [`MAX_TRIANGLES`] triangles; a larger one keeps its topology but not local thickness,
//!   and [`Measures::not_measured`] says why.
//! - The figures are part of the write stage's cached payload: a mesh is measured once.

use serde::{Deserialize, Serialize};

use latticebuild_geom::measure::{self, Stats};
use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::mesh_io::{ChunkSource, Pass};

/// How much of the report to measure (`[build] report`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ReportLevel {
    /// Topology only: no distance transform.
    Basic,
    /// Topology, wall thickness and pore size.
    #[default]
    Full,
}

impl ReportLevel {
    pub const NAMES: [&'static str; 2] = ["basic", "full"];

    pub fn parse(name: &str) -> Option<ReportLevel> {
        match name {
            "basic" => Some(ReportLevel::Basic),
            "full" => Some(ReportLevel::Full),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            ReportLevel::Basic => "basic",
            ReportLevel::Full => "full",
        }
    }
}

/// The most voxels a part's measuring grid holds (16.8 M, about 256³): what bounds the
/// measure's time and memory (about 10 bytes a voxel) on a part of any size.
pub const MEASURE_VOXELS: f64 = (1u64 << 24) as f64;

/// The most triangles of a streamed mesh gathered whole to be measured (about 1.5 GB with
/// the measure's triangle bins).
pub const MAX_TRIANGLES: u64 = 40_000_000;

/// The most solid pieces whose genus is listed (largest first); `components` counts them all.
pub const GENUS_LISTED: usize = 16;

/// Local thickness over one phase, in model units, with the voxel side it was measured on.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    pub min: f64,
    pub p05: f64,
    pub median: f64,
    pub max: f64,
    pub voxel: f64,
}

impl Spread {
    fn new(stats: Stats, voxel: f64) -> Spread {
        Spread {
            min: stats.min,
            p05: stats.p05,
            median: stats.median,
            max: stats.max,
            voxel,
        }
    }
}

/// What [`measure`] found.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Measures {
    pub wall_thickness: Option<Spread>,
    pub pore_size: Option<Spread>,
    /// Per solid piece, largest first (at most [`GENUS_LISTED`]): its outer surface's genus,
    /// `None` for a surface that is not closed.
    pub genus: Vec<Option<i64>>,
    /// Closed voids inside the solid (surfaces wound inward).
    pub cavities: u64,
    /// Why local thickness was not measured, when the level asked for it.
    pub not_measured: Option<String>,
}

/// The measures of `mesh` at `level`; pores are measured within `pore_box` only.
pub fn measure(mesh: &Mesh, level: ReportLevel, pore_box: Option<[[f64; 3]; 2]>) -> Measures {
    let topology = measure::solid_genera(mesh);
    let mut out = Measures {
        genus: topology.genus.iter().take(GENUS_LISTED).copied().collect(),
        cavities: topology.cavities as u64,
        ..Measures::default()
    };
    if level == ReportLevel::Basic || mesh.triangles.is_empty() {
        return out;
    }
    let Some(bounds) = pore_box.or_else(|| measure::bounds(mesh)) else {
        out.not_measured = Some("the mesh has no finite vertex".into());
        return out;
    };
    let volume: f64 = (0..3).map(|a| bounds[1][a] - bounds[0][a]).product();
    let spacing = measure::sample_spacing(mesh).max((volume / MEASURE_VOXELS).cbrt());
    if !(spacing.is_finite() && spacing > 0.0) {
        out.not_measured = Some("the mesh has no area".into());
        return out;
    }
    let t = measure::thickness(mesh, Some(bounds), spacing);
    out.wall_thickness = t.wall.map(|s| Spread::new(s, t.spacing[0]));
    if pore_box.is_some() {
        out.pore_size = t.pore.map(|s| Spread::new(s, t.spacing[1]));
    }
    out
}

/// [`measure`] of a streamed mesh, gathered whole when it is small enough (see the module
/// docs); an unreadable chunk is an error.
pub fn measure_chunked(
    chunks: &dyn ChunkSource,
    level: ReportLevel,
    pore_box: Option<[[f64; 3]; 2]>,
) -> std::io::Result<Measures> {
    let (vertices, triangles) = chunks.totals();
    if triangles > MAX_TRIANGLES {
        return Ok(Measures {
            not_measured: Some(format!(
                "{triangles} triangles: more than the {MAX_TRIANGLES} measured; \
                 measure a smaller part of the scaffold"
            )),
            ..Measures::default()
        });
    }
    let mut mesh = Mesh {
        vertices: Vec::with_capacity(vertices as usize),
        triangles: Vec::with_capacity(triangles as usize),
    };
    chunks.for_each_chunk(Pass::Facets, &mut |chunk| {
        mesh.vertices.extend_from_slice(&chunk.vertices);
        mesh.triangles.extend_from_slice(&chunk.triangles);
        Ok(())
    })?;
    Ok(measure(&mesh, level, pore_box))
}
