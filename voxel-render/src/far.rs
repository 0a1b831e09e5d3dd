//! A far view kept around a moving eye ([`FarField`]): the levels of detail of
//! [`voxel_mesh::levels`], generated and meshed off the frame (a worker thread, whose
//! meshing runs on rayon's pool; in turn, within a time budget, on wasm32), uploaded a whole
//! view at a time so that no frame draws a hole or a place twice.
//!
//! - **Coarse first**: a new view (the first, or after a jump) is built through its
//!   coarse-first views ([`LevelRings::coarse_first`]): the coarsest level alone fills the
//!   whole square, then each finer level in turn; each is drawn as soon as it is complete.
//! - **Hysteresis**: the view is planned around an *anchor*, which moves to the eye only
//!   when the eye is more than [`FarConfig::hysteresis`] blocks from it in x or z, so an eye
//!   that goes back and forth across a level's chunk border does not rebuild the view each
//!   time. The finer rings reach that much less far from the eye than from the anchor.
//! - **Swaps**: while the next view is built, the drawn one stays; when every mesh of the
//!   next view is ready, it is swapped in a square of the coarsest level at a time (nearest
//!   first, whole squares up to [`FarConfig::upload_budget`] bytes an update): each square
//!   changes from one tiling of its ground to the other in one update, so no frame draws a
//!   hole or a place twice. (For the few frames of a swap, a mesh beside a square not swapped
//!   yet was culled against its new neighbours: at most a skirt shows or is missing there.) A mesh depends on which of its neighbours the view holds
//!   (water only across a level border), so meshes are kept by chunk and those neighbours,
//!   and a chunk whose border changed is meshed again.
//! - **Edits** ([`FarField::set_block`]) reach every level that holds the edited block
//!   ([`voxel_core::level_cell`]): the worker keeps them and generates every chunk with
//!   them, and the drawn chunks whose meshes they change are meshed again ahead of the
//!   view being built and replaced in place (a mesh made before an edit it lacks is made
//!   again).

use std::collections::{HashMap, HashSet, VecDeque};
use std::sync::Arc;

use glam::DVec3;
use voxel_core::{BlockId, BlockRegistry, ChunkPos, TerrainGenerator, WorldPos};
use voxel_mesh::ChunkMeshes;
use voxel_mesh::levels::{LevelCache, LevelRings, chunks_an_edit_changes, mesh_level_chunks_with};

use crate::renderer::level_key;
use crate::{Error, Renderer, Result};

/// How a [`FarField`] follows the eye.
#[derive(Clone, Debug, PartialEq)]
pub struct FarConfig {
    /// The levels and their rings.
    pub rings: LevelRings,
    /// Blocks (x or z) the eye goes from the view's anchor before the view is planned
    /// around the eye again, 0 to 256. Default 16.
    pub hysteresis: f64,
    /// Chunks meshed per job (at least 1). Default 256.
    pub batch: usize,
    /// Bytes of quads a swap uploads per update at most (whole groups: at least one).
    /// Default 4 MiB.
    pub upload_budget: u64,
}

impl Default for FarConfig {
    fn default() -> Self {
        Self {
            rings: LevelRings::reaching(32, 512),
            hysteresis: 16.0,
            batch: 256,
            upload_budget: 4 << 20,
        }
    }
}

/// A chunk of a view and which of its neighbours the view holds: what its mesh is made of.
type Key = (u8, ChunkPos, u32);

/// What the last [`FarField::update`] did and what the field holds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FarStatus {
    /// The finest level of the view drawn (0: finished; `None`: nothing drawn yet).
    pub drawn_finest: Option<u8>,
    /// Chunks drawn.
    pub drawn_chunks: usize,
    /// Meshes waiting for the next view's swap, and chunks still to mesh for it.
    pub ready: usize,
    /// Chunks of the next view not meshed yet.
    pub missing: usize,
    /// Whether this update finished swapping a view in.
    pub swapped: bool,
    /// Bytes of quads uploaded by this update.
    pub uploaded_bytes: u64,
    /// When `swapped`: the bytes of quads the whole swap uploaded.
    pub swap_bytes: u64,
    /// Drawn chunks this update replaced with their meshes after edits.
    pub refreshed: usize,
    /// Drawn chunks that edits changed and that are not drawn again yet (0: every edit
    /// taken is drawn).
    pub edit_chunks_pending: usize,
}

