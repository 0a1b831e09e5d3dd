//! GPU time per pass from timestamp queries (when the adapter has `TIMESTAMP_QUERY`).
//!
//! Each render pass asks for a pair of queries under a label; passes with the same label
//! (the many passes of depth peeling, say) add up. Results arrive a frame or more later
//! without stalling ([`GpuTimer::poll`]), or at once for tools ([`GpuTimer::read_blocking`]).

use crate::GpuContext;
use crate::readback::QueryReadback;

/// Timestamp queries for the passes of one frame, and the latest results.
#[derive(Debug)]
pub struct GpuTimer {
    queries: QueryReadback,
    capacity: u32,
    labels: Vec<&'static str>,
    /// Labels of the frame whose timestamps are being copied or mapped.
    in_flight: Vec<&'static str>,
    latest: Vec<(&'static str, f64)>,
    period_ns: f64,
}

impl GpuTimer {
    /// A timer for up to `max_passes` timed passes per frame, or `None` without
    /// timestamp support.
    pub fn new(ctx: &GpuContext, max_passes: u32) -> Option<Self> {
        if !ctx.caps.timestamps() {
            return None;
        }
        Some(Self {
            queries: QueryReadback::new(
                ctx,
                "pass_timestamps",
                wgpu::QueryType::Timestamp,
                2 * max_passes,
            ),
            capacity: max_passes,
            labels: Vec::new(),
            in_flight: Vec::new(),
            latest: Vec::new(),
            period_ns: f64::from(ctx.queue.get_timestamp_period()),
        })
    }

    /// Starts recording a frame's passes.
    pub fn begin_frame(&mut self) {
        self.labels.clear();
    }

    /// Timestamp writes for one pass under `label`; `None` when the frame's queries are all
    /// used (the pass then goes untimed).
    pub fn pass(&mut self, label: &'static str) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let i = self.labels.len() as u32;
        if i >= self.capacity {
            return None;
        }
        self.labels.push(label);
        Some(wgpu::RenderPassTimestampWrites {
            query_set: self.queries.set(),
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        })
    }

    /// Records the copy of this frame's timestamps, unless an earlier frame's are still
    /// being read (that frame then goes untimed: timing never stalls rendering).
    pub fn end_frame(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let n = self.labels.len() as u32 * 2;
        if self.queries.copy(encoder, 0..n) {
            self.in_flight = self.labels.clone();
        }
    }

    /// Call after submitting the encoder passed to [`GpuTimer::end_frame`]: starts mapping.
    pub fn after_submit(&mut self) {
        self.queries.map();
    }

    fn record(&mut self, ticks: Option<Vec<u64>>) {
        let Some(ticks) = ticks else { return };
        let mut out: Vec<(&'static str, f64)> = Vec::new();
        for (label, pair) in self.in_flight.iter().zip(ticks.chunks_exact(2)) {
            let ms = pair[1].saturating_sub(pair[0]) as f64 * self.period_ns / 1e6;
            match out.iter_mut().find(|(l, _)| l == label) {
                Some((_, total)) => *total += ms,
                None => out.push((label, ms)),
            }
        }
        self.latest = out;
    }

    /// Takes finished results, if any, and returns the latest: milliseconds per label, in
    /// the order the labels first appeared. Needs `device.poll` to be called now and then.
    pub fn poll(&mut self) -> &[(&'static str, f64)] {
        let ticks = self.queries.take();
        self.record(ticks);
        &self.latest
    }

    /// Waits for the GPU and returns the results of the last submitted timed frame.
    pub fn read_blocking(&mut self, ctx: &GpuContext) -> Vec<(&'static str, f64)> {
        let ticks = self.queries.wait(ctx);
        self.record(ticks);
        self.latest.clone()
    }
}
