//! The stage DAG: compiled from a validated [`Manifest`], ordered, and printed.
//!
//! Invariants:
//! - The graph never runs geometry and never opens a file itself ([`status`] reads cache
//!   entries and output files' metadata through `cache/` and the `OutputSink`);
//!   [`crate::build`] executes it.
//! - Node ids are stable strings (`cell:gyroid`, `contour:g`, `write:g`) that depend only on
//!   the manifest's names, so cache records and `-v` explanations follow a node across edits.
//! - Nodes are stored in a topological order: every node comes after all of its inputs.

pub mod status;

use std::collections::BTreeMap;

use latticebuild_geom::islands::IslandFilter;

use crate::manifest::{CellSource, FitResolution, InputFile, Manifest, ScaffoldSource};
use crate::stages::Stage;
use crate::stages::crystal::CrystalStage;
use crate::stages::file::FileStage;
use crate::stages::islands::IslandsStage;
use crate::stages::mesh::MeshCellStage;
use crate::stages::points::PointCellStage;
use crate::stages::preview::PreviewStage;
use crate::stages::program::ProgramStage;
use crate::stages::sizing::{DensityStage, Over};
use crate::stages::symmetric::{Combination, CombineStage, ConstrainStage, FitStage, SampleStage};
use crate::stages::tile::TileStage;
use crate::stages::voxels::VoxelCellStage;
use crate::stages::warnings;
use crate::stages::write::{self, WriteStage};
use latticebuild_geom::mesh_io::Units;

/// The parameters a written file's stamp carries: the output's resolved parameters, as the
/// report's `resolved` gives them (`manifest::flatten`).
fn stamp_parameters(manifest: &Manifest, name: &str) -> Vec<(String, String)> {
    manifest
        .resolved(name)
        .map(|r| crate::manifest::flatten(&r))
        .unwrap_or_default()
}

/// Index of a node in [`Graph::nodes`].
pub type NodeId = usize;

#[derive(Clone, Debug)]
pub struct Node {
    /// Stable, human-readable id, e.g. `contour:g`.
    pub name: String,
    pub stage: Stage,
    /// Inputs, by node id, in the order the stage expects them.
    pub inputs: Vec<NodeId>,
}

#[derive(Clone, Debug, Default)]
pub struct Graph {
    pub nodes: Vec<Node>,
    /// For each output name, its final (`write`) node.
    pub outputs: BTreeMap<String, NodeId>,
    /// For each output name, its `preview` node (none with previews off).
    pub previews: BTreeMap<String, NodeId>,
}

/// Compiles cells into nodes once each, following blends and Minkowski combinations.
struct CellCompiler<'m> {
    manifest: &'m Manifest,
    /// Node id by node name, so a cell used twice is compiled once.
    done: BTreeMap<String, NodeId>,
    /// The cells being compiled, innermost last, to report a reference cycle as a path.
    visiting: Vec<String>,
}

