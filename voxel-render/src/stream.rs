//! Chunk streaming: the chunks around a moving eye generated, meshed and uploaded on
//! rayon's workers, nearest first, without a frame ever waiting for one.
//!
//! A [`ChunkStreamer`] owns the resident [`World`]. Each [`ChunkStreamer::update`] (once
//! a frame, with the eye) does a bounded amount of work on the calling thread and hands
//! the rest to its own pool ([`StreamConfig::threads`]: one thread fewer than the cores).
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

use std::collections::{BTreeMap, BinaryHeap, HashMap, VecDeque};
use std::panic::AssertUnwindSafe;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};

use glam::DVec3;
use voxel_core::{
    BlockId, BlockRegistry, CHUNK_SIZE, Chunk, ChunkPos, Neighbourhood, TerrainGenerator, World,
    WorldPos,
};
use voxel_mesh::{ChunkMeshes, Mesher};

use crate::{Error, Renderer, Result};

/// The largest view distance (and vertical distance) in chunks: 64 chunks is 2048 blocks
/// each way, about 116 000 positions with the default vertical distance.
pub const MAX_VIEW_DISTANCE: u32 = 64;

/// Where chunks come from. Called on rayon's workers, any number at once.
pub trait ChunkSource: Send + Sync + 'static {
    /// The blocks of the chunk at `pos` (a valid position). Every id must be in the
    /// registry the streamer was made with. A chunk whose generation panics or holds an
    /// unknown id is reported by the update ([`StreamFrame::failed`]) or by
    /// [`ChunkStreamer::set_block`] ([`Error::ChunkSource`]), and counts as air.
    fn generate(&self, pos: ChunkPos) -> Chunk;

    /// Whether its blocks are the registry's: checked by [`ChunkStreamer::new`] (default:
    /// nothing to check; a wrong id is then found per chunk).
    fn check(&self, _registry: &BlockRegistry) -> Result<()> {
        Ok(())
    }
}

impl ChunkSource for TerrainGenerator {
    fn generate(&self, pos: ChunkPos) -> Chunk {
        self.generate_chunk(pos)
    }

    /// A generator made for another registry (its roles' ids name other blocks here) is
    /// refused, naming each role ([`TerrainGenerator::check`]).
    fn check(&self, registry: &BlockRegistry) -> Result<()> {
        Ok(TerrainGenerator::check(self, registry)?)
    }
}

/// A fixed world as a source: its chunks, air elsewhere (a loaded scene, tests).
impl ChunkSource for World {
    fn generate(&self, pos: ChunkPos) -> Chunk {
        self.chunk(pos).cloned().unwrap_or_default()
    }
}

/// Where meshes go: the renderer, or the renderer and a second one beside it.
pub trait ChunkSink {
    /// Uploads (or replaces) the meshes of the chunk at `pos`.
    fn upload(&mut self, pos: ChunkPos, meshes: &ChunkMeshes) -> Result<()>;
    /// Drops the chunk at `pos`.
    fn remove(&mut self, pos: ChunkPos);
}

impl ChunkSink for Renderer {
    fn upload(&mut self, pos: ChunkPos, meshes: &ChunkMeshes) -> Result<()> {
        self.upload_chunk(pos, meshes)
    }

    fn remove(&mut self, pos: ChunkPos) {
        self.remove_chunk(pos);
    }
}

/// How far and how fast the streamer works.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamConfig {
    /// Chunks loaded each way horizontally (a circle of this radius around the eye's
    /// chunk), 1 to [`MAX_VIEW_DISTANCE`].
    pub view_distance: u32,
    /// Chunks loaded above and below the eye's chunk, 0 to [`MAX_VIEW_DISTANCE`].
    pub vertical_distance: u32,
    /// Extra chunks past the distances before a chunk unloads, 1 to [`MAX_VIEW_DISTANCE`]
    /// (at least 2 are kept either way: the rings just outside the view distance hold the
    /// neighbours the outermost meshes need, their diagonal ones up to √2 chunks out).
    pub hysteresis: u32,
    /// Bytes of quads uploaded per update at most (at least one mesh goes).
    pub upload_budget_bytes: u64,
    /// Worker threads of the streamer's own pool, 0 to 256; 0 picks one fewer than the
    /// cores (at least 1), leaving a core to the thread that records frames. Read when
    /// the streamer is made.
    pub threads: usize,
    /// Generation and meshing jobs in flight at most (at least 1).
    pub max_jobs: usize,
    /// Chunks dropped from the sink or from memory per update at most (at least 1).
    pub max_unloads: usize,
    /// Positions looked at per update at most (at least 1).
    pub scan_budget: usize,
}

impl Default for StreamConfig {
    fn default() -> Self {
        Self {
            view_distance: 8,
            vertical_distance: 4,
            hysteresis: 2,
            upload_budget_bytes: 1 << 20,
            threads: 0,
            max_jobs: 64,
            max_unloads: 256,
            scan_budget: 2048,
        }
    }
}

impl StreamConfig {
    /// Checks every field against its documented range.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidSetting(m));
        if !(1..=MAX_VIEW_DISTANCE).contains(&self.view_distance) {
            return bad(format!(
                "view distance {} chunks: it must be from 1 to {MAX_VIEW_DISTANCE}",
                self.view_distance
            ));
        }
        if self.vertical_distance > MAX_VIEW_DISTANCE {
            return bad(format!(
                "vertical distance {} chunks: it must be from 0 to {MAX_VIEW_DISTANCE}",
                self.vertical_distance
            ));
        }
        if !(1..=MAX_VIEW_DISTANCE).contains(&self.hysteresis) {
            return bad(format!(
                "hysteresis {} chunks: it must be from 1 to {MAX_VIEW_DISTANCE}",
                self.hysteresis
            ));
        }
        if self.threads > 256 {
            return bad(format!("{} threads: at most 256", self.threads));
        }
        if self.max_jobs == 0 || self.max_unloads == 0 || self.scan_budget == 0 {
            return bad("max_jobs, max_unloads and scan_budget must be at least 1".into());
        }
        Ok(())
    }
}

/// What one update did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StreamFrame {
    /// Meshes uploaded (or dropped, when a chunk's meshes became empty).
    pub uploads: usize,
    /// Bytes of quads uploaded.
    pub upload_bytes: u64,
    /// Chunks dropped from the sink or from memory.
    pub unloads: usize,
    /// Chunks whose generation finished.
    pub generated: usize,
    /// Chunks whose meshing finished.
    pub meshed: usize,
    /// Jobs in flight after the update.
    pub jobs: usize,
    /// Chunks whose blocks or meshes could not be made (the source panicked or made an
    /// unknown block id: the chunk counts as air) or uploaded, with why. Each failure is
    /// reported once, by the update that learns of it.
    pub failed: Vec<(ChunkPos, String)>,
    /// The positions uploaded (or dropped from the sink, their meshes empty) in this
    /// update, in order: what a game mirrors (its own per-chunk data, a minimap).
    pub uploaded: Vec<ChunkPos>,
}

/// Bytes counted per edited block ([`ChunkStreamer::memory_bytes`]), an upper bound: a
/// 4-byte entry (index, block id) in a B-tree leaf of 11 entries that is at least half
/// full (56 bytes for 5 entries), plus its share of the inner nodes. Measured by a
/// counting allocator (`tests/tests/stream_memory.rs`): 10.6 bytes per edit when whole
/// chunks are edited.
pub const EDIT_BYTES: usize = 20;
/// Bytes counted per edited chunk, an upper bound: its hash table slot (25 bytes at a load
/// of 7/16 to 7/8), the shared map (40) and its first leaf (56). Measured: 138 bytes per
/// chunk with one edit, over 10 000 chunks.
pub const EDITED_CHUNK_BYTES: usize = 160;

/// How far along a position is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// Its generation job is in flight.
    Generating,
    /// Its blocks are in the world (or it is air); not meshed, or edited since.
    Generated,
    /// Its meshing job is in flight.
    Meshing,
    /// Its meshes wait for their upload.
    Ready,
    /// Its meshes are in the sink (or it has none).
    Meshed,
}

#[derive(Clone, Copy, Debug)]
struct Slot {
    state: State,
    /// A new number (never reused, see [`ChunkStreamer::next_version`]) when a job's
    /// result must be ignored (edited, regenerated, unloaded).
    version: u64,
    /// Whether the sink holds meshes of it.
    uploaded: bool,
    /// The source failed for it: air stands in (reported when it happened).
    failed: bool,
    /// Whether it is in the unload queue.
    unload_queued: bool,
    /// Whether it is in the remesh queue.
    remesh_queued: bool,
}

impl Slot {
    fn new(state: State, version: u64) -> Self {
        Self {
            state,
            version,
            uploaded: false,
            failed: false,
            unload_queued: false,
            remesh_queued: false,
        }
    }

    /// Whether the job of `version` that leaves the slot in `state` is still the one it
    /// waits for (a stale job counts for nothing).
    fn awaits(&self, version: u64, state: State) -> bool {
        self.version == version && self.state == state
    }

    fn has_blocks(&self) -> bool {
        self.state != State::Generating
    }

    /// Whether its meshes are in the sink or on their way there: its neighbours must
    /// stay resident.
    fn needs_neighbours(&self) -> bool {
        self.uploaded || matches!(self.state, State::Meshing | State::Ready)
    }
}

/// The edits of one chunk: in-chunk index ([`local_index`]) → block.
type ChunkEdits = Arc<BTreeMap<u16, BlockId>>;

/// The index of a block within its chunk (x fastest), as the edit lists key it.
fn local_index([x, y, z]: [usize; 3]) -> u16 {
    (x + CHUNK_SIZE * (y + CHUNK_SIZE * z)) as u16
}

fn local_of(index: u16) -> [usize; 3] {
    let i = usize::from(index);
    [
        i % CHUNK_SIZE,
        (i / CHUNK_SIZE) % CHUNK_SIZE,
        i / (CHUNK_SIZE * CHUNK_SIZE),
    ]
}

enum Done {
    Generated {
        pos: ChunkPos,
        version: u64,
        chunk: Chunk,
    },
    Meshed {
        pos: ChunkPos,
        version: u64,
        meshes: std::result::Result<ChunkMeshes, String>,
        /// The centre it meshed, and the same blocks packed (when it was not).
        packed: Option<(Arc<Chunk>, Chunk)>,
    },
    Failed {
        pos: ChunkPos,
        version: u64,
        why: String,
    },
}

