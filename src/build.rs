//! Executes a [`Graph`] against the [`Cache`]: each node is looked up by its key, run only on
//! a miss, and recorded; independent nodes of one level run in parallel.
//!
//! Invariants:
//! - A node's key is computed from its inputs' payload hashes, so a rerun that reproduces the
//!   same bytes stops the rebuild there (early cutoff).
//! - Payloads are loaded only when a node that must run needs them: a fully cached build reads
//!   no meshes, only the small write records it verifies against the files on disk.
//! - A corrupt or missing cache entry is never fatal: the node is run again.
//! - Results go into the cache only after the stage succeeded; a failing stage leaves the
//!   previous files and entries in place. A failing stage fails only what depends on it: the
//!   other outputs still build ([`Built::failed`] names each failed output and why), while
//!   a cache error stops the build.
//! - A 3D tiling's mesh never passes through here whole: the tile stage's chunks are streamed
//!   into a pending cache entry by a writer thread (committed only when the stage succeeds),
//!   and its value is a handle on that entry ([`Value::Chunked`]: the open file and its
//!   verified trailer), which the write stage reads a chunk at a time. A chunk found corrupt
//!   while a write reads it removes the entry and reruns the tile node, then the write.
//! - Single-pass formats (STL) of a write node this build needs, and the pictures of its
//!   preview nodes, are made while the tiling runs, from the same chunks ([`crate::early`]);
//!   the write stage only puts such a file in place, the preview stage only adds the caption,
//!   and only when their input is the mesh it was made from (same hash). Unused files are
//!   removed when the build ends: the sink's files stay whole or absent.
//! - Likewise the pictures of a whole mesh's preview nodes are drawn while its write node runs,
//!   on a thread of their own whose parallel work goes to the global pool; the write's thread
//!   then waits by doing the pool's work, so that work is done even with one thread.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;
use std::sync::mpsc;
use std::time::Instant;

use rayon::prelude::*;

use latticebuild_geom::mesh::MeshChunk;

use crate::cache::{
    Cache, CacheError, ContentHash, EntryReader, Key, KeyDescription, Lookup, Opened, SizeLimit,
    explain,
};
use crate::early::{self, Consumers, Made};
use crate::graph::{Graph, NodeId};
use crate::progress::Progress;
use crate::stages::chunked::{ChunkedMesh, ChunkedWriter, is_chunked};
use crate::stages::islands::{IslandsFailure, IslandsStage};
use crate::stages::tile::{TileOutput, Tiled};
use crate::stages::write::{MeshInput, WriteError};
use crate::stages::{
    MeshArtifact, OutputSink, Stage, StageError, WrittenFile, WrittenOutput, warnings,
};

/// Waits for `thread`, which queues work on the global pool, by doing the pool's work
/// meanwhile: a thread of the pool that waited idle could leave that work undone (with one
/// thread, forever).
fn wait_helping_the_pool<T>(thread: &std::thread::ScopedJoinHandle<'_, T>) {
    while !thread.is_finished() {
        if rayon::yield_now() != Some(rayon::Yield::Executed) {
            std::thread::sleep(std::time::Duration::from_micros(50));
        }
    }
}

/// A tile stage's inputs: its cells' payloads, the scaffold file's bytes, the density table.
type TileInputs<'a> = (&'a [&'a [u8]], Option<&'a [u8]>, Option<&'a [u8]>);

/// Hands a mesh payload to a background cache write.
type StoreMesh<'s> = dyn FnMut(Key, Arc<MeshArtifact>, ContentHash) + 's;

/// How one node went.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeRun {
    pub node: String,
    pub stage: &'static str,
    pub cached: bool,
    pub seconds: f64,
    /// Why it ran (empty when cached).
    pub why: Vec<String>,
}

/// What a build produced for one output.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputResult {
    pub name: String,
    pub written: WrittenOutput,
    /// The runs of the nodes this output depends on, in graph order.
    pub stages: Vec<NodeRun>,
    /// The preview the `preview` node drew (`None` with previews off).
    pub preview: Option<WrittenFile>,
    /// What the stages before the write found worth saying (an automatic N that stopped at
    /// `max_n` short of its tolerance), read from their payloads, so a cached build says it
    /// too.
    pub warnings: Vec<String>,
}

/// What a build produced: the outputs that built, and why each of the others failed.
#[derive(Debug)]
pub struct Built {
    pub results: Vec<OutputResult>,
    /// `(output, error)` for each needed output that did not build, by output name; outputs
    /// failing for one stage's failure share its message.
    pub failed: Vec<(String, String)>,
}

#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    #[error(transparent)]
    Cache(#[from] CacheError),
    /// A node that failed earlier in this build (its stage's error, or an input's).
    #[error("{0}")]
    Failed(String),
    #[error("stage `{node}` failed: {error}")]
    Stage {
        node: String,
        #[source]
        error: StageError,
    },
}

/// A node's payload, decoded, as held in memory during one build.
#[derive(Clone)]
enum Value {
    Bytes(Arc<Vec<u8>>),
    Mesh(Arc<MeshArtifact>),
    /// A chunked mesh, left in its cache entry: the open entry and its verified trailer.
    Chunked(Arc<ChunkedMesh<EntryReader>>),
    Written(Arc<WrittenOutput>),
    /// A preview's record of its file.
    Preview(Arc<WrittenFile>),
}