impl CellCompiler<'_> {
    fn node(&mut self, graph: &mut Graph, name: &str) -> Result<NodeId, Cycle> {
        let cell = &self.manifest.cells[name];
        let final_name = match cell.symmetric {
            None => format!("cell:{name}"),
            Some(_) => format!("constrain:{name}"),
        };
        if let Some(&id) = self.done.get(&final_name) {
            return Ok(id);
        }
        if let Some(at) = self.visiting.iter().position(|v| v == name) {
            let mut path: Vec<String> = self.visiting[at..]
                .iter()
                .map(|v| format!("cell:{v}"))
                .collect();
            path.push(format!("cell:{name}"));
            return Err(Cycle(path));
        }
        self.visiting.push(name.to_string());
        let id = self.compile(graph, name)?;
        self.visiting.pop();
        self.done.insert(final_name, id);
        Ok(id)
    }

    /// The `file:` node of a mesh file, once per file name.
    fn file(&mut self, graph: &mut Graph, file: &InputFile) -> NodeId {
        let node = format!("file:{}", file.given);
        if let Some(&id) = self.done.get(&node) {
            return id;
        }
        let stage = Stage::File(FileStage {
            given: file.given.clone(),
            path: file.path.clone(),
        });
        let id = graph.push(node.clone(), stage, vec![]);
        self.done.insert(node, id);
        id
    }

    /// The `cell:` node of a formula or mesh cell: its canonical formula, or its placed mesh
    /// (reading the `file:` node).
    fn source(&mut self, graph: &mut Graph, name: &str) -> NodeId {
        let cell = &self.manifest.cells[name];
        match &cell.source {
            CellSource::Mesh(mesh) => {
                let file = self.file(graph, &mesh.file);
                let stage = Stage::MeshCell(MeshCellStage { cell: mesh.clone() });
                graph.push(format!("cell:{name}"), stage, vec![file])
            }
            CellSource::Voxels(voxels) => {
                let file = self.file(graph, &voxels.file);
                let stage = Stage::VoxelCell(VoxelCellStage {
                    cell: voxels.clone(),
                });
                graph.push(format!("cell:{name}"), stage, vec![file])
            }
            CellSource::Points(points) => {
                let file = self.file(graph, points);
                let stage = Stage::PointCell(PointCellStage {
                    file: points.clone(),
                });
                graph.push(format!("cell:{name}"), stage, vec![file])
            }
            CellSource::Crystal(crystal) => {
                let file = self.file(graph, &crystal.file);
                let stage = Stage::Crystal(CrystalStage {
                    cell: crystal.clone(),
                });
                graph.push(format!("cell:{name}"), stage, vec![file])
            }
            _ => graph.push(format!("cell:{name}"), Stage::cell(cell), vec![]),
        }
    }

    fn compile(&mut self, graph: &mut Graph, name: &str) -> Result<NodeId, Cycle> {
        let cell = &self.manifest.cells[name];
        let Some(spec) = &cell.symmetric else {
            return Ok(self.source(graph, name));
        };
        let fitted = match &cell.source {
            CellSource::Tpms(_)
            | CellSource::Expr(_)
            | CellSource::Mesh(_)
            | CellSource::Voxels(_)
            | CellSource::Points(_)
            | CellSource::Crystal(_)
            | CellSource::Ps { .. } => {
                let formula = self.source(graph, name);
                let fit = Stage::Fit(FitStage { spec: spec.clone() });
                match spec.n {
                    FitResolution::Fixed(n) => {
                        let sample = Stage::Sample(SampleStage {
                            spec: spec.clone(),
                            n,
                        });
                        let samples = graph.push(format!("sample:{name}"), sample, vec![formula]);
                        graph.push(format!("fit:{name}"), fit, vec![samples])
                    }
                    FitResolution::Auto { .. } => {
                        graph.push(format!("fit:{name}"), fit, vec![formula])
                    }
                }
            }
            CellSource::Blend { cells, weights } => {
                let inputs = cells
                    .iter()
                    .map(|c| self.node(graph, c))
                    .collect::<Result<Vec<_>, _>>()?;
                let combination = Combination::Blend {
                    weights: weights.clone(),
                };
                let stage = Stage::Combine(CombineStage {
                    spec: spec.clone(),
                    combination,
                });
                graph.push(format!("blend:{name}"), stage, inputs)
            }
            CellSource::Minkowski { op, cells } => {
                let inputs = cells
                    .iter()
                    .map(|c| self.node(graph, c))
                    .collect::<Result<Vec<_>, _>>()?;
                let n = match spec.n {
                    FitResolution::Fixed(n) => n,
                    FitResolution::Auto { .. } => 128,
                };
                let combination = Combination::Minkowski { op: *op, n };
                let stage = Stage::Combine(CombineStage {
                    spec: spec.clone(),
                    combination,
                });
                graph.push(format!("minkowski:{name}"), stage, inputs)
            }
        };
        let constrain = Stage::Constrain(ConstrainStage { spec: spec.clone() });
        Ok(graph.push(format!("constrain:{name}"), constrain, vec![fitted]))
    }
}

/// Output `name`'s preview stage, when the manifest draws previews.
fn preview(
    manifest: &Manifest,
    name: &str,
    stem: &str,
    domain: Option<[[f64; 3]; 2]>,
    within: bool,
) -> Option<PreviewStage> {
    manifest.previews.then(|| PreviewStage {
        output: name.to_string(),
        stem: stem.to_string(),
        size: manifest.preview_size,
        domain,
        within,
        carriers: Vec::new(),
    })
}

/// A dependency cycle, as the path of node names that closes it.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
#[error("dependency cycle: {}", .0.join(" → "))]
pub struct Cycle(pub Vec<String>);

