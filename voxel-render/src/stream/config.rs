//! How far and how fast the streamer works: [`StreamConfig`] and its ranges.

use std::time::Duration;

use crate::{Error, Result};

/// The largest view distance (and vertical distance) in chunks: 64 chunks is 2048 blocks
/// each way, about 116 000 positions with the default vertical distance.
pub const MAX_VIEW_DISTANCE: u32 = 64;

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
    /// the streamer is made. Not read on wasm32 (no threads) nor by
    /// [`ChunkStreamer::new_local`]: see [`StreamConfig::local_budget`].
    ///
    /// [`ChunkStreamer::new_local`]: super::ChunkStreamer::new_local
    pub threads: usize,
    /// Where jobs run on the updating thread (wasm32, [`ChunkStreamer::new_local`]): the
    /// time each update spends generating and meshing at most, past the job that crosses
    /// it (at least one job runs per update), up to 1 s. Default 4 ms: a quarter of a
    /// 60 Hz frame. Not read where worker threads do the jobs.
    ///
    /// [`ChunkStreamer::new_local`]: super::ChunkStreamer::new_local
    pub local_budget: Duration,
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
            local_budget: Duration::from_millis(4),
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
        if self.local_budget > Duration::from_secs(1) {
            return bad(format!(
                "local budget {:?}: at most 1 s per update",
                self.local_budget
            ));
        }
        if self.max_jobs == 0 || self.max_unloads == 0 || self.scan_budget == 0 {
            return bad("max_jobs, max_unloads and scan_budget must be at least 1".into());
        }
        Ok(())
    }
}
