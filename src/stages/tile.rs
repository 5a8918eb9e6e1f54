//! The `tile` stage: a fitted symmetric cell (or a transition between two) tiled into every
//! element of a scaffold — a mesh file's bytes or a generated grid — as one checked mesh, with
//! what the tiling found (elements, interior and boundary faces, the scaffold's volume).
//!
//! A 2D scaffold (quad, tri; planar or a surface in 3D) tiles into a region: by itself an open
//! triangle mesh, reported by its area over the scaffold's (a planar one also drawn as SVG over
//! its scaffold), or made a closed solid by `extrude` (planar only) or `thickness_normal`.
//!
//! A 3D scaffold's mesh is produced, checked and handed on a [`MeshChunk`] at a time (the
//! builder streams the chunks into the cache), so the stage never needs the whole mesh; its
//! result is then only the head (summary and tiling), [`TileOutput::Chunked`]. 2D tilings
//! stay whole meshes.
//!
//! Invariants:
//! - A pure function of its parameters and its inputs: the cells' coefficient tables (one, or
//!   two for a transition) and, for a `mesh =` scaffold, the file's bytes (last input). The
//!   key holds the file's extension (which may pick the reader), never its path, so renaming
//!   or touching a scaffold reruns nothing while editing it does.
//! - Everything only known once the scaffold is read is checked here with an error naming the
//!   file: the element kind against the cells' group, inverted or degenerate elements (by
//!   element tag), missing node-data views (listing those the file has), non-finite or
//!   non-positive graded values (by node tag). Nodal values are interpolated by the element's
//!   own (linear or quadratic) shape functions: transition weights are clamped to [0, 1] after
//!   interpolation, at every sample (so a `by` that leaves [0, 1] is the clamp of its
//!   interpolant), and a thickness whose quadratic interpolant dips to ≤ 0 inside an element is
//!   an error naming the element (`latticebuild_geom::tile`).
//! - Expressions are evaluated at the scaffold's node positions (model units).
//! - `extrude`/`thickness_normal` on a 3D scaffold, `skin` on a 2D one, and `extrude` on a
//!   curved surface are errors naming the file and its element kind.

use latticebuild_geom::contour::{BandMesh, steepest_at_level_within};
use latticebuild_geom::density::LevelTable;
use latticebuild_geom::distance::DistanceField;
use latticebuild_geom::element::Element3;
use latticebuild_geom::expr;
use latticebuild_geom::field::{Band, Grid, ScalarField, Solid};
use latticebuild_geom::mesh::{Mesh, MeshChunk, SpareArrays};
use latticebuild_geom::scaffold::{self, ElementKind, Scaffold};
use latticebuild_geom::symmetric::FittedCell;
use latticebuild_geom::tile::{
    RegionError, TiledRegion, TiledSolid, Transition, chunk_elements_for, extrude,
    reference_element, region_svg, stream_scaffold, thickness_normal, tile_surface_scaffold,
};
use latticebuild_geom::validate::{PieceCounter, StreamCheck};
use std::collections::VecDeque;
use std::sync::Arc;

use super::StageError;
use super::artifact::{MeshArtifact, MeshSummary, Planar, ShellSummary, TilingSummary};
use super::chunked::ChunkedHead;
use super::contour::sizing_param;
use super::sizing::{
    DensityStage, Over, SizingSummary, asked_length, graded_fraction_summary, length_summary,
    solve_uniform, table_of, tabled_fraction,
};
use super::symmetric::{FittedPayload, group_of};
use crate::cache::{KeyBuilder, Param};
use crate::manifest::{
    Continuity, GroupSpec, Manifest, NodalValue, ScaffoldGrid, ScaffoldSource, Sizing, Target,
    Thicken, TiledOutput, tiling_group,
};
use crate::progress::StageProgress;

/// 3: quadratic elements interpolate nodal values through all their nodes; weights clamped
/// after interpolation. 4: chunks of about 500k triangles (were 2M). 5: shells contoured as
/// the band between their two levels, and their wall measured (`shell` in the head).
/// 6: sized solids (`wall`, `grow`, `volume_fraction`) and their summary in the head.
/// 7: point-evaluated distances projected onto the surface (Newton): walls and growths
/// moved, and entries made before that kept a version that no longer described them.
/// 8: a 3D tiling's head records its scaffold's box (`scaffold_bbox`).
pub const VERSION: u32 = 8;

/// Triangles per chunk asked of the producer, about. Chunk boundaries are in the payload's
/// bytes, so in its hash: the chunk size is a function of the resolution (in the key) alone,
/// never of the machine. 500k rather than 2M: the chunks' working set then stays in cache
/// (measured on the 100k bracket: 5 % less CPU end to end, peak memory 600 → 230 MB), and
/// the pipeline fills and drains faster.
const CHUNK_TRIANGLES: usize = 500_000;

