//! Chunk streaming: the chunks around a moving eye generated, meshed and uploaded on
//! rayon's workers, nearest first, without a frame ever waiting for one.
//!
//! A [`ChunkStreamer`] owns the resident [`World`]. Each [`ChunkStreamer::update`] (once
//! a frame, with the eye) does a bounded amount of work on the calling thread and hands
//! the rest to its own pool ([`StreamConfig::threads`]: one thread fewer than the cores).
//! Where there are no threads (wasm32: a browser page has one; or a streamer made with
//! [`ChunkStreamer::new_local`]) the jobs run on the thread that calls the update, within
//! [`StreamConfig::local_budget`] per update (at least one job), and the contract below
//! holds the same.
//!
//! # The contract
//!
//! The *true world* is the [`ChunkSource`]'s blocks with every edit made through
//! [`ChunkStreamer::set_block`] applied over them, in order; where the source fails for a
//! chunk (it panics, or makes a block id the registry does not hold) that chunk is air,
//! and the failure is reported once per load, never propagated and never silent.
//!
//! - **Once idle, the sink holds the truth.** After any sequence of updates, moves,
//!   teleports, view-distance changes and edits (of loaded chunks, of chunks at the
//!   view-distance edge and their neighbours, of chunks not loaded), once
//!   [`ChunkStreamer::is_idle`] is true every chunk held by the [`ChunkSink`] holds
//!   exactly the meshes a fresh [`Mesher::mesh`] of the true world makes of it and its 26
//!   neighbours, every chunk within the view distance with a non-empty mesh is held, and
//!   none past the view distance plus the hysteresis is.
//! - **Idleness is reached.** With the eye still and no edits, updates reach
//!   [`ChunkStreamer::is_idle`] (each needs the workers to have finished: no update
//!   waits for them). No state waits for something that will not come: an edited chunk
//!   waits only for neighbours it asks for itself.
//! - **A drawn chunk's neighbourhood stays resident.** A chunk is meshed only when it and
//!   its 26 neighbours have their blocks, and a chunk leaves memory only when none of its
//!   neighbours is drawn, being meshed or wanted. So a mesh in the sink was made from the
//!   blocks the streamer holds now: an edit, a reload, or a source that answers
//!   differently each call cannot leave it stale. An edit remeshes the chunks it touches
//!   ([`voxel_core::touched_neighbours`]) before anything new; an edit of a chunk not
//!   loaded touches no drawn chunk.
//! - **Bounded work and memory.** At most [`StreamConfig::max_jobs`] jobs in flight,
//!   [`StreamConfig::scan_budget`] positions looked at, [`StreamConfig::max_unloads`]
//!   chunks dropped and [`StreamConfig::upload_budget_bytes`] of quads uploaded (at least
//!   one mesh) per update. The unload queue holds each chunk at most once, so a teleport
//!   costs no more than loading the new place and unloading the old at the budget.
//!   Resident blocks are those within the view distance plus the hysteresis (at least 2)
//!   and the ring of neighbours drawn chunks need. Edits are kept as a sparse list per
//!   chunk, [`EDIT_BYTES`] per edited block plus [`EDITED_CHUNK_BYTES`] per edited chunk
//!   ([`ChunkStreamer::memory_bytes`] counts them): an edited chunk that unloads keeps only
//!   its edits, and comes back as the source's blocks with its edits applied.
//!   [`ChunkStreamer::edits`] lists them for a game to save.
//! - **With light on** ([`ChunkStreamer::set_light`]), once idle every drawn chunk holds
//!   the meshes [`voxel_mesh::Mesher::mesh_lit`] makes of it with the light
//!   [`voxel_core::LightField::new`] gives the resident chunks (air ones included): light
//!   crosses chunk borders, and comes in and goes with the chunks. No update lights a
//!   chunk: the light job does, on the pool, and a chunk is meshed once it and its 26
//!   neighbours are lit.
//! - **Dropping the streamer stops its jobs**: queued jobs return at once, without
//!   calling the source or the mesher.
//!
//! # How
//!
//! - **Load**: the positions within the view distance (a cylinder: `view_distance`
//!   chunks across, `vertical_distance` up and down) are walked nearest first; a missing
//!   position and its missing neighbours are generated on a worker (with the chunk's
//!   edits applied there). A chunk whose 26 neighbours have their blocks is meshed on a
//!   worker, which also packs it ([`voxel_core::Chunk::pack`], about 1× a packed-index
//!   palette). Uniform air chunks are not stored.
//! - **Upload**: finished meshes wait in a queue, nearest first, and go to the
//!   [`ChunkSink`] (the [`Renderer`]) within the upload budget. Each position has a
//!   version: a job whose position was edited, unloaded or regenerated since comes back
//!   to nothing.
//! - **Unload**: when the eye's chunk changes, the positions past the view distance plus
//!   [`StreamConfig::hysteresis`] are queued (once each). A queued chunk that is drawn
//!   leaves the sink; one whose neighbours are not drawn, meshing or wanted leaves
//!   memory (its neighbours past the margin are queued in turn); one still needed is
//!   dropped from the queue and queued again when its drawn neighbour leaves.
//!
//! # Layout
//!
//! - `source`: where chunks come from and where meshes go ([`ChunkSource`],
//!   [`ChunkSink`]), and a source's blocks checked.
//! - `config`: [`StreamConfig`] and its ranges.
//! - `slot`: how far along each position is.
//! - `schedule`: one update ([`ChunkStreamer::update`], [`StreamFrame`]): what the
//!   workers finished, unloads, new jobs nearest first, uploads within the budget.
//! - `jobs`: the generation and meshing jobs the streamer's pool runs.
//! - `pool`: where they run (worker threads, or the updating thread within a budget).
//! - `edits`: edits of the blocks ([`ChunkStreamer::set_block`]), kept per chunk.
//! - `light`: light as chunks stream ([`ChunkStreamer::set_light`]): a light field over
//!   the resident chunks, updated by one job at a time on the pool, its snapshots read
//!   by the meshing jobs.
//! - `sun_feed`: sun shadows over the streamed chunks ([`SunFeed`]).
//!
//! [`SunFeed`]: crate::SunFeed
//!
//! [`Mesher::mesh`]: voxel_mesh::Mesher::mesh
//! [`Renderer`]: crate::Renderer

