//! Stipple (screen-door) transparency, the low-end mode (Mulder, Groen & van Wijk 1998,
//! with Bayer's ordered-dither matrices): a translucent fragment
//! is kept or discarded by comparing its alpha (texture alpha × uniform alpha × chunk
//! alpha) with a Bayer threshold at its screen position. No targets, no blending, no
//! sorting; kept pixels write depth unless configured not to (an open choice:
//! writing depth makes nearer stippled layers hide farther ones where they are kept, which
//! is what a screen door does; not writing lets farther layers show through the gaps of
//! nearer ones even where a nearer pixel was kept, which is wrong but softer).
//!
//! Its uniform (a packed 32-bit shading state) and the Bayer tables are its own group 2.
//! The shimmer when the camera moves is the technique's nature, kept as it is.

pub(crate) mod bayer;

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::context::Capabilities;
use crate::gpu::{self, ChunkPipeline, Depth, DepthMode, Pass, SidedPipeline, WgslConsts};
use crate::oit::{
    FrameView, OitConfig, Setup, Technique, TechniqueKind, TranslucentFrame, TranslucentTechnique,
};
use crate::stages::{TranslucentVariant, game_group, game_layout, game_prelude};
use crate::timing::GpuPass;
use crate::{Error, GpuContext, Result};

pub(crate) use bayer::BayerSize;
pub(crate) use bayer::ShadingState;

/// Settings of stipple. Every field has a reasoned default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StippleSettings {
    /// The Bayer pattern.
    pub bayer: BayerSize,
    /// Whether kept pixels write depth.
    pub depth_write: bool,
    /// Uniform alpha of the shading state, multiplying every translucent alpha (255 = 1).
    pub alpha: u8,
}

impl Default for StippleSettings {
    fn default() -> Self {
        Self {
            // 4×4: the classic console stipple, fine enough to read as a tint.
            bayer: BayerSize::B4,
            // Depth written as for opaque surfaces: nearer kept pixels hide what is behind
            // them, as a screen door does.
            depth_write: true,
            // 1: surfaces keep their own opacity.
            alpha: 255,
        }
    }
}

impl StippleSettings {
    /// The packed 32-bit shading state for these settings.
    pub(crate) fn shading_state(&self) -> ShadingState {
        ShadingState {
            alpha: self.alpha,
            pattern: self.bayer,
        }
    }

    /// Every value is valid (the types allow nothing else).
    pub fn validate(&self) -> Result<(), Error> {
        Ok(())
    }
}

/// The technique's uniform (`StippleParams` in `dither.wgsl`), 16 bytes: WebGL2 binds
/// no uniform of another size (wgpu's `BUFFER_BINDINGS_NOT_16_BYTE_ALIGNED`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(crate) struct StippleParams {
    /// [`ShadingState::pack`].
    pub shading_state: u32,
    /// Zeros, to 16 bytes (a uniform's array would be 16 bytes an element).
    pub pad0: u32,
    /// Zero.
    pub pad1: u32,
    /// Zero.
    pub pad2: u32,
}

/// The stipple shader: the Bayer offsets from Rust, the shared code, the screen door.
pub(crate) fn stipple_wgsl() -> String {
    [
        bayer_consts().as_str(),
        &crate::bindings::common_wgsl(),
        include_str!("dither.wgsl"),
        include_str!("stipple.wgsl"),
    ]
    .concat()
}

fn bayer_consts() -> String {
    let offsets = BayerSize::ALL.map(|b| bayer::bayer_offset(b) as u32);
    WgslConsts::default()
        .u32_array("BAYER_OFFSETS", &offsets)
        .u32("BAYER_VEC4S", bayer_vec4s().len() as u32)
        .finish()
}

/// The Bayer levels of [`bayer::bayer_levels`], four to a `vec4<u32>` (the last one padded
/// with zeros), as the uniform array of `dither.wgsl` holds them.
fn bayer_vec4s() -> Vec<[u32; 4]> {
    bayer::bayer_levels()
        .chunks(4)
        .map(|c| std::array::from_fn(|i| c.get(i).copied().unwrap_or(0)))
        .collect()
}

/// The group-2 entries of the stipple pipeline: the shading state and the Bayer tables,
/// both uniforms.
fn group_entries() -> [wgpu::BindGroupLayoutEntry; 2] {
    let uniform = |i| {
        gpu::buffer_entry(
            i,
            wgpu::ShaderStages::FRAGMENT,
            wgpu::BufferBindingType::Uniform,
        )
    };
    [uniform(0), uniform(1)]
}

/// The stipple pipeline and its uniform.
#[derive(Debug)]
pub(crate) struct Stipple {
    pipeline: SidedPipeline,
    depth_write: bool,
    params: wgpu::Buffer,
    levels: wgpu::Buffer,
    group: wgpu::BindGroup,
    game_layout: wgpu::BindGroupLayout,
}