/// A C¹ tiling's largest `|∇Φ·n|` on the faces, relative to the bound of `|∇Φ|`: rounding
/// only.
const NORMAL_TOLERANCE: f64 = 1e-9;

/// What the stage made: a whole mesh (2D tilings), or the head of a mesh whose chunks went to
/// the `chunks` callback of [`TileStage::run`].
// One value per stage run, moved once: its size does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
pub enum TileOutput {
    Whole(MeshArtifact),
    Chunked(ChunkedHead),
}

/// What a 3D tiling hands on while it runs ([`TileStage::run`]): its scaffold's box once the
/// scaffold is read, before anything else, then its chunks in order.
pub enum Tiled {
    /// The box of the nodes the elements use (also [`TilingSummary::scaffold_bbox`]).
    ScaffoldBox([[f64; 3]; 2]),
    Chunk(Arc<MeshChunk>),
}

/// Where the scaffold comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum ScaffoldInput {
    /// A file, as written in the manifest (its bytes are the stage's last input).
    File(String),
    Grid(ScaffoldGrid),
}

/// `tile`: one tiled output's solid.
#[derive(Clone, Debug, PartialEq)]
pub struct TileStage {
    /// The output's name and its cells' names, for messages only (not in the key).
    pub output: String,
    pub cells: Vec<String>,
    pub scaffold_name: String,
    pub scaffold: ScaffoldInput,
    /// The cells' group (named; validated).
    pub group: GroupSpec,
    /// The weight of the second cell, with a transition.
    pub by: Option<NodalValue>,
    pub solid: Solid,
    pub sizing: Sizing,
    pub thickness: Option<NodalValue>,
    pub offset: Option<NodalValue>,
    pub resolution: usize,
    pub skin: Option<f64>,
    /// How a 2D scaffold's region becomes a solid (`None`: the region).
    pub thicken: Option<Thicken>,
    /// `c1`: the scaffold's elements mapped by C¹ maps (quad4, hex8), the cells checked to meet
    /// their faces at right angles.
    pub continuity: Continuity,
}

fn nodal_param(value: &Option<NodalValue>) -> Param {
    Param::Str(match value {
        None => String::new(),
        Some(NodalValue::Expr(text)) => format!("expr:{text}"),
        Some(NodalValue::NodeData(view)) => format!("nodedata:{view}"),
    })
}

fn extension(given: &str) -> String {
    std::path::Path::new(given)
        .extension()
        .map_or(String::new(), |e| e.to_string_lossy().to_lowercase())
}

