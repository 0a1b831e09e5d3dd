// Copies sample 0 of the multisampled depth into the single-sample depth that the
// translucent pass tests against (appended to fullscreen.wgsl).

// Read as a float texture (`gpu::DEPTH_READ`).
@group(0) @binding(0) var msaa_depth: texture_multisampled_2d<f32>;

@fragment
fn fs_depth_resolve(in: FullscreenOut) -> @builtin(frag_depth) f32 {
    return textureLoad(msaa_depth, vec2<i32>(in.clip.xy), 0).x;
}
