//! What a frame asks of the GPU, counted while it is recorded: per render pass the draw
//! calls, pipeline and bind-group changes, full-screen draws and the bytes of the targets
//! it clears; measured by queries where the device has them, the fragments it shades
//! (pipeline statistics) and the samples it writes (occlusion queries), from which the
//! bytes of targets written and read follow. What decides a GPU's cost and a CPU
//! rasteriser hides: the lab reports it per technique ([`FrameCost`]).
//!
//! Off unless a frame is armed (`low_level::count_next_frame`); then the passes of that
//! frame are counted on the recording thread (a renderer records on the thread that calls
//! it, as `gpu::pipelines_built` counts), and the query results are read back
//! once the frame is submitted (`low_level::frame_cost`). A frame not armed pays one
//! thread-local look-up per recorded command.

use std::cell::RefCell;

use crate::timing::GpuPass;

/// What one render pass of a frame asked of the GPU.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PassCost {
    /// The pass's label.
    pub label: String,
    /// The kind of GPU work it counts as (`None`: an untimed pass).
    pub kind: Option<GpuPass>,
    /// Draw commands recorded: a `draw` or a `multi_draw_indirect` is one call.
    pub draw_calls: u32,
    /// Draws issued: each command of a multi-draw counts.
    pub draws: u32,
    /// Pipeline changes (a `set_pipeline` of the pipeline already set is not one).
    pub pipelines: u32,
    /// Bind group and vertex buffer changes (setting what is already bound is not one).
    pub bind_groups: u32,
    /// Calls into a game's own drawing (`stages::GameStages`); what a game's code
    /// records is not counted, except the ready-made content's.
    pub game_calls: u32,
    /// Full-screen triangles drawn.
    pub full_screen_draws: u32,
    /// Pixels those triangles cover (within the scissor rectangle in force).
    pub full_screen_pixels: u64,
    /// Bytes of the attachments it clears (every texel of each).
    pub clear_bytes: u64,
    /// Bytes each sample written moves into the attachments: the colour targets' texels,
    /// and the depth's where the pass writes depth.
    pub write_bytes_per_sample: u32,
    /// Bytes each sample written reads from the attachments: the colour targets' texels
    /// where the pass blends, the depth's where it tests depth.
    pub read_bytes_per_sample: u32,
    /// Bytes each shaded fragment reads from the textures the pass declares
    /// (`Pass::reads`: a composite's sums, a copy's source); the block textures and the
    /// media that chunk fragments read are not counted.
    pub texture_bytes_per_fragment: u32,
    /// Bytes a texture copy moved (read once, written once): a copy is a pass of its own
    /// here, with nothing drawn.
    pub copy_bytes: u64,
    /// Fragment shader invocations, as the driver counts them (pipeline statistics); `None`
    /// where the device has no such queries or the frame was not measured.
    pub fragments: Option<u64>,
    /// Samples that passed every per-fragment test (occlusion query): what was written or
    /// blended. `None` where not measured.
    pub samples: Option<u64>,
}

impl PassCost {
    /// Bytes written into the attachments: measured samples times the bytes a sample
    /// writes, plus the clears (`None` where the samples were not measured).
    pub fn bytes_written(&self) -> Option<u64> {
        if self.is_copy() {
            return Some(self.copy_bytes);
        }
        self.samples
            .map(|s| s * u64::from(self.write_bytes_per_sample) + self.clear_bytes)
    }

    /// Bytes read: measured samples times the bytes a sample reads of the attachments,
    /// plus shaded fragments times the declared texture bytes (`None` where not measured).
    pub fn bytes_read(&self) -> Option<u64> {
        if self.is_copy() {
            return Some(self.copy_bytes);
        }
        let samples = self.samples?;
        let fragments = self.fragments.unwrap_or(samples);
        Some(
            samples * u64::from(self.read_bytes_per_sample)
                + fragments * u64::from(self.texture_bytes_per_fragment),
        )
    }

    /// Whether it drew a full-screen triangle.
    pub(crate) fn is_full_screen(&self) -> bool {
        self.full_screen_draws > 0
    }

    /// Whether it is a texture copy rather than a render pass.
    pub(crate) fn is_copy(&self) -> bool {
        self.copy_bytes > 0
    }
}

