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

@fragment
fn fs_peel(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    // Sample first: derivatives need uniform control flow.
    let c = translucent_color(in, front);
    // A fragment that does not count (alpha 0) is no layer.
    if !peel_candidate(in.clip) || c.a <= 0.0 {
        discard;
    }
    return c;
}

// Peeling to convergence (after state.wgsl): a fragment is also a layer where it changes
// the medium, and the layer holds the volume in front of it.
@fragment
fn fs_peel_state(in: VsOut, @builtin(front_facing) front: bool) -> PeelLayer {
    let c = surface_color(in, front);
    let look = medium_look(in.block);
    let info = fragment_info(in.block, front, in.flags);
    if !peel_candidate(in.clip) || (c.a <= 0.0 && !changes_medium(look, info)) {
        discard;
    }
    return peel_layer(in.clip, c, look, info);
}
