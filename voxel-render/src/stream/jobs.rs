//! The jobs the streamer's pool runs: generating a chunk (the source's blocks checked,
//! its edits applied) and meshing one, and what they send back ([`Done`]).

use std::panic::AssertUnwindSafe;
use std::sync::Arc;
use std::sync::atomic::Ordering;

use voxel_core::{BlockRegistry, Chunk, ChunkPos, LightChunk, Neighbourhood};
use voxel_mesh::{ChunkMeshes, Mesher};

use super::ChunkStreamer;
use super::light::{LitWorld, Snapshots, StreamLight, light_job};
use super::slot::{Ready, Slot, State};
use super::source::generate_checked;

/// What a job sends back to the streamer.
pub(super) enum Done {
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
    /// A light job's result (see `light`): its world and field back (`None`: it
    /// panicked), the snapshots of the chunks whose light changed, what failed.
    Lit {
        epoch: u64,
        lit: Option<Box<LitWorld>>,
        changed: Snapshots,
        failed: Vec<(ChunkPos, String)>,
    },
}

/// The light of a chunk's neighbourhood, by `(dx + 1) * 9 + (dy + 1) * 3 + (dz + 1)`.
type Lights = [Option<Arc<LightChunk>>; 27];

thread_local! {
    /// Each worker's mesher (its scratch reused), for the registry it was made for.
    static MESHER: std::cell::RefCell<Option<(usize, Mesher)>> = const { std::cell::RefCell::new(None) };
}

fn mesh_on_worker(
    registry: &Arc<BlockRegistry>,
    centre: &Chunk,
    neighbours: &[Option<Arc<Chunk>>; 26],
    lights: Option<&Lights>,
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
        match lights {
            Some(lights) => {
                let mut out = ChunkMeshes::default();
                let light = |d: [i32; 3]| {
                    let i = (d[0] + 1) * 9 + (d[1] + 1) * 3 + (d[2] + 1);
                    lights[i as usize].as_deref()
                };
                mesher
                    .mesh_lit_from(centre, nb, light, &mut out)
                    .map(|()| out)
            }
            None => mesher.mesh(centre, nb),
        }
        .map_err(|e| e.to_string())
    })
}

impl ChunkStreamer {
    pub(super) fn generate(&mut self, pos: ChunkPos, centre: ChunkPos) {
        let version = self.next_version();
        self.slots
            .insert(pos, Slot::new(State::Generating, version));
        // A chunk outside the view distance is only a neighbour: packed at once.
        let pack = !self.wanted(pos, centre);
        let source = self.source.clone();
        let registry = self.registry.clone();
        let edits = self.edits.get(&pos).cloned();
        self.spawn(
            move || match generate_checked(&*source, &registry, pos, edits.as_deref()) {
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
            },
        );
    }

    pub(super) fn mesh(&mut self, pos: ChunkPos) {
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
        let lights = match &self.light {
            Some(light) => match light.neighbourhood(pos) {
                Some(l) => Some(l),
                // Not lit yet (`meshable` waits for it): meshed when it is.
                None => return,
            },
            None => None,
        };
        let Some(slot) = self.slots.get_mut(&pos) else {
            return;
        };
        slot.state = State::Meshing;
        let version = slot.version;
        let neighbours =
            Neighbourhood::OFFSETS.map(|d| pos.offset(d).and_then(|n| self.world.shared(n)));
        let registry = self.registry.clone();
        self.spawn(move || {
            std::panic::catch_unwind(AssertUnwindSafe(|| {
                let meshes = mesh_on_worker(&registry, &centre, &neighbours, lights.as_ref());
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
            })
        });
    }

    /// Sends what happened to the blocks to a light job (see `light`), if none is in
    /// flight.
    pub(super) fn dispatch_light(&mut self) {
        if self.jobs >= self.config.max_jobs {
            return;
        }
        let Some((mut lit, ops, epoch)) = self.light.as_mut().and_then(StreamLight::take_job)
        else {
            return;
        };
        self.spawn(move || {
            match std::panic::catch_unwind(AssertUnwindSafe(|| light_job(&mut lit, ops))) {
                Ok((changed, failed)) => Done::Lit {
                    epoch,
                    lit: Some(lit),
                    changed,
                    failed,
                },
                Err(_) => Done::Lit {
                    epoch,
                    lit: None,
                    changed: Vec::new(),
                    failed: Vec::new(),
                },
            }
        });
    }

    /// Runs `job` on the pool and sends what it made back, unless the streamer was dropped
    /// before the job started.
    pub(super) fn spawn(&mut self, job: impl FnOnce() -> Done + Send + 'static) {
        let tx = self.tx.clone();
        let cancelled = self.cancelled.clone();
        self.jobs += 1;
        self.pool.spawn(move || {
            if cancelled.load(Ordering::Relaxed) {
                return;
            }
            let _ = tx.send(job());
        });
    }
}
