//! Structs shared with WGSL (`shaders/common.wgsl`), byte for byte.

use bytemuck::{Pod, Zeroable};

/// `vec4`s of the fitted weight's optical-depth table.
pub const OPTICAL_DEPTH_VEC4S: usize =
    crate::layers::TILES * crate::layers::TILES * crate::layers::PROFILE_LEN / 4;

/// Per-frame uniforms: camera, lighting and transparency parameters (`Frame` in WGSL).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct FrameUniforms {
    /// Camera-relative view × reverse-Z projection.
    pub view_proj: [[f32; 4]; 4],
    /// Integer part of the eye, clamped to the i32 world.
    pub eye_int: [i32; 3],
    /// Vertical field of view, radians.
    pub fov_y: f32,
    /// Fractional part of the eye, in [0, 1).
    pub eye_frac: [f32; 3],
    /// Near plane distance.
    pub near: f32,
    /// Unit vector towards the sun.
    pub sun_dir: [f32; 3],
    /// Ambient light in [0, 1]: the share of light that does not depend on the normal.
    pub ambient: f32,
    /// Sky colour, linear.
    pub sky: [f32; 3],
    /// Far plane distance.
    pub far: f32,
    /// Render target size in pixels.
    pub viewport: [f32; 2],
    /// WBOIT weight function id ([`crate::WeightFunction`] as u32).
    pub weight_fn: u32,
    /// Scale of WBOIT accumulation outputs (keeps fp16 sums finite, see `oit::wboit`).
    pub accum_scale: f32,
    /// Packed stipple shading state (seed 001's bit layout).
    pub shading_state: u32,
    /// Frame counter.
    pub frame_index: u32,
    /// Nearest and farthest view depth of the visible translucent chunks (fitted weight).
    pub depth_range: [f32; 2],
    /// Per screen tile, the expected optical depth in front of log-spaced depths across
    /// `depth_range` (fitted weight; [`crate::layers`]).
    pub optical_depth: [[f32; 4]; OPTICAL_DEPTH_VEC4S],
}

/// Per-chunk uniforms (`ChunkInfo` in WGSL).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ChunkUniforms {
    /// World coordinates of the chunk's block (0, 0, 0).
    pub origin: [i32; 3],
    /// Whole-chunk opacity multiplier (fade-in), 1 when settled.
    pub alpha: f32,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The WGSL structs' sizes under uniform layout rules (vec3 + scalar share 16 bytes).
    #[test]
    fn sizes_match_wgsl() {
        assert_eq!(
            std::mem::size_of::<FrameUniforms>(),
            64 + 16 * 4 + 16 + 16 + 16 * OPTICAL_DEPTH_VEC4S
        );
        assert_eq!(std::mem::size_of::<ChunkUniforms>(), 16);
    }
}