/// Why running a node failed.
enum Failure {
    /// The stage failed: the build fails, naming the node.
    Failed(StageError),
    /// The chunked mesh of input `input` turned out corrupt while being read: the input is
    /// rebuilt and the node run again.
    CorruptInput { input: NodeId, reason: String },
}

impl From<StageError> for Failure {
    fn from(error: StageError) -> Failure {
        Failure::Failed(error)
    }
}

impl From<CacheError> for Failure {
    fn from(error: CacheError) -> Failure {
        Failure::Failed(error.into())
    }
}

/// Chunks in flight between the tile stage and the thread writing them to the cache: with
/// one being made and one being written, memory holds about three chunks.
const CHUNKS_IN_FLIGHT: usize = 1;

/// What the cache holds for a node this build needs.
enum CacheStatus {
    /// Up to date: its output hash, and its value when the lookup already loaded it (a write
    /// node's record of its files).
    Fresh {
        hash: ContentHash,
        value: Option<Value>,
    },
    /// No entry: the node runs; its record tells why.
    Missing,
    /// An entry that cannot be used (`why`): the node runs.
    Stale { why: String },
}

/// A node of a level that must run, and what its lookup found instead.
struct ToRun {
    id: NodeId,
    key: Key,
    desc: KeyDescription,
    /// Why its entry could not be used, when it had one.
    stale: Option<String>,
}

/// How running a node of a level went.
struct Ran {
    node: ToRun,
    result: Result<Value, Failure>,
    seconds: f64,
}

struct Resolved {
    key: Key,
    hash: ContentHash,
    value: Option<Value>,
}

pub struct Builder<'a> {
    pub graph: &'a Graph,
    pub cache: &'a Cache,
    pub sink: &'a dyn OutputSink,
    pub progress: &'a dyn Progress,
    resolved: HashMap<NodeId, Resolved>,
    runs: HashMap<NodeId, NodeRun>,
    /// The nodes this build resolves.
    needed: HashSet<NodeId>,
    /// Files written and pictures drawn while a tiling ran, by node.
    early: early::Ready,
    /// Nodes that failed, or whose input did, with the error of the stage that failed.
    failed: HashMap<NodeId, String>,
    /// How many bytes of entries the cache may keep beyond this build's ([`Cache::gc`]).
    cache_limit: SizeLimit,
}

impl<'a> Builder<'a> {
    pub fn new(
        graph: &'a Graph,
        cache: &'a Cache,
        sink: &'a dyn OutputSink,
        progress: &'a dyn Progress,
    ) -> Self {
        Builder {
            graph,
            cache,
            sink,
            progress,
            resolved: HashMap::new(),
            runs: HashMap::new(),
            needed: HashSet::new(),
            early: early::Ready::default(),
            failed: HashMap::new(),
            cache_limit: SizeLimit::bytes(u64::MAX),
        }
    }

    /// Bounds the cache's objects to `bytes` after the build (least recently used entries
    /// go first; this build's stay). Without it nothing is removed but crashed temporaries.
    pub fn with_cache_limit(mut self, limit: SizeLimit) -> Self {
        self.cache_limit = limit;
        self
    }

    /// Builds `targets` (all outputs when empty); the caller has checked the names. A stage
    /// that fails fails the outputs that need it, not the build: `Err` is a cache error.
    pub fn build(mut self, targets: &[String]) -> Result<Built, BuildError> {
        let needed = self.graph.needed(targets).unwrap_or_default();
        self.run_nodes(&needed)?;
        let mut results = Vec::new();
        let mut failed = Vec::new();
        for (name, &write) in &self.graph.outputs {
            if let Some(error) = self.failed.get(&write) {
                failed.push((name.clone(), error.clone()));
                continue;
            }
            let Some(Value::Written(written)) =
                self.resolved.get(&write).and_then(|r| r.value.clone())
            else {
                continue;
            };
            let preview_node = self.graph.previews.get(name).copied();
            let preview = match preview_node.and_then(|p| self.resolved.get(&p)) {
                Some(Resolved {
                    value: Some(Value::Preview(file)),
                    ..
                }) => Some((**file).clone()),
                _ => None,
            };
            let mut chain = Vec::new();
            let mut stack: Vec<NodeId> = [write].into_iter().chain(preview_node).collect();
            while let Some(id) = stack.pop() {
                chain.push(id);
                stack.extend(&self.graph.nodes[id].inputs);
            }
            chain.sort_unstable();
            chain.dedup();
            let stages = chain
                .iter()
                .filter_map(|id| self.runs.get(id).cloned())
                .collect();
            let mut warnings = Vec::new();
            for &id in &chain {
                warnings.extend(self.node_warning(id)?);
            }
            results.push(OutputResult {
                name: name.clone(),
                written: (*written).clone(),
                preview,
                stages,
                warnings,
            });
        }
        Ok(Built { results, failed })
    }

    /// The warning a node's payload carries: an automatic-N fit that stopped short of its
    /// tolerance, an `optimize` that did not reach its target, or a crystal cell through whose
    /// atoms several surfaces fit (the small payload is loaded for it); `None` for every other
    /// node.
    fn node_warning(&mut self, id: NodeId) -> Result<Option<String>, BuildError> {
        let node = &self.graph.nodes[id];
        if !warnings::carries_warning(&node.stage) {
            return Ok(None);
        }
        let mut ignore = |_: Key, _: Arc<MeshArtifact>, _: ContentHash| {};
        self.load(id, &mut ignore)?;
        let node = &self.graph.nodes[id];
        let Some(Value::Bytes(bytes)) = self.resolved.get(&id).and_then(|r| r.value.clone()) else {
            return Ok(None);
        };
        Ok(warnings::node_warning(&node.stage, &node.name, &bytes))
    }

