//! Whether a frame's encoder was submitted, learnt without anything to call after the
//! submit: the frame's encoder carries a mapping of a small sentinel buffer that wgpu
//! starts when the encoder is submitted (`map_buffer_on_submit`), and whose callback is
//! dropped, unrun, when the encoder is dropped unsubmitted. The next frame looks.
//!
//! The renderer uses it for three things: GPU timings end a profiler frame only once its
//! encoder is submitted (the timing module); a frame whose encoder was dropped has the
//! queue writes made meanwhile (chunk uploads) flushed by an empty submit, since wgpu
//! keeps queue writes, and their staging memory, until the next submit; and an exact
//! technique refuses to follow a frame in another encoder not yet submitted.
//!
//! A frame's own writes (uniforms, draw commands, quad order) are no queue writes:
//! [`FrameWrites`] records them as copies into the frame's encoder, from a staging buffer
//! the encoder keeps alive and frees with it, submitted or dropped.

use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

use crate::GpuContext;

const IDLE: u8 = 0;
const WAITING: u8 = 1;
const MAPPED: u8 = 2;
const SUBMITTED: u8 = 3;
const DROPPED: u8 = 4;

/// What became of the last frame's encoder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Outcome {
    /// No frame was waiting to be learnt of.
    Nothing,
    /// Not submitted yet (the next frame is recorded into the same encoder, or the game
    /// has not submitted it yet).
    Pending,
    /// Submitted (its mapping ran, successfully or not).
    Submitted,
    /// Dropped unsubmitted.
    Dropped,
}

/// An 8-byte buffer mapped when its frame's encoder is submitted.
#[derive(Debug)]
struct Sentinel {
    buffer: wgpu::Buffer,
    state: Arc<AtomicU8>,
    /// Which signal it carries ([`Submissions::attach`] counts them).
    serial: u64,
}

/// Held by the deferred mapping's callback: a callback dropped without running means its
/// encoder was dropped without being submitted.
struct Signal(Arc<AtomicU8>);

impl Drop for Signal {
    fn drop(&mut self) {
        let _ = self
            .0
            .compare_exchange(WAITING, DROPPED, Ordering::AcqRel, Ordering::Acquire);
    }
}

/// The submission signal of the last frame, and sentinels to reuse.
#[derive(Debug, Default)]
pub(crate) struct Submissions {
    waiting: Option<Sentinel>,
    idle: Vec<Sentinel>,
    /// Signals attached so far.
    serial: u64,
    /// A signal whose outcome is kept when it is settled ([`Submissions::watch`]), and
    /// that outcome once known.
    watched: Option<(u64, Option<Outcome>)>,
}

impl Submissions {
    /// What became of the last frame's encoder since it was recorded; after an outcome
    /// other than `Pending` the next frame gets a signal of its own.
    pub(crate) fn settle(&mut self, ctx: &GpuContext) -> Outcome {
        let Some(sentinel) = &self.waiting else {
            return Outcome::Nothing;
        };
        if sentinel.state.load(Ordering::Acquire) == WAITING {
            // A submitted encoder's mapping of the (otherwise unused) sentinel completes
            // at the next poll.
            let _ = ctx.device.poll(wgpu::PollType::Poll);
        }
        let outcome = match sentinel.state.load(Ordering::Acquire) {
            MAPPED => {
                sentinel.buffer.unmap();
                Outcome::Submitted
            }
            SUBMITTED => Outcome::Submitted,
            DROPPED => Outcome::Dropped,
            _ => return Outcome::Pending,
        };
        if let Some((serial, known)) = &mut self.watched
            && *serial == sentinel.serial
        {
            *known = Some(outcome);
        }
        if let Some(sentinel) = self.waiting.take() {
            sentinel.state.store(IDLE, Ordering::Release);
            self.idle.push(sentinel);
        }
        outcome
    }

    /// What became of the encoder that carries signal `serial` ([`Submissions::attach`]),
    /// without settling it: `Pending` while it is neither submitted nor dropped, `Nothing`
    /// when it was settled before it was watched ([`Submissions::watch`]).
    pub(crate) fn outcome_of(&self, ctx: &GpuContext, serial: u64) -> Outcome {
        if let Some((watched, Some(known))) = self.watched
            && watched == serial
        {
            return known;
        }
        let Some(sentinel) = self.waiting.as_ref().filter(|s| s.serial == serial) else {
            return Outcome::Nothing;
        };
        if sentinel.state.load(Ordering::Acquire) == WAITING {
            let _ = ctx.device.poll(wgpu::PollType::Poll);
        }
        match sentinel.state.load(Ordering::Acquire) {
            MAPPED | SUBMITTED => Outcome::Submitted,
            DROPPED => Outcome::Dropped,
            _ => Outcome::Pending,
        }
    }