impl TileStage {
    pub fn new(manifest: &Manifest, output: &TiledOutput) -> TileStage {
        let scaffold = &manifest.scaffolds[&output.scaffold];
        let group = manifest.cells[&output.cell]
            .symmetric
            .as_ref()
            .map_or(GroupSpec::Named(String::new()), |s| s.group.clone());
        let mut cells = vec![output.cell.clone()];
        cells.extend(output.transition.as_ref().map(|t| t.to.clone()));
        TileStage {
            output: output.name.text.clone(),
            cells,
            scaffold_name: output.scaffold.clone(),
            scaffold: match &scaffold.source {
                ScaffoldSource::Mesh(file) => ScaffoldInput::File(file.given.clone()),
                ScaffoldSource::Grid(grid) => ScaffoldInput::Grid(grid.clone()),
            },
            group,
            by: output.transition.as_ref().map(|t| t.by.clone()),
            solid: output.solid,
            sizing: output.sizing.clone(),
            thickness: output.thickness.clone(),
            offset: output.offset.clone(),
            resolution: output.resolution,
            skin: output.skin,
            thicken: output.thicken,
            continuity: scaffold.continuity,
        }
    }

    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        let scaffold = match &self.scaffold {
            ScaffoldInput::File(given) => Param::Str(format!("file.{}", extension(given))),
            ScaffoldInput::Grid(g) => {
                let mut items: Vec<Param> = vec![Param::Str(g.element.name().into())];
                items.extend(g.min.iter().chain(&g.max).map(|&v| Param::F64(v)));
                items.extend(g.divisions.iter().map(|&n| Param::U64(n as u64)));
                Param::List(items)
            }
        };
        let group = match &self.group {
            GroupSpec::Named(name) => name.clone(),
            GroupSpec::Generators { .. } => "generators".into(),
        };
        let (solid, offset, thickness) = match self.solid {
            Solid::Inside { offset } => ("inside", offset, 0.0),
            Solid::Outside { offset } => ("outside", offset, 0.0),
            Solid::Shell { thickness } => ("shell", 0.0, thickness),
            Solid::EccentricShell { offset, thickness } => ("eccentric_shell", offset, thickness),
        };
        key.param("scaffold", scaffold)
            .param("group", group.as_str())
            .param("by", nodal_param(&self.by))
            .param("solid", solid)
            .param("offset", offset)
            .param("thickness", thickness)
            .param("graded_thickness", nodal_param(&self.thickness))
            .param("graded_offset", nodal_param(&self.offset))
            .param("sizing", sizing_param(&self.sizing))
            .param("resolution", Param::U64(self.resolution as u64))
            .param("skin", self.skin.unwrap_or(0.0))
            .param("continuity", self.continuity.key())
            .param(
                "thicken",
                Param::List(match self.thicken {
                    None => Vec::new(),
                    Some(t) => vec![Param::Str(t.key().into()), Param::F64(t.length())],
                }),
            )
    }

    /// How many inputs are cells (then the scaffold file, if any, then the density table).
    pub fn cell_inputs(&self) -> usize {
        self.cells.len()
    }

    /// Whether the scaffold is a file (an input after the cells).
    pub fn reads_file(&self) -> bool {
        matches!(self.scaffold, ScaffoldInput::File(_))
    }

    /// Whether the stage reads a density table (its last input): to solve a volume fraction.
    pub fn reads_table(&self) -> bool {
        matches!(self.sizing, Sizing::VolumeFraction { .. })
    }

    /// The density stage whose table it reads: over the reference element, in its units.
    pub fn density(&self) -> Option<DensityStage> {
        self.reads_table().then(|| DensityStage {
            fitted: Some(self.group.clone()),
            over: Over::Element,
            projected: true,
            distance: self
                .sizing
                .distance_level(&self.solid)
                .map(|level| (level, [1.0; 3])),
        })
    }

    /// The scaffold from the file's bytes (`None` for a grid), checked for bad elements.
    fn scaffold(&self, file: Option<&[u8]>) -> Result<Scaffold, StageError> {
        let scaffold = match (&self.scaffold, file) {
            (ScaffoldInput::File(given), Some(bytes)) => {
                scaffold::read_scaffold(bytes, given, Some(&extension(given)))
                    .map_err(|e| StageError::geometry_of("cannot read the scaffold", e))?
            }
            (ScaffoldInput::Grid(g), _) => scaffold::grid(g.min, g.max, g.divisions, g.element)
                .map_err(|e| {
                    StageError::geometry_of(format!("scaffold `{}`", self.scaffold_name), e)
                })?,
            (ScaffoldInput::File(given), None) => {
                return Err(StageError::Internal(format!(
                    "the bytes of `{given}` are not an input"
                )));
            }
        };
        let mut scaffold = scaffold;
        if self.continuity == Continuity::C1 {
            scaffold
                .make_c1()
                .map_err(|e| StageError::geometry_of("scaffold", e))?;
        }
        // With C¹ maps this checks their Jacobians: graded spacing can fold a cubic edge.
        scaffold::check(&scaffold).map_err(|e| StageError::geometry_of("scaffold", e))?;
        Ok(scaffold)
    }

    fn source(&self) -> String {
        match &self.scaffold {
            ScaffoldInput::File(given) => format!("`{given}`"),
            ScaffoldInput::Grid(_) => format!("the grid `{}`", self.scaffold_name),
        }
    }

    /// A C¹ tiling's cell must meet its element's faces at right angles (docs/method.md §C¹
    /// element maps): `max |∇Φ·n|` on the faces, against the bound `2π N Σ |c|` of `|∇Φ|`.
    /// Quad and hex cells (D4, Oh) always do, their faces being mirror planes; the check
    /// names the cell should that ever fail.
    fn check_normal_to_faces(&self, name: &str, cell: &FittedCell) -> Result<(), StageError> {
        let residual = cell
            .max_face_normal_derivative()
            .map_err(StageError::from)?;
        let bound = std::f64::consts::TAU
            * cell.n() as f64
            * cell.coefficients().iter().map(|c| c.c.norm()).sum::<f64>();
        if residual <= NORMAL_TOLERANCE * bound {
            return Ok(());
        }
        Err(StageError::DoesNotFit(format!(
            "`outputs.{}` tiles {} with `continuity = \"c1\"`, which needs its cells to meet \
             the element's faces at right angles, but cell `{name}` crosses them with a normal \
             derivative up to {residual:.3e}: set `normal_to_faces = true` on `cells.{name}`",
            self.output,
            self.source()
        )))
    }

    /// The element kind against the cells' group, and the keys that need 2D (or 3D) elements.
    fn check_kind(&self, kind: ElementKind) -> Result<(), StageError> {
        let needed = tiling_group(kind);
        let GroupSpec::Named(group) = &self.group else {
            return Err(StageError::Internal(
                "tiling needs a cell with a named group".into(),
            ));
        };
        if group != needed {
            let cells = self
                .cells
                .iter()
                .map(|c| format!("`{c}`"))
                .collect::<Vec<_>>()
                .join(" and ");
            return Err(StageError::DoesNotFit(format!(
                "{} has {} elements, which need a cell of group `{needed}`, but {cells} of \
                 `outputs.{}` {} group `{group}`",
                self.source(),
                kind.name(),
                self.output,
                if self.cells.len() > 1 { "have" } else { "has" }
            )));
        }
        match (kind.dimension(), self.thicken, self.skin) {
            (2, _, Some(_)) => Err(StageError::DoesNotFit(format!(
                "`outputs.{}.skin` does not apply to 2D scaffolds, but {} has {} elements: \
                 use `extrude = h` or `thickness_normal = h` to make the region a solid",
                self.output,
                self.source(),
                kind.name()
            ))),
            (3, Some(thicken), _) => Err(StageError::DoesNotFit(format!(
                "`outputs.{}.{}` applies only to 2D scaffolds (quad, tri), but {} has {} \
                 elements, which tile into a solid already",
                self.output,
                thicken.key(),
                self.source(),
                kind.name()
            ))),
            _ => Ok(()),
        }
    }

    /// Runs the stage on the cells' coefficient tables and, for a file, its bytes. A 3D
    /// tiling's scaffold box, then its chunks (in order, as they are made and checked) go to
    /// `handed_on`.
    pub fn run(
        &self,
        cells: &[&[u8]],
        file: Option<&[u8]>,
        table: Option<&[u8]>,
        progress: &dyn StageProgress,
        handed_on: &mut (dyn FnMut(Tiled) -> Result<(), StageError> + Send),
    ) -> Result<TileOutput, StageError> {
        progress.phase("reading the scaffold");
        let scaffold = self.scaffold(file)?;
        self.check_kind(scaffold.kind)?;
        let group = group_of(&self.group)?;
        let fitted = cells
            .iter()
            .map(|bytes| FittedPayload::from_bytes(bytes)?.cell(&group))
            .collect::<Result<Vec<_>, StageError>>()?;
        if self.continuity == Continuity::C1 {
            for (name, cell) in self.cells.iter().zip(&fitted) {
                self.check_normal_to_faces(name, cell)?;
            }
        }
        let table = table.map(table_of).transpose()?;
        let sized = self.sized(&scaffold, fitted, table.as_ref())?;
        let fields = &sized.cells;
        let nodal =
            |what: &str, value: &Option<NodalValue>| -> Result<Option<Vec<f64>>, StageError> {
                value
                    .as_ref()
                    .map(|v| self.nodal_values(&scaffold, what, v))
                    .transpose()
            };
        let weight = nodal("by", &self.by)?;
        let thickness = match sized.thickness {
            Some(values) => Some(values),
            None => nodal("thickness", &self.thickness)?,
        };
        if let Some(values) = &thickness {
            self.positive(&scaffold, "thickness", values)?;
        }
        let offset = match sized.offset {
            Some(values) => Some(values),
            None => nodal("offset", &self.offset)?,
        };
        let solid = TiledSolid {
            cell: &*fields[0],
            transition: match (&weight, fields.get(1)) {
                (Some(weight), Some(to)) => Some(Transition {
                    to: &**to as &dyn ScalarField,
                    weight,
                }),
                _ => None,
            },
            solid: sized.solid,
            thickness: thickness.as_deref(),
            offset: offset.as_deref(),
        };
        progress.phase("tiling");
        if scaffold.kind.dimension() == 2 {
            return self
                .tile_surface(&scaffold, &solid, progress)
                .map(|artifact| {
                    TileOutput::Whole(MeshArtifact {
                        sizing: sized.summary.clone(),
                        ..artifact
                    })
                });
        }
        let scaffold_bbox = used_nodes_box(&scaffold);
        handed_on(Tiled::ScaffoldBox(scaffold_bbox))?;
        // The check takes each chunk on the pool while the next one is tiled (see
        // `stream_scaffold`'s sink): its parallel parts share both threads with the tiling,
        // where a check thread of its own was the pipeline's slowest stage.
        let mut check = StreamCheck::new();
        let mut pieces = PieceCounter::new();
        // The chunks handed on, oldest first, until the writers are done with them: their
        // arrays then serve the chunks tiled next (`SpareArrays::recycle`).
        let mut in_flight: VecDeque<Arc<MeshChunk>> = VecDeque::new();
        let spare = SpareArrays::default();
        let stats = stream_scaffold(
            &scaffold,
            &solid,
            self.skin,
            self.resolution,
            chunk_elements_for(self.resolution, CHUNK_TRIANGLES),
            &spare,
            &mut |chunk| {
                let chunk = Arc::new(chunk);
                // Handed on first, so the writers encode while this thread checks.
                handed_on(Tiled::Chunk(Arc::clone(&chunk))).map_err(|e| e.to_string())?;
                // Both on the pool: the piece count is serial, the check parallel inside.
                rayon::join(|| check.push(&chunk), || pieces.push(&chunk));
                in_flight.push_back(chunk);
                while in_flight.front().is_some_and(|c| Arc::strong_count(c) == 1) {
                    if let Some(Ok(done)) = in_flight.pop_front().map(Arc::try_unwrap) {
                        spare.recycle(done);
                    }
                }
                Ok(())
            },
        )
        .map_err(|e| StageError::geometry_of(format!("tiling {}", self.source()), e))?;
        let check = check.finish();
        if check.triangles == 0 {
            return Err(StageError::EmptySolid(format!(
                "the tiled solid of `outputs.{}` is empty: the cell has no solid part at this \
                 offset or thickness",
                self.output
            )));
        }
        Ok(TileOutput::Chunked(ChunkedHead {
            sizing: sized.summary,
            shell: self.shell_summary(&solid, reference_element(scaffold.kind)),
            summary: MeshSummary::from_check(&check).with_pieces(&pieces.finish(), false),
            tiling: Some(TilingSummary {
                element: scaffold.kind.name().to_string(),
                elements: stats.elements as u64,
                interior_faces: stats.interior_faces as u64,
                boundary_faces: stats.boundary_faces as u64,
                scaffold_volume: scaffold.measure(),
                region_area: None,
                scaffold_bbox: Some(scaffold_bbox),
            }),
        }))
    }

    /// What the report says of a tiled shell's wall (`None` for other solids): its thinnest
    /// part in lattice spacings, `thickness / |∇Φ|` with the steepest `|∇Φ|` per lattice step
    /// where the shell's middle level crosses the reference element's cube lattice
    /// (`steepest_at_level`, over the cubes inside the reference element for 3D ones, where
    /// alone the cell is drawn), the thinnest graded thickness and, for a transition, the
    /// steeper cell. An estimate, as the warning says: curved elements stretch the lattice.
    /// At most 64 points per edge are sampled, the gradient scaled to the resolution's
    /// spacing. A 2D region (`element` None) is sampled in the plane z = 0.
    fn shell_summary(&self, solid: &TiledSolid, element: Option<Element3>) -> Option<ShellSummary> {
        let planar = element.is_none();
        let band = solid.solid.band()?;
        let middle = band.lo + 0.5 * (band.hi - band.lo);
        let thickness = solid.thickness.map_or(band.hi - band.lo, |t| {
            t.iter().copied().fold(f64::INFINITY, f64::min)
        });
        let n = self.resolution.min(64);
        let grid = if planar {
            // One lattice step in z, from the plane: the gradient within it.
            let step = 1.0 / (n - 1) as f64;
            Grid::spanning([-0.5, -0.5, 0.0], [0.5, 0.5, step], [n, n, 2])
        } else {
            Grid::spanning([-0.5; 3], [0.5; 3], [n; 3])
        };
        let fields = std::iter::once(solid.cell).chain(solid.transition.as_ref().map(|t| t.to));
        let within = |p: [f64; 3]| element.is_none_or(|e| e.signed_distance(p) < 0.0);
        let steepest = fields
            .map(|field| steepest_at_level_within(field.sampler(&grid).as_ref(), middle, &within))
            .fold(0.0, f64::max)
            * (n - 1) as f64
            / (self.resolution - 1) as f64;
        let walls = Band {
            lo: middle - 0.5 * thickness,
            hi: middle + 0.5 * thickness,
        };
        Some(ShellSummary {
            thickness,
            thinnest_wall: BandMesh::wall(walls, steepest),
            samples: [self.resolution; 3],
            sampled: false,
            tiled: true,
            sized: !matches!(self.sizing, Sizing::Field),
        })
    }

    /// A 2D scaffold: its region, drawn when planar, or the closed solid made of it.
    fn tile_surface(
        &self,
        scaffold: &Scaffold,
        solid: &TiledSolid,
        progress: &dyn StageProgress,
    ) -> Result<MeshArtifact, StageError> {
        let fail = |e: RegionError| StageError::geometry_of(format!("tiling {}", self.source()), e);
        let scaffold_area = scaffold.measure();
        let (mesh, region, planar, scaffold_volume): (Mesh, TiledRegion, _, _) = match self.thicken
        {
            None => {
                let region =
                    tile_surface_scaffold(scaffold, solid, self.resolution).map_err(fail)?;
                let svg = region
                    .planar
                    .then(|| region_svg(&region, scaffold))
                    .transpose()
                    .map_err(fail)?;
                let planar = Planar {
                    boundary: Vec::new(),
                    element: Vec::new(),
                    element_area: scaffold_area,
                    svg,
                };
                (region.mesh.clone(), region, Some(planar), scaffold_area)
            }
            Some(Thicken::Extrude(h)) => {
                let region =
                    tile_surface_scaffold(scaffold, solid, self.resolution).map_err(fail)?;
                if !region.planar {
                    return Err(StageError::DoesNotFit(format!(
                        "`outputs.{}.extrude` needs a planar scaffold (every node at one z), \
                         but {} is a curved surface of {} elements: use `thickness_normal = \
                         {h}` to thicken it along its normals",
                        self.output,
                        self.source(),
                        scaffold.kind.name()
                    )));
                }
                let mesh = if region.mesh.is_empty() {
                    Mesh::default()
                } else {
                    extrude(&region, h).map_err(fail)?
                };
                (mesh, region, None, scaffold_area * h)
            }
            Some(Thicken::ThicknessNormal(h)) => {
                let shell = thickness_normal(scaffold, solid, self.resolution, h).map_err(fail)?;
                (shell.mesh, shell.mid, None, scaffold_area * h)
            }
        };
        if region.mesh.is_empty() {
            return Err(StageError::EmptySolid(format!(
                "the tiled region of `outputs.{}` is empty: the cell has no solid part at this \
                 offset or thickness",
                self.output
            )));
        }
        progress.phase("checking the mesh");
        let summary = MeshSummary::of_mesh(&mesh, planar.is_some());
        Ok(MeshArtifact {
            sizing: None,
            shell: self.shell_summary(solid, None),
            mesh,
            summary,
            planar,
            domain: None,
            tiling: Some(TilingSummary {
                element: scaffold.kind.name().to_string(),
                elements: region.stats.elements as u64,
                interior_faces: region.stats.interior_faces as u64,
                boundary_faces: region.stats.boundary_faces as u64,
                scaffold_volume,
                region_area: Some(region.area),
                scaffold_bbox: None,
            }),
        })
    }

    /// A nodal value at every node of the scaffold: an expression at the node positions, or
    /// a node-data view of the file. Non-finite values are errors naming the node.
    fn nodal_values(
        &self,
        scaffold: &Scaffold,
        what: &str,
        value: &NodalValue,
    ) -> Result<Vec<f64>, StageError> {
        let key = match what {
            "by" => format!("outputs.{}.cell.by", self.output),
            _ => format!("outputs.{}.{what}", self.output),
        };
        let values = match value {
            NodalValue::Expr(text) => {
                let field = expr::compile(text)
                    .map_err(|e| StageError::geometry_of(format!("`{key}`"), e))?;
                let coordinate = |a: usize| scaffold.nodes.iter().map(|p| p[a]).collect::<Vec<_>>();
                let mut out = vec![0.0; scaffold.nodes.len()];
                field.eval_points(&coordinate(0), &coordinate(1), &coordinate(2), &mut out);
                out
            }
            NodalValue::NodeData(view) => match scaffold.node_data(view) {
                Some(data) => data.values.clone(),
                None => {
                    let views: Vec<String> = scaffold
                        .node_data
                        .iter()
                        .map(|d| format!("`{}`", d.name))
                        .collect();
                    let has = if views.is_empty() {
                        "it has no node data views".to_string()
                    } else {
                        format!("its views are {}", views.join(", "))
                    };
                    return Err(StageError::DoesNotFit(format!(
                        "`{key}` reads node data `{view}`, but {} has no such view: {has}",
                        self.source()
                    )));
                }
            },
        };
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(StageError::ValueOutOfRange(format!(
                "`{key}` is {} at node {} of {}",
                values[i],
                scaffold.node_tags.get(i).copied().unwrap_or(i as u64),
                self.source()
            )));
        }
        Ok(values)
    }

    /// The cells and solid for the output's sizing, with the nodal thickness or offset it
    /// implies. Walls and growths in model units become reference units node by node,
    /// divided by the node's element scale ([`node_scales`]); where every element has one
    /// scale they stay uniform (one reference contour for all elements). A volume fraction
    /// of the reference element holds in every element an affine map takes it to, so it is
    /// solved once, in reference units.
    fn sized(
        &self,
        scaffold: &Scaffold,
        fitted: Vec<latticebuild_geom::symmetric::FittedCell>,
        table: Option<&LevelTable>,
    ) -> Result<TiledSizing, StageError> {
        let boxed = |cells: Vec<latticebuild_geom::symmetric::FittedCell>, level: Option<f64>| {
            cells
                .into_iter()
                .map(|cell| -> Box<dyn ScalarField> {
                    match level {
                        None => Box::new(cell),
                        Some(level) => Box::new(DistanceField {
                            inner: cell,
                            level,
                            scale: [1.0; 3],
                        }),
                    }
                })
                .collect::<Vec<_>>()
        };
        let shell = self.solid.band().is_some();
        let mut sized = TiledSizing {
            cells: Vec::new(),
            solid: self.solid,
            thickness: None,
            offset: None,
            summary: None,
        };
        match &self.sizing {
            Sizing::Field => sized.cells = boxed(fitted, None),
            Sizing::Length { level, graded } => {
                sized.cells = boxed(fitted, Some(*level));
                sized.summary = Some(length_summary(&self.solid, graded.is_none()));
                let (scales, uniform) = node_scales(scaffold);
                if let (Some(scale), None) = (uniform, graded) {
                    // One scale everywhere: the solid's own numbers, in reference units.
                    sized.solid = match self.solid {
                        Solid::Inside { offset } => Solid::Inside {
                            offset: offset / scale,
                        },
                        Solid::Outside { offset } => Solid::Outside {
                            offset: offset / scale,
                        },
                        solid => Solid::Shell {
                            thickness: asked_length(&solid) / scale,
                        },
                    };
                    return Ok(sized);
                }
                let what = if shell { "wall" } else { "grow" };
                let model = match graded {
                    Some(value) => self.nodal_values(scaffold, what, value)?,
                    None => vec![asked_length(&self.solid); scaffold.nodes.len()],
                };
                if shell {
                    self.positive(scaffold, what, &model)?;
                }
                let reference = model.iter().zip(&scales).map(|(v, s)| v / s);
                match self.solid {
                    Solid::Inside { .. } => sized.offset = Some(reference.collect()),
                    Solid::Outside { .. } => sized.offset = Some(reference.map(|v| -v).collect()),
                    _ => sized.thickness = Some(reference.collect()),
                }
            }
            Sizing::VolumeFraction { level, target } => {
                let table = table.ok_or_else(|| {
                    StageError::Internal("a volume fraction needs the cell's table".into())
                })?;
                sized.cells = boxed(fitted, shell.then_some(*level));
                match target {
                    Target::Uniform(phi) => {
                        let (solid, mut summary) = solve_uniform(table, self.solid, *phi)?;
                        if let Some(wall) = summary.solved_wall.as_mut() {
                            // In model units: the reference wall times the mean element scale.
                            let (scales, _) = node_scales(scaffold);
                            *wall *= scales.iter().sum::<f64>() / scales.len().max(1) as f64;
                        }
                        sized.solid = solid;
                        sized.summary = Some(summary);
                    }
                    Target::Graded(value) => {
                        let phis = self.nodal_values(scaffold, "volume_fraction", value)?;
                        if let Some(i) = phis.iter().position(|&p| !(p > 0.0 && p < 1.0)) {
                            return Err(StageError::ValueOutOfRange(format!(
                                "`outputs.{}.volume_fraction` is {} at node {} of {}, which \
                                 cannot be reached: the reachable range is 0 < \
                                 volume_fraction < 1",
                                self.output,
                                phis[i],
                                scaffold.node_tags.get(i).copied().unwrap_or(i as u64),
                                self.source()
                            )));
                        }
                        let levels = phis
                            .iter()
                            .map(|&p| table.level_at(tabled_fraction(&self.solid, p)));
                        match self.solid {
                            Solid::Inside { .. } | Solid::Outside { .. } => {
                                sized.offset = Some(levels.collect())
                            }
                            _ => sized.thickness = Some(levels.map(|h| 2.0 * h).collect()),
                        }
                        sized.summary = Some(graded_fraction_summary());
                    }
                }
            }
        }
        Ok(sized)
    }

    fn positive(&self, scaffold: &Scaffold, what: &str, values: &[f64]) -> Result<(), StageError> {
        match values.iter().position(|&v| v <= 0.0) {
            None => Ok(()),
            Some(i) => Err(StageError::ValueOutOfRange(format!(
                "`outputs.{}.{what}` must be greater than 0, but it is {} at node {} of {}",
                self.output,
                values[i],
                scaffold.node_tags.get(i).copied().unwrap_or(i as u64),
                self.source()
            ))),
        }
    }
}

