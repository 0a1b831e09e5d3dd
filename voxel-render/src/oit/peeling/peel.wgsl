// Depth peeling (appended to common.wgsl): a fragment is a candidate only strictly between
// the two layers already peeled at its pixel. The pass's depth test then keeps the nearest
// candidate (front peel, compare greater in reverse-Z) or the farthest (back peel), and its
// colour replaces the layer target's: after the pass the target holds that one layer.
//
// Depth epsilon: none. Positions are @invariant, so the same fragment has the same depth
// bits in every pass, and strict comparisons exclude exactly the layer peeled before. (An
// epsilon, like the 0.0001 of common implementations, would merge distinct layers closer
// than it: in reverse-Z a window-depth difference of 1e-4 is many blocks at a distance of
// 100.)

@group(2) @binding(0) var front_limit: texture_depth_2d;
@group(2) @binding(1) var back_limit: texture_depth_2d;

@fragment
fn fs_peel(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    // Sample first: derivatives need uniform control flow.
    let c = translucent_color(in, front);
    let p = vec2<i32>(in.clip.xy);
    let d = in.clip.z;
    // A fragment that does not count (alpha 0) is no layer.
    if !(d < textureLoad(front_limit, p, 0) && d > textureLoad(back_limit, p, 0)) || c.a <= 0.0 {
        discard;
    }
    return c;
}
