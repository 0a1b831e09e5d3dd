//! GPU time per pass, from timestamp queries written at pass boundaries (when the adapter
//! has `TIMESTAMP_QUERY`), by [`wgpu_profiler`]: it grows its query pools as a frame needs
//! (peeling to convergence records hundreds of passes) and reads results back a frame or
//! more later without stalling.
//!
//! Passes are named by [`GpuPass`]; passes of the same kind (the many passes of depth
//! peeling) add up.
//!
//! Nothing needs to be called once a frame is submitted: the renderer learns of the
//! submission from the next frame ([`crate::submission`]) and only then ends the
//! profiler's frame, which wgpu-profiler allows only after submission. A frame recorded
//! while the previous one is still unsubmitted (two frames in one encoder) goes untimed;
//! a frame whose encoder was dropped unsubmitted is ended and its results discarded.

use std::collections::VecDeque;
use std::fmt;

use wgpu_profiler::{GpuProfiler, GpuProfilerQuery, GpuProfilerSettings, GpuTimerQueryResult};

use crate::GpuContext;
use crate::submission::Outcome;

/// The kinds of GPU work a frame is timed by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GpuPass {
    /// The opaque pass (and the MSAA depth resolve).
    Opaque,
    /// The cutout (alpha-tested) pass.
    Cutout,
    /// A game's own passes: its opaque geometry and its overlays (the `stages` module).
    Game,
    /// The technique's passes over the translucent meshes.
    Translucent,
    /// The technique's composite(s) into the scene colour.
    Composite,
    /// With the eye inside a translucent volume: the medium's boundary depth and its fog.
    Medium,
    /// HDR scene colour to the output.
    Tonemap,
}

impl GpuPass {
    /// Every pass kind, in frame order.
    pub const ALL: [GpuPass; 7] = [
        GpuPass::Opaque,
        GpuPass::Cutout,
        GpuPass::Game,
        GpuPass::Translucent,
        GpuPass::Composite,
        GpuPass::Medium,
        GpuPass::Tonemap,
    ];

    /// The name used in labels and reports.
    pub fn name(self) -> &'static str {
        match self {
            GpuPass::Opaque => "opaque",
            GpuPass::Cutout => "cutout",
            GpuPass::Game => "game",
            GpuPass::Translucent => "translucent",
            GpuPass::Composite => "composite",
            GpuPass::Medium => "medium",
            GpuPass::Tonemap => "tonemap",
        }
    }

    fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }
}

impl fmt::Display for GpuPass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Milliseconds of GPU time per [`GpuPass`] of one frame (`None`: no such pass ran).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GpuTimes {
    ms: [Option<f64>; GpuPass::ALL.len()],
}

impl GpuTimes {
    /// The time of `pass`, if it ran.
    pub fn get(&self, pass: GpuPass) -> Option<f64> {
        self.ms[pass as usize]
    }

    /// Whether no pass was timed.
    pub fn is_empty(&self) -> bool {
        self.ms.iter().all(Option::is_none)
    }

    /// The passes that ran with their times, in frame order.
    pub fn iter(&self) -> impl Iterator<Item = (GpuPass, f64)> + '_ {
        GpuPass::ALL
            .into_iter()
            .filter_map(|p| self.get(p).map(|ms| (p, ms)))
    }

    /// The translucent work of the frame: the technique's passes and composites.
    pub fn translucent_work(&self) -> f64 {
        self.get(GpuPass::Translucent).unwrap_or(0.0) + self.get(GpuPass::Composite).unwrap_or(0.0)
    }

    fn add(&mut self, pass: GpuPass, ms: f64) {
        *self.ms[pass as usize].get_or_insert(0.0) += ms;
    }
}

/// Profiler frames ended and not yet read back, at most: below wgpu-profiler's
/// `max_num_pending_frames`, so that it never drops one (our discard flags stay in step).
const MAX_PENDING_FRAMES: usize = 4;

/// Timestamp queries around the passes of each frame, and the latest results.
pub(crate) struct Timer {
    profiler: GpuProfiler,
    period: f32,
    latest: GpuTimes,
    /// Whether the last timed frame's submission is still to be learnt of.
    unsettled: bool,
    /// Per profiler frame ended and not yet read back, oldest first: whether to discard it
    /// (its encoder was dropped unsubmitted).
    ended: VecDeque<bool>,
}

impl fmt::Debug for Timer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Timer")
            .field("latest", &self.latest)
            .finish_non_exhaustive()
    }
}

impl Timer {
    /// A timer, or `None` when the device has no timestamp queries (frames then go
    /// untimed).
    pub(crate) fn new(ctx: &GpuContext) -> Option<Self> {
        if !ctx.caps.timestamps() {
            return None;
        }
        let settings = GpuProfilerSettings {
            enable_debug_groups: false,
            max_num_pending_frames: MAX_PENDING_FRAMES + 1,
            ..GpuProfilerSettings::default()
        };
        match GpuProfiler::new(&ctx.device, settings) {
            Ok(profiler) => Some(Self {
                profiler,
                period: ctx.queue.get_timestamp_period(),
                latest: GpuTimes::default(),
                unsettled: false,
                ended: VecDeque::new(),
            }),
            Err(e) => {
                log::warn!("GPU pass timing off: {e}");
                None
            }
        }
    }

