//! The `tile` stage: a fitted symmetric cell (or a transition between two) tiled into every
//! element of a scaffold — a mesh file's bytes or a generated grid — as one checked mesh, with
//! what the tiling found (elements, interior and boundary faces, the scaffold's volume).
//!
//! Invariants:
//! - A pure function of its parameters and its inputs: the cells' coefficient tables (one, or
//!   two for a transition) and, for a `mesh =` scaffold, the file's bytes (last input). The
//!   key holds the file's extension (which may pick the reader), never its path, so renaming
//!   or touching a scaffold reruns nothing while editing it does.
//! - Everything only known once the scaffold is read is checked here with an error naming the
//!   file: the element kind against the cells' group, inverted or degenerate elements (by
//!   element tag), missing node-data views (listing those the file has), non-finite or
//!   non-positive graded values (by node tag). Transition weights are clamped to [0, 1].
//! - Expressions are evaluated at the scaffold's node positions (model units).

use latticebuild_geom::expr;
use latticebuild_geom::field::{ScalarField, Solid};
use latticebuild_geom::scaffold::{self, ElementKind, Scaffold};
use latticebuild_geom::tile::{TiledSolid, Transition, tile_scaffold_with_skin};
use latticebuild_geom::validate;

use super::artifact::{MeshArtifact, MeshSummary, TilingSummary};
use super::symmetric::{FittedPayload, group_of};
use crate::build::StageProgress;
use crate::cache::{KeyBuilder, Param};
use crate::manifest::{
    GroupSpec, Manifest, NodalValue, ScaffoldGrid, ScaffoldSource, TiledOutput, tiling_group,
};

