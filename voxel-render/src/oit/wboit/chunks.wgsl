// Weighted blended OIT, the chunk pipelines' entries (appended to common.wgsl and
// accumulate.wgsl).

fn accumulation(in: VsOut, c: vec4<f32>) -> vec4<f32> {
    return wboit_accumulation(in.clip, in.view_depth, c);
}

struct WboitOut {
    @location(0) accumulation: vec4<f32>,
    @location(1) revealage: vec4<f32>,
};

// Single pass, two targets (needs independent blend).
@fragment
fn fs_accumulate_mrt(in: VsOut, @builtin(front_facing) front: bool) -> WboitOut {
    // The colour once: a compiler need not merge two calls that each sample a texture.
    let c = translucent_color(in, front);
    var out: WboitOut;
    out.accumulation = accumulation(in, c);
    // α in every channel: the revealage blend multiplies by one minus the source colour.
    out.revealage = vec4<f32>(c.a);
    return out;
}

// Two passes (for adapters without independent blend): accumulation first, revealage
// second.
@fragment
fn fs_accumulate(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    return accumulation(in, translucent_color(in, front));
}

@fragment
fn fs_revealage(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    return vec4<f32>(translucent_color(in, front).a);
}
