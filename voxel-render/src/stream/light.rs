//! Light as chunks stream ([`ChunkStreamer::set_light`]): a [`LightField`] over the
//! resident chunks, updated on a worker, one job at a time, so that no update waits for it
//! (lighting a chunk of terrain takes about 2 ms, unlighting one as long).
//!
//! - **Two worlds.** The light job owns a [`LitWorld`]: its own [`World`] (the streamer's
//!   chunks, shared, not copied, plus the resident air chunks, so that light and the sky
//!   fill them) and the field. The streamer queues what happens to its blocks as
//!   [`LightOp`]s (a chunk in, packed, out; a block set) and sends them, in order, with
//!   the [`LitWorld`] to one job when none is in flight. So the job's world is always the
//!   streamer's world as it was some updates ago, and the field the light of that world.
//! - **Snapshots.** The job sends back, with the [`LitWorld`], a snapshot of the light of
//!   every chunk whose light changed ([`LightField::take_changed`]): the streamer keeps
//!   them (`lights`), and a mesh job reads the 27 of its chunk's neighbourhood
//!   ([`voxel_mesh::Mesher::mesh_lit_from`]). A chunk is meshed only when it and its 26
//!   neighbours are lit; a chunk drawn whose light or whose neighbours' light changed is
//!   meshed again. Once idle (no op waiting, no light job in flight, nothing to mesh),
//!   every drawn chunk holds the meshes [`voxel_mesh::Mesher::mesh_lit`] makes with the
//!   light [`LightField::new`] gives the resident chunks.
//! - **A light job that panics** (a bug: the field does not fail on valid blocks) loses
//!   its field: it is reported, and a new one is built from the resident chunks.

use std::collections::HashMap;
use std::sync::Arc;

use voxel_core::{
    BlockId, BlockRegistry, Chunk, ChunkPos, LightChunk, LightField, World, WorldPos,
};

use super::ChunkStreamer;
use super::slot::State;

/// The light job's world and field.
pub(super) struct LitWorld {
    world: World,
    field: LightField,
}

/// What happened to the streamer's blocks, for the light job to do to its world.
pub(super) enum LightOp {
    /// A chunk came in (air ones too), or was generated again.
    Insert(ChunkPos, Arc<Chunk>),
    /// The same blocks in another form (packed): nothing to light.
    Replace(ChunkPos, Arc<Chunk>),
    /// A chunk left memory.
    Remove(ChunkPos),
    /// A block was set.
    Set(WorldPos, BlockId),
}

/// The streamer's light: see the module docs.
pub(super) struct StreamLight {
    /// Tells this light's jobs from those of a light turned off and on again.
    epoch: u64,
    /// The job's world and field, while no job has them.
    home: Option<Box<LitWorld>>,
    /// What happened since the last job left.
    ops: Vec<LightOp>,
    /// The light of the lit chunks, as of the last job back.
    pub(super) lights: HashMap<ChunkPos, Arc<LightChunk>>,
    /// An air chunk, shared by every air position of the job's world.
    air: Arc<Chunk>,
}

impl StreamLight {
    /// Whether no op waits and no job is in flight.
    pub(super) fn is_idle(&self) -> bool {
        self.ops.is_empty() && self.home.is_some()
    }

    /// The world, the ops and the epoch for a light job, if ops wait and no job is in
    /// flight.
    pub(super) fn take_job(&mut self) -> Option<(Box<LitWorld>, Vec<LightOp>, u64)> {
        if self.ops.is_empty() {
            return None;
        }
        let lit = self.home.take()?;
        Some((lit, std::mem::take(&mut self.ops), self.epoch))
    }

    pub(super) fn push(&mut self, op: LightOp) {
        self.ops.push(op);
    }

    /// [`LightOp::Insert`] of the blocks at `pos`: `chunk`, or air.
    pub(super) fn insert(&mut self, pos: ChunkPos, chunk: Option<Arc<Chunk>>) {
        let chunk = chunk.unwrap_or_else(|| self.air.clone());
        self.ops.push(LightOp::Insert(pos, chunk));
    }

    /// Whether `pos`'s chunk and its 26 neighbours (those that exist) are lit.
    pub(super) fn lit_around(&self, pos: ChunkPos) -> bool {
        around(pos).all(|p| p.is_none_or(|p| self.lights.contains_key(&p)))
    }