pub(crate) mod config;
pub(crate) mod edits;
mod jobs;
mod light;
mod local;
mod pool;
pub(crate) mod schedule;
mod slot;
pub(crate) mod source;
pub(crate) mod sun_feed;

#[cfg(test)]
mod tests;

use std::collections::{BinaryHeap, HashMap, VecDeque};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};

use voxel_core::{BlockRegistry, Chunk, ChunkPos, World};

use crate::Result;

pub(crate) use config::StreamConfig;
pub(crate) use source::{ChunkSink, ChunkSource};

use edits::ChunkEdits;
use jobs::Done;
use pool::Pool;
use schedule::{distance2, within};
use slot::{Ready, Slot};

/// Loads, meshes, uploads and unloads the chunks around an eye (see the module docs).
pub struct ChunkStreamer {
    config: StreamConfig,
    pool: Pool,
    source: Arc<dyn ChunkSource>,
    registry: Arc<BlockRegistry>,
    world: World,
    slots: HashMap<ChunkPos, Slot>,
    /// Offsets within the view distance, nearest first.
    offsets: Vec<[i32; 3]>,
    centre: Option<ChunkPos>,
    /// Offsets before it are meshed or on their way.
    cursor: usize,
    /// Chunks to drop from the sink or from memory, each once ([`Slot::unload_queued`]).
    unload: VecDeque<ChunkPos>,
    /// Edited chunks to mesh again, each once ([`Slot::remesh_queued`]).
    remesh: VecDeque<ChunkPos>,
    ready: BinaryHeap<Ready>,
    /// Every edit made, per chunk: applied when the chunk is generated again.
    edits: HashMap<ChunkPos, ChunkEdits>,
    /// The source's blocks of the last chunk not loaded that an edit read (without its
    /// edits): many edits of one far chunk call the source once.
    last_source: Option<(ChunkPos, Arc<Chunk>)>,
    /// Set when the streamer is dropped: queued jobs return without working.
    cancelled: Arc<AtomicBool>,
    tx: Sender<Done>,
    rx: Receiver<Done>,
    jobs: usize,
    /// The next version number: versions are never reused, so that a job of a chunk that
    /// unloaded and loaded again cannot pass for the new one's (it may carry older edits).
    next_version: u64,
    /// Light, when on ([`ChunkStreamer::set_light`]).
    light: Option<light::StreamLight>,
}

