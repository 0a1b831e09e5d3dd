//! Sorted alpha blending (the classic forward pass, painter's order): translucent chunk meshes drawn back to
//! front, blended `SrcAlpha, OneMinusSrcAlpha` into the HDR scene colour, depth tested
//! without depth write. The test is strictly nearer (reverse-Z `Greater`), not the usual
//! nearer-or-equal: a translucent face exactly at the opaque depth (an edge on an opaque
//! silhouette) is hidden, as in every other technique and the reference.
//!
//! Chunks come farthest first by [`voxel_mesh::order::chunk_order_key`] (exact for a grid of
//! equal cubes). `sorted` draws each chunk's quads in mesher order, which is wrong wherever
//! a chunk holds layers that overlap on screen. `sorted-quads` also orders the quads inside
//! each visible chunk exactly ([`voxel_mesh::order`]): a per-chunk structure is built once
//! per mesh, and a chunk is re-sorted only when the eye crosses one of its trigger planes
//! (its region key changes), so a still camera sorts nothing. The order is exact on every
//! pixel except where quads form a cycle (no order exists; counted in [`SortReport`], those
//! quads drawn farthest centre first).
//!
//! A game's translucent objects are drawn among the chunks (`interleave`): each before
//! the first chunk it lies behind, by sound tests of its bounding ball against the box and
//! the planes of the chunk's translucent quads (distance, the box's faces, the quads'
//! planes). Where none decides (a bubble between a water surface and a pane of one chunk),
//! `sorted-quads` draws the object among the chunk's quads, whose order is exact: after
//! those whose plane has the ball on the eye's side, before those with it beyond (the split
//! that the fewest planes disagree with); `sorted` lets the box's centre decide. So a
//! bubble under a water surface is drawn before it, one above after it, one behind a pane
//! over the water between the two. It is not exact for an object that crosses a layer (a
//! cube through a water surface: the part on the other side is drawn on the wrong side),
//! where two objects overlap in depth (their centres decide), or for the faces within one
//! object (the game's order); `sorted` is not exact where the centre decides either.

pub(crate) mod interleave;

// std's Instant panics in a browser; web_time's is std's elsewhere.
use web_time::Instant;

use voxel_core::ChunkPos;
use voxel_mesh::PackedQuad;
use voxel_mesh::order::{QuadOrder, RegionKey};

use crate::chunks::{ChunkStore, PosMap};
use crate::context::Capabilities;
use crate::gpu::{self, ChunkPipeline, CountedPass, Depth, DepthMode, Pass, SidedPipeline};
use crate::oit::{
    FrameView, OitConfig, Setup, Technique, TechniqueKind, TechniqueReport, TranslucentFrame,
    TranslucentTechnique,
};
use crate::stages::{Clip, GameDraw, TranslucentVariant, game_group, game_layout, game_prelude};
use crate::timing::GpuPass;
use crate::{GpuContext, Result};

/// What sorting quads did in the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SortReport {
    /// CPU milliseconds spent building orders and sorting.
    pub ms: f64,
    /// Chunks whose quads were re-sorted (the eye crossed one of their trigger planes, or
    /// they were remeshed).
    pub chunks_resorted: usize,
    /// Chunks whose order structure was built (newly visible or remeshed).
    pub chunks_built: usize,
    /// Cycles met in the visible chunks (groups of quads no order draws exactly).
    pub cycles: u32,
    /// Quads in those cycles.
    pub quads_in_cycles: u32,
}

/// One chunk's exact order and what it was last sorted for.
#[derive(Debug)]
struct ChunkOrder {
    generation: u64,
    order: QuadOrder,
    /// The region the GPU order is exact for (`None`: sort again on the next frame).
    sorted_for: Option<RegionKey>,
    /// The chunk's order stamp when this order was written
    /// (`GpuChunk::order_stamp`): another one means the GPU draws another order now.
    stamp: u64,
    /// Cycles of the last sort.
    cycles: (u32, u32),
}

/// The most planes a part of an object is clipped by (two an axis); `clip.wgsl`'s array.
const CLIP_PLANES: usize = 6;
// A part lies between at most two cuts an axis.
const _: () = assert!(CLIP_PLANES >= 2 * 3);