    /// The light of `pos`'s chunk and its 26 neighbours, by `(dx + 1) * 9 + (dy + 1) * 3 +
    /// (dz + 1)`; `None` unless all of them that exist are lit.
    pub(super) fn neighbourhood(&self, pos: ChunkPos) -> Option<[Option<Arc<LightChunk>>; 27]> {
        let mut out: [Option<Arc<LightChunk>>; 27] = Default::default();
        for (o, p) in out.iter_mut().zip(around(pos)) {
            if let Some(p) = p {
                *o = Some(self.lights.get(&p)?.clone());
            }
        }
        Some(out)
    }
}

/// `pos` and its 26 neighbours, by `(dx + 1) * 9 + (dy + 1) * 3 + (dz + 1)` (`None` past
/// the world's edge).
fn around(pos: ChunkPos) -> impl Iterator<Item = Option<ChunkPos>> {
    (0..27).map(move |i| pos.offset([i / 9, i / 3 % 3, i % 3].map(|v| v - 1)))
}

/// A light snapshot per chunk whose light changed (`None`: no longer lit).
pub(super) type Snapshots = Vec<(ChunkPos, Option<Arc<LightChunk>>)>;

/// Runs `ops` on `lit`: the snapshots of the chunks whose light changed, and the ops that
/// failed, with why.
pub(super) fn light_job(
    lit: &mut LitWorld,
    ops: Vec<LightOp>,
) -> (Snapshots, Vec<(ChunkPos, String)>) {
    let LitWorld { world, field } = lit;
    let mut failed = Vec::new();
    let mut removed = Vec::new();
    // Chunks come in many at a time: lit together, with one flood.
    let mut batch: Vec<ChunkPos> = Vec::new();
    for op in ops {
        let (pos, done) = match op {
            LightOp::Insert(pos, chunk) => {
                let done = world.insert_shared(pos, chunk).map(drop);
                if done.is_ok() {
                    batch.push(pos);
                }
                (pos, done)
            }
            // The same blocks: nothing to light.
            LightOp::Replace(pos, chunk) => (pos, world.insert_shared(pos, chunk).map(drop)),
            LightOp::Remove(pos) => {
                light_batch(&mut batch, world, field, &mut failed);
                let done = field.remove_chunk(world, pos).map(drop);
                world.remove_shared(pos);
                removed.push(pos);
                (pos, done)
            }
            LightOp::Set(at, id) => {
                light_batch(&mut batch, world, field, &mut failed);
                (at.split().0, field.set_block(world, at, id).map(drop))
            }
        };
        if let Err(e) = done {
            failed.push((pos, format!("light: {e}")));
        }
    }
    light_batch(&mut batch, world, field, &mut failed);
    // Blocks set are not edits the job's world keeps track of.
    world.take_dirty();
    let mut changed: Vec<_> = field
        .take_changed()
        .into_iter()
        .map(|p| {
            field.compact_chunk(p);
            (p, field.shared(p))
        })
        .collect();
    changed.extend(
        removed
            .into_iter()
            .filter(|p| !field.is_lit(*p))
            .map(|p| (p, None)),
    );
    (changed, failed)
}

/// Lights the chunks of `batch` (in `world`, not lit yet) with one flood, and empties it.
fn light_batch(
    batch: &mut Vec<ChunkPos>,
    world: &World,
    field: &mut LightField,
    failed: &mut Vec<(ChunkPos, String)>,
) {
    if let Err(e) = field.add_chunks(world, batch) {
        failed.extend(batch.iter().map(|p| (*p, format!("light: {e}"))));
    }
    batch.clear();
}