    /// Builds node `id` and what it needs, and returns its payload (for `latticebuild cell`).
    pub fn build_node(mut self, id: NodeId) -> Result<Vec<u8>, BuildError> {
        let needed = self.graph.closure(&[id]);
        self.run_nodes(&needed)?;
        if let Some(error) = self.failed.get(&id) {
            return Err(BuildError::Failed(error.clone()));
        }
        let mut ignore = |_: Key, _: Arc<MeshArtifact>, _: ContentHash| {};
        self.load(id, &mut ignore)?;
        match self.resolved[&id].value.clone() {
            Some(Value::Bytes(bytes)) => Ok((*bytes).clone()),
            _ => Err(BuildError::Stage {
                node: self.graph.nodes[id].name.clone(),
                error: StageError::Internal("its payload is not a byte table".into()),
            }),
        }
    }

    /// Runs `needed` (closed under inputs, in order) level by level, then collects garbage.
    fn run_nodes(&mut self, needed: &[NodeId]) -> Result<(), BuildError> {
        self.needed = needed.iter().copied().collect();
        let mut level = vec![0usize; self.graph.nodes.len()];
        for &id in needed {
            level[id] = self.graph.nodes[id]
                .inputs
                .iter()
                .map(|&i| level[i] + 1)
                .max()
                .unwrap_or(0);
        }
        let depth = needed
            .iter()
            .map(|&id| level[id])
            .max()
            .map_or(0, |d| d + 1);
        // Large payloads are written to the cache on background threads (their hash is known
        // first), overlapping the 300 MB cache write of a mesh with writing its files.
        let cache = self.cache;
        std::thread::scope(|scope| -> Result<(), BuildError> {
            let mut stores = Vec::new();
            let mut outcome = Ok(());
            for d in 0..depth {
                let nodes: Vec<NodeId> = needed
                    .iter()
                    .copied()
                    .filter(|&id| level[id] == d)
                    .collect();
                outcome = self.run_level(&nodes, &mut |key: Key, mesh: Arc<MeshArtifact>, hash| {
                    stores.push(scope.spawn(move || {
                        let head = mesh.head();
                        let [vertices, triangles] = mesh.arrays();
                        cache.put_parts(&key, &[&head, vertices, triangles], hash)
                    }));
                });
                if outcome.is_err() {
                    break;
                }
            }
            for store in stores {
                store.join().map_err(|_| BuildError::Stage {
                    node: "cache".into(),
                    error: StageError::Panicked("a cache write"),
                })??;
            }
            outcome
        })?;
        self.collect_garbage(needed)?;
        Ok(())
    }

    /// Resolves one level: cache lookups first, then the misses in parallel. Meshes are handed
    /// to `store_mesh` with their hash, to be written to the cache in the background.
    fn run_level(
        &mut self,
        nodes: &[NodeId],
        store_mesh: &mut StoreMesh,
    ) -> Result<(), BuildError> {
        let mut to_run = Vec::new();
        for &id in nodes {
            let started = Instant::now();
            let node = &self.graph.nodes[id];
            if let Some(error) = node.inputs.iter().find_map(|i| self.failed.get(i)) {
                self.failed.insert(id, error.clone());
                continue;
            }
            if let Stage::File(file) = &node.stage {
                let read = self.read_file(id, file, started);
                self.isolate(id, read)?;
                continue;
            }
            let inputs: Vec<ContentHash> =
                node.inputs.iter().map(|i| self.resolved[i].hash).collect();
            let keyed = node.stage.key(&inputs).map_err(|e| BuildError::Stage {
                node: node.name.clone(),
                error: StageError::Key(e),
            });
            let Some((key, desc)) = self.isolate(id, keyed)? else {
                continue;
            };
            match self.lookup(id, &key)? {
                CacheStatus::Fresh { hash, value } => {
                    self.cache.record(&node.name, &key, &desc, &hash)?;
                    self.resolved.insert(id, Resolved { key, hash, value });
                    self.runs.insert(
                        id,
                        NodeRun {
                            node: node.name.clone(),
                            stage: node.stage.kind(),
                            cached: true,
                            seconds: started.elapsed().as_secs_f64(),
                            why: vec![],
                        },
                    );
                }
                CacheStatus::Missing => to_run.push(ToRun {
                    id,
                    key,
                    desc,
                    stale: None,
                }),
                CacheStatus::Stale { why } => to_run.push(ToRun {
                    id,
                    key,
                    desc,
                    stale: Some(why),
                }),
            }
        }
        let mut loaded = Vec::with_capacity(to_run.len());
        for node in to_run {
            let mut ok = true;
            for input in self.graph.nodes[node.id].inputs.clone() {
                let load = self.load(input, store_mesh);
                if self.isolate(node.id, load)?.is_none() {
                    ok = false;
                    break;
                }
            }
            if ok {
                loaded.push(node);
            }
        }
        let to_run = loaded;
        let this = &*self;
        let outcomes: Vec<Ran> = to_run
            .into_par_iter()
            .map(|node| {
                let started = Instant::now();
                let result = this.execute(node.id, &node.key);
                Ran {
                    node,
                    result,
                    seconds: started.elapsed().as_secs_f64(),
                }
            })
            .collect();
        for ran in outcomes {
            let Ran {
                node:
                    ToRun {
                        id,
                        key,
                        desc,
                        stale,
                    },
                result,
                mut seconds,
            } = ran;
            let value = match result {
                Ok(value) => Ok(value),
                Err(Failure::CorruptInput { input, reason }) => {
                    // Rebuild the input's entry, then run this node again, once.
                    match self.rerun_corrupt(input, &reason, store_mesh) {
                        Ok(()) => {
                            let started = Instant::now();
                            let again = self.execute(id, &key);
                            seconds += started.elapsed().as_secs_f64();
                            self.fail_on(id, again)
                        }
                        Err(error) => Err(error),
                    }
                }
                Err(failure) => self.fail_on(id, Err(failure)),
            };
            let Some(value) = self.isolate(id, value)? else {
                continue;
            };
            let node = &self.graph.nodes[id];
            let hash = self.store(&key, &value, store_mesh)?;
            let mut why = stale.map_or_else(Vec::new, |r| vec![r]);
            if why.is_empty() {
                why = match self.cache.previous(&node.name) {
                    Some(prev) if prev.key == key => vec!["its cache entry was missing".into()],
                    Some(prev) => explain(&prev.description, &desc),
                    None => vec!["it was never built".into()],
                };
            }
            self.cache.record(&node.name, &key, &desc, &hash)?;
            self.resolved.insert(
                id,
                Resolved {
                    key,
                    hash,
                    value: Some(value),
                },
            );
            self.runs.insert(
                id,
                NodeRun {
                    node: node.name.clone(),
                    stage: node.stage.kind(),
                    cached: false,
                    seconds,
                    why,
                },
            );
        }
        Ok(())
    }

