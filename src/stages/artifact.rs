//! Stage payloads: how a contoured mesh and a written output are stored in the cache.
//!
//! A mesh payload is `LBMESH01`, the vertex and triangle counts and the length of the summary
//! (u64 little-endian each), the summary as JSON, then the raw vertex (`3 × f32`) and triangle
//! (`3 × u32`) arrays. The arrays are copied as raw native bytes: the cache is per machine,
//! and every platform we build for is little-endian (checked at compile time below).

use serde::{Deserialize, Serialize};

use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::validate::{self, MeshCheck, Pieces};

use super::StageError;

pub use super::sizing::SizingSummary;

#[cfg(not(target_endian = "little"))]
compile_error!("mesh payloads store raw little-endian arrays");

const MESH_MAGIC: &[u8; 8] = b"LBMESH01";

/// What the report says about a mesh: counts, validity and measures, from our validator.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeshSummary {
    pub triangles: u64,
    pub vertices: u64,
    pub watertight: bool,
    pub manifold: bool,
    pub euler_characteristic: i64,
    pub volume: f64,
    pub area: f64,
    pub bbox_min: [f64; 3],
    pub bbox_max: [f64; 3],
    pub boundary_edges: u64,
    pub nonmanifold_edges: u64,
    pub misoriented_edges: u64,
    pub nonmanifold_vertices: u64,
    pub degenerate_triangles: u64,
    pub duplicate_positions: u64,
    /// Solid pieces (connected surfaces of positive volume; a cavity's surface is not one),
    /// and the largest one's share of the volume (of the area, for a planar region).
    #[serde(default)]
    pub components: u64,
    #[serde(default)]
    pub largest_component_fraction: f64,
    /// What the `islands` stage removed to make this mesh (`None`: nothing was asked to be);
    /// absent otherwise, so other payloads keep their bytes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub removed: Option<Removed>,
}

/// The pieces the `islands` stage removed (`keep`, `min_island_volume`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Removed {
    /// Solid pieces removed.
    pub pieces: u64,
    /// The volume removed (signed: kept plus removed is the mesh before).
    pub volume: f64,
    /// The largest removed piece's volume (0 when none was).
    pub largest_piece: f64,
    pub triangles: u64,
}

impl MeshSummary {
    /// The summary of a whole mesh: its check and its pieces (measured by area for a planar
    /// region, by volume for a solid).
    pub fn of_mesh(mesh: &Mesh, planar: bool) -> MeshSummary {
        MeshSummary::from_check(&validate::check(mesh)).with_pieces(&validate::pieces(mesh), planar)
    }

    /// With the pieces found in the mesh.
    pub fn with_pieces(self, pieces: &Pieces, planar: bool) -> MeshSummary {
        MeshSummary {
            components: pieces.count(planar) as u64,
            largest_component_fraction: pieces.largest_fraction(planar),
            ..self
        }
    }

    /// The check's part of the summary (no pieces yet: see [`MeshSummary::with_pieces`]).
    pub fn from_check(c: &MeshCheck) -> MeshSummary {
        MeshSummary {
            triangles: c.triangles as u64,
            vertices: c.vertices as u64,
            watertight: c.watertight,
            manifold: c.manifold,
            euler_characteristic: c.euler_characteristic,
            volume: c.volume,
            area: c.area,
            bbox_min: c.bbox_min,
            bbox_max: c.bbox_max,
            boundary_edges: c.boundary_edges as u64,
            nonmanifold_edges: c.nonmanifold_edges as u64,
            misoriented_edges: c.misoriented_edges as u64,
            nonmanifold_vertices: c.nonmanifold_vertices as u64,
            degenerate_triangles: c.degenerate_triangles as u64,
            duplicate_positions: c.duplicate_positions as u64,
            components: 0,
            largest_component_fraction: 0.0,
            removed: None,
        }
    }
}

/// A contoured mesh with its summary, and for 2D cells the planar region's outline.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshArtifact {
    pub mesh: Mesh,
    pub summary: MeshSummary,
    pub planar: Option<Planar>,
    /// The box `[min, max]` an SDF program was contoured over, found when it ran (its bounds
    /// are computed then); `None` for cells, whose domain is the manifest's.
    pub domain: Option<[[f64; 3]; 2]>,
    /// What a tiling found (`None` but for tiled outputs).
    pub tiling: Option<TilingSummary>,
    /// What the contourer saw of a shell's wall (`None` but for shells it measured).
    pub shell: Option<ShellSummary>,
    /// A solid sized by `wall`, `grow` or `volume_fraction`: what was asked and solved.
    pub sizing: Option<SizingSummary>,
}