/// What a frame asked of the GPU, pass by pass, and what it created and uploaded while it
/// was recorded.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameCost {
    /// The frame's size in pixels (for per-pixel figures).
    pub pixels: u64,
    /// Its render passes in the order recorded.
    pub passes: Vec<PassCost>,
    /// Buffer copies of the frame's own writes (`submission::FrameWrites`:
    /// uniforms, draw commands, re-sorted quads).
    pub uploads: u32,
    /// Their bytes.
    pub upload_bytes: u64,
    /// Buffers created while the frame was recorded.
    pub buffers_created: u32,
    /// Bind groups created while the frame was recorded.
    pub bind_groups_created: u32,
    /// Whether the fragments and samples were measured: the device has occlusion queries
    /// that count samples (not wgpu's GL backend, whose queries say only whether any
    /// sample passed, nor a browser's WebGPU), and the technique does not submit inside
    /// its frame. Where not, every measured figure is `None`.
    pub measured: bool,
}

impl FrameCost {
    /// The sums over the passes `which` selects.
    pub(crate) fn totals(&self, which: impl Fn(&PassCost) -> bool) -> CostTotals {
        let mut t = CostTotals {
            fragments: self.measured.then_some(0),
            samples: self.measured.then_some(0),
            bytes_written: self.measured.then_some(0),
            bytes_read: self.measured.then_some(0),
            ..CostTotals::default()
        };
        let add = |a: &mut Option<u64>, b: Option<u64>| {
            *a = a.zip(b).map(|(a, b)| a + b);
        };
        for p in self.passes.iter().filter(|p| which(p)) {
            if p.is_copy() {
                t.copies += 1;
            } else {
                t.passes += 1;
            }
            t.full_screen_passes += u32::from(p.is_full_screen());
            t.full_screen_pixels += p.full_screen_pixels;
            t.draw_calls += p.draw_calls;
            t.draws += p.draws;
            t.pipelines += p.pipelines;
            t.bind_groups += p.bind_groups;
            t.game_calls += p.game_calls;
            t.clear_bytes += p.clear_bytes;
            if p.is_copy() {
                add(&mut t.bytes_written, p.bytes_written());
                add(&mut t.bytes_read, p.bytes_read());
                continue;
            }
            add(&mut t.fragments, p.fragments.or(p.samples));
            add(&mut t.samples, p.samples);
            add(&mut t.bytes_written, p.bytes_written());
            add(&mut t.bytes_read, p.bytes_read());
        }
        t
    }

    /// The sums over the passes of the translucent work (the technique's passes and
    /// composites, as [`crate::GpuTimes::translucent_work`] times them).
    pub fn translucent(&self) -> CostTotals {
        self.totals(|p| matches!(p.kind, Some(GpuPass::Translucent | GpuPass::Composite)))
    }

    /// The sums over the passes of one kind.
    pub fn of_kind(&self, kind: GpuPass) -> CostTotals {
        self.totals(|p| p.kind == Some(kind))
    }

    /// The sums over every pass.
    pub fn all(&self) -> CostTotals {
        self.totals(|_| true)
    }
}

/// Sums of [`PassCost`]s over a set of passes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CostTotals {
    /// Render passes.
    pub passes: u32,
    /// Texture copies.
    pub copies: u32,
    /// Passes that drew a full-screen triangle.
    pub full_screen_passes: u32,
    /// Pixels those triangles covered.
    pub full_screen_pixels: u64,
    /// Draw commands recorded.
    pub draw_calls: u32,
    /// Draws issued.
    pub draws: u32,
    /// Pipeline changes.
    pub pipelines: u32,
    /// Bind group and vertex buffer changes.
    pub bind_groups: u32,
    /// Calls into a game's own drawing.
    pub game_calls: u32,
    /// Bytes of attachments cleared.
    pub clear_bytes: u64,
    /// Fragments shaded (the samples written where a pass's fragments were not counted).
    pub fragments: Option<u64>,
    /// Samples written or blended.
    pub samples: Option<u64>,
    /// Bytes written into attachments, clears included.
    pub bytes_written: Option<u64>,
    /// Bytes read from attachments and declared textures.
    pub bytes_read: Option<u64>,
}