    /// Reads a `file` node: its value is the file's bytes and its hash their content hash,
    /// so what reads it is keyed on the content. Never cached (the file is the source); shown
    /// as cached when the content is the one the previous build saw.
    fn read_file(
        &mut self,
        id: NodeId,
        file: &crate::stages::file::FileStage,
        started: Instant,
    ) -> Result<(), BuildError> {
        let node = &self.graph.nodes[id];
        let bytes = std::fs::read(&file.path).map_err(|e| BuildError::Stage {
            node: node.name.clone(),
            error: StageError::Unreadable {
                path: file.path.clone(),
                source: e,
            },
        })?;
        let hash = ContentHash::of(&bytes);
        let (key, desc) = node.stage.key(&[hash]).map_err(|e| BuildError::Stage {
            node: node.name.clone(),
            error: StageError::Key(e),
        })?;
        let unchanged = self
            .cache
            .previous(&node.name)
            .is_some_and(|prev| prev.key == key);
        self.cache.record(&node.name, &key, &desc, &hash)?;
        self.resolved.insert(
            id,
            Resolved {
                key,
                hash,
                value: Some(Value::Bytes(Arc::new(bytes))),
            },
        );
        let why = if unchanged {
            vec![]
        } else {
            vec![format!("`{}` is new or changed", file.given)]
        };
        self.runs.insert(
            id,
            NodeRun {
                node: node.name.clone(),
                stage: node.stage.kind(),
                cached: unchanged,
                seconds: started.elapsed().as_secs_f64(),
                why,
            },
        );
        Ok(())
    }

    /// Whether node `id`'s entry under `key` is up to date, and if not, why.
    fn lookup(&self, id: NodeId, key: &Key) -> Result<CacheStatus, BuildError> {
        let node = &self.graph.nodes[id];
        let Some(hash) = self.cache.peek_hash(key) else {
            return Ok(CacheStatus::Missing);
        };
        if !matches!(node.stage, Stage::Write(_) | Stage::Preview(_)) {
            return Ok(CacheStatus::Fresh { hash, value: None });
        }
        // A write (or preview) is only up to date if its files are still there, unchanged.
        match self.cache.get(key)? {
            Lookup::Hit { payload, hash } => {
                let record = match node.stage {
                    Stage::Preview(_) => serde_json::from_slice::<WrittenFile>(&payload)
                        .map(|file| (vec![file.clone()], Value::Preview(Arc::new(file)))),
                    _ => serde_json::from_slice::<WrittenOutput>(&payload)
                        .map(|w| (w.files.clone(), Value::Written(Arc::new(w)))),
                };
                match record {
                    Ok((files, value)) => match files.iter().find(|f| !self.sink.holds(f)) {
                        None => Ok(CacheStatus::Fresh {
                            hash,
                            value: Some(value),
                        }),
                        Some(f) => Ok(CacheStatus::Stale {
                            why: format!("`{}` is missing or was changed", f.path),
                        }),
                    },
                    Err(e) => Ok(CacheStatus::Stale {
                        why: format!("its cache entry is unreadable: {e}"),
                    }),
                }
            }
            Lookup::Corrupt { reason } => Ok(CacheStatus::Stale {
                why: format!("its cache entry was corrupt ({reason})"),
            }),
            Lookup::Miss => Ok(CacheStatus::Missing),
        }
    }