/// A finished mesh waiting for its upload, nearest first.
struct Ready {
    distance: i64,
    pos: ChunkPos,
    version: u64,
    meshes: ChunkMeshes,
}

impl PartialEq for Ready {
    fn eq(&self, other: &Self) -> bool {
        (self.distance, self.pos) == (other.distance, other.pos)
    }
}
impl Eq for Ready {}
impl PartialOrd for Ready {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Ready {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        // BinaryHeap pops the largest: the nearest must compare largest.
        (other.distance, other.pos).cmp(&(self.distance, self.pos))
    }
}

/// Loads, meshes, uploads and unloads the chunks around an eye (see the module docs).
pub struct ChunkStreamer {
    config: StreamConfig,
    pool: rayon::ThreadPool,
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
            .field("cursor", &(self.cursor, self.offsets.len()))
            .finish_non_exhaustive()
    }
}

impl Drop for ChunkStreamer {
    fn drop(&mut self) {
        // The pool finishes what is queued before its threads exit: make that nothing.
        self.cancelled.store(true, Ordering::Relaxed);
    }
}

/// Squared horizontal and vertical distance of an offset, for ordering and ranges.
fn within(d: [i64; 3], radius: u32, vertical: u32) -> bool {
    let r = i64::from(radius);
    d[0] * d[0] + d[2] * d[2] <= r * r && d[1].abs() <= i64::from(vertical)
}

