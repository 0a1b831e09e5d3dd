//! Whether a frame's encoder was submitted, learnt without anything to call after the
//! submit: the frame's encoder carries a mapping of a small sentinel buffer that wgpu
//! starts when the encoder is submitted (`map_buffer_on_submit`), and whose callback is
//! dropped, unrun, when the encoder is dropped unsubmitted. The next frame looks.
//!
//! The renderer uses it for two things: GPU timings end a profiler frame only once its
//! encoder is submitted (the timing module), and a frame whose encoder was dropped has
//! its queue writes (uniforms, draw commands) flushed by an empty submit. wgpu keeps
//! queue writes, and their staging memory, until the next submit: a game that drops
//! every encoder would otherwise grow by each frame's writes (about 20 KiB at view
//! distance 2).

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
        if let Some(sentinel) = self.waiting.take() {
            sentinel.state.store(IDLE, Ordering::Release);
            self.idle.push(sentinel);
        }
        outcome
    }

    /// Gives `encoder` a signal of its submission, unless the last frame's is still
    /// waiting (this frame then shares its encoder, or will be learnt of with it).
    pub(crate) fn attach(&mut self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder) {
        if self.waiting.is_some() {
            return;
        }
        let sentinel = self.idle.pop().unwrap_or_else(|| Sentinel {
            buffer: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("submission_sentinel"),
                size: 8,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            state: Arc::new(AtomicU8::new(IDLE)),
        });
        sentinel.state.store(WAITING, Ordering::Release);
        let signal = Signal(sentinel.state.clone());
        encoder.map_buffer_on_submit(&sentinel.buffer, wgpu::MapMode::Read, .., move |r| {
            let state = if r.is_ok() { MAPPED } else { SUBMITTED };
            signal.0.store(state, Ordering::Release);
        });
        self.waiting = Some(sentinel);
    }
}
