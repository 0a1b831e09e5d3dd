//! One update ([`ChunkStreamer::update`]): what the workers finished is taken in, chunks
//! past the margin unload, new jobs start nearest first, and finished meshes go to the
//! sink within the budget; what it did is its [`StreamFrame`].

use std::collections::VecDeque;

use glam::DVec3;
// std's Instant panics in a browser; web_time's is std's elsewhere.
use voxel_core::{BlockId, CHUNK_SIZE, ChunkPos, Neighbourhood};
use web_time::Instant;

use super::jobs::Done;
use super::light::LightOp;
use super::slot::{Ready, Slot, State};
use super::{ChunkSink, ChunkStreamer};
use crate::{Error, Result};

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

/// Squared horizontal and vertical distance of an offset, for ordering and ranges.
pub(super) fn within(d: [i64; 3], radius: u32, vertical: u32) -> bool {
    let r = i64::from(radius);
    d[0] * d[0] + d[2] * d[2] <= r * r && d[1].abs() <= i64::from(vertical)
}

pub(super) fn distance2(d: [i64; 3]) -> i64 {
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

pub(super) fn offset(pos: ChunkPos, centre: ChunkPos) -> [i64; 3] {
    [
        i64::from(pos.x) - i64::from(centre.x),
        i64::from(pos.y) - i64::from(centre.y),
        i64::from(pos.z) - i64::from(centre.z),
    ]
}

impl ChunkStreamer {
    /// The eye's chunk, clamped into the `i32` world; an error for a non-finite eye.
    pub(super) fn centre_of(eye: DVec3) -> Result<ChunkPos> {
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

    pub(super) fn keeps(&self, pos: ChunkPos, centre: ChunkPos) -> bool {
        // At least 2 horizontally: the diagonal neighbours of the outermost chunks (which
        // their ambient occlusion reads) lie up to √2 chunks farther out.
        let h = self.config.hysteresis.max(2);
        within(
            offset(pos, centre),
            self.config.view_distance + h,
            self.config.vertical_distance + h,
        )
    }

    pub(super) fn wanted(&self, pos: ChunkPos, centre: ChunkPos) -> bool {
        within(
            offset(pos, centre),
            self.config.view_distance,
            self.config.vertical_distance,
        )
    }

    /// A version number never handed out before.
    pub(super) fn next_version(&mut self) -> u64 {
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
    pub(super) fn queue_unloads(&mut self) {
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
    pub(super) fn queue_remesh(&mut self, pos: ChunkPos) {
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
        self.run_local(centre, &mut frame);
        self.upload_some(sink, &mut frame);
        frame.jobs = self.jobs;
        Ok(frame)
    }

    /// A local pool's jobs, on this thread within [`StreamConfig::local_budget`] (at least
    /// one): when the queue runs dry, what the finished jobs made possible is queued (new
    /// chunks meshed once their neighbours have their blocks). Nothing with worker threads.
    ///
    /// [`StreamConfig::local_budget`]: super::StreamConfig::local_budget
    fn run_local(&mut self, centre: ChunkPos, frame: &mut StreamFrame) {
        if !self.pool.is_local() {
            return;
        }
        let start = Instant::now();
        loop {
            let job = match self.pool.pop() {
                Some(job) => job,
                None => {
                    self.receive(centre, frame);
                    self.dispatch(centre);
                    match self.pool.pop() {
                        Some(job) => job,
                        None => break,
                    }
                }
            };
            job();
            if start.elapsed() >= self.config.local_budget {
                break;
            }
        }
        self.receive(centre, frame);
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
                    if let Some(light) = &mut self.light {
                        light.insert(pos, self.world.shared(pos));
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
                    if let Some((sent, chunk)) = packed
                        && self.world.replace_shared(pos, &sent, chunk)
                        && let (Some(light), Some(now)) = (&mut self.light, self.world.shared(pos))
                    {
                        light.push(LightOp::Replace(pos, now));
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
                        if let Some(light) = &mut self.light {
                            light.insert(pos, None);
                        }
                    }
                }
                Done::Lit {
                    epoch,
                    lit,
                    changed,
                    failed,
                } => {
                    frame.failed.extend(failed);
                    self.receive_light(epoch, lit, changed, &mut frame.failed);
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
                self.world.remove_shared(pos);
                if let Some(light) = &mut self.light {
                    light.push(LightOp::Remove(pos));
                }
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

    /// Whether the chunk at `pos` and its 26 neighbours have their blocks (faces are culled
    /// against the face neighbours; ambient occlusion reads the edge and corner ones).
    /// With light on, they are all lit too.
    fn meshable(&self, pos: ChunkPos) -> bool {
        self.slots
            .get(&pos)
            .is_some_and(|s| s.state == State::Generated)
            && Neighbourhood::OFFSETS.iter().all(|&d| {
                pos.offset(d)
                    .is_none_or(|n| self.slots.get(&n).is_some_and(Slot::has_blocks))
            })
            && self.light.as_ref().is_none_or(|l| l.lit_around(pos))
    }

    fn dispatch(&mut self, centre: ChunkPos) {
        self.dispatch_light();
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
}
