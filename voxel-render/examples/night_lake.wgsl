// The night_lake example's own shaders: a sheet of mist over the water, drawn in every
// pass of the transparency technique (its fragment ends in `oit_output`, declared by the
// technique's prelude put before this file), and a HUD drawn over the tonemapped output.

struct Mist {
    // Camera-relative view-projection (`GameFrame::view_proj`).
    view_proj: mat4x4<f32>,
    // The sheet's centre relative to the eye (xyz) and its half side (w), blocks.
    center: vec4<f32>,
    // Linear colour (lit by the frame's light) and the opacity at its middle.
    color: vec4<f32>,
    // The output's size in pixels (xy), for the HUD.
    size: vec4<f32>,
};
@group(0) @binding(0) var<uniform> mist: Mist;

const CORNERS = array<vec2<f32>, 6>(
    vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0),
    vec2(-1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0),
);

struct MistOut {
    // Invariant, as depth peeling needs of every translucent surface.
    @builtin(position) @invariant position: vec4<f32>,
    // Where in the sheet, -1 to 1 each way.
    @location(0) uv: vec2<f32>,
};

// A horizontal square, seen from above and from below (both windings drawn).
@vertex
fn vs_mist(@builtin(vertex_index) i: u32) -> MistOut {
    let c = CORNERS[i % 6u];
    let p = mist.center.xyz + vec3<f32>(c.x, 0.0, c.y) * mist.center.w;
    return MistOut(mist.view_proj * vec4<f32>(p, 1.0), c);
}

// Thickest in the middle, thinning out to nothing at the edge.
fn mist_color(uv: vec2<f32>) -> vec4<f32> {
    let fade = 1.0 - smoothstep(0.3, 1.0, length(uv));
    return vec4<f32>(mist.color.rgb, mist.color.a * fade);
}

// The HUD: a frame of four bars, 3 px wide, 12 px inside the output's edges.
@vertex
fn vs_hud(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let bar = i / 6u;
    let c = CORNERS[i % 6u] * 0.5 + 0.5;
    let size = mist.size.xy;
    let inner = size - vec2<f32>(24.0);
    var lo = vec2<f32>(12.0);
    var ext = vec2<f32>(inner.x, 3.0);
    if bar == 1u {
        lo = vec2<f32>(12.0, size.y - 15.0);
    } else if bar == 2u {
        ext = vec2<f32>(3.0, inner.y);
    } else if bar == 3u {
        lo = vec2<f32>(size.x - 15.0, 12.0);
        ext = vec2<f32>(3.0, inner.y);
    }
    let px = lo + c * ext;
    return vec4<f32>(px.x / size.x * 2.0 - 1.0, 1.0 - px.y / size.y * 2.0, 0.0, 1.0);
}

@fragment
fn fs_hud() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0);
}