    /// Makes sure node `id`'s value is in memory, from the cache or by running it again.
    fn load(&mut self, id: NodeId, store_mesh: &mut StoreMesh) -> Result<(), BuildError> {
        if self.resolved[&id].value.is_some() {
            return Ok(());
        }
        let key = self.resolved[&id].key;
        if let Some(value) = self.open_chunked(&key)? {
            self.resolved.get_mut(&id).expect("resolved").value = Some(value);
            return Ok(());
        }
        if let Lookup::Hit { payload, .. } = self.cache.get(&key)?
            && let Some(value) = decode(&self.graph.nodes[id].stage, payload)
        {
            self.resolved.get_mut(&id).expect("resolved").value = Some(value);
            return Ok(());
        }
        // The entry went bad between lookup and load: run the node again (deterministic, so
        // its hash and everything keyed on it stay the same).
        let why = "its cache entry was corrupt or gone when its payload was needed";
        self.rerun(id, why.into(), store_mesh)?;
        Ok(())
    }

    /// Runs node `id` again (its inputs loaded first), stores and records it as run for
    /// `why`; returns its hash.
    fn rerun(
        &mut self,
        id: NodeId,
        why: String,
        store_mesh: &mut StoreMesh,
    ) -> Result<ContentHash, BuildError> {
        let key = self.resolved[&id].key;
        let started = Instant::now();
        for input in self.graph.nodes[id].inputs.clone() {
            self.load(input, store_mesh)?;
        }
        let value = self.execute(id, &key);
        let value = self.fail_on(id, value)?;
        let hash = self.store(&key, &value, store_mesh)?;
        self.resolved.get_mut(&id).expect("resolved").value = Some(value);
        let node = &self.graph.nodes[id];
        self.runs.insert(
            id,
            NodeRun {
                node: node.name.clone(),
                stage: node.stage.kind(),
                cached: false,
                seconds: started.elapsed().as_secs_f64(),
                why: vec![why],
            },
        );
        Ok(hash)
    }

    /// `Some` value of a node's step, or `None` when a stage failed, the failure kept as node
    /// `id`'s (what needs it fails with it); a cache error stays an error.
    fn isolate<T>(
        &mut self,
        id: NodeId,
        result: Result<T, BuildError>,
    ) -> Result<Option<T>, BuildError> {
        match result {
            Ok(value) => Ok(Some(value)),
            Err(BuildError::Cache(error)) => Err(BuildError::Cache(error)),
            Err(error) => {
                self.failed.insert(id, error.to_string());
                Ok(None)
            }
        }
    }

    /// The value of a run, or the build error naming node `id`.
    fn fail_on(&self, id: NodeId, result: Result<Value, Failure>) -> Result<Value, BuildError> {
        let node = &self.graph.nodes[id];
        result.map_err(|failure| BuildError::Stage {
            node: node.name.clone(),
            error: match failure {
                Failure::Failed(error) => error,
                Failure::CorruptInput { reason, .. } => StageError::InputCorruptAgain(reason),
            },
        })
    }

    /// Input `id`'s chunked entry was found corrupt: removes it and runs the node again (it
    /// is deterministic, so its hash and every key built on it stay the same), and says so
    /// in its run.
    fn rerun_corrupt(
        &mut self,
        id: NodeId,
        reason: &str,
        store_mesh: &mut StoreMesh,
    ) -> Result<(), BuildError> {
        let key = self.resolved[&id].key;
        self.cache.remove(&key)?;
        self.resolved.get_mut(&id).expect("resolved").value = None;
        let why = format!("its cache entry was corrupt ({reason})");
        if self.rerun(id, why, store_mesh)? != self.resolved[&id].hash {
            return Err(BuildError::Stage {
                node: self.graph.nodes[id].name.clone(),
                error: StageError::NotDeterministic,
            });
        }
        Ok(())
    }

    /// `key`'s entry as a chunked mesh, if it is a good one. A chunked entry that fails
    /// verification is removed (so the node reruns); any other entry is left to `get`.
    fn open_chunked(&self, key: &Key) -> Result<Option<Value>, CacheError> {
        let Opened::Entry(reader) = self.cache.open_entry(key)? else {
            return Ok(None);
        };
        if !is_chunked(&reader).unwrap_or(false) {
            return Ok(None);
        }
        match ChunkedMesh::open(reader) {
            Ok(mesh) => Ok(Some(Value::Chunked(Arc::new(mesh)))),
            Err(_) => {
                self.cache.remove(key)?;
                Ok(None)
            }
        }
    }

