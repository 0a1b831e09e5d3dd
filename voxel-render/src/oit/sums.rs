//! What the techniques of weighted sums (WBOIT, MBOIT) share: additive blending, their
//! offscreen sums, and the chunk pass that draws into them over the opaque depth.

use crate::gpu::{self, ChunkGroups, ChunkPipeline, SidedPipeline, Target};

/// Source plus destination in every channel: how a fragment adds to a sum.
pub(super) const ADDITIVE: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
};

/// A colour target of `format` blended with `blend`, writing every channel.
pub(super) fn blended(
    format: wgpu::TextureFormat,
    blend: wgpu::BlendState,
) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend: Some(blend),
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// The sums' targets at `size`, one per `(label, format)`: drawn into, read by the
/// technique's composite, and copied out by the tests and the lab.
pub(super) fn targets<const N: usize>(
    device: &wgpu::Device,
    sums: [(&str, wgpu::TextureFormat); N],
    size: (u32, u32),
) -> [Target; N] {
    use wgpu::TextureUsages as U;
    let usage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC;
    sums.map(|(label, format)| gpu::target(device, label, format, usage, size))
}

/// Both variants of the chunk pass drawing fragment entry `fragment_entry` of `module`
/// into `targets`, testing the opaque depth and writing none.
pub(super) fn chunk_pass(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    fragment_entry: &str,
    groups: &ChunkGroups<'_>,
    targets: &[Option<wgpu::ColorTargetState>],
) -> SidedPipeline {
    ChunkPipeline {
        label,
        module,
        fragment_entry,
        groups,
        targets,
        depth: gpu::DepthMode::ReadOnly,
        samples: 1,
    }
    .build_sided(device)
}