impl Graph {
    /// Compiles the manifest: the nodes of every cell an output uses (a `cell` node for plain
    /// cells, reading a `file` node for mesh cells; `cell → sample → fit → constrain`, or `blend`/`minkowski → constrain`, for
    /// symmetric ones), then a `contour` (reading the part's `file` node too with `within`),
    /// an `islands` node when the output removes loose pieces, and a `write` node per output.
    pub fn compile(manifest: &Manifest) -> Result<Graph, Cycle> {
        let mut graph = Graph::default();
        let mut compiler = CellCompiler {
            manifest,
            done: BTreeMap::new(),
            visiting: Vec::new(),
        };
        for (name, output) in &manifest.outputs {
            let cell_node = compiler.node(&mut graph, &output.cell)?;
            let fitted = manifest.cells[&output.cell].symmetric.as_ref();
            let mut inputs = vec![cell_node];
            if let Some(part) = &output.within {
                inputs.push(compiler.file(&mut graph, part));
            }
            let mut stage = Stage::contour(output, fitted);
            if let Stage::Contour(contour) = &mut stage {
                contour.units = Units::from_name(&manifest.units).unwrap_or(Units::Millimeter);
            }
            if let Stage::Contour(contour) = &stage
                && let Some(density) = contour.density()
            {
                inputs.push(graph.density(&output.cell, density, cell_node));
            }
            let contour = graph.push(format!("contour:{name}"), stage, inputs);
            let stamp = write::stamp(name, &manifest.units, stamp_parameters(manifest, name));
            let write = WriteStage::new(output, manifest.report, stamp);
            let domain = Some([output.domain_min, output.domain_max]);
            let preview = preview(
                manifest,
                name,
                &output.stem,
                domain,
                output.within.is_some(),
            );
            graph.finish_output(name, &output.islands, contour, write, preview);
        }
        // An SDF output: `sdf` reading a `file:` node per mesh of its program, then `write`.
        for (name, output) in &manifest.program_outputs {
            let files = output.files.iter().map(|f| compiler.file(&mut graph, f));
            let files = files.collect();
            let stage = Stage::Program(ProgramStage::new(output));
            let solid = graph.push(format!("sdf:{name}"), stage, files);
            let write = WriteStage {
                formats: output.formats.clone(),
                encoding: output.encoding,
                stem: output.stem.clone(),
                report: manifest.report,
                // A program's box is its solid's or the user's, not the lattice's: the void
                // round a part filled by a program (a ball of gyroid) is not a pore.
                pore_box: None,
                stamp: write::stamp(name, &manifest.units, stamp_parameters(manifest, name)),
            };
            let preview = preview(manifest, name, &output.stem, None, false);
            graph.finish_output(name, &output.islands, solid, write, preview);
        }
        // A tiled output: `tile` reading its cells' `constrain` nodes (and the scaffold's
        // `file:` node), then `write`.
        for (name, output) in &manifest.tiled_outputs {
            let mut inputs = vec![compiler.node(&mut graph, &output.cell)?];
            if let Some(t) = &output.transition {
                inputs.push(compiler.node(&mut graph, &t.to)?);
            }
            let cell_node = inputs[0];
            if let ScaffoldSource::Mesh(file) = &manifest.scaffolds[&output.scaffold].source {
                inputs.push(compiler.file(&mut graph, file));
            }
            let tile = TileStage::new(manifest, output);
            if let Some(density) = tile.density() {
                inputs.push(graph.density(&output.cell, density, cell_node));
            }
            let stage = Stage::Tile(tile);
            let tiled = graph.push(format!("tile:{name}"), stage, inputs);
            let write = WriteStage {
                formats: output.formats.clone(),
                encoding: output.encoding,
                stem: output.stem.clone(),
                report: manifest.report,
                pore_box: None,
                stamp: write::stamp(name, &manifest.units, stamp_parameters(manifest, name)),
            };
            let preview = preview(manifest, name, &output.stem, None, false);
            graph.finish_output(name, &output.islands, tiled, write, preview);
        }
        graph.check_order()?;
        Ok(graph)
    }

    /// The node whose payload is cell `name`'s final field (formula or coefficient table),
    /// compiling it and what it needs on first use.
    pub fn compile_cell(&mut self, manifest: &Manifest, name: &str) -> Result<NodeId, Cycle> {
        let mut compiler = CellCompiler {
            manifest,
            done: BTreeMap::new(),
            visiting: Vec::new(),
        };
        for (id, node) in self.nodes.iter().enumerate() {
            compiler.done.insert(node.name.clone(), id);
        }
        compiler.node(self, name)
    }

    /// The `density` node of a cell's table, shared by every output asking for the same one
    /// (its name holds every parameter), so a second volume fraction costs no second table.
    fn density(&mut self, cell: &str, stage: DensityStage, cell_node: NodeId) -> NodeId {
        let over = match stage.over {
            Over::Period { dimension } => format!("period{dimension}"),
            Over::Element => "element".into(),
        };
        let distance = match stage.distance {
            None => String::new(),
            Some((level, scale)) => {
                format!(":distance({level},{},{},{})", scale[0], scale[1], scale[2])
            }
        };
        let projected = if stage.projected { ":projected" } else { "" };
        let name = format!("density:{cell}:{over}{distance}{projected}");
        if let Some(id) = self.nodes.iter().position(|n| n.name == name) {
            return id;
        }
        self.push(name, Stage::Density(stage), vec![cell_node])
    }