/// The levels of detail of generated terrain around a moving eye, on a [`Renderer`]'s GPU:
/// see the module docs. Call [`FarField::update`] once a frame with the eye; it never
/// waits for planning or meshing, which run on its worker.
pub struct FarField {
    generator: Arc<TerrainGenerator>,
    registry: Arc<BlockRegistry>,
    config: FarConfig,
    /// The eye the view is planned around.
    anchor: Option<DVec3>,
    /// The plan asked of the worker last (its number); older plans that come back are
    /// dropped.
    planning: Option<u64>,
    plans: u64,
    /// The view being built.
    target: Option<Target>,
    /// The view being swapped in.
    swapping: Option<Swap>,
    /// The view drawn.
    drawn: Option<View>,
    /// Meshes made, by chunk and neighbours held.
    ready: HashMap<Key, ChunkMeshes>,
    /// Chunks sent to be meshed and not back yet.
    in_flight: HashSet<Key>,
    /// Edits taken and not sent to the worker yet.
    new_edits: Vec<([i64; 3], BlockId)>,
    /// Every edit sent to the worker, in order: a mesh made after the first `n` of them
    /// lacks the rest.
    edits: Vec<[i64; 3]>,
    /// Drawn chunks being meshed again after edits, and their meshes that came back during
    /// a swap (uploaded when it ends).
    refreshing: HashSet<Key>,
    refreshed: HashMap<Key, ChunkMeshes>,
    /// Bytes of quads on the GPU by drawn chunk (level, position).
    bytes: HashMap<(u8, ChunkPos), u64>,
    jobs: Jobs,
}

/// What one level of a far view holds on the GPU ([`FarField::memory`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LevelMemory {
    /// The level (0: full detail).
    pub level: u8,
    /// Chunks drawn (with or without a face).
    pub chunks: usize,
    /// Quads uploaded, 8 bytes each.
    pub quads: u64,
}

/// A whole view: its rings, the anchor it is planned around, its chunks.
#[derive(Clone, Debug)]
struct View {
    rings: LevelRings,
    at: [f64; 3],
    keys: HashSet<Key>,
}

/// A view being built: its rings (a coarse-first view, or the finished one), the eye it is
/// planned around, its chunks, and those neither drawn nor meshed yet.
#[derive(Debug)]
struct Target {
    rings: LevelRings,
    at: [f64; 3],
    keys: Vec<Key>,
    pending: HashSet<Key>,
}

impl std::fmt::Debug for FarField {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FarField")
            .field("config", &self.config)
            .field("anchor", &self.anchor)
            .field(
                "drawn",
                &self.drawn.as_ref().map(|d| (d.rings.finest, d.keys.len())),
            )
            .field("edits", &self.edits.len())
            .field("ready", &self.ready.len())
            .field("in_flight", &self.in_flight.len())
            .finish_non_exhaustive()
    }
}

/// What the worker is asked: a view's chunks (plan number, rings, eye), the meshes of
/// some of them (for the view being built, or drawn chunks an edit changed), or an edit.
enum Job {
    Plan(u64, LevelRings, [f64; 3]),
    Mesh(Purpose, LevelRings, [f64; 3], Vec<Key>),
    Edit([i64; 3], BlockId),
}

/// What meshes are for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Purpose {
    /// The view being built.
    View,
    /// Drawn chunks that edits changed: the worker makes them before the others.
    Refresh,
}

impl Job {
    /// Whether the worker takes it before the jobs queued before it: edits, and meshes of
    /// drawn chunks they changed (in the order sent), so that an edit is drawn after at
    /// most the batch in progress.
    fn urgent(&self) -> bool {
        matches!(self, Job::Edit(..) | Job::Mesh(Purpose::Refresh, ..))
    }
}

/// What the worker answers; meshes with the number of edits they carry.
enum Done {
    Planned(u64, LevelRings, Vec<Key>),
    Meshed(
        Purpose,
        Vec<Key>,
        u64,
        std::result::Result<Vec<ChunkMeshes>, voxel_mesh::Error>,
    ),
}

/// Takes the next job from `queue`: the first urgent one, else the first.
fn next_job(queue: &mut VecDeque<Job>) -> Option<Job> {
    let i = queue.iter().position(Job::urgent).unwrap_or(0);
    queue.remove(i)
}

