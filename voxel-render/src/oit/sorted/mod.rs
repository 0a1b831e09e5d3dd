//! Sorted alpha blending (seed 003's forward pass): translucent chunk meshes drawn back to
//! front by the distance of their centres from the eye, blended `SrcAlpha,
//! OneMinusSrcAlpha` into the HDR scene colour, depth tested (nearer or equal: seed 003's
//! `LessEqual` in our reverse-Z) without depth write.
//!
//! `sorted` draws each chunk's quads in mesher order; `sorted-quads` also sorts the quads
//! inside each visible chunk back to front on the CPU ([`Sorted::prepare`]
//! (TranslucentTechnique::prepare)) and rewrites them in that order.

use std::collections::HashMap;
use std::time::Instant;

use glam::DVec3;
use voxel_core::ChunkPos;

use crate::chunks::ChunkStore;
use crate::context::Capabilities;
use crate::gpu::{self, ChunkPipeline, Depth, DepthMode, Pass};
use crate::oit::{
    FrameView, OitConfig, Setup, Technique, TechniqueKind, TechniqueReport, TranslucentFrame,
    TranslucentTechnique,
};
use crate::timing::GpuPass;
use crate::{Error, GpuContext, Result};

/// Settings of the sorted techniques. Every field has a reasoned default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SortedSettings {
    /// Sorted-quads: how far (blocks) the eye may move before a chunk's quads are
    /// re-sorted.
    pub resort_distance: f64,
}

impl Default for SortedSettings {
    fn default() -> Self {
        Self {
            // A quarter block changes the order of few quads, and a sort of a chunk's
            // translucent quads takes microseconds.
            resort_distance: 0.25,
        }
    }
}

impl SortedSettings {
    /// The distance must be a finite number of blocks, 0 or more.
    pub fn validate(&self) -> Result<()> {
        if self.resort_distance.is_finite() && self.resort_distance >= 0.0 {
            Ok(())
        } else {
            Err(Error::InvalidSetting(format!(
                "sorted.resort_distance {}: must be a finite number of blocks, 0 or more",
                self.resort_distance
            )))
        }
    }
}

/// What sorting quads cost in the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SortReport {
    /// CPU milliseconds spent sorting.
    pub ms: f64,
    /// Chunks whose quads were re-sorted.
    pub chunks_resorted: usize,
}

/// The blending pipeline, and for `sorted-quads` the eye each chunk was last sorted for.
#[derive(Debug)]
pub struct Sorted {
    pipeline: wgpu::RenderPipeline,
    sort_quads: bool,
    /// Per chunk: the generation and the eye its quads were last sorted for.
    sorted_for: HashMap<ChunkPos, (u64, DVec3)>,
    report: SortReport,
}

impl TechniqueKind for Sorted {
    type Key = ();

    fn key(_: Technique, _: &OitConfig, _: &Capabilities) {}

    fn create(setup: &Setup, technique: Technique, _: &OitConfig) -> Result<Self> {
        let device = &setup.ctx.device;
        let module = gpu::shader(
            device,
            "sorted",
            &[crate::bindings::COMMON_WGSL, include_str!("sorted.wgsl")],
        );
        let pipeline = ChunkPipeline {
            label: "sorted",
            module: &module,
            fragment_entry: "fs_sorted",
            groups: &setup.layouts.with(&[]),
            targets: &[gpu::scene_target(Some(wgpu::BlendState::ALPHA_BLENDING))],
            depth: DepthMode::ReadOnlyOrEqual,
            samples: 1,
        }
        .build(device);
        Ok(Self {
            pipeline,
            sort_quads: technique == Technique::SortedQuads,
            sorted_for: HashMap::new(),
            report: SortReport::default(),
        })
    }
}

impl TranslucentTechnique for Sorted {
    fn resize(&mut self, _: &GpuContext, _: u32, _: u32) -> Result<()> {
        Ok(())
    }

    /// Sorted-quads: re-sorts the quads of the visible chunks whose last sort was for an
    /// eye farther than [`SortedSettings::resort_distance`] away, or that were remeshed.
    fn prepare(
        &mut self,
        ctx: &GpuContext,
        config: &OitConfig,
        chunks: &mut ChunkStore,
        view: &FrameView<'_>,
    ) -> Result<()> {
        if !self.sort_quads {
            return Ok(());
        }
        let start = Instant::now();
        let eye = view.camera.eye;
        let threshold = config.sorted.resort_distance;
        let mut n = 0;
        for &pos in view.translucent {
            let Some(chunk) = chunks.get(pos) else {
                continue;
            };
            let generation = chunk.generation();
            if self
                .sorted_for
                .get(&pos)
                .is_some_and(|(g, e)| *g == generation && e.distance(eye) <= threshold)
            {
                continue;
            }
            let mut quads = chunk.translucent_quads().to_vec();
            let o = pos.origin();
            let local = eye - DVec3::new(o[0] as f64, o[1] as f64, o[2] as f64);
            voxel_mesh::sort::quads_back_to_front(&mut quads, local.as_vec3().to_array());
            chunks.reorder_translucent(ctx, pos, quads);
            self.sorted_for.insert(pos, (generation, eye));
            n += 1;
        }
        if self.sorted_for.len() > 2 * chunks.len() + 64 {
            self.sorted_for
                .retain(|pos, (g, _)| chunks.get(*pos).map(|c| c.generation()) == Some(*g));
        }
        self.report = SortReport {
            ms: start.elapsed().as_secs_f64() * 1e3,
            chunks_resorted: n,
        };
        Ok(())
    }

    fn render(
        &mut self,
        _: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &TranslucentFrame<'_>,
    ) -> Result<()> {
        let colors = [gpu::load(&frame.target.view)];
        Pass::new("sorted", GpuPass::Translucent, &colors)
            .depth(Depth::ReadOnly(&frame.depth.view))
            .record(encoder, frame.timer, |pass| {
                pass.set_pipeline(&self.pipeline);
                frame.draw_chunks(pass);
            });
        Ok(())
    }

    fn report(&self) -> TechniqueReport {
        TechniqueReport {
            sort: self.sort_quads.then_some(self.report),
            ..TechniqueReport::default()
        }
    }
}
