//! `latticebuild graph`: the DAG with each node marked cached or stale, computed from cache
//! headers only (no payload is read but the small write records), as text, JSON (`--json`)
//! or Graphviz (`--dot`).
//!
//! Invariants:
//! - The three forms come from one [`NodeStatus`] list, so they never disagree.
//! - The JSON is an array in build order (every node after its inputs): `id`, `kind`,
//!   `status` (`"cached"`, `"stale"` or `"error"`), `why` (`null` when cached) and `inputs`
//!   (ids); the DOT has one `"input" -> "node";` line per edge.

use std::collections::HashMap;

use serde::Serialize;

use super::{Graph, NodeId};
use crate::cache::{Cache, ContentHash, Lookup, explain};
use crate::stages::{OutputSink, Stage, WrittenFile, WrittenOutput};

/// One node's state, as every form prints it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NodeStatus {
    pub id: String,
    /// The stage's kind (`cell`, `fit`, `contour`, `write`, …).
    pub kind: &'static str,
    /// `"cached"`, `"stale"` or `"error"`.
    pub status: &'static str,
    /// Why it is stale (or cannot be keyed); `None` when cached.
    pub why: Option<String>,
    /// The ids of the nodes it reads.
    pub inputs: Vec<String>,
}

/// Every node's status, in build order.
pub fn statuses(graph: &Graph, cache: &Cache, sink: &dyn OutputSink) -> Vec<NodeStatus> {
    let mut hashes: HashMap<NodeId, ContentHash> = HashMap::new();
    let mut out = Vec::new();
    for (id, node) in graph.nodes.iter().enumerate() {
        let inputs: Option<Vec<ContentHash>> =
            node.inputs.iter().map(|i| hashes.get(i).copied()).collect();
        let stale = |why: String| ("stale", Some(why));
        let (status, why) = match inputs {
            None => stale("an input will be rebuilt".into()),
            Some(inputs) => match node.stage.key(&inputs) {
                Err(e) => ("error", Some(e.to_string())),
                Ok((key, desc)) => match cache.peek_hash(&key) {
                    Some(hash) if write_is_current(node, cache, &key, sink) => {
                        hashes.insert(id, hash);
                        ("cached", None)
                    }
                    Some(_) => stale("an output file is missing or was changed".into()),
                    None => match cache.previous(&node.name) {
                        Some(prev) => stale(explain(&prev.description, &desc).join("; ")),
                        None => stale("never built".into()),
                    },
                },
            },
        };
        out.push(NodeStatus {
            id: node.name.clone(),
            kind: node.stage.kind(),
            status,
            why,
            inputs: node
                .inputs
                .iter()
                .map(|&i| graph.nodes[i].name.clone())
                .collect(),
        });
    }
    out
}

/// One line per node, in build order: name, status, and what it reads.
pub fn lines(statuses: &[NodeStatus]) -> Vec<String> {
    let width = statuses.iter().map(|n| n.id.len()).max().unwrap_or(0);
    statuses
        .iter()
        .map(|node| {
            let status = match &node.why {
                None => node.status.to_string(),
                Some(why) => format!("{:<8} ({why})", node.status),
            };
            let arrow = if node.inputs.is_empty() {
                String::new()
            } else {
                format!("  <- {}", node.inputs.join(", "))
            };
            format!("{:<width$}  {status}{arrow}", node.id)
        })
        .collect()
}

/// The graph in Graphviz's DOT language: a node per stage (cached ones filled), an edge from
/// each input to what reads it.
pub fn dot(statuses: &[NodeStatus]) -> String {
    let mut text = String::from("digraph latticebuild {\n  rankdir=LR;\n  node [shape=box];\n");
    for node in statuses {
        let style = match node.status {
            "cached" => ", style=filled, fillcolor=\"#d8f0d8\"",
            "error" => ", color=red",
            _ => "",
        };
        text.push_str(&format!(
            "  {} [label={}{style}];\n",
            quoted(&node.id),
            quoted(&format!("{}\n{}", node.id, node.status))
        ));
    }
    for node in statuses {
        for input in &node.inputs {
            text.push_str(&format!("  {} -> {};\n", quoted(input), quoted(&node.id)));
        }
    }
    text.push_str("}\n");
    text
}

/// A DOT string literal: `"` and `\` escaped, a newline as `\n`.
fn quoted(text: &str) -> String {
    let mut out = String::from("\"");
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

fn write_is_current(
    node: &super::Node,
    cache: &Cache,
    key: &crate::cache::Key,
    sink: &dyn OutputSink,
) -> bool {
    let Ok(Lookup::Hit { payload, .. }) = (match node.stage {
        Stage::Write(_) | Stage::Preview(_) => cache.get(key),
        _ => return true,
    }) else {
        return false;
    };
    let files = match node.stage {
        Stage::Preview(_) => serde_json::from_slice::<WrittenFile>(&payload).map(|f| vec![f]),
        _ => serde_json::from_slice::<WrittenOutput>(&payload).map(|w| w.files),
    };
    files.is_ok_and(|files| files.iter().all(|f| sink.holds(f)))
}

#[cfg(test)]
mod tests {
    use super::{NodeStatus, dot, lines};

    fn node(id: &str, status: &'static str, inputs: &[&str]) -> NodeStatus {
        NodeStatus {
            id: id.into(),
            kind: "contour",
            status,
            why: (status != "cached").then(|| "never built".into()),
            inputs: inputs.iter().map(|s| s.to_string()).collect(),
        }
    }

    #[test]
    fn the_text_form_pads_names_and_names_inputs() {
        let nodes = [
            node("cell:a", "cached", &[]),
            node("contour:g", "stale", &["cell:a"]),
        ];
        assert_eq!(
            lines(&nodes),
            [
                "cell:a     cached",
                "contour:g  stale    (never built)  <- cell:a"
            ]
        );
    }

    #[test]
    fn dot_quotes_names_and_has_a_line_per_edge() {
        let nodes = [
            node("cell:a\"b", "cached", &[]),
            node("contour:g", "stale", &["cell:a\"b"]),
        ];
        let text = dot(&nodes);
        assert!(text.starts_with("digraph latticebuild {\n"), "{text}");
        assert!(
            text.contains("  \"cell:a\\\"b\" -> \"contour:g\";\n"),
            "{text}"
        );
        assert_eq!(text.matches(" -> ").count(), 1);
        assert!(text.ends_with("}\n"));
    }
}
