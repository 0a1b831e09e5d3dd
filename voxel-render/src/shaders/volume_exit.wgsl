// Where the volumes end along each pixel's ray (appended to common.wgsl), for the
// real-time techniques' path through the nearest volume (`path.wgsl`): the back faces
// of every volume type in front of the opaque surface, nearest kept in the depth
// attachment, which starts as a copy of the opaque depth. A volume entered at a front face
// then ends at the first of them, or at the opaque surface. With the eye inside a medium
// the faces up to that medium's boundary are its own way out, which the fog covers: they
// are dropped.
//
// In this pass group 0's `volume_depth` binding holds the opaque depth itself.
@fragment
fn fs_volume_exit(in: VsOut, @builtin(front_facing) front: bool) {
    if front || medium_look(in.block).a <= 0.0 {
        discard;
    }
    // At the boundary within rounding: the quads here are grown, the boundary's are not.
    if frame.medium != NO_MEDIUM && in.clip.z >= boundary_depth(in.clip.xy) * (1.0 - PATH_TIE) {
        discard;
    }
}

// The nearest entry into a volume in front of the opaque surface (a front face of a
// volume), its medium's look in the colour target: the volume the real-time techniques
// see fragments and the opaque picture through (`path.wgsl`). A chunk still dissolving in
// enters nothing where its face is dissolved. In this pass group 0's `volume_entry`
// binding holds the opaque depth itself.
@fragment
fn fs_volume_entry(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let m = medium_look(in.block);
    if !front || m.a <= 0.0 || faded_out(in) {
        discard;
    }
    return m;
}

// The farthest back face of a volume in front of the opaque surface and beyond the second
// entry (`fs_volume_entry2`): where the second volume ends, at worst (the sea behind a
// glass pillar standing in it, which leaves the loaded world through its side). The depth
// attachment starts at the near plane (1: no face), the farthest fragment kept; in this
// pass group 0's `volume_far` binding holds the opaque depth. After the second entry.
@fragment
fn fs_volume_far(in: VsOut, @builtin(front_facing) front: bool) {
    if front || medium_look(in.block).a <= 0.0 || in.clip.z <= depth_at(opaque_copy, in.clip.xy)
        || in.clip.z >= depth_at(volume_entry2, in.clip.xy) {
        discard;
    }
    // At the boundary within rounding: the quads here are grown, the boundary's are not.
    if frame.medium != NO_MEDIUM && in.clip.z >= boundary_depth(in.clip.xy) * (1.0 - PATH_TIE) {
        discard;
    }
}

// The nearest entry into a volume beyond where the nearest volume ends (at its end or
// farther, and beyond its entry), its medium's look in the colour target: the second
// volume along the ray (the sea behind a glass pillar standing in it, water under ice),
// which the real-time techniques see fragments through too (`path.wgsl`). A face at the
// first volume's end counts within rounding (another quad in the same plane). In this
// pass group 0's `volume_entry2` binding holds the opaque depth itself.
@fragment
fn fs_volume_entry2(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let m = medium_look(in.block);
    let z = in.clip.z;
    if !front || m.a <= 0.0 || faded_out(in) || z >= depth_at(volume_entry, in.clip.xy)
        || z > depth_at(volume_depth, in.clip.xy) * (1.0 + PATH_TIE) {
        discard;
    }
    return m;
}
