//! Sun shadows and the light volume over a lit streamer's chunks ([`SunFeed`]).

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use glam::DVec3;
use voxel_core::{ChunkPos, LightChunk, WorldPos};

use super::ChunkStreamer;
use super::schedule::StreamFrame;
use crate::{MAX_LIGHT_CHUNKS, MAX_SUN_CHUNKS, Renderer, Result, SunRegion};

/// Keeps a renderer's sun shadows (`docs/light.md`, "Sun shadows") and, on a lit
/// streamer, its light volume ("Light for a game's things") over the chunks a
/// [`ChunkStreamer`] holds around the eye, as they stream: one per renderer, called after
/// each [`ChunkStreamer::update`]. The sun's light dims and tints only on lit chunks
/// ([`ChunkStreamer::set_light`]).
#[derive(Debug, Default)]
pub struct SunFeed {
    /// The region's chunks read into the volume with their blocks. One read before its
    /// blocks came in read as air; it is read again when they are resident.
    read: HashSet<ChunkPos>,
    /// The light volume's chunks, with the light snapshot each was read with: a chunk is
    /// read again when the streamer's snapshot is another.
    lights: HashMap<ChunkPos, Arc<LightChunk>>,
}

/// A region of `chunks` an axis centred on `at`'s chunk.
fn centred(at: WorldPos, chunks: u32) -> SunRegion {
    let (c, _) = at.split();
    let half = (chunks / 2) as i32;
    SunRegion {
        min: ChunkPos::new(
            c.x.saturating_sub(half),
            c.y.saturating_sub(half),
            c.z.saturating_sub(half),
        ),
        chunks: [chunks; 3],
    }
}

impl SunFeed {
    /// A feed that has read nothing: its first [`SunFeed::update`] turns the shadows on.
    pub fn new() -> Self {
        Self::default()
    }

    /// The first call turns `renderer`'s sun shadows on over [`MAX_SUN_CHUNKS`] chunks
    /// along each axis centred on `eye`'s chunk ([`Renderer::set_sun_shadows`]); each call
    /// then moves the region with the eye along x and z ([`Renderer::follow_sun_shadows`]),
    /// reads each of its chunks once its blocks are resident, and reads again the chunks
    /// `frame` uploaded (an edit changed their blocks). Fails as
    /// [`Renderer::set_sun_shadows`] does (a region the adapter cannot hold).
    pub fn update(
        &mut self,
        renderer: &mut Renderer,
        streamer: &ChunkStreamer,
        eye: DVec3,
        frame: &StreamFrame,
    ) -> Result<()> {
        let world = streamer.world();
        let at = WorldPos::containing(eye.to_array());
        let region = match renderer.sun_region() {
            Some(old) => {
                renderer.follow_sun_shadows(world, at);
                let new = renderer.sun_region().unwrap_or(old);
                // Follow read the chunks that came in from the world as it is now.
                self.read.retain(|p| new.contains(*p));
                let came: Vec<ChunkPos> = new.positions().filter(|p| !old.contains(*p)).collect();
                self.read
                    .extend(came.into_iter().filter(|p| streamer.is_resident(*p)));
                new
            }
            None => {
                let region = centred(at, MAX_SUN_CHUNKS);
                renderer.set_sun_shadows(world, region)?;
                self.read = region
                    .positions()
                    .filter(|p| streamer.is_resident(*p))
                    .collect();
                region
            }
        };
        let mut fresh: Vec<ChunkPos> = region
            .positions()
            .filter(|p| !self.read.contains(p) && streamer.is_resident(*p))
            .collect();
        self.read.extend(fresh.iter().copied());
        fresh.extend(frame.uploaded.iter().filter(|p| region.contains(**p)));
        if !fresh.is_empty() {
            renderer.update_sun_shadows(world, &fresh);
        }
        if streamer.has_light() {
            self.update_light(renderer, streamer, at, frame)?;
        }
        Ok(())
    }

    /// The light volume: made over [`MAX_LIGHT_CHUNKS`] chunks an axis centred on `at`'s
    /// chunk on the first call, then moved with it; each chunk read again when its light
    /// snapshot changes, or `frame` uploaded it (its blocks changed).
    fn update_light(
        &mut self,
        renderer: &mut Renderer,
        streamer: &ChunkStreamer,
        at: WorldPos,
        frame: &StreamFrame,
    ) -> Result<()> {
        let world = streamer.world();
        let light = |p: ChunkPos| streamer.light_chunk(p);
        // The chunks read now with the light they were read with.
        let (region, came) = match renderer.light_region() {
            Some(old) => {
                renderer.follow_light_volume(world, &light, at);
                let new = renderer.light_region().unwrap_or(old);
                self.lights.retain(|p, _| new.contains(*p));
                (new, new.positions().filter(|p| !old.contains(*p)).collect())
            }
            None => {
                let region = centred(at, MAX_LIGHT_CHUNKS);
                renderer.set_light_volume(world, &light, region)?;
                self.lights.clear();
                (region, region.positions().collect::<Vec<_>>())
            }
        };
        for pos in came {
            if let Some(l) = light(pos) {
                self.lights.insert(pos, l);
            }
        }
        let mut changed = Vec::new();
        for pos in region.positions() {
            let now = light(pos);
            let same = match (self.lights.get(&pos), &now) {
                (Some(old), Some(now)) => Arc::ptr_eq(old, now),
                (None, None) => true,
                _ => false,
            };
            if !same || frame.uploaded.contains(&pos) {
                changed.push(pos);
            }
            match now {
                Some(now) => self.lights.insert(pos, now),
                None => self.lights.remove(&pos),
            };
        }
        if !changed.is_empty() {
            renderer.update_light_volume(world, &light, &changed);
        }
        Ok(())
    }
}