impl std::fmt::Debug for ChunkStreamer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ChunkStreamer")
            .field("config", &self.config)
            .field("centre", &self.centre)
            .field("positions", &self.slots.len())
            .field("resident", &self.world.len())
            .field("jobs", &self.jobs)
            .field("unload", &self.unload.len())
            .field("remesh", &self.remesh.len())
            .field("ready", &self.ready.len())
            .field("light", &self.light.is_some())
            .field("cursor", &(self.cursor, self.offsets.len()))
            .finish_non_exhaustive()
    }
}

impl Drop for ChunkStreamer {
    fn drop(&mut self) {
        // The pool finishes what is queued before its threads exit: make that nothing
        // (a local queue is dropped with the streamer).
        self.cancelled.store(true, Ordering::Relaxed);
    }
}

impl ChunkStreamer {
    /// A streamer over `registry` loading from `source`; nothing loads before the first
    /// [`ChunkStreamer::update`]. Fails on a configuration outside its ranges. Its jobs run
    /// on a pool of [`StreamConfig::threads`] worker threads; on wasm32, which has none,
    /// on the updating thread as with [`ChunkStreamer::new_local`].
    pub fn new(
        registry: Arc<BlockRegistry>,
        source: impl ChunkSource,
        config: StreamConfig,
    ) -> Result<Self> {
        config.validate()?;
        source.check(&registry)?;
        let pool = Pool::new(config.threads)?;
        Ok(Self::with_pool(registry, source, config, pool))
    }

    /// A streamer whose generation and meshing jobs run on the thread that calls
    /// [`ChunkStreamer::update`], within [`StreamConfig::local_budget`] per update (at
    /// least one job, so that a job longer than the budget still moves on), and no thread
    /// is started: what a browser page gets (wasm32; [`ChunkStreamer::new`] makes this
    /// there), or a game that wants its frames to do the work. `threads` is not read.
    /// Fails as [`ChunkStreamer::new`] does.
    pub fn new_local(
        registry: Arc<BlockRegistry>,
        source: impl ChunkSource,
        config: StreamConfig,
    ) -> Result<Self> {
        config.validate()?;
        source.check(&registry)?;
        Ok(Self::with_pool(registry, source, config, Pool::local()))
    }

    fn with_pool(
        registry: Arc<BlockRegistry>,
        source: impl ChunkSource,
        config: StreamConfig,
        pool: Pool,
    ) -> Self {
        let (tx, rx) = channel();
        Self {
            pool,
            offsets: Self::offsets(&config),
            config,
            source: Arc::new(source),
            world: World::new(registry.clone()),
            registry,
            slots: HashMap::new(),
            centre: None,
            cursor: 0,
            unload: VecDeque::new(),
            remesh: VecDeque::new(),
            ready: BinaryHeap::new(),
            edits: HashMap::new(),
            last_source: None,
            cancelled: Arc::new(AtomicBool::new(false)),
            tx,
            rx,
            jobs: 0,
            next_version: 0,
            light: None,
        }
    }

