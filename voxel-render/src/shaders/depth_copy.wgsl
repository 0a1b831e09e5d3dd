// Copies a depth texture into the depth attachment, texel for texel (appended to
// fullscreen.wgsl and `depth_uv`; `gpu::DepthCopy`), for devices that cannot copy depth
// textures.

@group(0) @binding(0) var source: texture_2d<f32>;
@group(0) @binding(1) var depth_sampler: sampler;

@fragment
fn fs_copy_depth(in: FullscreenOut) -> @builtin(frag_depth) f32 {
    let uv = depth_uv(in.clip.xy, textureDimensions(source));
    return textureSampleLevel(source, depth_sampler, uv, 0.0).x;
}