/// One clip as `clip.wgsl` reads it (`OitClip`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct ClipUniform {
    planes: [[f32; 4]; CLIP_PLANES],
    count: u32,
    far: u32,
    _pad: [u32; 2],
}

impl ClipUniform {
    /// `clip` for a frame drawn with `view_proj` from `eye` (the camera-relative origin of
    /// `view_proj`: its integer and fractional parts, as the frame splits it).
    fn new(clip: &Clip, view_proj: glam::Mat4, eye: glam::DVec3) -> Self {
        // A plane (n, w) of camera-relative positions is (M⁻¹)ᵀ (n, w) in clip space.
        let to_clip = glam::DMat4::from_cols_array(&view_proj.to_cols_array().map(f64::from))
            .inverse()
            .transpose();
        let mut out = Self::default();
        for (i, c) in clip.iter().take(CLIP_PLANES).enumerate() {
            let mut n = glam::DVec4::ZERO;
            n[c.axis] = c.eye_side;
            // Signed distance toward the eye: eye_side · (eye + rel − at) along the axis.
            n.w = c.eye_side * (eye[c.axis] - c.at);
            out.planes[i] = (to_clip * n).as_vec4().to_array();
            out.far |= u32::from(c.far) << i;
            out.count += 1;
        }
        out
    }
}

/// The clip WGSL of a game's prelude (`clip.wgsl`; the prelude declares
/// `OIT_OBJECT_DEPTH_BIAS`).
fn clip_wgsl() -> String {
    include_str!("clip.wgsl").to_owned()
}

/// The blending pipeline, and for `sorted-quads` each chunk's exact order.
#[derive(Debug)]
pub(crate) struct Sorted {
    pipeline: SidedPipeline,
    /// The group games bind (frame and boundary, and the clip of the parts drawn, at a
    /// dynamic offset).
    game_layout: wgpu::BindGroupLayout,
    /// Bytes between two clips in a frame's clip buffer (the device's uniform offset
    /// alignment).
    clip_stride: u64,
    sort_quads: bool,
    orders: PosMap<ChunkPos, ChunkOrder>,
    scratch: Vec<PackedQuad>,
    report: SortReport,
}

impl TechniqueKind for Sorted {
    type Key = ();

    const SORTS: bool = true;

    fn key(_: Technique, _: &OitConfig, _: &Capabilities) {}

    fn create(setup: &Setup, technique: Technique, _: &OitConfig) -> Result<Self> {
        let device = &setup.ctx.device;
        let module = gpu::shader(
            device,
            "sorted",
            &[&crate::bindings::common_wgsl(), include_str!("sorted.wgsl")],
        );
        let pipeline = ChunkPipeline {
            label: "sorted",
            module: &module,
            fragment_entry: "fs_sorted",
            groups: &setup.layouts.with(&[]),
            targets: &[gpu::scene_target(Some(wgpu::BlendState::ALPHA_BLENDING))],
            depth: DepthMode::ReadOnly,
            samples: 1,
        }
        .build_sided(device);
        let clip_entry = wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<ClipUniform>() as u64),
            },
            count: None,
        };
        let align = u64::from(device.limits().min_uniform_buffer_offset_alignment);
        let size = std::mem::size_of::<ClipUniform>() as u64;
        Ok(Self {
            pipeline,
            game_layout: game_layout(device, "sorted_game", &[clip_entry]),
            clip_stride: size.div_ceil(align) * align,
            sort_quads: technique == Technique::SortedQuads,
            orders: PosMap::default(),
            scratch: Vec::new(),
            report: SortReport::default(),
        })
    }
}

