// Depth peeling's limits (the technique's group 2): the layers already peeled at each
// pixel, front and back.

// Depth textures, read as float ones with group 0's nearest sampler (`gpu::DEPTH_READ`).
@group(2) @binding(0) var front_limit: texture_2d<f32>;
@group(2) @binding(1) var back_limit: texture_2d<f32>;

// Whether a fragment at `position` lies strictly between the two limits at its pixel.
fn peel_candidate(position: vec4<f32>) -> bool {
    let uv = depth_uv(position.xy, textureDimensions(front_limit));
    let d = position.z;
    return d < textureSampleLevel(front_limit, depth_sampler, uv, 0.0).x
        && d > textureSampleLevel(back_limit, depth_sampler, uv, 0.0).x;
}

// Peeling to convergence: per pixel, the medium the ray is in after the layers peeled so
// far (a look as halves: colour r, g in x; b and absorption in y), the last layer's depth
// (z, the bits of an f32) and whether a layer was peeled (w: 0 before the first, when the
// ray is still in the eye's medium, from the eye). Unused (1×1) in dual peeling.
@group(2) @binding(2) var peel_state: texture_2d<u32>;

// Where the ray stands at pixel `xy` after the layers peeled so far: its medium, and the
// depth it is in it since.
struct PeelFrom {
    medium: vec4<f32>,
    depth: f32,
};

fn peel_from_state(s: vec4<u32>) -> PeelFrom {
    if s.w == 0u {
        return PeelFrom(eye_medium(), EYE_Z);
    }
    return PeelFrom(vec4<f32>(unpack2x16float(s.x), unpack2x16float(s.y)), bitcast<f32>(s.z));
}

fn peel_from(xy: vec2<f32>) -> PeelFrom {
    return peel_from_state(textureLoad(peel_state, vec2<i32>(xy), 0));
}