pub const VERSION: u32 = 1;

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
    pub thickness: Option<NodalValue>,
    pub offset: Option<NodalValue>,
    pub resolution: usize,
    pub skin: Option<f64>,
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
            thickness: output.thickness.clone(),
            offset: output.offset.clone(),
            resolution: output.resolution,
            skin: output.skin,
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
            .param("resolution", Param::U64(self.resolution as u64))
            .param("skin", self.skin.unwrap_or(0.0))
    }

    /// How many inputs are cells (the rest is the scaffold file, if any).
    pub fn cell_inputs(&self) -> usize {
        self.cells.len()
    }

    /// The scaffold from the file's bytes (`None` for a grid), checked for bad elements.
    fn scaffold(&self, file: Option<&[u8]>) -> Result<Scaffold, String> {
        let scaffold = match (&self.scaffold, file) {
            (ScaffoldInput::File(given), Some(bytes)) => {
                scaffold::read_scaffold(bytes, given, Some(&extension(given)))
                    .map_err(|e| format!("cannot read the scaffold: {e}"))?
            }
            (ScaffoldInput::Grid(g), _) => scaffold::grid(g.min, g.max, g.divisions, g.element)
                .map_err(|e| format!("scaffold `{}`: {e}", self.scaffold_name))?,
            (ScaffoldInput::File(given), None) => {
                return Err(format!("the bytes of `{given}` are not an input"));
            }
        };
        scaffold::check(&scaffold).map_err(|e| format!("scaffold: {e}"))?;
        Ok(scaffold)
    }

    fn source(&self) -> String {
        match &self.scaffold {
            ScaffoldInput::File(given) => format!("`{given}`"),
            ScaffoldInput::Grid(_) => format!("the grid `{}`", self.scaffold_name),
        }
    }

    /// The element kind against the cells' group, and 2D scaffolds (not tiled yet).
    fn check_kind(&self, kind: ElementKind) -> Result<(), String> {
        let needed = tiling_group(kind);
        let GroupSpec::Named(group) = &self.group else {
            return Err("tiling needs a cell with a named group".into());
        };
        if group != needed {
            let cells = self
                .cells
                .iter()
                .map(|c| format!("`{c}`"))
                .collect::<Vec<_>>()
                .join(" and ");
            return Err(format!(
                "{} has {} elements, which need a cell of group `{needed}`, but {cells} of \
                 `outputs.{}` {} group `{group}`",
                self.source(),
                kind.name(),
                self.output,
                if self.cells.len() > 1 { "have" } else { "has" }
            ));
        }
        if kind.dimension() == 2 {
            return Err(format!(
                "{} has {} elements: tiling 2D scaffolds (quad, tri) is not supported yet",
                self.source(),
                kind.name()
            ));
        }
        Ok(())
    }

    /// Runs the stage on the cells' coefficient tables and, for a file, its bytes.
    pub fn run(
        &self,
        cells: &[&[u8]],
        file: Option<&[u8]>,
        progress: &dyn StageProgress,
    ) -> Result<MeshArtifact, String> {
        progress.phase("reading the scaffold");
        let scaffold = self.scaffold(file)?;
        self.check_kind(scaffold.kind)?;
        let group = group_of(&self.group)?;
        let fields = cells
            .iter()
            .map(|bytes| FittedPayload::from_bytes(bytes)?.cell(&group))
            .collect::<Result<Vec<_>, String>>()?;
        let nodal = |what: &str, value: &Option<NodalValue>| -> Result<Option<Vec<f64>>, String> {
            value
                .as_ref()
                .map(|v| self.nodal_values(&scaffold, what, v))
                .transpose()
        };
        let weight = nodal("by", &self.by)?
            .map(|w| w.into_iter().map(|v| v.clamp(0.0, 1.0)).collect::<Vec<_>>());
        let thickness = nodal("thickness", &self.thickness)?;
        if let Some(values) = &thickness {
            self.positive(&scaffold, "thickness", values)?;
        }
        let offset = nodal("offset", &self.offset)?;
        let solid = TiledSolid {
            cell: &fields[0],
            transition: match (&weight, fields.get(1)) {
                (Some(weight), Some(to)) => Some(Transition {
                    to: to as &dyn ScalarField,
                    weight,
                }),
                _ => None,
            },
            solid: self.solid,
            thickness: thickness.as_deref(),
            offset: offset.as_deref(),
        };
        progress.phase("tiling");
        let (mesh, stats) = tile_scaffold_with_skin(&scaffold, &solid, self.skin, self.resolution)
            .map_err(|e| format!("tiling {}: {e}", self.source()))?;
        if mesh.is_empty() {
            return Err(format!(
                "the tiled solid of `outputs.{}` is empty: the cell has no solid part at this \
                 offset or thickness",
                self.output
            ));
        }
        progress.phase("checking the mesh");
        let summary = MeshSummary::from_check(&validate::check(&mesh));
        Ok(MeshArtifact {
            mesh,
            summary,
            planar: None,
            domain: None,
            tiling: Some(TilingSummary {
                element: scaffold.kind.name().to_string(),
                elements: stats.elements as u64,
                interior_faces: stats.interior_faces as u64,
                boundary_faces: stats.boundary_faces as u64,
                scaffold_volume: scaffold.measure(),
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
    ) -> Result<Vec<f64>, String> {
        let key = match what {
            "by" => format!("outputs.{}.cell.by", self.output),
            _ => format!("outputs.{}.{what}", self.output),
        };
        let values = match value {
            NodalValue::Expr(text) => {
                let field = expr::compile(text).map_err(|e| format!("`{key}`: {}", e.message))?;
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
                    return Err(format!(
                        "`{key}` reads node data `{view}`, but {} has no such view: {has}",
                        self.source()
                    ));
                }
            },
        };
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(format!(
                "`{key}` is {} at node {} of {}",
                values[i],
                scaffold.node_tags.get(i).copied().unwrap_or(i as u64),
                self.source()
            ));
        }
        Ok(values)
    }

    fn positive(&self, scaffold: &Scaffold, what: &str, values: &[f64]) -> Result<(), String> {
        match values.iter().position(|&v| v <= 0.0) {
            None => Ok(()),
            Some(i) => Err(format!(
                "`outputs.{}.{what}` must be greater than 0, but it is {} at node {} of {}",
                self.output,
                values[i],
                scaffold.node_tags.get(i).copied().unwrap_or(i as u64),
                self.source()
            )),
        }
    }
}