impl Sorted {
    /// Sorts the quads of the chunk at `pos` for `eye` if its region changed (or it was
    /// remeshed). Returns (built, sorted).
    fn sort_chunk(
        &mut self,
        ctx: &GpuContext,
        chunks: &mut ChunkStore,
        pos: ChunkPos,
        eye: glam::DVec3,
    ) -> (bool, bool) {
        let Some(chunk) = chunks.get(pos) else {
            return (false, false);
        };
        let (generation, stamp) = (chunk.generation(), chunk.order_stamp());
        let built = self
            .orders
            .get(&pos)
            .is_none_or(|o| o.generation != generation);
        if built {
            let order = QuadOrder::new(chunk.translucent_quads());
            self.orders.insert(
                pos,
                ChunkOrder {
                    generation,
                    order,
                    sorted_for: None,
                    stamp: 0,
                    cycles: (0, 0),
                },
            );
        }
        let Some(entry) = self.orders.get_mut(&pos) else {
            return (built, false);
        };
        // The eye in chunk-local cells (blocks but in a level of detail, whose cells are
        // wider in x and z: a scale on an axis keeps which side of each plane the eye is
        // on), in f64: exact wherever the world is.
        let o = pos.origin();
        let scale = chunks.get(pos).map_or([1.0; 3], |c| c.scale());
        let local = [0, 1, 2].map(|k| (eye[k] - o[k] as f64) / scale[k]);
        let key = entry.order.region_key(local);
        if entry.sorted_for == Some(key)
            && (entry.stamp == stamp || chunks.reapply_order(pos, entry.stamp))
        {
            // Still drawn, or drawn again from where `sorted` put it aside.
            return (built, false);
        }
        let stats = entry.order.sort_into(local, &mut self.scratch);
        // Exact for the whole region: sort again only when the key changes; otherwise
        // (rare) also when the eye moves.
        entry.sorted_for = stats.is_exact_in_region().then_some(key);
        entry.cycles = (stats.cycles, stats.quads_in_cycles);
        chunks.reorder_translucent(ctx, pos, std::mem::take(&mut self.scratch));
        entry.stamp = chunks.get(pos).map_or(0, |c| c.order_stamp());
        (built, true)
    }
}

impl Sorted {
    /// The game's group for a frame: the renderer's resources and the frame's clips (the
    /// first none), one every `clip_stride` bytes.
    fn game_group(&self, ctx: &GpuContext, game: &GameDraw<'_>) -> wgpu::BindGroup {
        use wgpu::util::DeviceExt;
        let (eye_int, eye_frac) = (game.frame.eye_int, game.frame.eye_frac);
        let eye = glam::DVec3::new(
            eye_int[0] as f64 + f64::from(eye_frac.x),
            eye_int[1] as f64 + f64::from(eye_frac.y),
            eye_int[2] as f64 + f64::from(eye_frac.z),
        );
        let none = Clip::new();
        let clips = if game.clips.is_empty() {
            std::slice::from_ref(&none)
        } else {
            game.clips
        };
        let stride = self.clip_stride as usize;
        let mut bytes = vec![0u8; stride * clips.len()];
        for (i, clip) in clips.iter().enumerate() {
            let uniform = ClipUniform::new(clip, game.frame.view_proj, eye);
            let at = i * stride;
            bytes[at..at + std::mem::size_of::<ClipUniform>()]
                .copy_from_slice(bytemuck::bytes_of(&uniform));
        }
        // A buffer of the frame's own: a frame recorded before the last one is submitted
        // keeps its clips.
        crate::cost::created_buffer();
        let buffer = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("sorted_clips"),
                contents: &bytes,
                usage: wgpu::BufferUsages::UNIFORM,
            });
        let clip = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &buffer,
            offset: 0,
            size: wgpu::BufferSize::new(std::mem::size_of::<ClipUniform>() as u64),
        });
        game_group(&ctx.device, "sorted_game", &self.game_layout, game, &[clip])
    }
}

impl TranslucentTechnique for Sorted {
    fn resize(&mut self, _: &GpuContext, _: u32, _: u32) -> Result<()> {
        Ok(())
    }

    /// Sorted-quads: builds the order structure of every chunk with translucent quads that
    /// has none (or one of an older mesh), so that the first frame only sorts.
    fn warm(&mut self, chunks: &ChunkStore) {
        if !self.sort_quads {
            return;
        }
        for chunk in chunks.iter() {
            let quads = chunk.translucent_quads();
            if quads.is_empty() {
                continue;
            }
            let (pos, generation) = (chunk.pos(), chunk.generation());
            if self
                .orders
                .get(&pos)
                .is_some_and(|o| o.generation == generation)
            {
                continue;
            }
            self.orders.insert(
                pos,
                ChunkOrder {
                    generation,
                    order: QuadOrder::new(quads),
                    sorted_for: None,
                    stamp: 0,
                    cycles: (0, 0),
                },
            );
        }
    }