/// Where planning and meshing run: a worker thread, or (wasm32) the updating thread.
struct Jobs {
    #[cfg(not(target_arch = "wasm32"))]
    send: std::sync::mpsc::Sender<Job>,
    #[cfg(not(target_arch = "wasm32"))]
    receive: std::sync::mpsc::Receiver<Done>,
    #[cfg(target_arch = "wasm32")]
    queue: VecDeque<Job>,
    #[cfg(target_arch = "wasm32")]
    cache: LevelCache,
}

fn run_job(
    cache: &mut LevelCache,
    generator: &TerrainGenerator,
    registry: &BlockRegistry,
    job: Job,
) -> Option<Done> {
    match job {
        Job::Plan(n, rings, eye) => {
            let keys = rings
                .all(eye)
                .into_iter()
                .map(|(l, p)| (l, p, rings.neighbours_held(l, p, eye)))
                .collect();
            Some(Done::Planned(n, rings, keys))
        }
        Job::Mesh(purpose, rings, eye, keys) => {
            let chunks: Vec<(u8, ChunkPos)> = keys.iter().map(|&(l, p, _)| (l, p)).collect();
            let meshes = mesh_level_chunks_with(cache, generator, registry, &rings, eye, &chunks)
                .map(|v| v.into_iter().map(|(_, _, m)| m).collect());
            Some(Done::Meshed(purpose, keys, cache.edit_count(), meshes))
        }
        Job::Edit(block, id) => {
            cache.edit(block, id);
            None
        }
    }
}

impl Jobs {
    fn new(generator: &Arc<TerrainGenerator>, registry: &Arc<BlockRegistry>) -> Self {
        #[cfg(not(target_arch = "wasm32"))]
        {
            let (send, jobs) = std::sync::mpsc::channel::<Job>();
            let (done, receive) = std::sync::mpsc::channel();
            let (g, r) = (Arc::clone(generator), Arc::clone(registry));
            // The thread ends when the field (its sender) is dropped.
            std::thread::Builder::new()
                .name("far-field".into())
                .spawn(move || {
                    let mut cache = LevelCache::default();
                    let mut queue = VecDeque::new();
                    loop {
                        if queue.is_empty() {
                            match jobs.recv() {
                                Ok(job) => queue.push_back(job),
                                Err(_) => break,
                            }
                        }
                        queue.extend(jobs.try_iter());
                        let Some(job) = next_job(&mut queue) else {
                            continue;
                        };
                        if let Some(d) = run_job(&mut cache, &g, &r, job)
                            && done.send(d).is_err()
                        {
                            break;
                        }
                    }
                })
                .ok();
            Self { send, receive }
        }
        #[cfg(target_arch = "wasm32")]
        {
            let _ = (generator, registry);
            Self {
                queue: VecDeque::new(),
                cache: LevelCache::default(),
            }
        }
    }

    fn send(&mut self, job: Job) -> Result<()> {
        #[cfg(not(target_arch = "wasm32"))]
        {
            self.send
                .send(job)
                .map_err(|_| Error::Unsupported("the far field's worker thread is gone".into()))
        }
        #[cfg(target_arch = "wasm32")]
        {
            self.queue.push_back(job);
            Ok(())
        }
    }

    /// The jobs done since the last call (wasm32: runs queued jobs up to the first that
    /// answers).
    fn done(&mut self, _generator: &TerrainGenerator, _registry: &BlockRegistry) -> Vec<Done> {
        #[cfg(not(target_arch = "wasm32"))]
        {
            self.receive.try_iter().collect()
        }
        #[cfg(target_arch = "wasm32")]
        {
            while let Some(job) = next_job(&mut self.queue) {
                if let Some(d) = run_job(&mut self.cache, _generator, _registry, job) {
                    return vec![d];
                }
            }
            Vec::new()
        }
    }
}

impl FarField {
    /// A far view of `generator`'s terrain (over `registry`, which must hold its blocks and
    /// be the renderer's) with `config`. Nothing is drawn until [`FarField::update`].
    pub fn new(
        generator: Arc<TerrainGenerator>,
        registry: Arc<BlockRegistry>,
        config: FarConfig,
    ) -> Result<Self> {
        config.rings.validate().map_err(Error::InvalidSetting)?;
        if !(0.0..=256.0).contains(&config.hysteresis) {
            return Err(Error::InvalidSetting(format!(
                "far field hysteresis {} blocks: it must be from 0 to 256",
                config.hysteresis
            )));
        }
        generator.check(&registry)?;
        let jobs = Jobs::new(&generator, &registry);
        Ok(Self {
            generator,
            registry,
            config: FarConfig {
                batch: config.batch.max(1),
                ..config
            },
            anchor: None,
            planning: None,
            plans: 0,
            target: None,
            swapping: None,
            drawn: None,
            ready: HashMap::new(),
            in_flight: HashSet::new(),
            new_edits: Vec::new(),
            edits: Vec::new(),
            refreshing: HashSet::new(),
            refreshed: HashMap::new(),
            bytes: HashMap::new(),
            jobs,
        })
    }