    fn offsets(config: &StreamConfig) -> Vec<[i32; 3]> {
        let (r, v) = (config.view_distance as i32, config.vertical_distance as i32);
        let mut out = Vec::new();
        for dx in -r..=r {
            for dz in -r..=r {
                for dy in -v..=v {
                    let d = [dx, dy, dz].map(i64::from);
                    if within(d, config.view_distance, config.vertical_distance) {
                        out.push([dx, dy, dz]);
                    }
                }
            }
        }
        out.sort_by_key(|o| (distance2(o.map(i64::from)), *o));
        out
    }

    /// The configuration.
    pub fn config(&self) -> &StreamConfig {
        &self.config
    }

    /// Changes the configuration (a new view distance loads or unloads from the next
    /// update on). Fails, changing nothing, on a value outside its range.
    pub fn set_config(&mut self, config: StreamConfig) -> Result<()> {
        config.validate()?;
        let reach = (
            config.view_distance,
            config.vertical_distance,
            config.hysteresis,
        );
        let old = (
            self.config.view_distance,
            self.config.vertical_distance,
            self.config.hysteresis,
        );
        self.config = config;
        if reach != old {
            self.offsets = Self::offsets(&config);
            self.cursor = 0;
            self.queue_unloads();
        }
        Ok(())
    }

    /// Changes only the view distance (see [`ChunkStreamer::set_config`]).
    pub fn set_view_distance(&mut self, view_distance: u32) -> Result<()> {
        self.set_config(StreamConfig {
            view_distance,
            ..self.config
        })
    }

    /// The resident blocks (the loaded chunks; air elsewhere, as far as this world knows).
    pub fn world(&self) -> &World {
        &self.world
    }

    /// Whether the blocks of `pos` are resident (in [`ChunkStreamer::world`], or air
    /// there, or air standing in for a failed source): what a mesh may be made from.
    pub fn is_resident(&self, pos: ChunkPos) -> bool {
        self.slots.get(&pos).is_some_and(Slot::has_blocks)
    }

    /// Bytes of the chunks held (heap and inline) plus the edits kept
    /// ([`EDIT_BYTES`] per edited block, [`EDITED_CHUNK_BYTES`] per edited chunk). Besides
    /// these the streamer keeps the source's blocks of the last chunk not loaded that an
    /// edit read (one chunk).
    pub fn memory_bytes(&self) -> usize {
        self.world.chunk_memory_bytes() + self.edit_bytes()
    }

    /// Positions whose meshes are in the sink.
    pub fn uploaded(&self) -> impl Iterator<Item = ChunkPos> + '_ {
        self.slots
            .iter()
            .filter(|(_, s)| s.uploaded)
            .map(|(p, _)| *p)
    }

    /// Positions known (loaded, or on their way).
    pub fn positions(&self) -> usize {
        self.slots.len()
    }

    #[cfg(test)]
    /// Chunks in the unload queue (each at most once: never more than
    /// [`ChunkStreamer::positions`]).
    pub(crate) fn queued_unloads(&self) -> usize {
        self.unload.len()
    }

    /// Jobs in flight.
    pub fn jobs(&self) -> usize {
        self.jobs
    }

    /// Whether everything within the view distance is meshed and uploaded, every edit
    /// remeshed, and nothing is left to unload (see the module docs).
    pub fn is_idle(&self) -> bool {
        self.centre.is_some()
            && self.jobs == 0
            && self.ready.is_empty()
            && self.unload.is_empty()
            && self.remesh.is_empty()
            && self.cursor >= self.offsets.len()
            && self.light.as_ref().is_none_or(light::StreamLight::is_idle)
    }

    /// The positions whose blocks are resident ([`ChunkStreamer::is_resident`]).
    pub fn resident(&self) -> impl Iterator<Item = ChunkPos> + '_ {
        self.slots
            .iter()
            .filter(|(_, s)| s.has_blocks())
            .map(|(p, _)| *p)
    }
}