impl CostTotals {
    /// Bytes written and read together (`None` where not measured).
    pub fn bytes(&self) -> Option<u64> {
        Some(self.bytes_written? + self.bytes_read?)
    }
}

/// How a pass's attachments and declared reads cost, known when it begins.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PassShape {
    /// Bytes of the attachments it clears.
    pub clear_bytes: u64,
    /// Bytes a written sample moves into the attachments.
    pub write_bytes: u32,
    /// Bytes a written sample reads of the attachments.
    pub read_bytes: u32,
    /// Bytes a shaded fragment reads of declared textures.
    pub texture_bytes: u32,
    /// The attachments' size, for the full-screen pixels.
    pub size: (u32, u32),
}

/// The bytes a texel of `format` takes in a target (the depth aspect of depth formats).
pub(crate) fn texel_bytes(format: wgpu::TextureFormat) -> u32 {
    format
        .target_pixel_byte_cost()
        .or_else(|| format.block_copy_size(Some(wgpu::TextureAspect::DepthOnly)))
        .or_else(|| format.block_copy_size(None))
        .unwrap_or(4)
}

/// The bytes of every texel of `texture`.
pub(crate) fn texture_bytes(texture: &wgpu::Texture) -> u64 {
    u64::from(texture.width())
        * u64::from(texture.height())
        * u64::from(texture.sample_count())
        * u64::from(texel_bytes(texture.format()))
}

/// Occlusion and pipeline-statistics query slots of a measured frame.
#[derive(Clone, Debug)]
pub(crate) struct QuerySlots {
    /// One occlusion query per pass.
    pub occlusion: wgpu::QuerySet,
    /// One pipeline-statistics query per pass (fragment shader invocations), where the
    /// device has them.
    pub statistics: Option<wgpu::QuerySet>,
    /// Slots in each set.
    pub capacity: u32,
}

/// The queries a pass of a measured frame writes: its slot in the sets.
#[derive(Clone, Debug)]
pub(crate) struct PassQueries {
    /// The slot.
    pub index: u32,
    /// The occlusion set, unless the pass uses occlusion queries of its own.
    pub occlusion: Option<wgpu::QuerySet>,
    /// The statistics set, where the device has one.
    pub statistics: Option<wgpu::QuerySet>,
}

/// Where the state set in the current pass stands, to tell changes from repeats.
#[derive(Debug, Default)]
struct Bound {
    pipeline: Option<wgpu::RenderPipeline>,
    groups: Vec<Option<(wgpu::BindGroup, Vec<u32>)>>,
    scissor: Option<u64>,
}

#[derive(Debug)]
struct Recorder {
    frame: FrameCost,
    queries: Option<QuerySlots>,
    next_query: u32,
    /// For each pass, its query slot (`None`: not measured).
    slots: Vec<Option<u32>>,
    current: Option<(PassCost, Bound, (u32, u32))>,
}

thread_local! {
    static RECORDER: RefCell<Option<Recorder>> = const { RefCell::new(None) };
}

fn with_pass(f: impl FnOnce(&mut PassCost, &mut Bound, (u32, u32))) {
    RECORDER.with_borrow_mut(|r| {
        if let Some((cost, bound, size)) = r.as_mut().and_then(|r| r.current.as_mut()) {
            f(cost, bound, *size);
        }
    });
}

fn with_frame(f: impl FnOnce(&mut FrameCost)) {
    RECORDER.with_borrow_mut(|r| {
        if let Some(r) = r.as_mut() {
            f(&mut r.frame);
        }
    });
}

/// Starts counting the frame about to be recorded on this thread, of `pixels` pixels,
/// measuring with `queries` when given. What an earlier frame left uncollected is
/// dropped.
pub(crate) fn begin_frame(pixels: u64, queries: Option<QuerySlots>) {
    RECORDER.with_borrow_mut(|r| {
        *r = Some(Recorder {
            frame: FrameCost {
                pixels,
                measured: queries.is_some(),
                ..FrameCost::default()
            },
            queries,
            next_query: 0,
            slots: Vec::new(),
            current: None,
        });
    });
}

/// Ends the frame begun with [`begin_frame`]: what was counted, each pass's query slot,
/// and how many slots were used. `None` when no frame was being counted.
pub(crate) fn end_frame() -> Option<(FrameCost, Vec<Option<u32>>, u32)> {
    RECORDER
        .with_borrow_mut(Option::take)
        .map(|r| (r.frame, r.slots, r.next_query))
}

