// Moment-based OIT, the chunk pipelines' entries (appended to common.wgsl, moments.wgsl
// and, for the resolve, resolve.wgsl).

struct MomentsOut {
    @location(0) b0: vec4<f32>,
    @location(1) moments: vec4<f32>,
};

@fragment
fn fs_moments(in: VsOut, @builtin(front_facing) front: bool) -> MomentsOut {
    let m = mboit_moments(in.view_depth, translucent_color(in, front).a);
    return MomentsOut(m.b0, m.moments);
}