    /// Sorted-quads: sorts the visible chunks whose region key changed since their last
    /// sort, building the order structure of newly visible or remeshed chunks first.
    fn prepare(
        &mut self,
        ctx: &GpuContext,
        _config: &OitConfig,
        chunks: &mut ChunkStore,
        view: &FrameView<'_>,
    ) -> Result<()> {
        if !self.sort_quads {
            // The mesher's order, whatever a technique drew before.
            chunks.restore_mesher_order();
            return Ok(());
        }
        let start = Instant::now();
        let mut report = SortReport::default();
        for &pos in view.translucent {
            let (built, sorted) = self.sort_chunk(ctx, chunks, pos, view.camera.eye);
            report.chunks_built += usize::from(built);
            report.chunks_resorted += usize::from(sorted);
            if let Some(o) = self.orders.get(&pos) {
                report.cycles += o.cycles.0;
                report.quads_in_cycles += o.cycles.1;
            }
        }
        // Forget chunks that were removed or remeshed since (kept bounded by the store).
        if self.orders.len() > 2 * chunks.len() + 64 {
            self.orders
                .retain(|pos, o| chunks.get(*pos).map(|c| c.generation()) == Some(o.generation));
        }
        report.ms = start.elapsed().as_secs_f64() * 1e3;
        self.report = report;
        Ok(())
    }

    fn render(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &TranslucentFrame<'_>,
    ) -> Result<()> {
        let colors = [gpu::load(&frame.target.view)];
        let pipeline = self.pipeline.get(frame.two_sided);
        let group = frame.game.map(|g| self.game_group(ctx, g));
        let stride = self.clip_stride;
        Pass::new("sorted", GpuPass::Translucent, &colors)
            .depth(Depth::ReadOnly(&frame.depth.view))
            .record(encoder, frame.timer, |pass| {
                pass.set_pipeline(pipeline);
                let (Some(game), Some(group)) = (frame.game, &group) else {
                    frame.draw_chunks(pass);
                    return;
                };
                // The objects where `interleave` put them (before a chunk, or among its
                // quads), each run with its clip, then the rest.
                pass.set_bind_group(0, frame.scene, &[]);
                let draws = frame.draws;
                let objects = |pass: &mut CountedPass<'_, '_>, range, clip: u32| {
                    let offset = (u64::from(clip) * stride) as u32;
                    game.draw_offsets(pass, 0, group, &[offset], range);
                };
                // The game's draws change the pipeline and group 0: set again before the
                // next chunk quads, not between two runs of objects.
                let lost = std::cell::Cell::new(false);
                let chunk_state = |pass: &mut CountedPass<'_, '_>| {
                    if lost.replace(false) {
                        pass.set_pipeline(pipeline);
                        pass.set_bind_group(0, frame.scene, &[]);
                    }
                };
                // Chunks before `chunk` are drawn, and quads `..quad` of it.
                let (mut next, mut chunk, mut quad) = (0, 0usize, 0u32);
                for split in game.splits {
                    let c = split.chunk as usize;
                    if c > chunk {
                        if quad > 0 {
                            chunk_state(pass);
                            draws.draw_quads(frame.chunks, chunk, quad..u32::MAX, pass);
                            chunk += 1;
                        }
                        if chunk < c {
                            chunk_state(pass);
                            draws.draw_range(frame.chunks, chunk..c, pass);
                        }
                        (chunk, quad) = (c, 0);
                    }
                    if split.quad > quad {
                        chunk_state(pass);
                        draws.draw_quads(frame.chunks, c, quad..split.quad, pass);
                        quad = split.quad;
                    }
                    let (start, end) = (split.start as usize, split.end as usize);
                    if end > start {
                        objects(pass, start..end, split.clip);
                        lost.set(true);
                        next = next.max(end);
                    }
                }
                chunk_state(pass);
                if quad > 0 {
                    draws.draw_quads(frame.chunks, chunk, quad..u32::MAX, pass);
                    chunk += 1;
                }
                draws.draw_range(frame.chunks, chunk..usize::MAX, pass);
                // A game that orders nothing (no objects declared) draws everything here.
                if next < game.objects || game.objects == 0 {
                    objects(pass, next..game.objects, 0);
                }
            });
        Ok(())
    }

