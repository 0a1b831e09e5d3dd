//! Sun shadows over a lit streamer's chunks ([`SunFeed`]).

use std::collections::HashSet;

use glam::DVec3;
use voxel_core::{ChunkPos, WorldPos};

use super::ChunkStreamer;
use super::schedule::StreamFrame;
use crate::{MAX_SUN_CHUNKS, Renderer, Result, SunRegion};

/// Keeps a renderer's sun shadows (`docs/light.md`, "Sun shadows") over the chunks a
/// [`ChunkStreamer`] holds around the eye, as they stream: one per renderer, called after
/// each [`ChunkStreamer::update`]. The sun's light dims and tints only on lit chunks
/// ([`ChunkStreamer::set_light`]).
#[derive(Debug, Default)]
pub struct SunFeed {
    /// The region's chunks read into the volume with their blocks. One read before its
    /// blocks came in read as air; it is read again when they are resident.
    read: HashSet<ChunkPos>,
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
                let (c, _) = at.split();
                let half = (MAX_SUN_CHUNKS / 2) as i32;
                let region = SunRegion {
                    min: ChunkPos::new(
                        c.x.saturating_sub(half),
                        c.y.saturating_sub(half),
                        c.z.saturating_sub(half),
                    ),
                    chunks: [MAX_SUN_CHUNKS; 3],
                };
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
        Ok(())
    }
}