    /// Runs the tile stage with its chunks streamed into `key`'s entry by a writer thread,
    /// committed only if the stage succeeds; a whole mesh (2D) comes back as it is.
    fn run_tile(
        &self,
        id: NodeId,
        stage: &crate::stages::tile::TileStage,
        name: &str,
        key: &Key,
        (cells, file, table): TileInputs,
    ) -> Result<Value, Failure> {
        let cache = self.cache;
        let progress = self.progress.start(name, 0);
        std::thread::scope(|scope| {
            let needed = |node| self.needed.contains(&node);
            let mut consumers = Consumers::begin(self.graph, needed, self.sink, id, scope);
            let (send, receive) = mpsc::sync_channel::<Arc<MeshChunk>>(CHUNKS_IN_FLIGHT);
            let writer = scope.spawn(move || -> Result<_, StageError> {
                // Begun on the first chunk, so a 2D tiling makes no temporary file.
                let mut writer = None;
                for chunk in receive {
                    if writer.is_none() {
                        // Self-verifying: the payload's trailer holds every section's hash, so
                        // hashing the whole again as it is written (5% of a cold tiling's CPU)
                        // would only repeat them.
                        let pending = cache.begin_self_verified(key)?;
                        writer = Some(ChunkedWriter::new(pending).map_err(StageError::CacheBegin)?);
                    }
                    if let Some(w) = writer.as_mut() {
                        w.push(&chunk).map_err(StageError::CacheWrite)?;
                    }
                }
                Ok(writer)
            });
            let output = stage.run(cells, file, table, &*progress, &mut |event| {
                consumers.hand_on(&event, scope);
                match event {
                    Tiled::Chunk(chunk) => {
                        send.send(chunk).map_err(|_| StageError::CacheWriterStopped)
                    }
                    Tiled::ScaffoldBox(_) => Ok(()),
                }
            });
            drop(send);
            let made = consumers.finish();
            let written = writer
                .join()
                .map_err(|_| StageError::Panicked("the cache writer"))?;
            // A writer error explains a stage's "writer stopped", so it comes first.
            let writer = written?;
            match (output?, writer) {
                (TileOutput::Whole(mesh), None) => Ok(Value::Mesh(Arc::new(mesh))),
                (TileOutput::Chunked(head), Some(writer)) => {
                    let (pending, _, check) =
                        writer.finish(head).map_err(StageError::CacheWrite)?;
                    pending.commit_declared(check)?;
                    match self.open_chunked(key)? {
                        Some(value) => {
                            if let Value::Chunked(mesh) = &value {
                                self.early.keep(mesh.source().hash(), made);
                            }
                            Ok(value)
                        }
                        None => Err(StageError::EntryUnreadable.into()),
                    }
                }
                (TileOutput::Chunked(_), None) => {
                    Err(StageError::Internal("the tiling produced no chunks".into()).into())
                }
                (TileOutput::Whole(_), Some(_)) => Err(StageError::Internal(
                    "the tiling produced chunks and a whole mesh".into(),
                )
                .into()),
            }
        })
    }

    /// The failure of an `islands` node reading node `input`.
    fn islands_failure(&self, input: NodeId, failure: IslandsFailure) -> Failure {
        match failure {
            IslandsFailure::Failed(error) => Failure::Failed(error),
            IslandsFailure::CorruptInput(reason) => Failure::CorruptInput { input, reason },
        }
    }

    /// Runs an `islands` node on a chunked mesh (node `input`'s entry): the kept chunks are
    /// streamed into `key`'s entry by a writer thread, as a tiling's are, committed only if
    /// the stage succeeds.
    fn run_islands_chunked(
        &self,
        input: NodeId,
        stage: &IslandsStage,
        key: &Key,
        mesh: &ChunkedMesh<EntryReader>,
    ) -> Result<Value, Failure> {
        let cache = self.cache;
        std::thread::scope(|scope| {
            let (send, receive) = mpsc::sync_channel::<Arc<MeshChunk>>(CHUNKS_IN_FLIGHT);
            let writer = scope.spawn(move || -> Result<_, StageError> {
                let pending = cache.begin_self_verified(key)?;
                let mut writer = ChunkedWriter::new(pending).map_err(StageError::CacheBegin)?;
                for chunk in receive {
                    writer.push(&chunk).map_err(StageError::CacheWrite)?;
                }
                Ok(writer)
            });
            let head = stage.run_chunked(mesh, &mut |chunk| {
                send.send(chunk).map_err(|_| StageError::CacheWriterStopped)
            });
            drop(send);
            let writer = writer
                .join()
                .map_err(|_| StageError::Panicked("the cache writer"))?;
            // A writer error explains a stage's "writer stopped", so it comes first.
            let writer = writer?;
            let head = head.map_err(|failure| self.islands_failure(input, failure))?;
            let (pending, _, check) = writer.finish(head).map_err(StageError::CacheWrite)?;
            pending.commit_declared(check)?;
            match self.open_chunked(key)? {
                Some(value) => Ok(value),
                None => Err(StageError::EntryUnreadable.into()),
            }
        })
    }