fn distance2(d: [i64; 3]) -> i64 {
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

fn offset(pos: ChunkPos, centre: ChunkPos) -> [i64; 3] {
    [
        i64::from(pos.x) - i64::from(centre.x),
        i64::from(pos.y) - i64::from(centre.y),
        i64::from(pos.z) - i64::from(centre.z),
    ]
}

thread_local! {
    /// Each worker's mesher (its scratch reused), for the registry it was made for.
    static MESHER: std::cell::RefCell<Option<(usize, Mesher)>> = const { std::cell::RefCell::new(None) };
}

fn mesh_on_worker(
    registry: &Arc<BlockRegistry>,
    centre: &Chunk,
    neighbours: &[Option<Arc<Chunk>>; 26],
) -> std::result::Result<ChunkMeshes, String> {
    let key = Arc::as_ptr(registry) as usize;
    MESHER.with_borrow_mut(|m| {
        let mesher = match m {
            Some((k, mesher)) if *k == key => mesher,
            _ => &mut m.insert((key, Mesher::new(registry))).1,
        };
        let nb = Neighbourhood::from_fn(|d| {
            let i = Neighbourhood::OFFSETS.iter().position(|&o| o == d)?;
            neighbours[i].as_deref()
        });
        mesher.mesh(centre, nb).map_err(|e| e.to_string())
    })
}

/// Calls the source for `pos`, catching a panic, and checks its block ids: the chunk, or
/// why it failed. Then applies `edits` (ids the registry holds: checked when made).
fn generate_checked(
    source: &dyn ChunkSource,
    registry: &BlockRegistry,
    pos: ChunkPos,
    edits: Option<&BTreeMap<u16, BlockId>>,
) -> std::result::Result<Chunk, String> {
    let mut chunk = std::panic::catch_unwind(AssertUnwindSafe(|| source.generate(pos)))
        .map_err(|_| "the chunk source panicked".to_owned())?;
    if let Some(id) = chunk
        .palette()
        .map(|(id, _)| id)
        .find(|id| !registry.contains(*id))
    {
        return Err(format!(
            "the chunk source made block id {}, unknown to the registry of {} blocks",
            id.0,
            registry.len()
        ));
    }
    for (&index, &id) in edits.into_iter().flatten() {
        let [x, y, z] = local_of(index);
        chunk.set(x, y, z, id).map_err(|e| e.to_string())?;
    }
    Ok(chunk)
}

impl ChunkStreamer {
    /// A streamer over `registry` loading from `source`; nothing loads before the first
    /// [`ChunkStreamer::update`]. Fails on a configuration outside its ranges.
    pub fn new(
        registry: Arc<BlockRegistry>,
        source: impl ChunkSource,
        config: StreamConfig,
    ) -> Result<Self> {
        config.validate()?;
        source.check(&registry)?;
        let threads = match config.threads {
            0 => {
                std::thread::available_parallelism().map_or(1, |n| n.get().saturating_sub(1).max(1))
            }
            n => n,
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("chunk-streamer-{i}"))
            .build()
            .map_err(|e| Error::InvalidSetting(format!("the streamer's {threads} threads: {e}")))?;
        let (tx, rx) = channel();
        Ok(Self {
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
        })
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

    /// Bytes counted for the edits kept (see [`ChunkStreamer::memory_bytes`]).
    pub fn edit_bytes(&self) -> usize {
        self.edits
            .values()
            .map(|e| EDITED_CHUNK_BYTES + EDIT_BYTES * e.len())
            .sum()
    }

    /// Every edit kept, per chunk: `(position in the world, block)` for each block set
    /// through [`ChunkStreamer::set_block`] (the last value set), for a game to save.
    pub fn edits(&self) -> impl Iterator<Item = (WorldPos, BlockId)> + '_ {
        self.edits.iter().flat_map(|(pos, e)| {
            let o = pos.origin();
            e.iter().map(move |(&i, &id)| {
                let [x, y, z] = local_of(i);
                let at = |k: usize, v: usize| (o[k] + v as i64) as i32;
                (WorldPos::new(at(0, x), at(1, y), at(2, z)), id)
            })
        })
    }

    /// Restores saved edits ([`ChunkStreamer::edits`] of an earlier run, in any order):
    /// each chunk not loaded keeps them to apply when it loads (no chunk is generated
    /// here, unlike [`ChunkStreamer::set_block`]); a loaded one is edited now. Fails on
    /// the first block id the registry does not hold, having restored none of them.
    pub fn restore_edits(
        &mut self,
        edits: impl IntoIterator<Item = (WorldPos, BlockId)>,
    ) -> Result<()> {
        let edits: Vec<(WorldPos, BlockId)> = edits.into_iter().collect();
        if let Some(&(_, id)) = edits.iter().find(|(_, id)| !self.registry.contains(*id)) {
            return Err(voxel_core::Error::UnknownBlock(id, self.registry.len()).into());
        }
        for (pos, id) in edits {
            if self.slots.contains_key(&pos.split().0) {
                self.set_block(pos, id)?;
            } else {
                self.record_edit(pos, id);
            }
        }
        Ok(())
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

    /// Chunks in the unload queue (each at most once: never more than
    /// [`ChunkStreamer::positions`]).
    pub fn queued_unloads(&self) -> usize {
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
    }

    /// The eye's chunk, clamped into the `i32` world; an error for a non-finite eye.
    fn centre_of(eye: DVec3) -> Result<ChunkPos> {
        if !eye.is_finite() {
            return Err(Error::InvalidSetting(format!(
                "streaming eye {eye:?} is not finite"
            )));
        }
        let c = (eye / CHUNK_SIZE as f64).floor().clamp(
            DVec3::splat(f64::from(ChunkPos::MIN)),
            DVec3::splat(f64::from(ChunkPos::MAX)),
        );
        Ok(ChunkPos::new(c.x as i32, c.y as i32, c.z as i32))
    }

    fn keeps(&self, pos: ChunkPos, centre: ChunkPos) -> bool {
        // At least 2 horizontally: the diagonal neighbours of the outermost chunks (which
        // their ambient occlusion reads) lie up to √2 chunks farther out.
        let h = self.config.hysteresis.max(2);
        within(
            offset(pos, centre),
            self.config.view_distance + h,
            self.config.vertical_distance + h,
        )
    }

    fn wanted(&self, pos: ChunkPos, centre: ChunkPos) -> bool {
        within(
            offset(pos, centre),
            self.config.view_distance,
            self.config.vertical_distance,
        )
    }

    /// A version number never handed out before.
    fn next_version(&mut self) -> u64 {
        self.next_version += 1;
        self.next_version
    }

    /// Queues `pos` for unloading unless it is queued already.
    fn queue_unload(&mut self, pos: ChunkPos) {
        if let Some(slot) = self.slots.get_mut(&pos)
            && !slot.unload_queued
        {
            slot.unload_queued = true;
            self.unload.push_back(pos);
        }
    }

    /// Queues every position past the margin (each once).
    fn queue_unloads(&mut self) {
        let Some(centre) = self.centre else { return };
        let far: Vec<ChunkPos> = self
            .slots
            .iter()
            .filter(|(p, s)| !s.unload_queued && !self.keeps(**p, centre))
            .map(|(p, _)| *p)
            .collect();
        for pos in far {
            self.queue_unload(pos);
        }
    }

    /// Queues `pos` for meshing again unless it is queued already.
    fn queue_remesh(&mut self, pos: ChunkPos) {
        if let Some(slot) = self.slots.get_mut(&pos)
            && !slot.remesh_queued
        {
            slot.remesh_queued = true;
            self.remesh.push_back(pos);
        }
    }

    /// One frame's streaming for `eye`: takes what the workers finished, unloads, starts
    /// new jobs nearest first, and uploads finished meshes to `sink` within the budget.
    /// Never waits for a job. Fails only on a non-finite eye (nothing done).
    pub fn update(&mut self, eye: DVec3, sink: &mut impl ChunkSink) -> Result<StreamFrame> {
        let centre = Self::centre_of(eye)?;
        let mut frame = StreamFrame::default();
        if self.centre != Some(centre) {
            self.centre = Some(centre);
            self.cursor = 0;
            self.queue_unloads();
        }
        self.receive(centre, &mut frame);
        self.unload_some(centre, sink, &mut frame);
        self.dispatch(centre);
        self.upload_some(sink, &mut frame);
        frame.jobs = self.jobs;
        Ok(frame)
    }

    fn receive(&mut self, centre: ChunkPos, frame: &mut StreamFrame) {
        while let Ok(done) = self.rx.try_recv() {
            self.jobs -= 1;
            match done {
                Done::Generated {
                    pos,
                    version,
                    chunk,
                } => {
                    let Some(slot) = self
                        .slots
                        .get_mut(&pos)
                        .filter(|s| s.awaits(version, State::Generating))
                    else {
                        continue;
                    };
                    slot.state = State::Generated;
                    frame.generated += 1;
                    if chunk.as_uniform() != Some(BlockId::AIR) {
                        // The source's ids were checked by the job.
                        let _ = self.world.insert_chunk(pos, chunk);
                    }
                }
                Done::Meshed {
                    pos,
                    version,
                    meshes,
                    packed,
                } => {
                    let Some(slot) = self
                        .slots
                        .get_mut(&pos)
                        .filter(|s| s.awaits(version, State::Meshing))
                    else {
                        continue;
                    };
                    frame.meshed += 1;
                    if let Some((sent, chunk)) = packed {
                        self.world.replace_shared(pos, &sent, chunk);
                    }
                    match meshes {
                        Ok(meshes) => {
                            slot.state = State::Ready;
                            self.ready.push(Ready {
                                distance: distance2(offset(pos, centre)),
                                pos,
                                version,
                                meshes,
                            });
                        }
                        Err(why) => {
                            slot.state = State::Meshed;
                            frame.failed.push((pos, why));
                        }
                    }
                }
                Done::Failed { pos, version, why } => {
                    if let Some(slot) = self.slots.get_mut(&pos)
                        && slot.awaits(version, State::Generating)
                    {
                        // Not retried while loaded: the source failed for this position.
                        // Air stands in, so that its neighbours still mesh.
                        slot.state = State::Meshed;
                        slot.failed = true;
                        frame.failed.push((pos, why));
                    }
                }
            }
        }
        // Blocks inserted or packed: not edits.
        self.world.take_dirty();
    }

    /// Whether the chunk at `pos` may leave memory: none of its neighbours is drawn, on
    /// its way to the sink, or wanted (about to be meshed from it).
    fn may_leave(&self, pos: ChunkPos, centre: ChunkPos) -> bool {
        Neighbourhood::OFFSETS.iter().all(|&d| {
            pos.offset(d).is_none_or(|n| {
                !self.wanted(n, centre) && !self.slots.get(&n).is_some_and(Slot::needs_neighbours)
            })
        })
    }

    fn unload_some(
        &mut self,
        centre: ChunkPos,
        sink: &mut impl ChunkSink,
        frame: &mut StreamFrame,
    ) {
        while frame.unloads < self.config.max_unloads {
            let Some(pos) = self.unload.pop_front() else {
                break;
            };
            let Some(slot) = self.slots.get_mut(&pos) else {
                continue;
            };
            slot.unload_queued = false;
            if self.keeps(pos, centre) {
                continue;
            }
            let slot = self.slots.get_mut(&pos).map(|s| *s);
            let Some(mut slot) = slot else { continue };
            let mut worked = false;
            if slot.needs_neighbours() {
                // Out of the sink first; a mesh on its way comes back to nothing.
                if slot.uploaded {
                    sink.remove(pos);
                    slot.uploaded = false;
                }
                // Whatever it had (a mesh drawn, in flight or waiting), it has none now:
                // if it stays resident (a neighbour needs its blocks) and is wanted again,
                // it must be meshed and uploaded again, not taken as done.
                slot.version = self.next_version();
                slot.state = State::Generated;
                self.slots.insert(pos, slot);
                worked = true;
                // Its neighbours past the margin may leave memory now.
                for d in Neighbourhood::OFFSETS {
                    if let Some(n) = pos.offset(d)
                        && !self.keeps(n, centre)
                    {
                        self.queue_unload(n);
                    }
                }
            }
            if self.may_leave(pos, centre) {
                self.slots.remove(&pos);
                // Its edits stay in `edits`: it comes back as the source plus them.
                self.world.remove_chunk(pos);
                worked = true;
                // A neighbour meshed to nothing from its blocks (none of them needs
                // neighbours, see `may_leave`) is not done any more: the blocks it was
                // meshed against may come back different (a source that changes).
                for d in Neighbourhood::OFFSETS {
                    if let Some(n) = pos.offset(d) {
                        let version = self.next_version();
                        if let Some(s) = self.slots.get_mut(&n)
                            && s.state == State::Meshed
                            && !s.failed
                        {
                            s.version = version;
                            s.state = State::Generated;
                        }
                    }
                }
            }
            // A chunk still needed stays resident, out of the queue: the neighbour that
            // needs it queues it again when it leaves the sink.
            frame.unloads += usize::from(worked);
        }
        self.world.take_dirty();
    }

    fn generate(&mut self, pos: ChunkPos, centre: ChunkPos) {
        let version = self.next_version();
        self.slots
            .insert(pos, Slot::new(State::Generating, version));
        // A chunk outside the view distance is only a neighbour: packed at once.
        let pack = !self.wanted(pos, centre);
        let source = self.source.clone();
        let registry = self.registry.clone();
        let edits = self.edits.get(&pos).cloned();
        let tx = self.tx.clone();
        let cancelled = self.cancelled.clone();
        self.jobs += 1;
        self.pool.spawn(move || {
            if cancelled.load(Ordering::Relaxed) {
                return;
            }
            let done = match generate_checked(&*source, &registry, pos, edits.as_deref()) {
                Ok(mut chunk) => {
                    if pack {
                        chunk.pack();
                    }
                    Done::Generated {
                        pos,
                        version,
                        chunk,
                    }
                }
                Err(why) => Done::Failed { pos, version, why },
            };
            let _ = tx.send(done);
        });
    }

    /// Whether the chunk at `pos` and its 26 neighbours have their blocks (faces are culled
    /// against the face neighbours; ambient occlusion reads the edge and corner ones).
    fn meshable(&self, pos: ChunkPos) -> bool {
        self.slots
            .get(&pos)
            .is_some_and(|s| s.state == State::Generated)
            && Neighbourhood::OFFSETS.iter().all(|&d| {
                pos.offset(d)
                    .is_none_or(|n| self.slots.get(&n).is_some_and(Slot::has_blocks))
            })
    }

    fn mesh(&mut self, pos: ChunkPos) {
        let Some(slot) = self.slots.get_mut(&pos) else {
            return;
        };
        let Some(centre) = self.world.shared(pos) else {
            // Air: no faces, nothing to upload (a chunk that held some is dropped).
            slot.state = State::Ready;
            let version = slot.version;
            self.ready.push(Ready {
                distance: 0,
                pos,
                version,
                meshes: ChunkMeshes::default(),
            });
            return;
        };
        slot.state = State::Meshing;
        let version = slot.version;
        let neighbours =
            Neighbourhood::OFFSETS.map(|d| pos.offset(d).and_then(|n| self.world.shared(n)));
        let registry = self.registry.clone();
        let tx = self.tx.clone();
        let cancelled = self.cancelled.clone();
        self.jobs += 1;
        self.pool.spawn(move || {
            if cancelled.load(Ordering::Relaxed) {
                return;
            }
            let done = std::panic::catch_unwind(AssertUnwindSafe(|| {
                let meshes = mesh_on_worker(&registry, &centre, &neighbours);
                let packed = (!centre.is_packed()).then(|| {
                    let mut c = (*centre).clone();
                    c.pack();
                    (centre, c)
                });
                Done::Meshed {
                    pos,
                    version,
                    meshes,
                    packed,
                }
            }))
            .unwrap_or_else(|_| Done::Failed {
                pos,
                version,
                why: "meshing panicked".into(),
            });
            let _ = tx.send(done);
        });
    }

    fn dispatch(&mut self, centre: ChunkPos) {
        // Edited chunks first. One that waits for neighbours asks for them itself, like a
        // wanted one; one past the margin is left to its unload.
        let mut waiting = VecDeque::new();
        while self.jobs < self.config.max_jobs
            && let Some(pos) = self.remesh.pop_front()
        {
            let Some(slot) = self.slots.get_mut(&pos) else {
                continue;
            };
            slot.remesh_queued = false;
            if slot.state != State::Generated {
                continue;
            }
            if !self.keeps(pos, centre) {
                self.queue_unload(pos);
                continue;
            }
            if !self.advance(pos, centre) {
                waiting.push_back(pos);
            }
        }
        for pos in waiting {
            self.queue_remesh(pos);
        }

        let mut scanned = 0;
        let mut i = self.cursor;
        let mut all_done = true;
        while i < self.offsets.len()
            && scanned < self.config.scan_budget
            && self.jobs < self.config.max_jobs
        {
            let o = self.offsets[i];
            i += 1;
            scanned += 1;
            let pos = ChunkPos::new(
                centre.x.saturating_add(o[0]),
                centre.y.saturating_add(o[1]),
                centre.z.saturating_add(o[2]),
            );
            let done = !pos.is_valid() || self.advance(pos, centre);
            if done && all_done {
                self.cursor = i;
            } else {
                all_done = false;
            }
        }
    }

    /// Moves `pos` one step on (generating it or its neighbours, or meshing it); returns
    /// whether it needs nothing more.
    fn advance(&mut self, pos: ChunkPos, centre: ChunkPos) -> bool {
        match self.slots.get(&pos).map(|s| s.state) {
            Some(State::Meshing | State::Ready | State::Meshed) => return true,
            Some(State::Generating) => {}
            None => {
                if self.jobs >= self.config.max_jobs {
                    return false;
                }
                self.generate(pos, centre);
            }
            Some(State::Generated) => {}
        }
        for d in Neighbourhood::OFFSETS {
            if let Some(n) = pos.offset(d)
                && !self.slots.contains_key(&n)
            {
                if self.jobs >= self.config.max_jobs {
                    return false;
                }
                self.generate(n, centre);
            }
        }
        if self.jobs < self.config.max_jobs && self.meshable(pos) {
            self.mesh(pos);
            return true;
        }
        false
    }

    fn upload_some(&mut self, sink: &mut impl ChunkSink, frame: &mut StreamFrame) {
        while let Some(next) = self.ready.peek() {
            let bytes = next.meshes.len() as u64 * crate::arena::QUAD_BYTES;
            if frame.uploads > 0 && frame.upload_bytes + bytes > self.config.upload_budget_bytes {
                break;
            }
            let Some(r) = self.ready.pop() else { break };
            let Some(slot) = self
                .slots
                .get_mut(&r.pos)
                .filter(|s| s.awaits(r.version, State::Ready))
            else {
                continue;
            };
            slot.state = State::Meshed;
            if r.meshes.is_empty() {
                if slot.uploaded {
                    sink.remove(r.pos);
                    slot.uploaded = false;
                    frame.uploads += 1;
                    frame.uploaded.push(r.pos);
                }
                continue;
            }
            match sink.upload(r.pos, &r.meshes) {
                Ok(()) => {
                    slot.uploaded = true;
                    frame.uploads += 1;
                    frame.upload_bytes += bytes;
                    frame.uploaded.push(r.pos);
                }
                Err(e) => {
                    // The sink kept what it had, if anything: take it out, so that it
                    // draws nothing stale.
                    if slot.uploaded {
                        sink.remove(r.pos);
                        slot.uploaded = false;
                    }
                    frame.failed.push((r.pos, e.to_string()));
                }
            }
        }
    }

    /// The blocks of the chunk at `pos` generated here, on the calling thread, with its
    /// edits: for an edit of a chunk whose generation is in flight.
    fn generate_here(&self, pos: ChunkPos) -> Result<Chunk> {
        generate_checked(
            &*self.source,
            &self.registry,
            pos,
            self.edits.get(&pos).map(|e| &**e),
        )
        .map_err(|why| Error::ChunkSource { pos, why })
    }

    /// The source's block at `local` of the chunk at `pos` (not loaded), its ids checked;
    /// the chunk is kept for the next edit of the same chunk.
    fn source_block(&mut self, pos: ChunkPos, [x, y, z]: [usize; 3]) -> Result<BlockId> {
        let chunk = match &self.last_source {
            Some((p, c)) if *p == pos => c.clone(),
            _ => {
                let c = generate_checked(&*self.source, &self.registry, pos, None)
                    .map_err(|why| Error::ChunkSource { pos, why })?;
                let c = Arc::new(c);
                self.last_source = Some((pos, c.clone()));
                c
            }
        };
        Ok(chunk.get(x, y, z)?)
    }

    /// Records an edit in the chunk's edit list.
    fn record_edit(&mut self, pos: WorldPos, id: BlockId) {
        let (c, local) = pos.split();
        Arc::make_mut(self.edits.entry(c).or_default()).insert(local_index(local), id);
    }

    /// Sets the block at `pos` and returns the old one. The chunks whose meshes it touches
    /// are meshed again before any new chunk. The edit is kept (see the module docs): a
    /// chunk not loaded is generated here to read the old block (one chunk's work on this
    /// thread), and comes back edited when it loads. Fails, changing nothing, on a block
    /// id the registry does not hold, and with [`Error::ChunkSource`] where the source
    /// fails for the chunk (it panicked or made unknown ids): the panic is caught here.
    pub fn set_block(&mut self, pos: WorldPos, id: BlockId) -> Result<BlockId> {
        if !self.registry.contains(id) {
            return Err(voxel_core::Error::UnknownBlock(id, self.registry.len()).into());
        }
        let (c, [x, y, z]) = pos.split();
        match self.slots.get(&c).map(|s| (s.state, s.failed)) {
            None => {
                // Not loaded: no drawn chunk's mesh depends on it (see `may_leave`).
                let old = match self
                    .edits
                    .get(&c)
                    .and_then(|e| e.get(&local_index([x, y, z])))
                {
                    Some(&old) => old,
                    None => self.source_block(c, [x, y, z])?,
                };
                self.record_edit(pos, id);
                return Ok(old);
            }
            Some((_, true)) => {
                return Err(Error::ChunkSource {
                    pos: c,
                    why: "the chunk source failed for it when it loaded (it stands as air)".into(),
                });
            }
            Some((State::Generating, false)) => {
                // Its job's result will not count: generate it here.
                let chunk = self.generate_here(c)?;
                let version = self.next_version();
                if let Some(slot) = self.slots.get_mut(&c) {
                    slot.version = version;
                    slot.state = State::Generated;
                }
                if chunk.as_uniform() != Some(BlockId::AIR) {
                    self.world.insert_chunk(c, chunk)?;
                }
            }
            Some(_) => {}
        }
        self.world.take_dirty();
        let old = self.world.set_block(pos, id)?;
        self.record_edit(pos, id);
        for d in self.world.take_dirty() {
            let version = self.next_version();
            if let Some(slot) = self.slots.get_mut(&d)
                && matches!(slot.state, State::Meshing | State::Ready | State::Meshed)
                && !slot.failed
            {
                slot.version = version;
                slot.state = State::Generated;
                self.queue_remesh(d);
            }
        }
        Ok(old)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;
    use voxel_core::blocks;

    /// Issue 23: a streamer over the default terrain with a game's registry whose ids name
    /// other blocks is refused at `new`, naming the roles; with the default registry it is
    /// made.
    #[test]
    fn a_generator_for_another_registry_is_refused_at_new() {
        let mut game = BlockRegistry::new();
        let _ = game.register(voxel_core::BlockDef::new(
            "amber_glass",
            [200, 140, 40],
            0.5,
        ));
        for (_, def) in BlockRegistry::default().iter().skip(1) {
            let _ = game.register(def.clone());
        }
        let generator = TerrainGenerator::new(voxel_core::TerrainConfig::default());
        let config = StreamConfig::default();
        let err = ChunkStreamer::new(Arc::new(game), generator.clone(), config)
            .unwrap_err()
            .to_string();
        assert!(err.contains("but this registry's"), "{err}");
        ChunkStreamer::new(Arc::new(BlockRegistry::default()), generator, config).unwrap();
    }

    /// A sink that records what it holds and checks the streamer's calls.
    #[derive(Default)]
    struct Recorder {
        held: HashMap<ChunkPos, usize>,
        order: Vec<ChunkPos>,
    }

    impl ChunkSink for Recorder {
        fn upload(&mut self, pos: ChunkPos, meshes: &ChunkMeshes) -> Result<()> {
            assert!(!meshes.is_empty(), "empty meshes uploaded at {pos:?}");
            self.held.insert(pos, meshes.len());
            self.order.push(pos);
            Ok(())
        }

        fn remove(&mut self, pos: ChunkPos) {
            assert!(
                self.held.remove(&pos).is_some(),
                "removed {pos:?}, never uploaded"
            );
        }
    }

    /// One glass block in every chunk at y = 0, stone in the chunks below: every chunk
    /// near the eye has something to draw.
    struct Pillars;

    impl ChunkSource for Pillars {
        fn generate(&self, pos: ChunkPos) -> Chunk {
            match pos.y {
                y if y < 0 => Chunk::uniform(blocks::STONE),
                0 => {
                    let mut c = Chunk::default();
                    let _ = c.set(5, 5, 5, blocks::GLASS);
                    c
                }
                _ => Chunk::default(),
            }
        }
    }

    fn registry() -> Arc<BlockRegistry> {
        Arc::new(BlockRegistry::default())
    }

    fn config(view_distance: u32) -> StreamConfig {
        StreamConfig {
            view_distance,
            vertical_distance: 1,
            ..StreamConfig::default()
        }
    }

    /// Updates until idle (at most `limit` updates), returning the frames.
    fn settle(
        s: &mut ChunkStreamer,
        eye: DVec3,
        sink: &mut Recorder,
        limit: usize,
    ) -> Vec<StreamFrame> {
        let mut frames = Vec::new();
        for _ in 0..limit {
            frames.push(s.update(eye, sink).unwrap());
            if s.is_idle() {
                return frames;
            }
            std::thread::sleep(std::time::Duration::from_micros(200));
        }
        panic!("not idle after {limit} updates: {s:?}");
    }

    fn expected(centre: ChunkPos, view_distance: u32) -> HashSet<ChunkPos> {
        let r = view_distance as i32;
        let mut out = HashSet::new();
        for dx in -r..=r {
            for dz in -r..=r {
                if dx * dx + dz * dz <= r * r {
                    // Only y = 0 draws: glass (stone below is hidden, the level below
                    // shows its top faces: stone under air at y = -1).
                    out.insert(ChunkPos::new(centre.x + dx, 0, centre.z + dz));
                    out.insert(ChunkPos::new(centre.x + dx, -1, centre.z + dz));
                }
            }
        }
        out.retain(|p| centre.y - 1 <= p.y && p.y <= centre.y + 1);
        out
    }

    #[test]
    fn loads_the_view_distance_nearest_first() {
        let eye = DVec3::new(16.0, 16.0, 16.0);
        // One job at a time: the order is exactly nearest first.
        let mut s = ChunkStreamer::new(
            registry(),
            Pillars,
            StreamConfig {
                max_jobs: 1,
                ..config(3)
            },
        )
        .unwrap();
        let mut sink = Recorder::default();
        settle(&mut s, eye, &mut sink, 10_000);
        let centre = ChunkPos::new(0, 0, 0);
        let keys: HashSet<ChunkPos> = sink.held.keys().copied().collect();
        assert_eq!(keys, expected(centre, 3));
        let d: Vec<i64> = sink
            .order
            .iter()
            .map(|p| distance2(offset(*p, centre)))
            .collect();
        assert!(
            d.windows(2).all(|w| w[0] <= w[1]),
            "not nearest first: {d:?}"
        );

        // Many jobs at once: the same chunks, uploaded once each.
        let mut s = ChunkStreamer::new(registry(), Pillars, config(3)).unwrap();
        let mut sink = Recorder::default();
        settle(&mut s, eye, &mut sink, 10_000);
        assert_eq!(sink.order.len(), sink.held.len(), "a chunk uploaded twice");
        assert_eq!(
            sink.held.keys().copied().collect::<HashSet<_>>(),
            expected(centre, 3)
        );
        // Meshed chunks are packed; uniform air is not stored.
        assert!(
            s.world()
                .iter()
                .all(|(p, c)| c.is_packed() || c.as_uniform().is_some() || !s.wanted(p, centre))
        );
        assert!(
            s.world()
                .iter()
                .all(|(_, c)| c.as_uniform() != Some(BlockId::AIR))
        );
    }

    #[test]
    fn unloads_past_the_distance_and_hysteresis() {
        let mut s = ChunkStreamer::new(registry(), Pillars, config(3)).unwrap();
        let mut sink = Recorder::default();
        settle(&mut s, DVec3::splat(16.0), &mut sink, 10_000);
        // Four chunks along +x.
        let eye = DVec3::new(16.0 + 4.0 * 32.0, 16.0, 16.0);
        settle(&mut s, eye, &mut sink, 10_000);
        let centre = ChunkPos::new(4, 0, 0);
        let keep = |p: &ChunkPos| within(offset(*p, centre), 3 + 2, 1 + 2);
        assert!(
            sink.held.keys().all(keep),
            "a chunk past the hysteresis is drawn"
        );
        // Past the margin only the ring that drawn chunks' meshes were made from stays.
        let drawn_neighbour = |p: ChunkPos| {
            Neighbourhood::OFFSETS
                .iter()
                .any(|&d| p.offset(d).is_some_and(|n| sink.held.contains_key(&n)))
        };
        assert!(
            s.world()
                .iter()
                .all(|(p, _)| keep(&p) || drawn_neighbour(p)),
            "a chunk past it stays loaded"
        );
        assert!(s.world().iter().any(|(p, _)| !keep(&p)), "the ring is kept");
        // Within the hysteresis, what was drawn stays drawn.
        assert!(
            sink.held.contains_key(&ChunkPos::new(0, 0, 0)),
            "dropped within the margin"
        );
        for p in expected(centre, 3) {
            assert!(sink.held.contains_key(&p), "{p:?} not drawn");
        }
    }

    #[test]
    fn uploads_stay_within_the_budget() {
        let mut s = ChunkStreamer::new(
            registry(),
            Pillars,
            StreamConfig {
                upload_budget_bytes: 100,
                ..config(4)
            },
        )
        .unwrap();
        let mut sink = Recorder::default();
        let frames = settle(&mut s, DVec3::splat(16.0), &mut sink, 20_000);
        let most = frames.iter().map(|f| f.upload_bytes).max().unwrap();
        // A glass block is 6 quads (48 bytes), a stone top 1 quad (8 bytes).
        assert!(most <= 100, "{most} bytes in one update");
        let total: usize = sink.held.values().map(|q| q * 8).sum();
        let busy = frames.iter().filter(|f| f.uploads > 0).count();
        assert!(busy >= total / 100, "{total} bytes in {busy} updates");
    }

    #[test]
    fn a_teleport_drops_and_reloads_within_the_unload_budget() {
        let mut s = ChunkStreamer::new(
            registry(),
            Pillars,
            StreamConfig {
                max_unloads: 10,
                ..config(4)
            },
        )
        .unwrap();
        let mut sink = Recorder::default();
        settle(&mut s, DVec3::splat(16.0), &mut sink, 10_000);
        let before = sink.held.len();
        let far = DVec3::new(16.0 + 10_000.0 * 32.0, 16.0, 16.0);
        let frames = settle(&mut s, far, &mut sink, 20_000);
        assert!(frames.iter().all(|f| f.unloads <= 10));
        assert!(frames.iter().map(|f| f.unloads).sum::<usize>() >= before);
        let centre = ChunkPos::new(10_000, 0, 0);
        assert_eq!(
            sink.held.keys().copied().collect::<HashSet<_>>(),
            expected(centre, 4)
        );
        // Back again, and to the edge of the world.
        settle(&mut s, DVec3::splat(16.0), &mut sink, 20_000);
        assert_eq!(
            sink.held.keys().copied().collect::<HashSet<_>>(),
            expected(ChunkPos::new(0, 0, 0), 4)
        );
        let edge = DVec3::new(f64::from(i32::MAX) - 10.0, 16.0, 16.0);
        settle(&mut s, edge, &mut sink, 20_000);
        assert!(sink.held.keys().all(|p| p.is_valid()));
    }

    #[test]
    fn edits_remesh_and_survive_unloading() {
        let mut s = ChunkStreamer::new(registry(), Pillars, config(2)).unwrap();
        let mut sink = Recorder::default();
        let eye = DVec3::splat(16.0);
        settle(&mut s, eye, &mut sink, 10_000);
        let at = ChunkPos::new(1, 0, 0);
        let quads = sink.held[&at];
        // A second glass block beside the first, not touching: 6 more quads.
        s.set_block(WorldPos::new(32 + 20, 5, 5), blocks::GLASS)
            .unwrap();
        settle(&mut s, eye, &mut sink, 10_000);
        assert_eq!(sink.held[&at], quads + 6);
        // A block on the border of two chunks remeshes both.
        let edge = s.set_block(WorldPos::new(31, 5, 5), blocks::STONE).unwrap();
        assert_eq!(edge, BlockId::AIR);
        settle(&mut s, eye, &mut sink, 10_000);
        assert_eq!(
            sink.held[&ChunkPos::new(0, 0, 0)],
            12,
            "glass and the new stone"
        );

        // Far away: generated, edited and kept; it comes back edited.
        let far = WorldPos::new(100 * 32 + 7, 7, 7);
        assert_eq!(s.set_block(far, blocks::GLASS).unwrap(), BlockId::AIR);
        assert_eq!(s.set_block(far, blocks::GLASS).unwrap(), blocks::GLASS);
        let there = DVec3::new(100.0 * 32.0 + 16.0, 16.0, 16.0);
        settle(&mut s, there, &mut sink, 20_000);
        assert_eq!(sink.held[&ChunkPos::new(100, 0, 0)], 12, "two glass blocks");
        // Away and back: the edit of chunk (1, 0, 0) is still there.
        settle(&mut s, eye, &mut sink, 20_000);
        assert_eq!(sink.held[&at], quads + 6);

        // Bad input.
        assert!(s.set_block(far, BlockId(60_000)).is_err());
        assert!(s.update(DVec3::NAN, &mut sink).is_err());
    }

    #[test]
    fn bad_configurations_are_errors() {
        for (vd, vv, h) in [
            (0, 1, 2),
            (MAX_VIEW_DISTANCE + 1, 1, 2),
            (4, MAX_VIEW_DISTANCE + 1, 2),
            (4, 1, 0),
        ] {
            let c = StreamConfig {
                view_distance: vd,
                vertical_distance: vv,
                hysteresis: h,
                ..StreamConfig::default()
            };
            assert!(ChunkStreamer::new(registry(), Pillars, c).is_err(), "{c:?}");
        }
        let mut s = ChunkStreamer::new(registry(), Pillars, config(2)).unwrap();
        assert!(s.set_view_distance(0).is_err());
        assert_eq!(s.config().view_distance, 2, "unchanged after an error");
        assert!(s.set_view_distance(MAX_VIEW_DISTANCE).is_ok());
    }

    /// A source that panics on one chunk and makes an unknown id in another.
    struct Broken;

    impl ChunkSource for Broken {
        fn generate(&self, pos: ChunkPos) -> Chunk {
            match (pos.x, pos.y, pos.z) {
                (1, 0, 0) => panic!("broken source"),
                (-1, 0, 0) => Chunk::uniform(BlockId(60_000)),
                _ => Pillars.generate(pos),
            }
        }
    }

    #[test]
    fn a_broken_source_is_reported_and_never_hangs() {
        let mut s = ChunkStreamer::new(registry(), Broken, config(2)).unwrap();
        let mut sink = Recorder::default();
        let frames = settle(&mut s, DVec3::splat(16.0), &mut sink, 10_000);
        let failed: Vec<ChunkPos> = frames
            .iter()
            .flat_map(|f| f.failed.iter().map(|x| x.0))
            .collect();
        assert!(failed.contains(&ChunkPos::new(1, 0, 0)));
        assert!(failed.contains(&ChunkPos::new(-1, 0, 0)));
        assert!(
            sink.held.contains_key(&ChunkPos::new(0, 0, 0)),
            "its neighbours still draw"
        );
    }

    // ---- The contract, against an oracle written without the streamer's code ----

    /// What a test source makes at a position.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    enum Kind {
        /// Blocks (deterministic from the position, or from each call).
        Blocks,
        /// The source panics.
        Panics,
        /// The source makes a block id the registry does not hold.
        Unknown,
    }

    fn mix(mut h: u64) -> u64 {
        h ^= h >> 33;
        h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
        h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        h ^ (h >> 33)
    }

    fn hash(pos: ChunkPos, salt: u64) -> u64 {
        let p = |v: i32| u64::from(v as u32);
        mix(p(pos.x) ^ mix(p(pos.y) ^ mix(p(pos.z) ^ mix(salt))))
    }

    /// The blocks a test source makes for `pos` from `seed`: air, uniform stone or water,
    /// or a few small boxes of stone, glass, water, leaves and red glass, many of them on
    /// the chunk's faces, edges and corners (where the neighbours' meshes read them).
    fn blocks_of(pos: ChunkPos, seed: u64) -> Chunk {
        let h = hash(pos, seed);
        match h % 10 {
            0..=2 => Chunk::default(),
            3 => Chunk::uniform(if pos.y < 0 {
                blocks::STONE
            } else {
                BlockId::AIR
            }),
            4 => Chunk::uniform(blocks::WATER),
            _ => {
                let mut next = crate::arena::tests::rng(h | 1);
                let mut c = Chunk::default();
                let ids = [
                    blocks::STONE,
                    blocks::GLASS,
                    blocks::WATER,
                    blocks::LEAVES,
                    blocks::RED_GLASS,
                ];
                for _ in 0..(next() % 6 + 1) {
                    let id = ids[(next() % 5) as usize];
                    let corner = |r: u64| match r % 4 {
                        0 => 0,
                        1 => 31 - (r / 4 % 3) as usize,
                        _ => (r / 4 % 32) as usize,
                    };
                    let lo = [corner(next()), corner(next()), corner(next())];
                    let size = [next() % 4, next() % 4, next() % 4];
                    for x in lo[0]..=(lo[0] + size[0] as usize).min(31) {
                        for y in lo[1]..=(lo[1] + size[1] as usize).min(31) {
                            for z in lo[2]..=(lo[2] + size[2] as usize).min(31) {
                                let _ = c.set(x, y, z, id);
                            }
                        }
                    }
                }
                c
            }
        }
    }

    /// Which positions fail, with `failing` set: one in 17 panics, one in 17 makes an
    /// unknown id.
    fn kind_of(pos: ChunkPos, failing: bool) -> Kind {
        match hash(pos, 99) % 17 {
            0 if failing => Kind::Panics,
            1 if failing => Kind::Unknown,
            _ => Kind::Blocks,
        }
    }

    /// The test source: `blocks_of` from a fixed seed, or from a new seed each call
    /// (`changing`), failing where [`kind_of`] says.
    struct TestSource {
        failing: bool,
        changing: Option<std::sync::atomic::AtomicU64>,
    }

    impl ChunkSource for TestSource {
        fn generate(&self, pos: ChunkPos) -> Chunk {
            match kind_of(pos, self.failing) {
                Kind::Panics => panic!("test source: broken at {pos:?}"),
                Kind::Unknown => Chunk::uniform(BlockId(60_000)),
                Kind::Blocks => {
                    let seed = self
                        .changing
                        .as_ref()
                        .map_or(7, |n| n.fetch_add(1, Ordering::Relaxed) + 1000);
                    blocks_of(pos, seed)
                }
            }
        }
    }

    /// The true world of a deterministic test source: its blocks (air where it fails) with
    /// every edit applied in order. Written from the contract, not from the streamer.
    struct Truth {
        failing: bool,
        edits: HashMap<ChunkPos, Vec<([usize; 3], BlockId)>>,
    }

    impl Truth {
        fn chunk(&self, pos: ChunkPos) -> Chunk {
            if kind_of(pos, self.failing) != Kind::Blocks {
                return Chunk::default();
            }
            let mut c = blocks_of(pos, 7);
            for &([x, y, z], id) in self.edits.get(&pos).into_iter().flatten() {
                let _ = c.set(x, y, z, id);
            }
            c
        }

        fn block(&self, pos: WorldPos) -> BlockId {
            let (c, [x, y, z]) = pos.split();
            self.chunk(c).get(x, y, z).unwrap_or(BlockId::AIR)
        }

        fn edit(&mut self, pos: WorldPos, id: BlockId) {
            let (c, local) = pos.split();
            self.edits.entry(c).or_default().push((local, id));
        }
    }

    /// A fresh mesh of `pos` from `chunk_at` (its 26 neighbours included).
    fn fresh_mesh(pos: ChunkPos, chunk_at: &dyn Fn(ChunkPos) -> Option<Chunk>) -> ChunkMeshes {
        let centre = chunk_at(pos).unwrap_or_default();
        let around: Vec<Option<Chunk>> = Neighbourhood::OFFSETS
            .iter()
            .map(|&d| pos.offset(d).and_then(chunk_at))
            .collect();
        let mut mesher = Mesher::new(&registry());
        let nb = Neighbourhood::from_fn(|d| {
            let i = Neighbourhood::OFFSETS.iter().position(|&o| o == d)?;
            around[i].as_ref()
        });
        mesher.mesh(&centre, nb).unwrap()
    }

    /// A sink holding every chunk's meshes, as the renderer would.
    #[derive(Default)]
    struct Holder {
        held: HashMap<ChunkPos, ChunkMeshes>,
    }

    impl ChunkSink for Holder {
        fn upload(&mut self, pos: ChunkPos, meshes: &ChunkMeshes) -> Result<()> {
            assert!(!meshes.is_empty(), "empty meshes uploaded at {pos:?}");
            self.held.insert(pos, meshes.clone());
            Ok(())
        }

        fn remove(&mut self, pos: ChunkPos) {
            assert!(
                self.held.remove(&pos).is_some(),
                "removed {pos:?}, not held"
            );
        }
    }

    /// Updates until idle; `None` if not within `limit` updates. Collects the failures
    /// reported.
    fn run_to_idle(
        s: &mut ChunkStreamer,
        eye: DVec3,
        sink: &mut Holder,
        failed: &mut HashSet<ChunkPos>,
        limit: usize,
    ) -> Option<usize> {
        for i in 0..limit {
            let f = s.update(eye, sink).unwrap();
            failed.extend(f.failed.iter().map(|x| x.0));
            if s.is_idle() {
                return Some(i);
            }
            if s.jobs() > 0 {
                std::thread::sleep(std::time::Duration::from_micros(30));
            }
        }
        None
    }

    /// The contract's checks once idle: the sink holds exactly the true world's fresh
    /// meshes, every chunk within the view distance that has faces, nothing past the
    /// margin; resident blocks equal the true world's; failures were reported.
    fn check_against_truth(
        s: &ChunkStreamer,
        sink: &Holder,
        truth: &Truth,
        eye: DVec3,
        failed: &HashSet<ChunkPos>,
        what: &str,
    ) {
        let centre = ChunkStreamer::centre_of(eye).unwrap();
        let cache: std::cell::RefCell<HashMap<ChunkPos, Chunk>> = Default::default();
        let chunk_at = |p: ChunkPos| -> Option<Chunk> {
            Some(
                cache
                    .borrow_mut()
                    .entry(p)
                    .or_insert_with(|| truth.chunk(p))
                    .clone(),
            )
        };
        for (&pos, meshes) in &sink.held {
            assert!(s.keeps(pos, centre), "{what}: {pos:?} past the margin");
            let fresh = fresh_mesh(pos, &chunk_at);
            assert!(
                *meshes == fresh,
                "{what}: {pos:?} drawn with {} quads, a fresh mesh of the true world has {}",
                meshes.len(),
                fresh.len()
            );
        }
        for o in &s.offsets {
            let pos = ChunkPos::new(centre.x + o[0], centre.y + o[1], centre.z + o[2]);
            if !sink.held.contains_key(&pos) {
                let fresh = fresh_mesh(pos, &chunk_at);
                assert!(
                    fresh.is_empty(),
                    "{what}: {pos:?} within the view distance not drawn ({} quads)",
                    fresh.len()
                );
            }
            if kind_of(pos, truth.failing) != Kind::Blocks {
                assert!(failed.contains(&pos), "{what}: {pos:?} failed unreported");
            }
        }
        for (pos, c) in s.world().iter() {
            let t = chunk_at(pos).unwrap_or_default();
            for z in 0..CHUNK_SIZE {
                for y in 0..CHUNK_SIZE {
                    for x in 0..CHUNK_SIZE {
                        assert_eq!(
                            c.get(x, y, z).unwrap(),
                            t.get(x, y, z).unwrap(),
                            "{what}: resident block {x},{y},{z} of {pos:?}"
                        );
                    }
                }
            }
        }
    }

    /// For a source that answers differently each call there is no true world beyond what
    /// the streamer holds: every drawn chunk equals a fresh mesh of the streamer's own
    /// resident blocks, all 26 of its neighbours resident, and every chunk within the view
    /// distance whose fresh mesh of those blocks has faces is drawn.
    fn check_against_own_world(s: &ChunkStreamer, sink: &Holder, eye: DVec3, what: &str) {
        let chunk_at = |p: ChunkPos| s.world().chunk(p).cloned();
        let centre = ChunkStreamer::centre_of(eye).unwrap();
        for o in &s.offsets {
            let pos = ChunkPos::new(centre.x + o[0], centre.y + o[1], centre.z + o[2]);
            if !sink.held.contains_key(&pos) {
                let fresh = fresh_mesh(pos, &chunk_at);
                assert!(
                    fresh.is_empty(),
                    "{what}: {pos:?} within the view distance not drawn ({} quads)",
                    fresh.len()
                );
            }
        }
        for (&pos, meshes) in &sink.held {
            for d in Neighbourhood::OFFSETS {
                let n = pos.offset(d).unwrap();
                assert!(
                    s.is_resident(n),
                    "{what}: {pos:?} drawn, neighbour {n:?} not held"
                );
            }
            assert!(
                *meshes == fresh_mesh(pos, &chunk_at),
                "{what}: {pos:?} differs from a fresh mesh of the streamer's own world"
            );
        }
    }

    /// A block position in chunk `c`: on a face, edge or corner (or inside) at random.
    fn block_in(c: ChunkPos, next: &mut impl FnMut() -> u64) -> WorldPos {
        let o = c.origin();
        let local = |r: u64| match r % 3 {
            0 => 0,
            1 => 31,
            _ => (r / 3 % 32) as i64,
        };
        WorldPos::new(
            (o[0] + local(next())) as i32,
            (o[1] + local(next())) as i32,
            (o[2] + local(next())) as i32,
        )
    }

    /// Random sequences of moves, teleports (away and back), view-distance changes, partial
    /// updates and edits (near the eye, on chunks at the view-distance edge and just past
    /// it, on chunks not loaded next to loaded ones and far away, on failing chunks), with
    /// sources that are deterministic, fail (panic, unknown ids) or change on each call.
    /// Now and then, and at the end, the streamer must become idle and then hold the
    /// truth (see the module docs).
    #[test]
    fn random_sequences_hold_the_truth_once_idle() {
        let mut checks = 0;
        let mut edits_made = [0usize; 5];
        for seq in 0..36u64 {
            let mut next = crate::arena::tests::rng(0x5eed_0000 + seq * 7919);
            let failing = seq % 3 == 1;
            let changing = seq % 3 == 2;
            let config = StreamConfig {
                view_distance: 1 + (seq % 3) as u32,
                vertical_distance: 1,
                hysteresis: 1 + (seq % 2) as u32,
                threads: 2,
                max_jobs: [1, 4, 64][(seq % 3) as usize],
                max_unloads: [1, 7, 256][(seq / 3 % 3) as usize],
                scan_budget: [3, 2048][(seq % 2) as usize],
                upload_budget_bytes: [64, 1 << 20][(seq / 2 % 2) as usize],
            };
            let source = TestSource {
                failing,
                changing: changing.then(|| std::sync::atomic::AtomicU64::new(0)),
            };
            let mut s = ChunkStreamer::new(registry(), source, config).unwrap();
            let mut truth = Truth {
                failing,
                edits: HashMap::new(),
            };
            let mut sink = Holder::default();
            let mut failed = HashSet::new();
            let home = DVec3::new(5.0, 10.0, 5.0);
            let mut eye = home;
            for step in 0..40 {
                let what = format!("sequence {seq} step {step}");
                let centre = ChunkStreamer::centre_of(eye).unwrap();
                let r = next() % 100;
                match r {
                    0..=14 => {
                        let d = |n: u64| (n % 65) as f64 - 32.0;
                        eye += DVec3::new(d(next()), d(next()) / 4.0, d(next()));
                    }
                    15..=19 => {
                        // Far away, a few chunks away (past the view distance, within
                        // or past the margin: chunks leave the sink but stay resident
                        // for their neighbours), or back home (flying away and back).
                        let k = f64::from(1 + (next() % 8) as u32) * 32.0;
                        eye = match next() % 3 {
                            0 => home + DVec3::new(32.0 * 40.0, 0.0, -32.0 * 25.0),
                            1 => home + DVec3::new(k, 0.0, -((next() % 2) as f64) * k),
                            _ => home,
                        };
                    }
                    20..=22 => {
                        let mut c = *s.config();
                        c.view_distance = 1 + (next() % 3) as u32;
                        s.set_config(c).unwrap();
                    }
                    23..=39 => {
                        for _ in 0..next() % 4 {
                            let f = s.update(eye, &mut sink).unwrap();
                            failed.extend(f.failed.iter().map(|x| x.0));
                        }
                    }
                    _ => {
                        // An edit: which chunk, by kind.
                        let vd = i32::try_from(s.config().view_distance).unwrap();
                        let kind = (next() % 5) as usize;
                        let c = match kind {
                            // Near the eye.
                            0 => ChunkPos::new(
                                centre.x + (next() % 3) as i32 - 1,
                                centre.y + (next() % 3) as i32 - 1,
                                centre.z + (next() % 3) as i32 - 1,
                            ),
                            // At the view-distance edge, or one or two past it.
                            1 => {
                                let out = vd + (next() % 3) as i32;
                                let side = [(out, 0), (-out, 0), (0, out), (0, -out)]
                                    [(next() % 4) as usize];
                                ChunkPos::new(centre.x + side.0, centre.y, centre.z + side.1)
                            }
                            // Just past the margin, next to the loaded ring.
                            2 => ChunkPos::new(
                                centre.x + vd + 3 + (next() % 2) as i32,
                                centre.y,
                                centre.z,
                            ),
                            // Far away, not loaded.
                            3 => ChunkPos::new(
                                centre.x + 60 + (next() % 5) as i32,
                                centre.y,
                                centre.z - 40,
                            ),
                            // Around home, wherever the eye is.
                            _ => ChunkPos::new(
                                (next() % 5) as i32 - 2,
                                (next() % 3) as i32 - 1,
                                (next() % 5) as i32 - 2,
                            ),
                        };
                        let at = block_in(c, &mut next);
                        let id = [
                            BlockId::AIR,
                            blocks::STONE,
                            blocks::GLASS,
                            blocks::WATER,
                            blocks::LEAVES,
                        ][(next() % 5) as usize];
                        let expected_old = truth.block(at);
                        match s.set_block(at, id) {
                            Ok(old) => {
                                assert_eq!(kind_of(c, failing), Kind::Blocks, "{what}");
                                if !changing {
                                    assert_eq!(old, expected_old, "{what}: old block at {at:?}");
                                }
                                truth.edit(at, id);
                                edits_made[kind] += 1;
                            }
                            Err(e) => {
                                assert!(matches!(e, Error::ChunkSource { .. }), "{what}: {e}");
                                assert_ne!(kind_of(c, failing), Kind::Blocks, "{what}: {e}");
                            }
                        }
                    }
                }
                if step % 13 == 12 || step == 39 {
                    let idle = run_to_idle(&mut s, eye, &mut sink, &mut failed, 20_000);
                    assert!(idle.is_some(), "{what}: never idle: {s:?}");
                    if changing {
                        check_against_own_world(&s, &sink, eye, &what);
                    } else {
                        check_against_truth(&s, &sink, &truth, eye, &failed, &what);
                    }
                    assert!(s.queued_unloads() <= s.positions());
                    checks += 1;
                }
            }
        }
        assert!(checks >= 36 * 4, "{checks} checks");
        // Every kind of edit was made, many times.
        assert!(edits_made.iter().all(|&n| n >= 20), "{edits_made:?}");
    }

    fn deterministic(view_distance: u32, hysteresis: u32) -> (ChunkStreamer, Truth) {
        let config = StreamConfig {
            view_distance,
            vertical_distance: 1,
            hysteresis,
            threads: 2,
            ..StreamConfig::default()
        };
        let source = TestSource {
            failing: false,
            changing: None,
        };
        let s = ChunkStreamer::new(registry(), source, config).unwrap();
        let truth = Truth {
            failing: false,
            edits: HashMap::new(),
        };
        (s, truth)
    }

    /// Runs to idle (within `limit` updates) and checks the contract.
    fn settle_and_check(
        s: &mut ChunkStreamer,
        sink: &mut Holder,
        truth: &Truth,
        eye: DVec3,
        limit: usize,
        what: &str,
    ) {
        let mut failed = HashSet::new();
        let idle = run_to_idle(s, eye, sink, &mut failed, limit);
        assert!(
            idle.is_some(),
            "{what}: not idle after {limit} updates: {s:?}"
        );
        check_against_truth(s, sink, truth, eye, &failed, what);
    }

    /// The middle of chunk `c` at height 10, as an eye.
    fn eye_in(c: ChunkPos) -> DVec3 {
        DVec3::new(
            f64::from(c.x) * 32.0 + 16.0,
            f64::from(c.y) * 32.0 + 10.0,
            f64::from(c.z) * 32.0 + 16.0,
        )
    }

    /// Issue 26, row 1: the eye flies two chunks away and back (the outer neighbour of the
    /// chunk at the view-distance edge passed the margin meanwhile), then a block is placed
    /// on that chunk's outer face: it is drawn and the streamer becomes idle (before, the
    /// remesh waited for the neighbour for ever and the old mesh stayed). Then far away and
    /// back: still there.
    #[test]
    fn an_edit_at_the_view_distance_edge_after_flying_away_and_back_is_drawn() {
        let (mut s, mut truth) = deterministic(2, 1);
        let mut sink = Holder::default();
        let home = eye_in(ChunkPos::new(0, 0, 0));
        settle_and_check(&mut s, &mut sink, &truth, home, 5_000, "loaded");
        settle_and_check(
            &mut s,
            &mut sink,
            &truth,
            eye_in(ChunkPos::new(-2, 0, 0)),
            5_000,
            "away",
        );
        settle_and_check(&mut s, &mut sink, &truth, home, 5_000, "back");
        for at in [
            WorldPos::new(2 * 32 + 31, 5, 7),
            WorldPos::new(2 * 32 + 31, 31, 0),
        ] {
            s.set_block(at, blocks::RED_GLASS).unwrap();
            truth.edit(at, blocks::RED_GLASS);
        }
        settle_and_check(&mut s, &mut sink, &truth, home, 5_000, "edited");
        assert!(sink.held.contains_key(&ChunkPos::new(2, 0, 0)));
        settle_and_check(
            &mut s,
            &mut sink,
            &truth,
            eye_in(ChunkPos::new(50, 0, 0)),
            5_000,
            "far",
        );
        settle_and_check(&mut s, &mut sink, &truth, home, 5_000, "home again");
    }

    /// Return trips of every length, at view distances 3, 8 and 16 (vertical 1, default
    /// hysteresis): from home the eye flies `k` chunks away (along an axis or a diagonal),
    /// settles, flies back and settles, for every `k` from 1 to past the margin. Each stop
    /// is checked against the true world. Chunks past the view distance leave the sink but
    /// stay resident while a neighbour still needs their blocks; once wanted again they
    /// must be meshed and uploaded again (they were left as done: a hole beside the eye).
    #[test]
    fn return_trips_of_every_length_hold_the_truth() {
        for view_distance in [3u32, 8, 16] {
            let (mut s, truth) = deterministic(view_distance, StreamConfig::default().hysteresis);
            let mut sink = Holder::default();
            let home = eye_in(ChunkPos::new(0, 0, 0));
            let what = format!("view distance {view_distance}");
            settle_and_check(&mut s, &mut sink, &truth, home, 50_000, &what);
            let reach = view_distance as i32 + 2 * 2 + 2;
            for k in 1..=reach {
                let away = if k % 2 == 0 {
                    ChunkPos::new(k, 0, 0)
                } else {
                    ChunkPos::new(-k, 0, k / 2)
                };
                let what = format!("view distance {view_distance}, {away:?} and back");
                // The far stop is checked where the margin can matter; every return is.
                if view_distance < 16 || k > view_distance as i32 {
                    settle_and_check(&mut s, &mut sink, &truth, eye_in(away), 50_000, &what);
                } else {
                    let mut failed = HashSet::new();
                    let idle = run_to_idle(&mut s, eye_in(away), &mut sink, &mut failed, 50_000);
                    assert!(idle.is_some(), "{what}: not idle away: {s:?}");
                }
                settle_and_check(&mut s, &mut sink, &truth, home, 50_000, &what);
            }
        }
    }

    /// Issue 26, row 2: a chunk drawn at the edge of the margin, whose outer neighbour lies
    /// past it, is edited: it is meshed again (its neighbour stayed resident for it) and the
    /// streamer becomes idle (it never did: it waited for a neighbour nobody loaded).
    #[test]
    fn an_edit_of_a_chunk_whose_outer_neighbour_is_past_the_margin_is_remeshed() {
        let (mut s, mut truth) = deterministic(2, 1);
        let mut sink = Holder::default();
        settle_and_check(
            &mut s,
            &mut sink,
            &truth,
            eye_in(ChunkPos::new(0, 0, 0)),
            5_000,
            "at 0",
        );
        // Two chunks along -x: chunk (2, 0, 0) is 4 away, at the margin's edge (2 + 2);
        // (3, 0, 0) lies past it.
        let eye = eye_in(ChunkPos::new(-2, 0, 0));
        settle_and_check(&mut s, &mut sink, &truth, eye, 5_000, "moved");
        let edge = ChunkPos::new(2, 0, 0);
        let outer = ChunkPos::new(3, 0, 0);
        let centre = ChunkStreamer::centre_of(eye).unwrap();
        assert!(s.keeps(edge, centre) && !s.keeps(outer, centre));
        assert!(
            !sink.held.contains_key(&edge) || s.is_resident(outer),
            "a drawn chunk's neighbour left memory"
        );
        for at in [
            WorldPos::new(2 * 32 + 31, 3, 3),
            WorldPos::new(2 * 32 + 31, 31, 31),
        ] {
            s.set_block(at, blocks::STONE).unwrap();
            truth.edit(at, blocks::STONE);
        }
        settle_and_check(&mut s, &mut sink, &truth, eye, 20_000, "edited");
    }

    /// Issue 26, row 3: the chunk just past the margin next to a drawn one is edited on the
    /// face they share: the drawn chunk's border faces follow (its neighbour is resident,
    /// so the edit remeshes it). And an edit of a chunk far away changes no drawn chunk.
    #[test]
    fn an_edit_beside_a_drawn_chunk_remeshes_its_border() {
        let (mut s, mut truth) = deterministic(2, 1);
        let mut sink = Holder::default();
        settle_and_check(
            &mut s,
            &mut sink,
            &truth,
            eye_in(ChunkPos::new(0, 0, 0)),
            5_000,
            "at 0",
        );
        let eye = eye_in(ChunkPos::new(-2, 0, 0));
        settle_and_check(&mut s, &mut sink, &truth, eye, 5_000, "moved");
        let outer = ChunkPos::new(3, 0, 0);
        // Fill the face of the outer chunk that touches chunk (2, 0, 0): every face of
        // the drawn chunk's border layer changes.
        for y in 0..32 {
            for z in 0..32 {
                let at = WorldPos::new(3 * 32, y, z);
                s.set_block(at, blocks::STONE).unwrap();
                truth.edit(at, blocks::STONE);
            }
        }
        let far = WorldPos::new(40 * 32 + 3, 4, 5);
        s.set_block(far, blocks::GLASS).unwrap();
        truth.edit(far, blocks::GLASS);
        settle_and_check(&mut s, &mut sink, &truth, eye, 5_000, "edited");
        assert!(s.is_resident(outer) || !sink.held.contains_key(&ChunkPos::new(2, 0, 0)));
    }

    /// Issue 26, row 4: a source that answers differently on each call; flying away and
    /// back, every drawn chunk still equals a fresh mesh of the streamer's own blocks (a
    /// neighbour generated anew under a drawn chunk left it stale).
    #[test]
    fn a_source_that_changes_leaves_no_stale_mesh() {
        let config = StreamConfig {
            view_distance: 3,
            vertical_distance: 1,
            hysteresis: 1,
            threads: 2,
            max_unloads: 5,
            ..StreamConfig::default()
        };
        let source = TestSource {
            failing: false,
            changing: Some(std::sync::atomic::AtomicU64::new(0)),
        };
        let mut s = ChunkStreamer::new(registry(), source, config).unwrap();
        let mut sink = Holder::default();
        let mut failed = HashSet::new();
        for (i, c) in [0, 3, 6, 9, 4, 0, -5, 0].into_iter().enumerate() {
            let eye = eye_in(ChunkPos::new(c, 0, c / 2));
            // Half the way settled, half not: chunks unload and reload in between.
            let limit = if i % 2 == 0 { 20_000 } else { 40 };
            let idle = run_to_idle(&mut s, eye, &mut sink, &mut failed, limit);
            if limit == 20_000 {
                assert!(idle.is_some(), "not idle: {s:?}");
                check_against_own_world(&s, &sink, eye, &format!("stop {i}"));
            }
        }
    }

    /// Issue 26, rows 5 and 6: an edit of a chunk whose source panics or makes unknown ids
    /// is an error (the panic never reaches the caller), whether the chunk is not loaded,
    /// on its way, or loaded (where it stands as air, reported by the update).
    #[test]
    fn edits_of_chunks_whose_source_fails_are_errors() {
        let config = StreamConfig {
            view_distance: 3,
            vertical_distance: 1,
            threads: 1,
            max_jobs: 1,
            ..StreamConfig::default()
        };
        let mut s = ChunkStreamer::new(registry(), Broken, config).unwrap();
        let mut sink = Holder::default();
        // (1, 0, 0) panics, (-1, 0, 0) makes unknown ids; far copies of them too.
        for c in [1, -1] {
            let at = WorldPos::new(c * 32 + 4, 4, 4);
            let e = s.set_block(at, blocks::GLASS).unwrap_err();
            assert!(matches!(e, Error::ChunkSource { .. }), "{e:?}");
            let msg = e.to_string();
            assert!(msg.contains(&format!("x: {c}")), "{msg}");
            assert!(
                msg.contains(if c == 1 { "panicked" } else { "unknown" }),
                "{msg}"
            );
        }
        // On their way: one job at a time, so both are still generating after an update.
        s.update(DVec3::splat(16.0), &mut sink).unwrap();
        for c in [1, -1] {
            assert!(
                s.set_block(WorldPos::new(c * 32 + 4, 4, 4), blocks::GLASS)
                    .is_err()
            );
        }
        let mut failed = HashSet::new();
        run_to_idle(&mut s, DVec3::splat(16.0), &mut sink, &mut failed, 20_000).unwrap();
        assert!(
            failed.contains(&ChunkPos::new(1, 0, 0)) && failed.contains(&ChunkPos::new(-1, 0, 0))
        );
        for c in [1, -1] {
            let e = s
                .set_block(WorldPos::new(c * 32 + 4, 4, 4), blocks::GLASS)
                .unwrap_err();
            assert!(e.to_string().contains("stands as air"), "{e}");
            assert!(!sink.held.contains_key(&ChunkPos::new(c, 0, 0)));
        }
        // Their neighbours draw; an edit next to them works.
        assert!(sink.held.contains_key(&ChunkPos::new(0, 0, 0)));
        s.set_block(WorldPos::new(31, 5, 5), blocks::STONE).unwrap();
    }

    /// Issue 26, row 7: the unload queue holds each chunk once. After a teleport, the eye
    /// moves to a new chunk every update while unloads trickle (one per update): the queue
    /// never holds more than the positions known (it used to take every far chunk again
    /// on every move: 730 MiB and 292 ms updates at view distance 64).
    #[test]
    fn the_unload_queue_holds_each_chunk_once() {
        let config = StreamConfig {
            view_distance: 6,
            vertical_distance: 1,
            max_unloads: 1,
            threads: 1,
            ..StreamConfig::default()
        };
        let mut s = ChunkStreamer::new(registry(), Pillars, config).unwrap();
        let mut sink = Recorder::default();
        settle(&mut s, DVec3::splat(16.0), &mut sink, 20_000);
        let loaded = s.positions();
        let mut most = 0;
        for i in 0..300 {
            let eye = DVec3::new(16.0 + 32.0 * (5_000.0 + f64::from(i)), 16.0, 16.0);
            s.update(eye, &mut sink).unwrap();
            assert!(s.queued_unloads() <= s.positions(), "update {i}: {s:?}");
            most = most.max(s.queued_unloads());
        }
        assert!(most <= loaded + s.positions(), "{most}");
        // And it all drains: the old place leaves memory, the new one loads.
        let eye = DVec3::new(16.0 + 32.0 * 5_300.0, 16.0, 16.0);
        settle(&mut s, eye, &mut sink, 50_000);
        let centre = ChunkPos::new(5_300, 0, 0);
        assert!(s.world().iter().all(|(p, _)| (p.x - centre.x).abs() < 20));
    }

    /// A source that counts its calls and takes 2 ms each.
    struct Slow(Arc<std::sync::atomic::AtomicUsize>);

    impl ChunkSource for Slow {
        fn generate(&self, _: ChunkPos) -> Chunk {
            std::thread::sleep(std::time::Duration::from_millis(2));
            self.0.fetch_add(1, Ordering::SeqCst);
            Chunk::uniform(blocks::STONE)
        }
    }

    /// Issue 26, row 8: dropping the streamer with 64 jobs queued stops them: at most the
    /// one running goes on (they all ran, 64 calls, before).
    #[test]
    fn dropping_the_streamer_stops_its_jobs() {
        let calls = Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let config = StreamConfig {
            view_distance: 8,
            threads: 1,
            max_jobs: 64,
            ..StreamConfig::default()
        };
        let mut s = ChunkStreamer::new(registry(), Slow(calls.clone()), config).unwrap();
        s.update(DVec3::splat(16.0), &mut Recorder::default())
            .unwrap();
        assert_eq!(s.jobs(), 64);
        drop(s);
        let at_drop = calls.load(Ordering::SeqCst);
        std::thread::sleep(std::time::Duration::from_millis(300));
        let after = calls.load(Ordering::SeqCst);
        assert!(
            after <= at_drop + 1,
            "{at_drop} calls at the drop, {after} after"
        );
    }

    /// Issue 26, row 8: 10 000 edits of chunks far away are kept as edits, within the
    /// documented bound (they took 135 MB as whole chunks), and each comes back when its
    /// chunk loads; the edit list reports them for saving.
    #[test]
    fn far_edits_are_kept_within_the_bound() {
        let mut s = ChunkStreamer::new(registry(), Pillars, config(1)).unwrap();
        let mut sink = Recorder::default();
        settle(&mut s, DVec3::splat(16.0), &mut sink, 10_000);
        let before = s.memory_bytes();
        let at = |i: i32| WorldPos::new(1000 * 32 + (i % 100) * 64 + 3, 7, (i / 100) * 64 + 9);
        for i in 0..10_000 {
            assert_eq!(s.set_block(at(i), blocks::GLASS).unwrap(), BlockId::AIR);
        }
        let kept = s.memory_bytes() - before;
        assert_eq!(kept, s.edit_bytes());
        assert_eq!(kept, 10_000 * (EDIT_BYTES + EDITED_CHUNK_BYTES));
        assert!(kept < 2 << 20, "{kept} bytes");
        assert_eq!(s.edits().count(), 10_000);
        assert!(
            s.edits()
                .any(|(p, id)| p == at(4321) && id == blocks::GLASS)
        );
        // One of them, loaded: the glass is there, drawn.
        let (c, [x, y, z]) = at(4321).split();
        let eye = DVec3::new(
            f64::from(c.x) * 32.0 + 16.0,
            16.0,
            f64::from(c.z) * 32.0 + 16.0,
        );
        settle(&mut s, eye, &mut sink, 20_000);
        assert_eq!(
            s.world().chunk(c).unwrap().get(x, y, z).unwrap(),
            blocks::GLASS
        );
        assert!(sink.held.contains_key(&c));
    }
}
