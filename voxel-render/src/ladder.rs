//! The capability ladder: what each pass needs of a device (optional features, downlevel
//! flags, limits, formats), declared beside the code that needs it and checked before
//! anything is created, so that a technique a device cannot run is an
//! [`Error::Unsupported`] naming what is missing, never a wgpu validation error or a panic.
//! wgpu's examples declare `required_features`, `required_downlevel_capabilities` and
//! `required_limits` the same way.
//!
//! Where a device lacks something, the renderer steps down: the world's quads as instances
//! where the vertex stage has no storage buffers (`QuadFetch::Instanced`: WebGL2, many
//! GLES 3.1 devices), two-pass WBOIT without independent blend or a second colour
//! attachment, peel-to-convergence for the A-buffer without fragment storage; what has no
//! step down is refused. `Technique::LADDER` is the order a game goes down for the best
//! technique a device runs, stipple (which needs nothing but the world's own passes) last.

use std::fmt;

use crate::context::Capabilities;
use crate::{Error, Result};

/// A device limit the renderer depends on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Limit {
    /// `max_storage_buffers_per_shader_stage`.
    StorageBuffersPerStage,
    /// `max_storage_buffer_binding_size`, bytes.
    StorageBufferBindingSize,
    /// `max_sampled_textures_per_shader_stage`.
    SampledTexturesPerStage,
    /// `max_vertex_buffers`.
    VertexBuffers,
    /// `max_vertex_attributes`.
    VertexAttributes,
    /// `max_vertex_buffer_array_stride`, bytes.
    VertexBufferArrayStride,
    /// `max_dynamic_uniform_buffers_per_pipeline_layout`.
    DynamicUniformBuffers,
    /// `max_color_attachments`.
    ColorAttachments,
    /// `max_color_attachment_bytes_per_sample`.
    ColorAttachmentBytesPerSample,
    /// `max_inter_stage_shader_variables`.
    InterStageShaderVariables,
    /// `max_texture_dimension_2d`, texels.
    TextureDimension2d,
}

impl Limit {
    /// wgpu's name of the limit.
    pub fn name(self) -> &'static str {
        match self {
            Limit::StorageBuffersPerStage => "max_storage_buffers_per_shader_stage",
            Limit::StorageBufferBindingSize => "max_storage_buffer_binding_size",
            Limit::SampledTexturesPerStage => "max_sampled_textures_per_shader_stage",
            Limit::VertexBuffers => "max_vertex_buffers",
            Limit::VertexAttributes => "max_vertex_attributes",
            Limit::VertexBufferArrayStride => "max_vertex_buffer_array_stride",
            Limit::DynamicUniformBuffers => "max_dynamic_uniform_buffers_per_pipeline_layout",
            Limit::ColorAttachments => "max_color_attachments",
            Limit::ColorAttachmentBytesPerSample => "max_color_attachment_bytes_per_sample",
            Limit::InterStageShaderVariables => "max_inter_stage_shader_variables",
            Limit::TextureDimension2d => "max_texture_dimension_2d",
        }
    }

    /// Its value in `limits`.
    pub(crate) fn of(self, limits: &wgpu::Limits) -> u64 {
        match self {
            Limit::StorageBuffersPerStage => limits.max_storage_buffers_per_shader_stage.into(),
            Limit::StorageBufferBindingSize => limits.max_storage_buffer_binding_size,
            Limit::SampledTexturesPerStage => limits.max_sampled_textures_per_shader_stage.into(),
            Limit::VertexBuffers => limits.max_vertex_buffers.into(),
            Limit::VertexAttributes => limits.max_vertex_attributes.into(),
            Limit::VertexBufferArrayStride => limits.max_vertex_buffer_array_stride.into(),
            Limit::DynamicUniformBuffers => limits
                .max_dynamic_uniform_buffers_per_pipeline_layout
                .into(),
            Limit::ColorAttachments => limits.max_color_attachments.into(),
            Limit::ColorAttachmentBytesPerSample => {
                limits.max_color_attachment_bytes_per_sample.into()
            }
            Limit::InterStageShaderVariables => limits.max_inter_stage_shader_variables.into(),
            Limit::TextureDimension2d => limits.max_texture_dimension_2d.into(),
        }
    }
}

