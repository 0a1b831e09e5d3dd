// Moment-based OIT, the chunk pipelines' resolve entry (appended to common.wgsl,
// moments.wgsl and resolve.wgsl).

@fragment
fn fs_resolve(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    return mboit_resolve(in.clip, in.view_depth, translucent_color(in, front));
}