/// Whether a frame is being counted on this thread.
pub(crate) fn counting() -> bool {
    RECORDER.with_borrow(Option::is_some)
}

/// Begins counting a pass; returns its query slots when the frame is measured and slots
/// are left. `own_occlusion`: the pass writes occlusion queries of its own (then it gets
/// no occlusion slot, and its samples are not measured).
pub(crate) fn begin_pass(
    label: &str,
    kind: Option<GpuPass>,
    shape: PassShape,
    own_occlusion: bool,
) -> Option<PassQueries> {
    RECORDER.with_borrow_mut(|r| {
        let r = r.as_mut()?;
        let cost = PassCost {
            label: label.to_owned(),
            kind,
            clear_bytes: shape.clear_bytes,
            write_bytes_per_sample: shape.write_bytes,
            read_bytes_per_sample: shape.read_bytes,
            texture_bytes_per_fragment: shape.texture_bytes,
            ..PassCost::default()
        };
        let bound = Bound {
            scissor: None,
            ..Bound::default()
        };
        r.current = Some((cost, bound, shape.size));
        let queries = r.queries.as_ref().filter(|q| r.next_query < q.capacity);
        let slot = queries.map(|q| PassQueries {
            index: r.next_query,
            occlusion: (!own_occlusion).then(|| q.occlusion.clone()),
            statistics: q.statistics.clone(),
        });
        r.slots.push(slot.as_ref().map(|s| s.index));
        if slot.is_some() {
            r.next_query += 1;
        }
        slot
    })
}

/// Ends the pass begun with [`begin_pass`].
pub(crate) fn end_pass() {
    RECORDER.with_borrow_mut(|r| {
        if let Some(r) = r.as_mut()
            && let Some((cost, _, _)) = r.current.take()
        {
            r.frame.passes.push(cost);
        }
    });
}

/// A pipeline set in the current pass.
pub(crate) fn set_pipeline(pipeline: &wgpu::RenderPipeline) {
    with_pass(|c, b, _| {
        if b.pipeline.as_ref() != Some(pipeline) {
            c.pipelines += 1;
            b.pipeline = Some(pipeline.clone());
        }
    });
}

/// A bind group set at `index` in the current pass (`None`: unset).
pub(crate) fn set_bind_group(index: u32, group: Option<&wgpu::BindGroup>, offsets: &[u32]) {
    with_pass(|c, b, _| {
        let i = index as usize;
        if b.groups.len() <= i {
            b.groups.resize(i + 1, None);
        }
        let new = group.map(|g| (g.clone(), offsets.to_vec()));
        if b.groups[i] != new {
            c.bind_groups += 1;
            b.groups[i] = new;
        }
    });
}

/// A vertex buffer bound in the current pass (always counted as a change).
pub(crate) fn set_vertex_buffer() {
    with_pass(|c, _, _| c.bind_groups += 1);
}

/// `calls` draw commands issuing `draws` draws in the current pass.
pub(crate) fn draw(calls: u32, draws: u32) {
    with_pass(|c, _, _| {
        c.draw_calls += calls;
        c.draws += draws;
    });
}

/// A full-screen triangle drawn in the current pass.
pub(crate) fn full_screen() {
    with_pass(|c, b, (w, h)| {
        c.draw_calls += 1;
        c.draws += 1;
        c.full_screen_draws += 1;
        c.full_screen_pixels += b.scissor.unwrap_or(u64::from(w) * u64::from(h));
    });
}

/// The scissor rectangle of the current pass covers `pixels`.
pub(crate) fn scissor(pixels: u64) {
    with_pass(|_, b, _| b.scissor = Some(pixels));
}

/// A call into a game's own drawing begins.
pub(crate) fn game_call() {
    with_pass(|c, _, _| c.game_calls += 1);
}

/// A call into a game's own drawing ended: what it set is unknown (the ready-made content
/// counts its own commands, `content::draw`; a game's are not counted).
pub(crate) fn game_call_done() {
    with_pass(|_, b, _| {
        b.pipeline = None;
        b.groups.clear();
    });
}