/// The box of the scaffold's nodes that its elements use (a file may hold others).
fn used_nodes_box(scaffold: &Scaffold) -> [[f64; 3]; 2] {
    let mut bbox = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
    for &node in &scaffold.connectivity {
        if let Some(p) = scaffold.nodes.get(node as usize) {
            for a in 0..3 {
                bbox[0][a] = bbox[0][a].min(p[a]);
                bbox[1][a] = bbox[1][a].max(p[a]);
            }
        }
    }
    bbox
}

/// The cells and solid a tiling is made of, once sized (see [`TileStage::sized`]).
struct TiledSizing {
    cells: Vec<Box<dyn ScalarField>>,
    solid: Solid,
    thickness: Option<Vec<f64>>,
    offset: Option<Vec<f64>>,
    summary: Option<SizingSummary>,
}

/// Per node, the linear scale of the elements around it (model units per reference unit):
/// `(measure / reference measure)^(1/d)` per element, averaged over the elements using the
/// node; and that scale when every element has it (to 1 part in 10⁹). Exact for elements
/// that are similar copies of the reference element; for stretched ones, their mean size.
fn node_scales(scaffold: &Scaffold) -> (Vec<f64>, Option<f64>) {
    let (reference, dimension) = match reference_element(scaffold.kind) {
        Some(Element3::Cube) => (1.0, 3),
        // The regular tetrahedron of edge √2 inscribed in the unit cube.
        Some(Element3::Tetrahedron) => (1.0 / 3.0, 3),
        None if scaffold.kind.corner_count() == 3 => (3f64.sqrt() / 4.0, 2),
        None => (1.0, 2),
    };
    let rule = scaffold.measure_rule();
    let element_scales: Vec<f64> = (0..scaffold.element_count())
        .map(|e| {
            (scaffold.element_measure(e, &rule).abs() / reference).powf(1.0 / dimension as f64)
        })
        .collect();
    let mut sums = vec![0.0; scaffold.nodes.len()];
    let mut counts = vec![0u32; scaffold.nodes.len()];
    for (e, scale) in element_scales.iter().enumerate() {
        for &node in scaffold.element(e) {
            sums[node as usize] += scale;
            counts[node as usize] += 1;
        }
    }
    let scales = sums
        .iter()
        .zip(&counts)
        .map(|(s, &c)| if c == 0 { 1.0 } else { s / c as f64 })
        .collect();
    let first = element_scales.first().copied().unwrap_or(1.0);
    let uniform = element_scales
        .iter()
        .all(|s| (s - first).abs() <= 1e-9 * first)
        .then_some(first);
    (scales, uniform)
}

