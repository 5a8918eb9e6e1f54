//! The stage DAG: compiled from a validated [`Manifest`], ordered, and printed.
//!
//! Invariants:
//! - The graph never runs geometry and never touches files; [`crate::build`] executes it.
//! - Node ids are stable strings (`cell:gyroid`, `contour:g`, `write:g`) that depend only on
//!   the manifest's names, so cache records and `-v` explanations follow a node across edits.
//! - Nodes are stored in a topological order: every node comes after all of its inputs.

pub mod status;

use std::collections::BTreeMap;

use crate::manifest::Manifest;
use crate::stages::Stage;

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
}

/// A dependency cycle, as the path of node names that closes it.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
#[error("dependency cycle: {}", .0.join(" → "))]
pub struct Cycle(pub Vec<String>);

impl Graph {
    /// Compiles the manifest: one `cell` node per cell used by an output, and a `contour` and
    /// a `write` node per output.
    pub fn compile(manifest: &Manifest) -> Result<Graph, Cycle> {
        let mut graph = Graph::default();
        let mut cell_nodes: BTreeMap<&str, NodeId> = BTreeMap::new();
        for (name, output) in &manifest.outputs {
            let cell = &manifest.cells[&output.cell];
            let cell_node = *cell_nodes.entry(output.cell.as_str()).or_insert_with(|| {
                graph.push(
                    format!("cell:{}", cell.name.text),
                    Stage::cell(cell),
                    vec![],
                )
            });
            let contour = graph.push(
                format!("contour:{name}"),
                Stage::contour(output),
                vec![cell_node],
            );
            let write = graph.push(format!("write:{name}"), Stage::write(output), vec![contour]);
            graph.outputs.insert(name.clone(), write);
        }
        graph.check_order()?;
        Ok(graph)
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
        let mut wanted = vec![false; self.nodes.len()];
        let mut stack: Vec<NodeId> = if targets.is_empty() {
            self.outputs.values().copied().collect()
        } else {
            targets.iter().map(|t| self.outputs[t]).collect()
        };
        while let Some(id) = stack.pop() {
            if !std::mem::replace(&mut wanted[id], true) {
                stack.extend(&self.nodes[id].inputs);
            }
        }
        Ok((0..self.nodes.len()).filter(|&id| wanted[id]).collect())
    }
}
