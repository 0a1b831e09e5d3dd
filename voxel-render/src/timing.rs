//! GPU time per pass from timestamp queries (when the adapter has `TIMESTAMP_QUERY`).
//!
//! Each render pass asks for a pair of queries under a label; passes with the same label
//! (the many passes of depth peeling, say) add up. Results arrive a frame or more later
//! without stalling ([`GpuTimer::poll`]), or at once for tools ([`GpuTimer::read_blocking`]).

use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

use crate::GpuContext;

const IDLE: u8 = 0;
const MAPPING: u8 = 1;
const MAPPED: u8 = 2;
const FAILED: u8 = 3;

/// Timestamp queries for the passes of one frame, and the latest results.
#[derive(Debug)]
pub struct GpuTimer {
    query_set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    capacity: u32,
    labels: Vec<&'static str>,
    /// Labels of the frame whose timestamps are being copied or mapped.
    in_flight: Option<Vec<&'static str>>,
    copy_recorded: bool,
    state: Arc<AtomicU8>,
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
        let count = 2 * max_passes;
        let size = u64::from(count) * 8;
        let query_set = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass_timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count,
        });
        let buffer = |label, usage| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        Some(Self {
            query_set,
            resolve: buffer(
                "pass_timestamps_resolve",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            readback: buffer(
                "pass_timestamps_readback",
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            ),
            capacity: max_passes,
            labels: Vec::new(),
            in_flight: None,
            copy_recorded: false,
            state: Arc::new(AtomicU8::new(IDLE)),
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
            query_set: &self.query_set,
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        })
    }

    /// Records the copy of this frame's timestamps, unless an earlier frame's are still
    /// being read (that frame then goes untimed: timing never stalls rendering).
    pub fn end_frame(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if self.labels.is_empty()
            || self.state.load(Ordering::Acquire) != IDLE
            || self.copy_recorded
        {
            return;
        }
        let n = self.labels.len() as u32 * 2;
        encoder.resolve_query_set(&self.query_set, 0..n, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.readback, 0, u64::from(n) * 8);
        self.in_flight = Some(self.labels.clone());
        self.copy_recorded = true;
    }

    /// Call after submitting the encoder passed to [`GpuTimer::end_frame`]: starts mapping.
    pub fn after_submit(&mut self) {
        if !self.copy_recorded {
            return;
        }
        self.copy_recorded = false;
        self.state.store(MAPPING, Ordering::Release);
        let state = self.state.clone();
        self.readback
            .slice(..)
            .map_async(wgpu::MapMode::Read, move |r| {
                state.store(if r.is_ok() { MAPPED } else { FAILED }, Ordering::Release);
            });
    }

    /// Takes finished results, if any, and returns the latest: milliseconds per label, in
    /// the order the labels first appeared. Needs `device.poll` to be called now and then.
    pub fn poll(&mut self) -> &[(&'static str, f64)] {
        match self.state.load(Ordering::Acquire) {
            MAPPED => {
                if let (Some(labels), Ok(view)) = (
                    self.in_flight.take(),
                    self.readback.slice(..).get_mapped_range(),
                ) {
                    let ticks: &[u64] = bytemuck::cast_slice(&view[..labels.len() * 16]);
                    let mut out: Vec<(&'static str, f64)> = Vec::new();
                    for (label, pair) in labels.iter().zip(ticks.chunks_exact(2)) {
                        let ms = pair[1].saturating_sub(pair[0]) as f64 * self.period_ns / 1e6;
                        match out.iter_mut().find(|(l, _)| l == label) {
                            Some((_, total)) => *total += ms,
                            None => out.push((label, ms)),
                        }
                    }
                    self.latest = out;
                }
                self.readback.unmap();
                self.state.store(IDLE, Ordering::Release);
            }
            FAILED => {
                self.in_flight = None;
                self.state.store(IDLE, Ordering::Release);
            }
            _ => {}
        }
        &self.latest
    }

    /// Waits for the GPU and returns the results of the last submitted timed frame.
    pub fn read_blocking(&mut self, ctx: &GpuContext) -> Vec<(&'static str, f64)> {
        if self.state.load(Ordering::Acquire) == MAPPING {
            let _ = ctx.device.poll(wgpu::PollType::wait_indefinitely());
        }
        self.poll().to_vec()
    }
}