/// A shell's wall as its samples saw it, for the report's thin-wall warning.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShellSummary {
    /// The shell's width in field values.
    pub thickness: f64,
    /// The thinnest wall in sample spacings: `thickness / |∇f|`, with `|∇f|` per sample step
    /// at its largest over the grid cubes the shell's middle level crosses (forward
    /// differences averaged per axis); `None` when that level crosses no cube.
    pub thinnest_wall: Option<f64>,
    /// The samples per axis it was contoured with (for the advice on how many would do).
    pub samples: [usize; 3],
    /// Contoured from the sampled `|f − c| − w/2` (a shell confined to a part), not as the
    /// band between two levels: a wall between two samples is then lost, not just coarse.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub sampled: bool,
    /// Tiled into a scaffold: `samples` is the resolution, walls are in lattice spacings of
    /// the reference element (an estimate where elements are curved or stretched).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub tiled: bool,
    /// Sized by `wall` or `volume_fraction`: `thickness` is then a width of the distance field
    /// (normalised for a graded one), and the advice is a thicker `wall`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub sized: bool,
}

/// The tiler's highest resolution (points per element edge).
const MAX_RESOLUTION: u64 = 256;

impl ShellSummary {
    /// Walls thinner than this many sample spacings are warned about: below it a wall is
    /// crossed by few grid edges, so its volume and shape are only roughly resolved (and a
    /// sampler that did not contour the two levels separately would lose it entirely).
    pub const THIN_WALL: f64 = 2.0;

    /// The warning for a wall thinner than [`ShellSummary::THIN_WALL`] sample spacings, with
    /// the samples per axis that would make it that thick.
    pub fn warning(&self) -> Option<String> {
        let wall = self.thinnest_wall.filter(|&w| w < Self::THIN_WALL)?;
        let factor = Self::THIN_WALL / wall;
        let more = |n: usize| ((n - 1) as f64 * factor).ceil() as u64 + 1;
        let (measured, larger) = if self.sized {
            (
                "measured on the distance field the wall is sized on".to_string(),
                "a thicker `wall` (or a higher `volume_fraction`)",
            )
        } else {
            (
                format!(
                    "thickness {} over the steepest field gradient",
                    self.thickness
                ),
                "a larger thickness",
            )
        };
        let effect = if self.sampled {
            "poorly resolved, and the thinner ones can vanish (this solid is sampled as one \
             function, not contoured from its two levels)"
        } else {
            "poorly resolved"
        };
        let (spacings, advice) = if self.tiled {
            let resolution = more(self.samples[0]);
            let advice = if resolution > MAX_RESOLUTION {
                return Some(format!(
                    "the thinnest shell wall is about {wall:.2} lattice spacings ({measured}); \
                     walls under {} spacings are {effect}, and even the highest resolution \
                     ({MAX_RESOLUTION}) leaves it under {}: use {larger}",
                    Self::THIN_WALL,
                    Self::THIN_WALL,
                ));
            } else {
                format!("`resolution = {resolution}`")
            };
            ("lattice spacings", advice)
        } else {
            let counts: Vec<String> = self.samples.iter().map(|&n| more(n).to_string()).collect();
            ("sample spacings", format!("{} samples", counts.join(" × ")))
        };
        Some(format!(
            "the thinnest shell wall is about {wall:.2} {spacings} ({measured}); walls under {} \
             spacings are {effect}: use about {advice}, or {larger}",
            Self::THIN_WALL,
        ))
    }
}

/// What the `tile` stage reports besides the mesh: the scaffold's elements and faces (edges,
/// for a 2D scaffold), and its volume (the reference of the volume fraction). For a 2D
/// scaffold `scaffold_volume` is its area, times `h` when the region is extruded or thickened
/// by `h`, and `region_area` is the tiled region's area (the mid-surface's, when thickened).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TilingSummary {
    /// The element kind (`tet4`, `hex27`, …).
    pub element: String,
    pub elements: u64,
    pub interior_faces: u64,
    pub boundary_faces: u64,
    /// From the elements' isoparametric maps (curved for quadratic elements).
    pub scaffold_volume: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region_area: Option<f64>,
    /// A 3D scaffold's box (of the nodes its elements use): known before the first triangle,
    /// so the preview, fitted to it, can be drawn while the tiling runs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scaffold_bbox: Option<[[f64; 3]; 2]>,
}

/// What the SVG of a 2D region needs, and the area its fraction is over. A 2D cell carries its
/// boundary loops and the element's outline (drawn by the write stage); a region tiled into a
/// planar scaffold its finished drawing (`svg`, the scaffold drawn faintly); a region tiled
/// into a curved surface neither (no SVG: `element` and `svg` are empty).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Planar {
    pub boundary: Vec<Vec<[f64; 2]>>,
    pub element: Vec<[f64; 2]>,
    /// The element's area, or the scaffold's for a tiled region.
    pub element_area: f64,
    // Absent for cells, so their payloads (and hashes) are what they were before tiling.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub svg: Option<String>,
}

