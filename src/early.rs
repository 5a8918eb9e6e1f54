//! Work done from a tiling's chunks while the tiling makes them, so that a mesh of tens of
//! millions of triangles is not read back from the cache to be written or drawn: the STL
//! files of the write nodes that read the tile node, and the pictures of its preview nodes.
//!
//! Invariants:
//! - Each consumer is a thread of its own fed through a bounded channel, and never uses the
//!   global rayon pool: the pool's threads are the tiling's, blocked while they hand a chunk
//!   on, so waiting for them would deadlock. STL files are encoded on the thread itself
//!   ([`Workers::Caller`]); a picture is drawn in a one-thread pool of its own.
//! - What is made early is exactly what the stage would make later from the cache entry: the
//!   same chunks in the same order, and for a picture the same [`Spec`] (checked by the
//!   preview stage, which draws from the entry when they differ). It is used only by the node
//!   it was made for, and only if the tiling's entry hashes to the mesh that node reads.
//! - A consumer that fails just stops (its file is removed, its picture dropped); the stage
//!   then does the work itself. The tiling never waits on a stopped consumer.

use std::collections::HashMap;
use std::sync::mpsc;
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::{Scope, ScopedJoinHandle};

use latticebuild_geom::mesh::MeshChunk;
use latticebuild_geom::mesh_io::{Format, StlStream, Workers};
use latticebuild_geom::render::{Preview, Spec};

use crate::cache::ContentHash;
use crate::graph::{Graph, NodeId};
use crate::stages::Stage;
use crate::stages::preview::PreviewStage;
use crate::stages::tile::Tiled;
use crate::stages::write::{OutputSink, Prewritten};

/// Chunks in flight to each consumer: with one being made and one being used, memory holds
/// about three chunks.
const IN_FLIGHT: usize = 1;

/// What a consumer made for its node.
pub enum Made {
    /// A write node's STL file, not yet in place.
    File(Prewritten),
    /// A preview node's picture, drawn but without its caption.
    Picture(Box<Preview>),
}

/// The consumers of one tiling while it runs.
pub struct Consumers<'scope> {
    running: Vec<(NodeId, Consumer<'scope>)>,
    /// Preview nodes waiting for the scaffold's box, whose picture they are fitted to.
    to_draw: Vec<(NodeId, PreviewStage)>,
}

struct Consumer<'scope> {
    send: mpsc::SyncSender<Arc<MeshChunk>>,
    thread: ScopedJoinHandle<'scope, Option<Made>>,
}

/// What the consumers made, by node, with the hash of the mesh they made it from.
#[derive(Default)]
pub struct Ready(Mutex<HashMap<NodeId, (ContentHash, Made)>>);

impl<'scope> Consumers<'scope> {
    /// Starts a consumer for each write node among `needed` that reads `tile` and writes an
    /// STL, and readies one for each such preview node (it starts on the scaffold's box).
    pub fn begin<'env>(
        graph: &'env Graph,
        needed: impl Fn(NodeId) -> bool,
        sink: &'env dyn OutputSink,
        tile: NodeId,
        scope: &'scope Scope<'scope, 'env>,
    ) -> Consumers<'scope> {
        let mut consumers = Consumers {
            running: Vec::new(),
            to_draw: Vec::new(),
        };
        for (node, n) in graph.nodes.iter().enumerate() {
            if n.inputs.first() != Some(&tile) || !needed(node) {
                continue;
            }
            match &n.stage {
                Stage::Write(write) if write.formats.contains(&Format::Stl) => {
                    let Ok(file) = sink.begin_file(&write.path(Format::Stl)) else {
                        continue;
                    };
                    let (encoding, stamp) = (write.encoding, &write.stamp);
                    let consumer = Consumer::spawn(scope, move |receive| {
                        let mut file = file;
                        let mut stream =
                            StlStream::begin(encoding, stamp, Workers::Caller, &mut file).ok()?;
                        for chunk in receive {
                            stream.push(&chunk, &mut file).ok()?;
                        }
                        stream.finish(&mut file).ok()?;
                        Some(Made::File(Prewritten {
                            format: Format::Stl,
                            file,
                        }))
                    });
                    consumers.running.push((node, consumer));
                }
                Stage::Preview(preview) => consumers.to_draw.push((node, preview.clone())),
                _ => {}
            }
        }
        consumers
    }

    /// Hands `event` to every consumer (a stopped one is skipped: its work is done later).
    pub fn hand_on(&mut self, event: &Tiled, scope: &'scope Scope<'scope, '_>) {
        match event {
            Tiled::ScaffoldBox(bbox) => {
                for (node, preview) in self.to_draw.drain(..) {
                    let spec = preview.tiling_spec(*bbox);
                    let consumer = Consumer::spawn(scope, move |receive| draw(spec, receive));
                    self.running.push((node, consumer));
                }
            }
            Tiled::Chunk(chunk) => {
                for (_, consumer) in &self.running {
                    let _ = consumer.send.send(Arc::clone(chunk));
                }
            }
        }
    }

    /// Waits for the consumers: what each made, by node (none for a stopped one).
    pub fn finish(self) -> Vec<(NodeId, Made)> {
        self.running
            .into_iter()
            .filter_map(|(node, Consumer { send, thread })| {
                drop(send);
                Some((node, thread.join().ok().flatten()?))
            })
            .collect()
    }
}

impl<'scope> Consumer<'scope> {
    fn spawn<'env>(
        scope: &'scope Scope<'scope, 'env>,
        work: impl FnOnce(mpsc::Receiver<Arc<MeshChunk>>) -> Option<Made> + Send + 'scope,
    ) -> Consumer<'scope> {
        let (send, receive) = mpsc::sync_channel(IN_FLIGHT);
        let thread = scope.spawn(move || work(receive));
        Consumer { send, thread }
    }
}

/// Draws the chunks received into a picture of `spec`, in a one-thread pool of its own.
fn draw(spec: Spec, receive: mpsc::Receiver<Arc<MeshChunk>>) -> Option<Made> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .thread_name(|_| "latticebuild-preview".into())
        .build()
        .ok()?;
    let mut picture = Preview::new(spec);
    for chunk in receive {
        pool.install(|| picture.add_chunk(&chunk)).ok()?;
    }
    Some(Made::Picture(Box::new(picture)))
}

impl Ready {
    /// Keeps what was made from the mesh of hash `mesh`.
    pub fn keep(&self, mesh: ContentHash, made: Vec<(NodeId, Made)>) {
        let mut ready = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        for (node, made) in made {
            ready.insert(node, (mesh, made));
        }
    }

    /// What was made for node `id`, if it was made from the mesh `input` hashes to.
    pub fn take(&self, id: NodeId, input: ContentHash) -> Option<Made> {
        let mut ready = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        match ready.remove(&id) {
            Some((mesh, made)) if mesh == input => Some(made),
            _ => None,
        }
    }
}