/// One thing a pass needs of the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Need {
    /// Optional features enabled on the device.
    Feature(wgpu::Features),
    /// Downlevel capabilities of the adapter.
    Downlevel(wgpu::DownlevelFlags),
    /// A limit of at least this value.
    Limit(Limit, u64),
    /// A colour format that can be rendered to.
    RenderTarget(wgpu::TextureFormat),
    /// A colour format that can be rendered to with blending.
    BlendableTarget(wgpu::TextureFormat),
    /// Each buffer and texture bound where the shaders declare it (not so on desktop GL
    /// below 4.2 that reports compute shaders).
    ShaderBindings,
    /// Waiting for the GPU within a frame, for a result the frame goes on with (the
    /// exact references' counts): not in a browser, whose page runs on one thread that
    /// must not block.
    WaitForGpu,
}

impl Need {
    /// Whether the device of `caps` has it.
    pub(crate) fn met(&self, caps: &Capabilities) -> bool {
        match *self {
            Need::Feature(f) => caps.features.contains(f),
            Need::Downlevel(d) => caps.downlevel.contains(d),
            Need::Limit(limit, value) => limit.of(&caps.limits) >= value,
            Need::RenderTarget(format) => caps.renders_to(format, false),
            Need::BlendableTarget(format) => caps.renders_to(format, true),
            Need::ShaderBindings => caps.shader_bindings(),
            Need::WaitForGpu => !cfg!(target_arch = "wasm32"),
        }
    }

    /// What it is, and what the device of `caps` has instead.
    pub(crate) fn describe(&self, caps: &Capabilities) -> String {
        match *self {
            Need::Limit(limit, value) => format!(
                "{} of at least {value} (this device: {})",
                limit.name(),
                limit.of(&caps.limits)
            ),
            other => other.to_string(),
        }
    }
}

impl fmt::Display for Need {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Need::Feature(features) => write!(f, "feature {features:?}"),
            Need::Downlevel(flags) => write!(f, "downlevel flag {flags:?}"),
            Need::Limit(limit, value) => write!(f, "{} of at least {value}", limit.name()),
            Need::RenderTarget(format) => write!(f, "{format:?} render targets"),
            Need::BlendableTarget(format) => write!(f, "blending into {format:?} render targets"),
            Need::ShaderBindings => write!(
                f,
                "resources bound where the shaders declare them (wgpu binds them all to \
                 slot 0 on desktop GL below 4.2 with compute shaders)"
            ),
            Need::WaitForGpu => write!(
                f,
                "waiting for the GPU within a frame (a web page's thread cannot block)"
            ),
        }
    }
}

/// The needs of `needs` that the device of `caps` lacks, described, joined with "; "
/// (`None` when it has them all).
pub(crate) fn missing(needs: &[Need], caps: &Capabilities) -> Option<String> {
    let lacking: Vec<String> = needs
        .iter()
        .filter(|n| !n.met(caps))
        .map(|n| n.describe(caps))
        .collect();
    (!lacking.is_empty()).then(|| lacking.join("; "))
}

/// `Ok` when the device of `caps` has every need of `what`, else [`Error::Unsupported`]
/// naming `what` and each capability it lacks.
pub fn check(what: &str, needs: &[Need], caps: &Capabilities) -> Result<()> {
    match missing(needs, caps) {
        None => Ok(()),
        Some(lacking) => Err(Error::Unsupported(format!(
            "{what} needs {lacking}, which this device ({}) lacks",
            caps.adapter_name
        ))),
    }
}

/// What the world's own passes need on every device, whichever way quads reach the
/// vertex shader (`QuadFetch::needs` adds that way's needs): the HDR scene colour
/// rendered to and blended into (the medium's fog, the composites, a game's overlays),
/// and the chunk shaders' ten values passed from vertex to fragment (`VsOut` in
/// `shaders/common.wgsl`), each bound where the shaders declare it.
pub(crate) fn world_needs() -> Vec<Need> {
    vec![
        Need::BlendableTarget(crate::SCENE_FORMAT),
        Need::Limit(Limit::InterStageShaderVariables, 11),
        Need::ShaderBindings,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn needs_say_what_they_are() {
        let storage = Limit::StorageBuffersPerStage;
        assert_eq!(
            Need::Limit(storage, 3).to_string(),
            "max_storage_buffers_per_shader_stage of at least 3"
        );
        assert_eq!(
            Need::Downlevel(wgpu::DownlevelFlags::VERTEX_STORAGE).to_string(),
            "downlevel flag DownlevelFlags(VERTEX_STORAGE)"
        );
        assert_eq!(
            Need::BlendableTarget(wgpu::TextureFormat::Rgba16Float).to_string(),
            "blending into Rgba16Float render targets"
        );
        let limits = wgpu::Limits::downlevel_webgl2_defaults();
        assert_eq!(storage.of(&limits), 0);
        assert_eq!(Limit::VertexBufferArrayStride.of(&limits), 255);
        assert_eq!(Limit::InterStageShaderVariables.of(&limits), 15);
    }
}