#[cfg(test)]
mod tests {
    use super::*;
    use latticebuild_geom::symmetric::{Complex64, Group};

    fn stage(group: &str) -> TileStage {
        TileStage {
            output: "lattice".into(),
            cells: vec!["cell".into()],
            scaffold_name: "block".into(),
            scaffold: ScaffoldInput::File("block.msh".into()),
            group: GroupSpec::Named(group.into()),
            by: None,
            solid: Solid::Inside { offset: 0.0 },
            sizing: Sizing::Field,
            thickness: None,
            offset: None,
            resolution: 8,
            skin: None,
            thicken: None,
            continuity: Continuity::C1,
        }
    }

    /// A cell of `group` from a few low frequencies with unequal weights.
    fn cell(group: &str) -> FittedCell {
        let group = Group::by_name(group).unwrap();
        let terms = [([1, 0, 0], 1.0), ([1, 1, 0], 0.5), ([1, 1, 1], -0.3)];
        FittedCell::from_coefficients(group, 8, terms.map(|(f, c)| (f, Complex64::new(c, 0.0))))
            .unwrap()
    }

    #[test]
    fn c1_tilings_need_cells_that_meet_the_faces_at_right_angles() {
        // Oh: the cube's faces are mirror planes of any periodic Oh field.
        assert!(
            stage("Oh")
                .check_normal_to_faces("cell", &cell("Oh"))
                .is_ok()
        );
        // Td: the tetrahedron's faces are not, so an unconstrained cell crosses them obliquely.
        let td = cell("Td");
        assert!(td.max_face_normal_derivative().unwrap() > 0.1);
        let error = stage("Td")
            .check_normal_to_faces("cell", &td)
            .unwrap_err()
            .to_string();
        assert!(error.contains("cell `cell`"), "{error}");
        assert!(error.contains("normal_to_faces = true"), "{error}");
        let (constrained, _) = td.constrain_normal_to_faces().unwrap();
        let stage = stage("Td");
        assert!(stage.check_normal_to_faces("cell", &constrained).is_ok());
    }
}