    fn variants(&self) -> Vec<TranslucentVariant> {
        vec![TranslucentVariant {
            name: "sorted",
            wgsl: game_prelude(
                &clip_wgsl(),
                "struct OitOutput {\n    @location(0) color: vec4<f32>,\n};\n\n\
                 // Blended SrcAlpha, OneMinusSrcAlpha over what is behind, outside the\n\
                 // part being drawn discarded.\n\
                 fn oit_output(position: vec4<f32>, color: vec4<f32>) -> OitOutput {\n    \
                 if oit_clipped(position) {\n        discard;\n    }\n    \
                 return OitOutput(fogged(position.xy, position.z, color));\n}\n",
            ),
            targets: vec![gpu::scene_target(Some(wgpu::BlendState::ALPHA_BLENDING))],
            depth_stencil: gpu::depth_state(DepthMode::ReadOnly),
            layout: self.game_layout.clone(),
        }]
    }

    fn report(&self) -> TechniqueReport {
        TechniqueReport {
            sort: self.sort_quads.then_some(self.report),
            ..TechniqueReport::default()
        }
    }
}

#[cfg(test)]
mod clip_tests {
    use super::*;
    use crate::stages::ClipPlane;

    /// A clip plane in clip space gives, at a point's normalised device position, its
    /// signed distance from the plane over its view depth: what `clip.wgsl` compares.
    #[test]
    fn clip_planes_measure_the_distance_to_the_plane_over_the_view_depth() {
        let eye = glam::DVec3::new(1000.25, 64.5, -3000.75);
        let camera = crate::Camera::look_at(
            eye,
            eye + glam::DVec3::new(3.0, -1.0, -8.0),
            70.0,
            0.1,
            500.0,
        )
        .expect("a valid camera");
        let view_proj = camera.view_proj(16.0 / 9.0);
        for (axis, at) in [(1usize, 64.0), (0, 1003.0), (2, -3010.0)] {
            let eye_side = if eye[axis] >= at { 1.0 } else { -1.0 };
            let clip = vec![ClipPlane {
                axis,
                at,
                eye_side,
                far: false,
            }];
            let u = ClipUniform::new(&clip, view_proj, eye);
            assert_eq!(u.count, 1);
            let plane = glam::Vec4::from_array(u.planes[0]);
            for k in 0..50 {
                let t = f64::from(k) / 50.0;
                let p = eye
                    + glam::DVec3::new(3.0 + 4.0 * t, -1.0 - 2.0 * t, -8.0 + t) * (1.0 + 5.0 * t);
                let rel = (p - eye).as_vec3();
                let c = view_proj * rel.extend(1.0);
                let ndc = glam::Vec4::new(c.x / c.w, c.y / c.w, c.z / c.w, 1.0);
                let want = (p[axis] - at) * eye_side;
                let got = f64::from(plane.dot(ndc)) * f64::from(c.w);
                assert!(
                    (got - want).abs() < 1e-3 * (1.0 + want.abs()),
                    "axis {axis}: {got} against {want}"
                );
            }
        }
    }

    #[test]
    fn the_clip_uniform_is_laid_out_as_its_wgsl() {
        use crate::wgsl_layout::{assert_layout, field};
        let module = crate::wgsl_layout::parse(
            &("const OIT_OBJECT_DEPTH_BIAS: f32 = 0.0;\nstruct Frame { viewport: vec2<f32> };\n@group(0) @binding(0) var<uniform> frame: Frame;\n".to_owned()
                + &clip_wgsl()),
        );
        assert_layout::<ClipUniform>(
            &module,
            "OitClip",
            &[
                field!(ClipUniform, planes),
                field!(ClipUniform, count),
                field!(ClipUniform, far),
            ],
        );
    }
}