/// A texture copy of `bytes` outside any pass, of the kind `kind`.
pub(crate) fn copied(label: &str, kind: Option<GpuPass>, bytes: u64) {
    RECORDER.with_borrow_mut(|r| {
        if let Some(r) = r.as_mut() {
            r.frame.passes.push(PassCost {
                label: label.to_owned(),
                kind,
                copy_bytes: bytes.max(1),
                ..PassCost::default()
            });
            r.slots.push(None);
        }
    });
}

/// The frame's own writes: `copies` buffer copies of `bytes` in all.
pub(crate) fn uploaded(copies: u32, bytes: u64) {
    with_frame(|f| {
        f.uploads += copies;
        f.upload_bytes += bytes;
    });
}

/// A buffer created while the frame is recorded.
pub(crate) fn created_buffer() {
    with_frame(|f| f.buffers_created += 1);
}

/// A bind group created while the frame is recorded.
pub(crate) fn created_bind_group() {
    with_frame(|f| f.bind_groups_created += 1);
}

/// Query slots per measured frame: far above the passes of a real-time frame (depth
/// peeling's 8 layers record about 20).
pub(crate) const QUERY_CAPACITY: u32 = 256;

/// The query sets a renderer measures its frames with, and the buffers their results
/// come back through.
#[derive(Debug)]
pub(crate) struct CostQueries {
    slots: QuerySlots,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    /// Where the statistics start in the buffers (after the occlusion results, aligned).
    statistics_at: u64,
}

impl CostQueries {
    /// Query sets on `device`: occlusion always, pipeline statistics where `statistics`.
    pub(crate) fn new(device: &wgpu::Device, statistics: bool) -> Self {
        let capacity = QUERY_CAPACITY;
        let occlusion = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("cost_occlusion"),
            ty: wgpu::QueryType::Occlusion,
            count: capacity,
        });
        let statistics = statistics.then(|| {
            device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("cost_statistics"),
                ty: wgpu::QueryType::PipelineStatistics(
                    wgpu::PipelineStatisticsTypes::FRAGMENT_SHADER_INVOCATIONS,
                ),
                count: capacity,
            })
        });
        let align = wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT;
        let statistics_at = (u64::from(capacity) * 8).next_multiple_of(align);
        let size = 2 * statistics_at;
        let buffer = |label, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        Self {
            slots: QuerySlots {
                occlusion,
                statistics,
                capacity,
            },
            resolve: buffer("cost_resolve", U::QUERY_RESOLVE | U::COPY_SRC),
            readback: buffer("cost_readback", U::MAP_READ | U::COPY_DST),
            statistics_at,
        }
    }

    /// The slots a measured frame writes.
    pub(crate) fn slots(&self) -> QuerySlots {
        self.slots.clone()
    }

    /// Records the copy of the first `used` slots' results for [`CostQueries::read`].
    pub(crate) fn resolve(&self, encoder: &mut wgpu::CommandEncoder, used: u32) {
        if used == 0 {
            return;
        }
        let bytes = u64::from(used) * 8;
        encoder.resolve_query_set(&self.slots.occlusion, 0..used, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.readback, 0, bytes);
        if let Some(stats) = &self.slots.statistics {
            let at = self.statistics_at;
            encoder.resolve_query_set(stats, 0..used, &self.resolve, at);
            encoder.copy_buffer_to_buffer(&self.resolve, at, &self.readback, at, bytes);
        }
    }

    /// Waits for the results of a frame that used `used` slots (submitted) and returns,
    /// per slot, the samples passed and the fragments shaded (where counted).
    pub(crate) fn read(
        &self,
        ctx: &crate::GpuContext,
        used: u32,
    ) -> crate::Result<Vec<(u64, Option<u64>)>> {
        if used == 0 {
            return Ok(Vec::new());
        }
        let slice = self.readback.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        ctx.device.poll(wgpu::PollType::wait_indefinitely())?;
        match rx.try_recv() {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return Err(crate::Error::ReadbackData(format!("cost queries: {e}"))),
            Err(_) => {
                return Err(crate::Error::ReadbackData(
                    "cost queries: the mapping never completed".into(),
                ));
            }
        }
        let out = {
            let data = slice.get_mapped_range()?;
            let word = |at: usize| {
                data.get(at..at + 8)
                    .and_then(|b| b.try_into().ok())
                    .map_or(0, u64::from_le_bytes)
            };
            (0..used as usize)
                .map(|i| {
                    let fragments = self
                        .slots
                        .statistics
                        .as_ref()
                        .map(|_| word(self.statistics_at as usize + 8 * i));
                    (word(8 * i), fragments)
                })
                .collect()
        };
        self.readback.unmap();
        Ok(out)
    }
}