/// The JSON part of a mesh payload.
#[derive(Serialize, Deserialize)]
struct MeshHead {
    summary: MeshSummary,
    planar: Option<Planar>,
    // Absent for cells, so their payloads (and hashes) are what they were before SDF outputs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    domain: Option<[[f64; 3]; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    tiling: Option<TilingSummary>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    shell: Option<ShellSummary>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sizing: Option<SizingSummary>,
}

impl MeshArtifact {
    /// The payload is `head()` followed by the two `arrays()`, written one after the other so
    /// a 300 MB mesh is never concatenated in memory.
    pub fn head(&self) -> Vec<u8> {
        let head = MeshHead {
            summary: self.summary.clone(),
            planar: self.planar.clone(),
            domain: self.domain,
            tiling: self.tiling.clone(),
            shell: self.shell.clone(),
            sizing: self.sizing.clone(),
        };
        let summary = serde_json::to_vec(&head).expect("summary serializes");
        let mut head = Vec::with_capacity(32 + summary.len());
        head.extend_from_slice(MESH_MAGIC);
        head.extend_from_slice(&(self.mesh.vertices.len() as u64).to_le_bytes());
        head.extend_from_slice(&(self.mesh.triangles.len() as u64).to_le_bytes());
        head.extend_from_slice(&(summary.len() as u64).to_le_bytes());
        head.extend_from_slice(&summary);
        head
    }

    /// The raw vertex and triangle arrays that follow the head.
    pub fn arrays(&self) -> [&[u8]; 2] {
        [
            bytemuck::cast_slice(&self.mesh.vertices),
            bytemuck::cast_slice(&self.mesh.triangles),
        ]
    }

    pub fn decode(payload: &[u8]) -> Result<MeshArtifact, StageError> {
        let bad = |what: &str| StageError::Malformed {
            payload: "mesh",
            detail: Some(what.to_string()),
        };
        let take = |at: usize| -> Result<u64, StageError> {
            let bytes = payload
                .get(at..at + 8)
                .ok_or_else(|| bad("truncated header"))?;
            Ok(u64::from_le_bytes(
                bytes.try_into().map_err(|_| bad("header"))?,
            ))
        };
        if payload.get(..8) != Some(MESH_MAGIC.as_slice()) {
            return Err(bad("wrong magic"));
        }
        let (nv, nt, ns) = (take(8)? as usize, take(16)? as usize, take(24)? as usize);
        let summary_end = 32usize
            .checked_add(ns)
            .ok_or_else(|| bad("summary length"))?;
        let vertices_end = summary_end
            .checked_add(nv * 12)
            .ok_or_else(|| bad("vertex count"))?;
        let end = vertices_end
            .checked_add(nt * 12)
            .ok_or_else(|| bad("triangle count"))?;
        if payload.len() != end {
            return Err(bad("length does not match the counts"));
        }
        let MeshHead {
            summary,
            planar,
            domain,
            tiling,
            shell,
            sizing,
        } = serde_json::from_slice(&payload[32..summary_end]).map_err(|e| bad(&e.to_string()))?;
        let vertices = bytemuck::pod_collect_to_vec(&payload[summary_end..vertices_end]);
        let triangles = bytemuck::pod_collect_to_vec(&payload[vertices_end..end]);
        Ok(MeshArtifact {
            mesh: Mesh {
                vertices,
                triangles,
            },
            summary,
            planar,
            domain,
            tiling,
            shell,
            sizing,
        })
    }
}

/// One file the write stage produced.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct WrittenFile {
    /// Path relative to the output directory.
    pub path: String,
    pub format: String,
    pub bytes: u64,
    /// Modification time when written (ns since the epoch): with the size, how a later build
    /// tells that the file is still the one it wrote.
    pub modified_ns: u64,
}

/// The write stage's payload: the files and the summary of the mesh they hold.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WrittenOutput {
    pub files: Vec<WrittenFile>,
    pub summary: MeshSummary,
    /// For a 2D cell, the element's area (the report's fraction is area over it).
    pub planar_element_area: Option<f64>,
    /// For an SDF program, the box it was contoured over (see [`MeshArtifact::domain`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub domain: Option<[[f64; 3]; 2]>,
    /// For a tiled output, what the tiling found (see [`MeshArtifact::tiling`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tiling: Option<TilingSummary>,
    /// For a shell, its wall (see [`MeshArtifact::shell`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shell: Option<ShellSummary>,
    /// See [`MeshArtifact::sizing`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sizing: Option<SizingSummary>,
    /// What was measured of the mesh (`None` for a planar region).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measures: Option<super::measure::Measures>,
}