impl TechniqueKind for Stipple {
    /// Depth write is baked into the pipeline; the pattern and alpha are uniforms.
    type Key = bool;

    fn key(_: Technique, config: &OitConfig, _: &Capabilities) -> bool {
        config.stipple.depth_write
    }

    fn create(setup: &Setup, _: Technique, config: &OitConfig) -> Result<Self> {
        let device = &setup.ctx.device;
        let layout = gpu::layout(device, "stipple_layout", &group_entries());
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("stipple_params"),
            contents: bytemuck::bytes_of(&StippleParams::default()),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let levels = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("bayer_levels"),
            contents: bytemuck::cast_slice(&bayer_vec4s()),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let group = gpu::bind_group(
            device,
            "stipple",
            &layout,
            &[params.as_entire_binding(), levels.as_entire_binding()],
        );
        let module = gpu::shader(device, "stipple", &[&stipple_wgsl()]);
        let depth_write = config.stipple.depth_write;
        let pipeline = ChunkPipeline {
            label: "stipple",
            module: &module,
            fragment_entry: "fs_stipple",
            groups: &setup.layouts.with(&[&layout]),
            targets: &[gpu::scene_target(None)],
            depth: if depth_write {
                DepthMode::Write
            } else {
                DepthMode::ReadOnly
            },
            samples: 1,
        }
        .build_sided(device);
        Ok(Self {
            pipeline,
            depth_write,
            params,
            levels,
            group,
            game_layout: game_layout(device, "stipple_game", &group_entries()),
        })
    }
}

impl TranslucentTechnique for Stipple {
    fn resize(&mut self, _: &GpuContext, _: u32, _: u32) -> Result<()> {
        Ok(())
    }

    fn prepare(
        &mut self,
        _ctx: &GpuContext,
        config: &OitConfig,
        _chunks: &mut crate::chunks::ChunkStore,
        view: &FrameView<'_>,
    ) -> Result<()> {
        let params = StippleParams {
            shading_state: config.stipple.shading_state().pack(),
            ..StippleParams::default()
        };
        view.write(&self.params, 0, bytemuck::bytes_of(&params));
        Ok(())
    }

    fn render(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        frame: &TranslucentFrame<'_>,
    ) -> Result<()> {
        let depth = if self.depth_write {
            Depth::Load(&frame.depth.view)
        } else {
            Depth::ReadOnly(&frame.depth.view)
        };
        let game = frame.game.map(|g| {
            let own = [
                self.params.as_entire_binding(),
                self.levels.as_entire_binding(),
            ];
            (
                g,
                game_group(&ctx.device, "stipple_game", &self.game_layout, g, &own),
            )
        });
        let colors = [gpu::load(&frame.target.view)];
        Pass::new("stipple", GpuPass::Translucent, &colors)
            .depth(depth)
            .opaque()
            .record(encoder, frame.timer, |pass| {
                pass.set_pipeline(self.pipeline.get(frame.two_sided));
                pass.set_bind_group(2, &self.group, &[]);
                frame.draw_chunks(pass);
                if let Some((g, group)) = &game {
                    g.draw_all(pass, 0, group);
                }
            });
        Ok(())
    }

    fn variants(&self) -> Vec<TranslucentVariant> {
        let own = bayer_consts() + include_str!("dither.wgsl");
        vec![TranslucentVariant {
            name: "stipple",
            wgsl: game_prelude(
                &own,
                "struct OitOutput {\n    @location(0) color: vec4<f32>,\n};\n\n\
                 // Kept opaque through the screen door, or discarded.\n\
                 fn oit_output(position: vec4<f32>, color: vec4<f32>) -> OitOutput {\n    \
                 return OitOutput(stipple(position, fogged(position.xy, position.z, color)));\n}\n",
            ),
            targets: vec![gpu::scene_target(None)],
            depth_stencil: gpu::depth_state(if self.depth_write {
                DepthMode::Write
            } else {
                DepthMode::ReadOnly
            }),
            layout: self.game_layout.clone(),
        }]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wgsl_layout::{assert_layout, field, parse};

    #[test]
    fn the_uniform_tables_hold_every_level_in_order() {
        let levels = bayer::bayer_levels();
        let packed: Vec<u32> = bayer_vec4s().into_iter().flatten().collect();
        assert_eq!(&packed[..levels.len()], &levels[..]);
        assert!(
            packed[levels.len()..].iter().all(|&v| v == 0),
            "zero padding"
        );
        assert!(packed.len() - levels.len() < 4);
    }

    #[test]
    fn params_match_their_wgsl() {
        assert_layout::<StippleParams>(
            &parse(&stipple_wgsl()),
            "StippleParams",
            &[
                field!(StippleParams, shading_state),
                field!(StippleParams, pad0),
                field!(StippleParams, pad1),
                field!(StippleParams, pad2),
            ],
        );
    }
}