    /// Reserves the timestamps of one pass of kind `pass`; give the query to
    /// [`Timer::end`] once the pass has ended.
    pub(crate) fn begin(
        &self,
        pass: GpuPass,
        encoder: &mut wgpu::CommandEncoder,
    ) -> GpuProfilerQuery {
        self.profiler.begin_pass_query(pass.name(), encoder)
    }

    /// Closes a query from [`Timer::begin`].
    pub(crate) fn end(&self, encoder: &mut wgpu::CommandEncoder, query: GpuProfilerQuery) {
        self.profiler.end_query(encoder, query);
    }

    /// Whether the next frame can be timed, given what became of the last frame's
    /// encoder (`last`): ends the last timed frame if it was submitted (or dropped) since,
    /// and reads back what has arrived. False while that encoder is still unsubmitted, or
    /// too many frames are still in flight.
    pub(crate) fn begin_frame(&mut self, ctx: &GpuContext, last: Outcome) -> bool {
        if ctx.check_device().is_err() {
            return false;
        }
        self.settle(ctx, last);
        self.poll_profiler();
        !self.unsettled && self.ended.len() < MAX_PENDING_FRAMES
    }

    /// Records the copy of the frame's timestamps at the end of `encoder`.
    pub(crate) fn end_frame(&mut self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder) {
        if ctx.check_device().is_err() {
            // Nothing of a lost device is read back: its buffers may not even exist.
            return;
        }
        self.profiler.resolve_queries(encoder);
        self.unsettled = true;
    }

    /// Ends the profiler frame of the last timed frame once its encoder was submitted
    /// (wgpu-profiler maps its buffers then) or dropped (its results are discarded).
    fn settle(&mut self, ctx: &GpuContext, last: Outcome) {
        if !self.unsettled {
            return;
        }
        // The profiler maps its buffers when its frame ends: never on a lost device, whose
        // buffers made after the loss are invalid (wgpu's handler would panic).
        if ctx.check_device().is_err() {
            return;
        }
        let discard = match last {
            Outcome::Pending | Outcome::Nothing => return,
            Outcome::Dropped => true,
            Outcome::Submitted => false,
        };
        self.unsettled = false;
        match self.profiler.end_frame() {
            Ok(()) => self.ended.push_back(discard),
            Err(e) => log::warn!("GPU pass timing lost a frame: {e}"),
        }
    }

    fn poll_profiler(&mut self) {
        while let Some(results) = self.profiler.process_finished_frame(self.period) {
            if !self.ended.pop_front().unwrap_or(false) {
                self.latest = Self::sum(&results);
            }
        }
    }

    /// Takes finished frames, if any, and returns the latest results, given what became
    /// of the last frame's encoder. Results arrive when the GPU is done and wgpu has been
    /// polled (each `queue.submit` polls).
    pub(crate) fn poll(&mut self, ctx: &GpuContext, last: Outcome) -> GpuTimes {
        self.settle(ctx, last);
        self.poll_profiler();
        self.latest
    }

    /// Waits for the GPU, then [`Timer::poll`]: the last submitted frame's results.
    /// `settle` learns what became of the last frame's encoder.
    pub(crate) fn read_blocking(
        &mut self,
        ctx: &GpuContext,
        mut settle: impl FnMut() -> Outcome,
    ) -> GpuTimes {
        let wait = || {
            if let Err(e) = ctx.device.poll(wgpu::PollType::wait_indefinitely()) {
                log::warn!("waiting for GPU timings: {e}");
            }
        };
        wait();
        let last = settle();
        self.settle(ctx, last);
        wait();
        self.poll(ctx, Outcome::Nothing)
    }

    fn sum(results: &[GpuTimerQueryResult]) -> GpuTimes {
        let mut times = GpuTimes::default();
        for r in results {
            if let (Some(pass), Some(t)) = (GpuPass::from_name(&r.label), &r.time) {
                times.add(pass, (t.end - t.start) * 1e3);
            }
        }
        times
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_of_a_kind_add_up_and_names_round_trip() {
        let mut t = GpuTimes::default();
        assert!(t.is_empty());
        t.add(GpuPass::Translucent, 1.5);
        t.add(GpuPass::Translucent, 2.0);
        t.add(GpuPass::Composite, 0.25);
        assert_eq!(t.get(GpuPass::Translucent), Some(3.5));
        assert_eq!(t.get(GpuPass::Opaque), None);
        assert_eq!(t.translucent_work(), 3.75);
        assert_eq!(
            t.iter().collect::<Vec<_>>(),
            [(GpuPass::Translucent, 3.5), (GpuPass::Composite, 0.25)]
        );
        for p in GpuPass::ALL {
            assert_eq!(GpuPass::from_name(p.name()), Some(p));
        }
    }
}