    /// Keeps the outcome of signal `serial` when it is settled, for
    /// [`Submissions::outcome_of`] (one signal at a time: the last counted frame's).
    pub(crate) fn watch(&mut self, serial: u64) {
        self.watched = Some((serial, None));
    }

    /// Gives `encoder` a signal of its submission, unless the last frame's is still
    /// waiting (this frame then shares its encoder, or will be learnt of with it); returns
    /// the signal's serial.
    pub(crate) fn attach(&mut self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder) -> u64 {
        if let Some(waiting) = &self.waiting {
            return waiting.serial;
        }
        self.serial += 1;
        let serial = self.serial;
        let sentinel = self.idle.pop().unwrap_or_else(|| Sentinel {
            buffer: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("submission_sentinel"),
                size: 8,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            state: Arc::new(AtomicU8::new(IDLE)),
            serial,
        });
        let sentinel = Sentinel { serial, ..sentinel };
        sentinel.state.store(WAITING, Ordering::Release);
        let signal = Signal(sentinel.state.clone());
        encoder.map_buffer_on_submit(&sentinel.buffer, wgpu::MapMode::Read, .., move |r| {
            let state = if r.is_ok() { MAPPED } else { SUBMITTED };
            signal.0.store(state, Ordering::Release);
        });
        self.waiting = Some(sentinel);
        serial
    }
}

/// Buffer writes of one frame that land where its commands are: copies recorded into its
/// encoder (from one staging buffer made for them) by [`FrameWrites::record`], before its
/// first pass. `Queue::write_buffer` lands at the next submit instead, before every command
/// of it: two frames recorded before one submit would both read the second's uniforms,
/// draw commands and quad order. Bytes are gathered on the CPU until recorded.
#[derive(Debug, Default)]
pub(crate) struct FrameWrites {
    /// Every write's bytes, each padded to [`wgpu::COPY_BUFFER_ALIGNMENT`].
    bytes: Vec<u8>,
    /// Target buffer, offset in it, offset in `bytes`, length.
    copies: Vec<(wgpu::Buffer, u64, u64, u64)>,
}

impl FrameWrites {
    /// Writes `data` into `target` at `offset` (both as `Queue::write_buffer` needs them:
    /// multiples of 4, in bounds, `COPY_DST` usage) when recorded.
    pub(crate) fn write(&mut self, target: &wgpu::Buffer, offset: u64, data: &[u8]) {
        if data.is_empty() {
            return;
        }
        let at = self.bytes.len() as u64;
        self.bytes.extend_from_slice(data);
        let align = wgpu::COPY_BUFFER_ALIGNMENT as usize;
        self.bytes
            .resize(self.bytes.len().next_multiple_of(align), 0);
        self.copies
            .push((target.clone(), offset, at, data.len() as u64));
    }

    /// The copies waiting to be recorded, and their bytes.
    pub(crate) fn pending(&self) -> (u32, u64) {
        let bytes = self.copies.iter().map(|c| c.3).sum();
        (self.copies.len() as u32, bytes)
    }

    /// Moves `other`'s writes after this one's.
    pub(crate) fn append(&mut self, other: &mut FrameWrites) {
        let base = self.bytes.len() as u64;
        self.bytes.append(&mut other.bytes);
        self.copies.extend(
            other
                .copies
                .drain(..)
                .map(|(target, offset, at, len)| (target, offset, at + base, len)),
        );
    }

    /// Records the copies into `encoder`, in the order written, and forgets them.
    pub(crate) fn record(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
    ) -> crate::Result<()> {
        if self.copies.is_empty() {
            return Ok(());
        }
        // Mapped at creation and written once: no map request, nothing to wait for. wgpu
        // keeps it until the copies have run (or their encoder is dropped).
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame_writes"),
            size: self.bytes.len() as u64,
            usage: wgpu::BufferUsages::MAP_WRITE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: true,
        });
        staging
            .slice(..)
            .get_mapped_range_mut()?
            .copy_from_slice(&self.bytes);
        staging.unmap();
        for (target, offset, at, len) in self.copies.drain(..) {
            encoder.copy_buffer_to_buffer(&staging, at, &target, offset, len);
        }
        self.bytes.clear();
        Ok(())
    }
}

/// Where a buffer write lands: at the next submit (data uploaded between frames), or in
/// the frame being recorded ([`FrameWrites`]).
#[derive(Debug)]
pub(crate) enum Upload<'a> {
    /// `Queue::write_buffer`.
    Queue(&'a wgpu::Queue),
    /// A copy in the frame's encoder.
    Frame(&'a mut FrameWrites),
}

impl Upload<'_> {
    /// Writes `data` into `target` at `offset`.
    pub(crate) fn write(&mut self, target: &wgpu::Buffer, offset: u64, data: &[u8]) {
        match self {
            Upload::Queue(queue) => queue.write_buffer(target, offset, data),
            Upload::Frame(writes) => writes.write(target, offset, data),
        }
    }
}
