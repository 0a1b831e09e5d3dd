// Exact reference, pass 1 for chunks (appended to common.wgsl, types.wgsl and
// abuffer.wgsl).

@fragment
fn fs_abuffer(in: VsOut, @builtin(front_facing) front: bool) {
    // Derivatives first, while every invocation of the quad still runs.
    let slope = vec2<f32>(dpdx(in.clip.z), dpdy(in.clip.z));
    // The face alone: the references put the volumes between the faces themselves.
    let info = fragment_info(in.block, front, in.flags);
    let keep = changes_medium(medium_look(in.block), info);
    abuffer_append(in.clip, slope, surface_color(in, front), info, keep);
}