    /// Runs node `id`'s stage (keyed `key`) on its inputs' values, which must be loaded.
    fn execute(&self, id: NodeId, key: &Key) -> Result<Value, Failure> {
        let node = &self.graph.nodes[id];
        let input = |k: usize| {
            self.resolved[&node.inputs[k]]
                .value
                .clone()
                .expect("inputs are loaded")
        };
        let bytes = |k: usize| match input(k) {
            Value::Bytes(b) => Ok(b),
            _ => Err(StageError::Internal(format!(
                "input {k} of `{}` is not a byte payload",
                node.name
            ))),
        };
        // Stages that do not count steps get a spinner, shown once they pass half a second
        // (a big file's write, a chunked mesh's islands); the others start their own bar.
        let spinner = match &node.stage {
            Stage::File(_) | Stage::Contour(_) | Stage::Program(_) | Stage::Tile(_) => None,
            _ => Some(self.progress.start(&node.name, 0)),
        };
        if let (Some(spinner), Stage::Write(_)) = (&spinner, &node.stage) {
            spinner.phase("writing and measuring");
        }
        match &node.stage {
            Stage::File(file) => {
                Err(StageError::Internal(format!("`{}` is read, not run", file.given)).into())
            }
            Stage::Cell(stage) => Ok(Value::Bytes(Arc::new(stage.run()?))),
            Stage::MeshCell(stage) => Ok(Value::Bytes(Arc::new(stage.run(&bytes(0)?)?))),
            Stage::VoxelCell(stage) => Ok(Value::Bytes(Arc::new(stage.run(&bytes(0)?)?))),
            Stage::PointCell(stage) => Ok(Value::Bytes(Arc::new(stage.run(&bytes(0)?)?))),
            Stage::Crystal(stage) => Ok(Value::Bytes(Arc::new(stage.run(&bytes(0)?)?))),
            Stage::Sample(stage) => Ok(Value::Bytes(Arc::new(stage.run(&bytes(0)?)?))),
            Stage::Fit(stage) => Ok(Value::Bytes(Arc::new(stage.run(&bytes(0)?)?))),
            Stage::Constrain(stage) => Ok(Value::Bytes(Arc::new(stage.run(&bytes(0)?)?))),
            Stage::Density(stage) => Ok(Value::Bytes(Arc::new(stage.run(&bytes(0)?)?))),
            Stage::Combine(stage) => {
                let inputs = (0..node.inputs.len())
                    .map(bytes)
                    .collect::<Result<Vec<_>, _>>()?;
                let slices: Vec<&[u8]> = inputs.iter().map(|b| b.as_slice()).collect();
                Ok(Value::Bytes(Arc::new(stage.run(&slices)?)))
            }
            Stage::Contour(stage) => {
                let Value::Bytes(cell) = input(0) else {
                    return Err(StageError::Internal("input is not a cell".into()).into());
                };
                // Inputs: the cell, the part (with `within`), the density table (when solved).
                let part = match stage.within {
                    Some(_) => Some(bytes(1)?),
                    None => None,
                };
                let table = match stage.reads_table() {
                    true => Some(bytes(node.inputs.len() - 1)?),
                    false => None,
                };
                let progress = self.progress.start(&node.name, stage.steps());
                let mesh = stage.run(
                    &cell,
                    part.as_deref().map(|b| b.as_slice()),
                    table.as_deref().map(|b| b.as_slice()),
                    &*progress,
                )?;
                Ok(Value::Mesh(Arc::new(mesh)))
            }
            Stage::Program(stage) => {
                let files = (0..node.inputs.len())
                    .map(bytes)
                    .collect::<Result<Vec<_>, _>>()?;
                let slices: Vec<&[u8]> = files.iter().map(|b| b.as_slice()).collect();
                let progress = self.progress.start(&node.name, stage.steps());
                Ok(Value::Mesh(Arc::new(stage.run(&slices, &*progress)?)))
            }
            Stage::Tile(stage) => {
                let inputs = (0..node.inputs.len())
                    .map(bytes)
                    .collect::<Result<Vec<_>, _>>()?;
                let slices: Vec<&[u8]> = inputs.iter().map(|b| b.as_slice()).collect();
                // Inputs: the cells, the scaffold file (unless a grid), the density table.
                let (cells, rest) = slices.split_at(stage.cell_inputs().min(slices.len()));
                let file = rest.first().copied().filter(|_| stage.reads_file());
                let table = rest.last().copied().filter(|_| stage.reads_table());
                self.run_tile(id, stage, &node.name, key, (cells, file, table))
            }
            Stage::Islands(stage) => match input(0) {
                Value::Mesh(mesh) => match stage.run(&mesh) {
                    Ok(kept) => Ok(Value::Mesh(Arc::new(kept))),
                    Err(failure) => Err(self.islands_failure(node.inputs[0], failure)),
                },
                Value::Chunked(mesh) => self.run_islands_chunked(node.inputs[0], stage, key, &mesh),
                _ => Err(StageError::Internal("input is not a mesh".into()).into()),
            },
            Stage::Preview(stage) => self.run_preview(id, stage),
            Stage::Write(stage) => {
                let prewritten = match self.early.take(id, self.resolved[&node.inputs[0]].hash) {
                    Some(Made::File(file)) => vec![file],
                    _ => Vec::new(),
                };
                let input = match input(0) {
                    Value::Mesh(mesh) => {
                        // The pictures of the previews of this write are drawn while it
                        // writes: writing and measuring leave a core idle much of the time.
                        let (written, pictures) = std::thread::scope(|scope| {
                            let drawing = scope.spawn(|| self.draw_beside(id, &mesh));
                            let written = stage.run(MeshInput::Whole(&mesh), self.sink, prewritten);
                            wait_helping_the_pool(&drawing);
                            (written, drawing.join().unwrap_or_default())
                        });
                        self.early
                            .keep(self.resolved[&node.inputs[0]].hash, pictures);
                        written
                    }
                    Value::Chunked(mesh) => stage.run(
                        MeshInput::Chunked {
                            chunks: &*mesh,
                            head: &mesh.trailer.head,
                        },
                        self.sink,
                        prewritten,
                    ),
                    _ => return Err(StageError::Internal("input is not a mesh".into()).into()),
                };
                match input {
                    Ok(written) => Ok(Value::Written(Arc::new(written))),
                    Err(WriteError::Failed(error)) => Err(Failure::Failed(error)),
                    Err(WriteError::CorruptInput(reason)) => Err(Failure::CorruptInput {
                        input: node.inputs[0],
                        reason,
                    }),
                }
            }
        }
    }