/// Fills the measured figures of `cost` from `results` (per slot) and each pass's slot.
pub(crate) fn fill(cost: &mut FrameCost, slots: &[Option<u32>], results: &[(u64, Option<u64>)]) {
    for (pass, slot) in cost.passes.iter_mut().zip(slots) {
        if let Some((samples, fragments)) = slot.and_then(|s| results.get(s as usize)) {
            pass.samples = Some(*samples);
            pass.fragments = *fragments;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn totals_add_the_selected_passes_and_derive_bytes() {
        let pass = |kind, samples, fragments| PassCost {
            kind: Some(kind),
            draw_calls: 2,
            draws: 5,
            clear_bytes: 100,
            write_bytes_per_sample: 8,
            read_bytes_per_sample: 12,
            texture_bytes_per_fragment: 1,
            samples,
            fragments,
            ..PassCost::default()
        };
        let frame = FrameCost {
            pixels: 10,
            passes: vec![
                pass(GpuPass::Translucent, Some(10), Some(12)),
                pass(GpuPass::Composite, Some(4), None),
                pass(GpuPass::Opaque, Some(1000), Some(1000)),
            ],
            measured: true,
            ..FrameCost::default()
        };
        let t = frame.translucent();
        assert_eq!((t.passes, t.draw_calls, t.draws), (2, 4, 10));
        // Fragments: 12 shaded, plus 4 samples where shading was not counted.
        assert_eq!(t.fragments, Some(16));
        assert_eq!(t.samples, Some(14));
        assert_eq!(t.bytes_written, Some(10 * 8 + 100 + 4 * 8 + 100));
        assert_eq!(t.bytes_read, Some(10 * 12 + 12 + 4 * 12 + 4));
        assert_eq!(frame.all().passes, 3);
    }

    #[test]
    fn an_unmeasured_pass_leaves_the_measured_totals_unknown() {
        let frame = FrameCost {
            passes: vec![PassCost {
                kind: Some(GpuPass::Translucent),
                ..PassCost::default()
            }],
            measured: true,
            ..FrameCost::default()
        };
        assert_eq!(frame.translucent().samples, None);
        assert_eq!(frame.translucent().bytes(), None);
    }

    #[test]
    fn changes_are_counted_repeats_are_not_and_nothing_counts_outside_a_frame() {
        // Outside a frame: nothing recorded, nothing panics.
        draw(1, 1);
        assert!(end_frame().is_none());
        begin_frame(100, None);
        assert!(counting());
        let shape = PassShape {
            size: (10, 10),
            ..PassShape::default()
        };
        assert!(begin_pass("p", Some(GpuPass::Translucent), shape, false).is_none());
        draw(1, 7);
        full_screen();
        scissor(12);
        full_screen();
        game_call();
        game_call_done();
        set_vertex_buffer();
        end_pass();
        created_buffer();
        uploaded(3, 40);
        let (cost, slots, used) = end_frame().expect("a frame was counted");
        assert!(!counting());
        assert_eq!((slots, used), (vec![None], 0));
        let p = &cost.passes[0];
        assert_eq!((p.draw_calls, p.draws, p.full_screen_draws), (3, 9, 2));
        assert_eq!(p.full_screen_pixels, 100 + 12);
        assert_eq!((p.game_calls, p.bind_groups), (1, 1));
        assert_eq!(
            (cost.uploads, cost.upload_bytes, cost.buffers_created),
            (3, 40, 1)
        );
    }

    #[test]
    fn texel_bytes_of_the_renderers_formats() {
        assert_eq!(texel_bytes(wgpu::TextureFormat::Rgba16Float), 8);
        assert_eq!(texel_bytes(wgpu::TextureFormat::R8Unorm), 1);
        assert_eq!(texel_bytes(wgpu::TextureFormat::Depth32Float), 4);
        assert_eq!(texel_bytes(wgpu::TextureFormat::Rgba32Float), 16);
    }
}
