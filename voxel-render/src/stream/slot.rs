//! How far along each position is: its [`State`], the [`Slot`] that holds it, and a
//! finished mesh waiting for its upload ([`Ready`]).

use voxel_core::ChunkPos;
use voxel_mesh::ChunkMeshes;

/// How far along a position is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum State {
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
pub(super) struct Slot {
    pub(super) state: State,
    /// A new number (never reused, see [`ChunkStreamer::next_version`]) when a job's
    /// result must be ignored (edited, regenerated, unloaded).
    ///
    /// [`ChunkStreamer::next_version`]: super::ChunkStreamer::next_version
    pub(super) version: u64,
    /// Whether the sink holds meshes of it.
    pub(super) uploaded: bool,
    /// The source failed for it: air stands in (reported when it happened).
    pub(super) failed: bool,
    /// Whether it is in the unload queue.
    pub(super) unload_queued: bool,
    /// Whether it is in the remesh queue.
    pub(super) remesh_queued: bool,
}

impl Slot {
    pub(super) fn new(state: State, version: u64) -> Self {
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
    pub(super) fn awaits(&self, version: u64, state: State) -> bool {
        self.version == version && self.state == state
    }

    pub(super) fn has_blocks(&self) -> bool {
        self.state != State::Generating
    }

    /// Whether its meshes are in the sink or on their way there: its neighbours must
    /// stay resident.
    pub(super) fn needs_neighbours(&self) -> bool {
        self.uploaded || matches!(self.state, State::Meshing | State::Ready)
    }
}

/// A finished mesh waiting for its upload, nearest first.
pub(super) struct Ready {
    pub(super) distance: i64,
    pub(super) pos: ChunkPos,
    pub(super) version: u64,
    pub(super) meshes: ChunkMeshes,
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