    /// The pictures of the preview nodes that read write node `write` and its whole mesh
    /// `mesh` ([`crate::stages::preview::PreviewStage::draw_whole`]).
    fn draw_beside(&self, write: NodeId, mesh: &MeshArtifact) -> Vec<(NodeId, Made)> {
        let source = self.graph.nodes[write].inputs.first();
        let readers = self
            .graph
            .nodes
            .iter()
            .enumerate()
            .filter_map(|(id, n)| match &n.stage {
                Stage::Preview(preview)
                    if n.inputs.first() == source && n.inputs.get(1) == Some(&write) =>
                {
                    Some((id, preview))
                }
                _ => None,
            });
        readers
            .filter_map(|(id, preview)| {
                let picture = preview.draw_whole(mesh)?;
                Some((id, Made::Picture(Box::new(picture))))
            })
            .collect()
    }

    /// Runs a `preview` node: its inputs are the mesh, the write's record, then the cell
    /// nodes whose warnings the caption repeats.
    fn run_preview(
        &self,
        id: NodeId,
        stage: &crate::stages::preview::PreviewStage,
    ) -> Result<Value, Failure> {
        let node = &self.graph.nodes[id];
        let value = |k: usize| self.resolved[&node.inputs[k]].value.clone();
        let Some(Value::Written(written)) = value(1) else {
            return Err(StageError::Internal("input 1 is not a write record".into()).into());
        };
        let mut cell_warnings = Vec::new();
        for k in 2..node.inputs.len() {
            let carrier = &self.graph.nodes[node.inputs[k]];
            if let Some(Value::Bytes(bytes)) = value(k) {
                cell_warnings.extend(warnings::node_warning(
                    &carrier.stage,
                    &carrier.name,
                    &bytes,
                ));
            }
        }
        let early = match self.early.take(id, self.resolved[&node.inputs[0]].hash) {
            Some(Made::Picture(picture)) => Some(*picture),
            _ => None,
        };
        let drawn = match value(0) {
            Some(Value::Mesh(mesh)) => stage.run(
                MeshInput::Whole(&mesh),
                &written,
                &cell_warnings,
                self.sink,
                early,
            ),
            Some(Value::Chunked(mesh)) => stage.run(
                MeshInput::Chunked {
                    chunks: &*mesh,
                    head: &mesh.trailer.head,
                },
                &written,
                &cell_warnings,
                self.sink,
                early,
            ),
            _ => return Err(StageError::Internal("input is not a mesh".into()).into()),
        };
        match drawn {
            Ok(file) => Ok(Value::Preview(Arc::new(file))),
            Err(WriteError::Failed(error)) => Err(Failure::Failed(error)),
            Err(WriteError::CorruptInput(reason)) => Err(Failure::CorruptInput {
                input: node.inputs[0],
                reason,
            }),
        }
    }

    fn store(
        &self,
        key: &Key,
        value: &Value,
        store_mesh: &mut StoreMesh,
    ) -> Result<ContentHash, BuildError> {
        Ok(match value {
            Value::Bytes(bytes) => self.cache.put(key, bytes)?,
            Value::Mesh(mesh) => {
                let head = mesh.head();
                let [vertices, triangles] = mesh.arrays();
                let hash = ContentHash::of_parts(&[&head, vertices, triangles]);
                store_mesh(*key, Arc::clone(mesh), hash);
                hash
            }
            // Streamed into its entry while it ran.
            Value::Chunked(mesh) => mesh.source().hash(),
            Value::Written(written) => {
                let json = serde_json::to_vec(&**written).expect("written output serializes");
                self.cache.put(key, &json)?
            }
            Value::Preview(file) => {
                let json = serde_json::to_vec(&**file).expect("a file record serializes");
                self.cache.put(key, &json)?
            }
        })
    }

    /// Keeps what this build used and as many of the other entries, most recently used
    /// first, as fit in the cache limit, so an optimization loop over thousands of parameter
    /// values does not fill the disk while one that comes back to a value finds it cached.
    fn collect_garbage(&self, needed: &[NodeId]) -> Result<(), BuildError> {
        let keep: HashSet<Key> = needed
            .iter()
            .filter_map(|id| self.resolved.get(id).map(|r| r.key))
            .collect();
        self.cache.gc(&keep, self.cache_limit)?;
        Ok(())
    }
}

/// The value of node payload `payload`, if it decodes.
fn decode(stage: &Stage, payload: Vec<u8>) -> Option<Value> {
    match stage {
        Stage::File(_)
        | Stage::Cell(_)
        | Stage::MeshCell(_)
        | Stage::VoxelCell(_)
        | Stage::PointCell(_)
        | Stage::Crystal(_)
        | Stage::Sample(_)
        | Stage::Fit(_)
        | Stage::Combine(_)
        | Stage::Constrain(_)
        | Stage::Density(_) => Some(Value::Bytes(Arc::new(payload))),
        Stage::Contour(_) | Stage::Program(_) | Stage::Tile(_) | Stage::Islands(_) => {
            Some(Value::Mesh(Arc::new(MeshArtifact::decode(&payload).ok()?)))
        }
        Stage::Write(_) => serde_json::from_slice(&payload)
            .ok()
            .map(|w| Value::Written(Arc::new(w))),
        Stage::Preview(_) => serde_json::from_slice(&payload)
            .ok()
            .map(|f| Value::Preview(Arc::new(f))),
    }
}
