// Depth peeling composites (appended to fullscreen.wgsl). A layer target holds one layer's
// straight colour and alpha (transparent where the layer is empty).

@group(0) @binding(0) var layer: texture_2d<f32>;

// Front layers, nearest first, under-blended into the front accumulation
// (blend OneMinusDstAlpha, One): acc += (1 − acc.a) · (C·α, α).
@fragment
fn fs_under(in: FullscreenOut) -> @location(0) vec4<f32> {
    let c = textureLoad(layer, vec2<i32>(in.clip.xy), 0);
    return vec4<f32>(c.rgb * c.a, c.a);
}

// Back layers, farthest first, blended over the scene (SrcAlpha, OneMinusSrcAlpha).
@fragment
fn fs_over(in: FullscreenOut) -> @location(0) vec4<f32> {
    return textureLoad(layer, vec2<i32>(in.clip.xy), 0);
}

// The front accumulation (premultiplied) over the scene (One, OneMinusSrcAlpha).
@fragment
fn fs_front(in: FullscreenOut) -> @location(0) vec4<f32> {
    return textureLoad(layer, vec2<i32>(in.clip.xy), 0);
}