impl ChunkStreamer {
    /// Turns light on or off: with it on, every chunk is meshed with the light of a
    /// [`LightField`] over the resident chunks ([`voxel_mesh::Mesher::mesh_lit`]), lit on
    /// a worker as chunks stream in, go and are edited, never on the updating thread
    /// beyond queueing what changed (where the streamer has worker threads). A chunk is
    /// meshed once it and its 26 neighbours are lit; one whose light changes is meshed
    /// again. Turned on or off while streaming, every drawn chunk is meshed again. Once
    /// idle, every drawn chunk holds the meshes of the resident world's light
    /// ([`LightField::new`] of the resident chunks, air ones included). The registry's
    /// light sources ([`voxel_core::BlockDef::emission`]) glow; the sky lights every
    /// column from above its highest resident chunk.
    pub fn set_light(&mut self, on: bool) {
        if on == self.light.is_some() {
            return;
        }
        let epoch = self.next_version();
        self.light = on.then(|| {
            let registry: Arc<BlockRegistry> = self.registry.clone();
            let mut light = StreamLight {
                epoch,
                home: Some(Box::new(LitWorld {
                    world: World::new(registry.clone()),
                    field: LightField::empty(registry),
                })),
                ops: Vec::new(),
                lights: HashMap::new(),
                air: Arc::new(Chunk::default()),
            };
            for (&pos, slot) in &self.slots {
                if slot.has_blocks() {
                    light.insert(pos, self.world.shared(pos));
                }
            }
            light
        });
        let drawn: Vec<ChunkPos> = self.slots.keys().copied().collect();
        for pos in drawn {
            self.stale(pos);
        }
    }

    /// [`ChunkStreamer::set_light`]`(true)`, for a streamer being made.
    pub fn with_light(mut self) -> Self {
        self.set_light(true);
        self
    }

    /// Whether light is on ([`ChunkStreamer::set_light`]).
    pub fn has_light(&self) -> bool {
        self.light.is_some()
    }

    /// The light at `pos` as the last light job left it (`None` where light is off or
    /// its chunk is not lit yet): what a game's content standing there is lit by.
    pub fn light_at(&self, pos: WorldPos) -> Option<voxel_core::Light> {
        let (c, [x, y, z]) = pos.split();
        self.light.as_ref()?.lights.get(&c)?.get(x, y, z)
    }

    /// The light of the chunk at `pos` as the last light job left it, if lit.
    pub fn light_chunk(&self, pos: ChunkPos) -> Option<Arc<LightChunk>> {
        self.light.as_ref()?.lights.get(&pos).cloned()
    }

    /// Bytes of the light snapshots held (the light job's field shares them, besides the
    /// chunks written since).
    pub fn light_bytes(&self) -> usize {
        self.light
            .as_ref()
            .map_or(0, |l| l.lights.values().map(|c| c.memory_bytes()).sum())
    }

    /// Marks the chunk at `pos` as not meshed for what it holds now (a job in flight comes
    /// back to nothing) and queues it, if it has meshes drawn or on their way.
    pub(super) fn stale(&mut self, pos: ChunkPos) {
        let version = self.next_version();
        if let Some(slot) = self.slots.get_mut(&pos)
            && matches!(slot.state, State::Meshing | State::Ready | State::Meshed)
            && !slot.failed
        {
            slot.version = version;
            slot.state = State::Generated;
            self.queue_remesh(pos);
        }
    }

    /// Takes a light job's result in: its snapshots, and the chunks to mesh again.
    pub(super) fn receive_light(
        &mut self,
        epoch: u64,
        lit: Option<Box<LitWorld>>,
        changed: Snapshots,
        failed: &mut Vec<(ChunkPos, String)>,
    ) {
        let Some(light) = self.light.as_mut().filter(|l| l.epoch == epoch) else {
            return;
        };
        let Some(lit) = lit else {
            // The field is lost: light the resident chunks again.
            failed.push((
                ChunkPos::new(0, 0, 0),
                "the light job panicked: lighting the resident chunks again".into(),
            ));
            self.light = None;
            self.set_light(true);
            return;
        };
        light.home = Some(lit);
        let mut touched = Vec::with_capacity(changed.len());
        for (pos, snapshot) in changed {
            match snapshot {
                Some(s) => light.lights.insert(pos, s),
                None => light.lights.remove(&pos),
            };
            touched.push(pos);
        }
        // A chunk's border vertices read its neighbours' light.
        for pos in touched {
            for d in voxel_core::Neighbourhood::OFFSETS
                .iter()
                .chain([&[0, 0, 0]])
            {
                if let Some(n) = pos.offset(*d) {
                    self.stale(n);
                }
            }
        }
    }
}