    /// Its configuration.
    pub fn config(&self) -> &FarConfig {
        &self.config
    }

    /// The chunks drawn, by level and position (each level's own chunk coordinates).
    pub fn drawn(&self) -> impl Iterator<Item = (u8, ChunkPos)> + '_ {
        self.drawn
            .iter()
            .flat_map(|d| d.keys.iter().map(|&(l, p, _)| (l, p)))
    }

    /// Whether the view around the eye last given is drawn whole, at full detail, with
    /// every edit taken: nothing is planned, meshed or swapped in.
    pub fn is_idle(&self) -> bool {
        self.drawn.as_ref().is_some_and(|d| d.rings.finest == 0)
            && self.planning.is_none()
            && self.target.is_none()
            && self.swapping.is_none()
            && self.new_edits.is_empty()
            && self.refreshing.is_empty()
            && self.refreshed.is_empty()
    }

    /// What each level of the drawn view holds on the GPU, finest first (the quads; the
    /// arena's free room and the records are the renderer's, `Renderer::memory`).
    pub fn memory(&self) -> Vec<LevelMemory> {
        let mut out: Vec<LevelMemory> = (0..=self.config.rings.coarsest)
            .map(|level| LevelMemory {
                level,
                ..LevelMemory::default()
            })
            .collect();
        for (&(l, _), &b) in &self.bytes {
            if let Some(m) = out.get_mut(usize::from(l)) {
                m.chunks += 1;
                m.quads += b / 8;
            }
        }
        out
    }

    /// Uploads the meshes of chunk `pos` of level `level`, and counts them.
    fn upload(
        &mut self,
        renderer: &mut Renderer,
        level: u8,
        pos: ChunkPos,
        m: &ChunkMeshes,
    ) -> Result<u64> {
        renderer.upload_level_chunk(level, pos, m)?;
        let b = 8 * m.len() as u64;
        self.bytes.insert((level, pos), b);
        Ok(b)
    }

    /// Sets the block at `pos` to `id` in the far view's terrain, at every level that
    /// holds it (every level whose cell samples the block's column,
    /// [`voxel_core::level_cell`]; level 0 always): the next [`FarField::update`] sends it
    /// to the worker, which meshes the drawn chunks it changes before anything else, and
    /// they are replaced as soon as they come back (so an edit is drawn after at most the
    /// batch the worker is meshing and its own chunks: [`FarStatus::edit_chunks_pending`] says
    /// when). Chunks made later carry it. A block id the registry does not hold is
    /// [`voxel_core::Error::UnknownBlock`], and nothing changes.
    pub fn set_block(&mut self, pos: WorldPos, id: BlockId) -> Result<()> {
        self.registry.get(id)?;
        self.new_edits
            .push(([i64::from(pos.x), i64::from(pos.y), i64::from(pos.z)], id));
        Ok(())
    }

    /// Whether the mesh of `key` made after the first `seen` edits lacks one of the others.
    fn stale(&self, key: &Key, seen: usize) -> bool {
        self.edits.get(seen..).is_some_and(|later| {
            later
                .iter()
                .any(|&e| chunks_an_edit_changes(e).contains(&(key.0, key.1)))
        })
    }

    /// Sends the edits taken since the last update to the worker, then the drawn chunks
    /// (and those of a view being swapped in) they change to be meshed again; meshes made
    /// for the view being built that they change are made again.
    fn send_edits(&mut self) -> Result<()> {
        if self.new_edits.is_empty() {
            return Ok(());
        }
        let mut changed: HashSet<(u8, ChunkPos)> = HashSet::new();
        for (block, id) in std::mem::take(&mut self.new_edits) {
            self.jobs.send(Job::Edit(block, id))?;
            self.edits.push(block);
            changed.extend(chunks_an_edit_changes(block));
        }
        let hit = |k: &&Key| changed.contains(&(k.0, k.1));
        let views: Vec<(LevelRings, [f64; 3], Vec<Key>)> = self
            .drawn
            .iter()
            .chain(self.swapping.as_ref().map(|s| &s.view))
            .map(|v| {
                (
                    v.rings.clone(),
                    v.at,
                    v.keys.iter().filter(hit).copied().collect(),
                )
            })
            .collect();
        for (rings, at, keys) in views {
            self.refreshing.extend(keys.iter().copied());
            for batch in keys.chunks(self.config.batch) {
                self.jobs.send(Job::Mesh(
                    Purpose::Refresh,
                    rings.clone(),
                    at,
                    batch.to_vec(),
                ))?;
            }
        }
        let stale: Vec<Key> = self.ready.keys().filter(hit).copied().collect();
        for k in &stale {
            self.ready.remove(k);
        }
        if let Some(t) = &mut self.target {
            let send: Vec<Key> = stale
                .into_iter()
                .filter(|k| t.keys.contains(k) && !self.in_flight.contains(k))
                .collect();
            t.pending.extend(send.iter().copied());
            self.in_flight.extend(send.iter().copied());
            let (rings, at) = (t.rings.clone(), t.at);
            for batch in send.chunks(self.config.batch) {
                self.jobs
                    .send(Job::Mesh(Purpose::View, rings.clone(), at, batch.to_vec()))?;
            }
        }
        Ok(())
    }

    /// Meshes of drawn chunks made again after edits came back: each replaces the drawn
    /// one (kept until a swap in progress ends). Returns how many were drawn.
    fn refresh(&mut self, renderer: &mut Renderer) -> Result<usize> {
        if self.swapping.is_some() {
            return Ok(0);
        }
        let mut n = 0;
        for (key, m) in std::mem::take(&mut self.refreshed) {
            if self.drawn.as_ref().is_some_and(|d| d.keys.contains(&key)) {
                self.upload(renderer, key.0, key.1, &m)?;
                n += 1;
            }
        }
        Ok(n)
    }

    /// Follows the eye at `eye` (world blocks): asks for a new plan when the eye left the
    /// anchor, takes the plans and meshes the worker made, sends the chunks a view lacks to
    /// be meshed, and swaps the view in when it is complete. Never waits for the worker. A
    /// NaN eye is ignored (the drawn view stays).
    pub fn update(&mut self, renderer: &mut Renderer, eye: DVec3) -> Result<FarStatus> {
        let mut status = FarStatus::default();
        // A view being swapped in is finished before the eye is followed again; the next
        // finer view is built meanwhile.
        if eye.is_finite() {
            if self.swapping.is_none() {
                self.follow(eye)?;
            } else {
                self.step_finer()?;
            }
        }
        self.send_edits()?;
        for done in self.jobs.done(&self.generator, &self.registry) {
            match done {
                Done::Planned(n, rings, keys) if self.planning == Some(n) => {
                    self.planning = None;
                    self.planned(rings, keys)?;
                }
                Done::Planned(..) => {}
                Done::Meshed(purpose, keys, seen, meshes) => {
                    let meshes = meshes.map_err(|e| {
                        Error::Unsupported(format!("the far field could not mesh a chunk: {e}"))
                    })?;
                    self.meshed(purpose, keys, seen as usize, meshes)?;
                }
            }
        }
        status.refreshed = self.refresh(renderer)?;
        if self.swapping.is_none() && self.target.as_ref().is_some_and(|t| t.pending.is_empty()) {
            self.start_swap();
        }
        let (bytes, swapped) = self.go_on_swapping(renderer)?;
        status.uploaded_bytes = bytes;
        if let Some(total) = swapped {
            status.swapped = true;
            status.swap_bytes = total;
        }
        status.drawn_finest = self.drawn.as_ref().map(|d| d.rings.finest);
        status.drawn_chunks = self.drawn.as_ref().map_or(0, |d| d.keys.len());
        status.ready = self.ready.len();
        status.missing = self.target.as_ref().map_or(0, |t| t.pending.len());
        status.edit_chunks_pending = self.refreshing.len() + self.refreshed.len();
        Ok(status)
    }

    /// Meshes came back from the worker, made after its first `seen` edits: those an edit
    /// sent since changes are made again (for the view being built) or dropped (a refresh:
    /// that edit sent its own); the others go to the view being built, or replace drawn
    /// chunks.
    fn meshed(
        &mut self,
        purpose: Purpose,
        keys: Vec<Key>,
        seen: usize,
        meshes: Vec<ChunkMeshes>,
    ) -> Result<()> {
        let mut again = Vec::new();
        for (k, m) in keys.into_iter().zip(meshes) {
            let stale = self.stale(&k, seen);
            match purpose {
                Purpose::View => {
                    if stale {
                        again.push(k);
                        continue;
                    }
                    self.in_flight.remove(&k);
                    if let Some(t) = &mut self.target {
                        t.pending.remove(&k);
                    }
                    self.ready.insert(k, m);
                }
                Purpose::Refresh => {
                    if stale {
                        continue;
                    }
                    // Made with every edit that changes it.
                    self.refreshing.remove(&k);
                    self.refreshed.insert(k, m);
                }
            }
        }
        if again.is_empty() {
            return Ok(());
        }
        match &self.target {
            Some(t) => {
                let (rings, at) = (t.rings.clone(), t.at);
                self.jobs.send(Job::Mesh(Purpose::View, rings, at, again))?;
            }
            None => {
                for k in &again {
                    self.in_flight.remove(k);
                }
            }
        }
        Ok(())
    }

    /// Asks for the plan of the finished view around the eye when it left the anchor (or
    /// there is none), or of the next finer view when the last one was drawn.
    fn follow(&mut self, eye: DVec3) -> Result<()> {
        let h = self.config.hysteresis;
        let moved = self
            .anchor
            .is_none_or(|a| (eye.x - a.x).abs() > h || (eye.z - a.z).abs() > h);
        if moved {
            self.anchor = Some(eye);
            self.target = None;
            return self.ask(self.config.rings.coarse_first(0));
        }
        self.step_finer()
    }

    /// The latest view: the one being swapped in, else the one drawn.
    fn latest(&self) -> Option<&View> {
        self.swapping
            .as_ref()
            .map(|s| &s.view)
            .or(self.drawn.as_ref())
    }

    /// Asks for the plan of the next finer coarse-first view when the latest one (drawn,
    /// or being swapped in) is not the finished view and nothing else is being built.
    fn step_finer(&mut self) -> Result<()> {
        if self.target.is_none()
            && self.planning.is_none()
            && let Some(finest) = self.latest().map(|d| d.rings.finest)
            && finest > 0
        {
            return self.ask(self.config.rings.coarse_first(finest - 1));
        }
        Ok(())
    }

    /// Asks the worker for the chunks of view `rings` around the anchor.
    fn ask(&mut self, rings: LevelRings) -> Result<()> {
        let Some(at) = self.anchor else { return Ok(()) };
        self.plans += 1;
        self.planning = Some(self.plans);
        self.jobs.send(Job::Plan(self.plans, rings, at.to_array()))
    }

    /// A plan came back: builds it, or, for a finished view whose horizon (its coarsest
    /// level) is less than half drawn (the first view, or after a jump), asks for its
    /// coarsest coarse-first view instead. (The horizon, not the whole view: a coarse-first
    /// view drawn holds the finished view's horizon but not its finer levels, and the
    /// finished view is its next step.)
    fn planned(&mut self, rings: LevelRings, keys: Vec<Key>) -> Result<()> {
        if rings.finest == 0 && rings.coarsest > 0 {
            let drawn: HashSet<(u8, ChunkPos)> = self
                .latest()
                .into_iter()
                .flat_map(|d| d.keys.iter().map(|&(l, p, _)| (l, p)))
                .collect();
            let horizon = keys.iter().filter(|k| k.0 == rings.coarsest);
            let kept = horizon
                .clone()
                .filter(|&&(l, p, _)| drawn.contains(&(l, p)))
                .count();
            if kept * 2 < horizon.count() {
                return self.ask(self.config.rings.coarse_first(rings.coarsest));
            }
        }
        // What the latest view holds is drawn, or will be when its swap ends.
        let drawn = self.latest().map(|d| &d.keys);
        let pending: HashSet<Key> = keys
            .iter()
            .filter(|k| !self.ready.contains_key(k) && !drawn.is_some_and(|d| d.contains(k)))
            .copied()
            .collect();
        let send: Vec<Key> = keys
            .iter()
            .filter(|k| pending.contains(k) && !self.in_flight.contains(k))
            .copied()
            .collect();
        let at = self.anchor.map_or([0.0; 3], |a| a.to_array());
        for batch in send.chunks(self.config.batch) {
            self.in_flight.extend(batch.iter().copied());
            self.jobs
                .send(Job::Mesh(Purpose::View, rings.clone(), at, batch.to_vec()))?;
        }
        self.target = Some(Target {
            rings,
            at,
            keys,
            pending,
        });
        Ok(())
    }

    /// Starts drawing the complete target view in place of the drawn one: the chunks to
    /// remove and to upload, grouped by the coarsest level's chunk they lie in (each group
    /// a tiling of its square in both views), nearest the anchor first.
    fn start_swap(&mut self) {
        let Some(target) = self.target.take() else {
            return;
        };
        let new: HashSet<Key> = target.keys.iter().copied().collect();
        let old = self
            .drawn
            .as_ref()
            .map(|d| d.keys.clone())
            .unwrap_or_default();
        let k = self.config.rings.coarsest;
        let cell = |&(l, p, _): &Key| {
            let d = 1i64 << (k - l.min(k));
            (i64::from(p.x).div_euclid(d), i64::from(p.z).div_euclid(d))
        };
        let mut groups: HashMap<(i64, i64), Group> = HashMap::new();
        for key in old.difference(&new) {
            groups.entry(cell(key)).or_default().0.push(*key);
        }
        for key in &target.keys {
            if old.contains(key) {
                continue;
            }
            if let Some(m) = self.ready.remove(key) {
                groups.entry(cell(key)).or_default().1.push((*key, m));
            }
        }
        let a = self.anchor.unwrap_or_default();
        let w = (voxel_core::CHUNK_SIZE as i64 * voxel_core::level_scale(k)) as f64;
        let mut groups: Vec<_> = groups.into_iter().collect();
        groups.sort_by(|(c, _), (d, _)| {
            let dist = |c: &(i64, i64)| {
                let (x, z) = ((c.0 as f64 + 0.5) * w - a.x, (c.1 as f64 + 0.5) * w - a.z);
                x * x + z * z
            };
            dist(c).total_cmp(&dist(d)).then(c.cmp(d))
        });
        self.swapping = Some(Swap {
            view: View {
                rings: target.rings,
                at: target.at,
                keys: new,
            },
            groups: groups.into_iter().map(|(_, g)| g).rev().collect(),
            bytes: 0,
        });
    }

    /// Goes on with the swap in progress: whole groups until [`FarConfig::upload_budget`]
    /// bytes are uploaded (at least one group). Returns the bytes uploaded, and the swap's
    /// bytes when it ended.
    fn go_on_swapping(&mut self, renderer: &mut Renderer) -> Result<(u64, Option<u64>)> {
        let Some(mut swap) = self.swapping.take() else {
            return Ok((0, None));
        };
        let mut bytes = 0;
        while let Some((remove, upload)) = swap.groups.pop() {
            // Removed first: a chunk kept under the same GPU key by both views (a level
            // chunk whose neighbours changed, or a coarse chunk and the first of the finer
            // ones that replace it) is replaced by the upload after.
            for &(l, p, _) in &remove {
                if let Some(k) = level_key(l, p) {
                    renderer.remove_chunk(k);
                }
                self.bytes.remove(&(l, p));
            }
            for ((l, p, _), m) in &upload {
                bytes += self.upload(renderer, *l, *p, m)?;
            }
            if bytes >= self.config.upload_budget {
                break;
            }
        }
        swap.bytes += bytes;
        if !swap.groups.is_empty() {
            self.swapping = Some(swap);
            return Ok((bytes, None));
        }
        let total = swap.bytes;
        self.drawn = Some(swap.view);
        // Meshes of views no longer wanted go (those of the view being built stay); those
        // in flight stay wanted.
        match &self.target {
            Some(t) => {
                let wanted: HashSet<&Key> = t.keys.iter().collect();
                self.ready.retain(|k, _| wanted.contains(k));
            }
            None => self.ready.clear(),
        }
        Ok((bytes, Some(total)))
    }
}

/// The chunks of one square of the coarsest level a swap removes, and those it uploads.
type Group = (Vec<Key>, Vec<(Key, ChunkMeshes)>);

/// A view being swapped in, a group of chunks at a time: the view, the groups left
/// (removals and uploads; the next is last), and the bytes uploaded so far.
struct Swap {
    view: View,
    groups: Vec<Group>,
    bytes: u64,
}
