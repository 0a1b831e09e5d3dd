// Depth peeling's limits (the technique's group 2): the layers already peeled at each
// pixel, front and back.

@group(2) @binding(0) var front_limit: texture_depth_2d;
@group(2) @binding(1) var back_limit: texture_depth_2d;

// Whether a fragment at `position` lies strictly between the two limits at its pixel.
fn peel_candidate(position: vec4<f32>) -> bool {
    let p = vec2<i32>(position.xy);
    let d = position.z;
    return d < textureLoad(front_limit, p, 0) && d > textureLoad(back_limit, p, 0);
}
