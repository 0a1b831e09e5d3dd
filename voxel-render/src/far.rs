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
//!   next view is ready, one [`FarField::update`] uploads the meshes it lacks and removes the
//!   chunks it no longer has. A mesh depends on which of its neighbours the view holds
//!   (water only across a level border), so meshes are kept by chunk and those neighbours,
//!   and a chunk whose border changed is meshed again.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use glam::DVec3;
use voxel_core::{BlockRegistry, ChunkPos, TerrainGenerator};
use voxel_mesh::ChunkMeshes;
use voxel_mesh::levels::{LevelRings, mesh_level_chunks};

use crate::{Error, Renderer, Result, level_key};

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
}

impl Default for FarConfig {
    fn default() -> Self {
        Self {
            rings: LevelRings::reaching(32, 512),
            hysteresis: 16.0,
            batch: 256,
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
    /// Whether this update swapped a view in.
    pub swapped: bool,
    /// Bytes of quads uploaded by this update.
    pub uploaded_bytes: u64,
}

/// The levels of detail of generated terrain around a moving eye, on a [`Renderer`]'s GPU:
/// see the module docs. Call [`FarField::update`] once a frame with the eye; it never
/// waits for meshing.
pub struct FarField {
    generator: Arc<TerrainGenerator>,
    registry: Arc<BlockRegistry>,
    config: FarConfig,
    /// The eye the target view is planned around.
    anchor: Option<DVec3>,
    /// The view being built (a coarse-first view, then the finished one), its chunks.
    target: Option<(LevelRings, [f64; 3], Vec<Key>)>,
    /// The view drawn: its finest level and chunks.
    drawn: Option<(u8, HashSet<Key>)>,
    /// Meshes made, by chunk and neighbours held.
    ready: HashMap<Key, ChunkMeshes>,
    /// Chunks sent to be meshed and not back yet.
    in_flight: HashSet<Key>,
    jobs: Jobs,
}

impl std::fmt::Debug for FarField {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FarField")
            .field("config", &self.config)
            .field("anchor", &self.anchor)
            .field("drawn", &self.drawn.as_ref().map(|(l, d)| (*l, d.len())))
            .field("ready", &self.ready.len())
            .field("in_flight", &self.in_flight.len())
            .finish_non_exhaustive()
    }
}

/// A job: the view (rings and eye) and the chunks to mesh for it.
type Job = (LevelRings, [f64; 3], Vec<Key>);
/// A job's result.
type Done = (
    Vec<Key>,
    std::result::Result<Vec<ChunkMeshes>, voxel_mesh::Error>,
);

/// Where meshing runs: a worker thread, or (wasm32) the updating thread.
struct Jobs {
    #[cfg(not(target_arch = "wasm32"))]
    send: std::sync::mpsc::Sender<Job>,
    #[cfg(not(target_arch = "wasm32"))]
    receive: std::sync::mpsc::Receiver<Done>,
    #[cfg(target_arch = "wasm32")]
    queue: Vec<Job>,
}

fn run_job(generator: &TerrainGenerator, registry: &BlockRegistry, job: Job) -> Done {
    let (rings, eye, keys) = job;
    let chunks: Vec<(u8, ChunkPos)> = keys.iter().map(|&(l, p, _)| (l, p)).collect();
    let meshes = mesh_level_chunks(generator, registry, &rings, eye, &chunks)
        .map(|v| v.into_iter().map(|(_, _, m)| m).collect());
    (keys, meshes)
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
                    for job in jobs {
                        if done.send(run_job(&g, &r, job)).is_err() {
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
            Self { queue: Vec::new() }
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
            self.queue.push(job);
            Ok(())
        }
    }

    /// The jobs done since the last call (wasm32: runs one queued job).
    fn done(&mut self, _generator: &TerrainGenerator, _registry: &BlockRegistry) -> Vec<Done> {
        #[cfg(not(target_arch = "wasm32"))]
        {
            self.receive.try_iter().collect()
        }
        #[cfg(target_arch = "wasm32")]
        {
            if self.queue.is_empty() {
                return Vec::new();
            }
            let job = self.queue.remove(0);
            vec![run_job(_generator, _registry, job)]
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
            target: None,
            drawn: None,
            ready: HashMap::new(),
            in_flight: HashSet::new(),
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
            .flat_map(|(_, d)| d.iter().map(|&(l, p, _)| (l, p)))
    }

    /// Follows the eye at `eye` (world blocks): plans the view when the eye left the
    /// anchor, sends the chunks it lacks to be meshed, takes the meshes made, and swaps the
    /// next view in when it is complete. Never waits for meshing. A NaN eye is ignored (the
    /// drawn view stays).
    pub fn update(&mut self, renderer: &mut Renderer, eye: DVec3) -> Result<FarStatus> {
        let mut status = FarStatus::default();
        if eye.is_finite() {
            self.plan(eye);
        }
        for (keys, meshes) in self.jobs.done(&self.generator, &self.registry) {
            for k in &keys {
                self.in_flight.remove(k);
            }
            let meshes = meshes.map_err(|e| {
                Error::Unsupported(format!("the far field could not mesh a chunk: {e}"))
            })?;
            for (k, m) in keys.into_iter().zip(meshes) {
                self.ready.insert(k, m);
            }
        }
        let Some((rings, at, keys)) = self.target.clone() else {
            return Ok(self.status(status));
        };
        let drawn = self.drawn.as_ref().map(|(_, d)| d);
        let missing: Vec<Key> = keys
            .iter()
            .filter(|k| {
                !self.ready.contains_key(k)
                    && !self.in_flight.contains(k)
                    && !drawn.is_some_and(|d| d.contains(k))
            })
            .copied()
            .collect();
        for batch in missing.chunks(self.config.batch) {
            self.in_flight.extend(batch.iter().copied());
            self.jobs.send((rings.clone(), at, batch.to_vec()))?;
        }
        let complete = keys
            .iter()
            .all(|k| self.ready.contains_key(k) || drawn.is_some_and(|d| d.contains(k)));
        if complete {
            status.uploaded_bytes = self.swap(renderer, &rings, &keys)?;
            status.swapped = true;
        }
        Ok(self.status(status))
    }

    fn status(&self, mut status: FarStatus) -> FarStatus {
        status.drawn_finest = self.drawn.as_ref().map(|(l, _)| *l);
        status.drawn_chunks = self.drawn.as_ref().map_or(0, |(_, d)| d.len());
        status.ready = self.ready.len();
        status.missing = self.target.as_ref().map_or(0, |(_, _, keys)| {
            keys.iter()
                .filter(|k| {
                    !self.ready.contains_key(k)
                        && !self.drawn.as_ref().is_some_and(|(_, d)| d.contains(k))
                })
                .count()
        });
        status
    }

    /// Moves the anchor to the eye when it left it (or there is none), and picks the view
    /// to build: the finished view, or, where little of it is drawn, the coarsest
    /// coarse-first view not drawn yet.
    fn plan(&mut self, eye: DVec3) {
        let h = self.config.hysteresis;
        let moved = self
            .anchor
            .is_none_or(|a| (eye.x - a.x).abs() > h || (eye.z - a.z).abs() > h);
        let rings = &self.config.rings;
        if moved {
            self.anchor = Some(eye);
            let at = eye.to_array();
            let finished = rings.coarse_first(0);
            let keys = Self::keys(&finished, at);
            // Chunks of the finished view drawn already (whatever their neighbours).
            let drawn: HashSet<(u8, ChunkPos)> = self.drawn().collect();
            let kept = keys
                .iter()
                .filter(|&&(l, p, _)| drawn.contains(&(l, p)))
                .count();
            // Most of the view drawn already: build the finished one; else coarse first.
            let finest = if kept * 2 >= keys.len() {
                0
            } else {
                rings.coarsest
            };
            let plan = rings.coarse_first(finest);
            let keys = Self::keys(&plan, at);
            self.target = Some((plan, at, keys));
        } else if self.target.is_none() {
            // The target was drawn: go on one level finer.
            if let (Some((finest, _)), Some(a)) = (&self.drawn, self.anchor)
                && *finest > 0
            {
                let plan = rings.coarse_first(finest - 1);
                let at = a.to_array();
                let keys = Self::keys(&plan, at);
                self.target = Some((plan, at, keys));
            }
        }
    }

    fn keys(rings: &LevelRings, eye: [f64; 3]) -> Vec<Key> {
        rings
            .all(eye)
            .into_iter()
            .map(|(l, p)| (l, p, rings.neighbours_held(l, p, eye)))
            .collect()
    }

    /// Draws the view of `keys` in place of the drawn one; returns the bytes of quads
    /// uploaded.
    fn swap(&mut self, renderer: &mut Renderer, rings: &LevelRings, keys: &[Key]) -> Result<u64> {
        let new: HashSet<Key> = keys.iter().copied().collect();
        let old = self.drawn.take().map(|(_, d)| d).unwrap_or_default();
        // Removed first: a chunk kept under the same GPU key by both views (a level chunk
        // whose neighbours changed) is replaced by the upload below.
        for &(l, p, _) in old.difference(&new) {
            if let Some(k) = level_key(l, p) {
                renderer.remove_chunk(k);
            }
        }
        let mut bytes = 0;
        for k in keys {
            if old.contains(k) {
                continue;
            }
            if let Some(m) = self.ready.remove(k) {
                bytes += 8 * m.len() as u64;
                renderer.upload_level_chunk(k.0, k.1, &m)?;
            }
        }
        self.drawn = Some((rings.finest, new));
        self.target = None;
        // Meshes of views no longer wanted go.
        self.ready.clear();
        Ok(bytes)
    }
}
