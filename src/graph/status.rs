//! `latticebuild graph`: the DAG with each node marked cached or stale, computed from cache
//! headers only (no payload is read but the small write records).

use std::collections::HashMap;

use super::{Graph, NodeId};
use crate::cache::{Cache, ContentHash, Lookup, explain};
use crate::stages::{OutputSink, Stage, WrittenFile, WrittenOutput};

/// One line per node, in build order: name, status, and what it reads.
pub fn lines(graph: &Graph, cache: &Cache, sink: &dyn OutputSink) -> Vec<String> {
    let mut hashes: HashMap<NodeId, ContentHash> = HashMap::new();
    let width = graph.nodes.iter().map(|n| n.name.len()).max().unwrap_or(0);
    let mut out = Vec::new();
    for (id, node) in graph.nodes.iter().enumerate() {
        let inputs: Option<Vec<ContentHash>> =
            node.inputs.iter().map(|i| hashes.get(i).copied()).collect();
        let status = match inputs {
            None => "stale    (an input will be rebuilt)".to_string(),
            Some(inputs) => match node.stage.key(&inputs) {
                Err(e) => format!("error    ({e})"),
                Ok((key, desc)) => match cache.peek_hash(&key) {
                    Some(hash) if write_is_current(node, cache, &key, sink) => {
                        hashes.insert(id, hash);
                        "cached".to_string()
                    }
                    Some(_) => "stale    (an output file is missing or was changed)".to_string(),
                    None => match cache.previous(&node.name) {
                        Some(prev) => format!(
                            "stale    ({})",
                            explain(&prev.description, &desc).join("; ")
                        ),
                        None => "stale    (never built)".to_string(),
                    },
                },
            },
        };
        let reads: Vec<&str> = node
            .inputs
            .iter()
            .map(|&i| graph.nodes[i].name.as_str())
            .collect();
        let arrow = if reads.is_empty() {
            String::new()
        } else {
            format!("  <- {}", reads.join(", "))
        };
        out.push(format!("{:<width$}  {status}{arrow}", node.name));
    }
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
