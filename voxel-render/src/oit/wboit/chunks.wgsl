// Weighted blended OIT, the chunk pipelines' entries (appended to common.wgsl and
// accumulate.wgsl).

fn accumulation(in: VsOut, front: bool) -> vec4<f32> {
    return wboit_accumulation(in.clip, in.view_depth, translucent_color(in, front));
}

struct WboitOut {
    @location(0) accumulation: vec4<f32>,
    @location(1) revealage: vec4<f32>,
};

// Single pass, two targets (needs independent blend).
@fragment
fn fs_accumulate_mrt(in: VsOut, @builtin(front_facing) front: bool) -> WboitOut {
    var out: WboitOut;
    out.accumulation = accumulation(in, front);
    // α in every channel: the revealage blend multiplies by one minus the source colour.
    out.revealage = vec4<f32>(translucent_color(in, front).a);
    return out;
}

// Two passes (for adapters without independent blend): accumulation first, revealage
// second.
@fragment
fn fs_accumulate(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    return accumulation(in, front);
}

@fragment
fn fs_revealage(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    return vec4<f32>(translucent_color(in, front).a);
}