    /// The node whose mesh output `name` writes: `mesh` itself, or an `islands` node reading
    /// it when the output removes pieces (only then, so outputs without the keys keep the
    /// graph, keys and cache entries they had).
    /// An output's last nodes after the one making its mesh: `islands` when it removes loose
    /// pieces, then `write`, which becomes the output's target, and `preview` (reading the
    /// mesh, the write's record and the cell nodes whose warnings its caption repeats).
    fn finish_output(
        &mut self,
        name: &str,
        filter: &IslandFilter,
        mesh: NodeId,
        write: WriteStage,
        preview: Option<PreviewStage>,
    ) {
        let mesh = self.islands(name, filter, mesh);
        // `formats = []` writes no file at all, so no preview either.
        let preview = preview.filter(|_| !write.formats.is_empty());
        let write = self.push(format!("write:{name}"), Stage::Write(write), vec![mesh]);
        self.outputs.insert(name.to_string(), write);
        if let Some(mut preview) = preview {
            let carriers: Vec<NodeId> = self
                .closure(&[mesh])
                .into_iter()
                .filter(|&id| warnings::carries_warning(&self.nodes[id].stage))
                .collect();
            preview.carriers = carriers
                .iter()
                .map(|&id| self.nodes[id].name.clone())
                .collect();
            let inputs = [mesh, write].into_iter().chain(carriers).collect();
            let node = self.push(format!("preview:{name}"), Stage::Preview(preview), inputs);
            self.previews.insert(name.to_string(), node);
        }
    }

    fn islands(&mut self, name: &str, filter: &IslandFilter, mesh: NodeId) -> NodeId {
        if !filter.is_active() {
            return mesh;
        }
        let stage = Stage::Islands(IslandsStage {
            output: name.to_string(),
            filter: *filter,
        });
        self.push(format!("islands:{name}"), stage, vec![mesh])
    }

    fn push(&mut self, name: String, stage: Stage, inputs: Vec<NodeId>) -> NodeId {
        self.nodes.push(Node {
            name,
            stage,
            inputs,
        });
        self.nodes.len() - 1
    }

    /// Verifies the topological order; a back edge means a cycle, reported as a path.
    fn check_order(&self) -> Result<(), Cycle> {
        for (id, node) in self.nodes.iter().enumerate() {
            if let Some(&back) = node.inputs.iter().find(|&&input| input >= id) {
                return Err(Cycle(self.cycle_through(back, id)));
            }
        }
        Ok(())
    }

    /// A path from `to` back to itself through `from` (depth-first over inputs).
    fn cycle_through(&self, from: NodeId, to: NodeId) -> Vec<String> {
        let mut path = vec![to];
        let mut stack = vec![(from, vec![from])];
        let mut seen = vec![false; self.nodes.len()];
        while let Some((at, trail)) = stack.pop() {
            if at == to {
                path.extend(trail);
                break;
            }
            if std::mem::replace(&mut seen[at], true) {
                continue;
            }
            for &next in &self.nodes[at].inputs {
                let mut t = trail.clone();
                t.push(next);
                stack.push((next, t));
            }
        }
        path.into_iter()
            .map(|id| self.nodes[id].name.clone())
            .collect()
    }

    /// The nodes needed for `targets` (output names; all outputs when empty), in order.
    /// Unknown target names are returned as the error.
    pub fn needed(&self, targets: &[String]) -> Result<Vec<NodeId>, Vec<String>> {
        let unknown: Vec<String> = targets
            .iter()
            .filter(|t| !self.outputs.contains_key(*t))
            .cloned()
            .collect();
        if !unknown.is_empty() {
            return Err(unknown);
        }
        let names: Vec<&String> = if targets.is_empty() {
            self.outputs.keys().collect()
        } else {
            targets.iter().collect()
        };
        let roots: Vec<NodeId> = names
            .into_iter()
            .flat_map(|t| [Some(self.outputs[t]), self.previews.get(t).copied()])
            .flatten()
            .collect();
        Ok(self.closure(&roots))
    }

    /// `roots` and everything they read, in build order.
    pub fn closure(&self, roots: &[NodeId]) -> Vec<NodeId> {
        let mut wanted = vec![false; self.nodes.len()];
        let mut stack = roots.to_vec();
        while let Some(id) = stack.pop() {
            if !std::mem::replace(&mut wanted[id], true) {
                stack.extend(&self.nodes[id].inputs);
            }
        }
        (0..self.nodes.len()).filter(|&id| wanted[id]).collect()
    }
}
